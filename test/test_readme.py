"""The README's Python examples run as written, and its set-up commands are the Makefile's."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text()
PYTHON_BLOCKS = re.findall(r"```python\n(.*?)```", README, flags=re.S)


def test_readme_has_python_examples():
    assert PYTHON_BLOCKS


@pytest.mark.parametrize("block", PYTHON_BLOCKS)
def test_readme_python_example_runs(block, capsys):
    namespace = {}
    exec(compile(block, "README.md", "exec"), namespace)  # our own documentation, run as written
    for name, value in namespace.items():
        if name.startswith("test_") and callable(value):
            value()  # an example pytest test in the README must pass too
    capsys.readouterr()


def test_readme_set_up_commands_exist_in_makefile():
    makefile = (REPO / "Makefile").read_text()
    for target in ("demo", "test"):
        assert f"make {target}" in README
        assert re.search(rf"^{target}:", makefile, flags=re.M)
    assert "make test" in (REPO / ".ci" / "run").read_text()
