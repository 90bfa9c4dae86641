"""The README's and docs' Python examples run as written, the README's set-up commands are the
Makefile's, and its links point to files that exist."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text()
#: pages whose Python examples run as written (the README's and the harness example)
EXAMPLE_PAGES = ("README.md", "docs/ros2_integration.md")
PYTHON_BLOCKS = [
    block
    for page in EXAMPLE_PAGES
    for block in re.findall(r"```python\n(.*?)```", (REPO / page).read_text(), flags=re.S)
]
CONTROLLER_PAGE = (REPO / "docs" / "nodes" / "rns_controller.md").read_text()


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


def test_the_quoted_hold_correction_figures_are_todays():
    """The controller's page quotes the core loop's base deviation for midpoint and naive holds;
    a change of model, scenario or law that moves them must update the page too (2 digits)."""
    from rns_ros.analysis.closed_loop import run_scenario
    from rns_ros.control.scenario import load_scenario
    from rns_ros.core import load_model
    from rns_ros.resources import config_dir, default_model_config

    quoted = re.search(
        r"keeps the base still over each held period \(([0-9.e-]+) deg over\s+the 20 s "
        r"satellite-observation scenario at 100 Hz, against ([0-9.e-]+) deg for `naive`\)",
        CONTROLLER_PAGE,
    )
    assert quoted, "the hold-correction sentence of the controller page changed; update this test"
    robot = load_model(default_model_config())
    scenario = load_scenario(config_dir() / "scenarios" / "satellite_observation.yaml")
    for text, hold in zip(quoted.groups(), ("midpoint", "naive"), strict=True):
        measured = run_scenario(robot, scenario, hold_correction=hold).max_base_deviation_deg
        assert float(text) == float(f"{measured:.1e}"), f"{hold}: page {text}, now {measured:.2e}"


def test_readme_links_point_to_files_that_exist():
    links = re.findall(r"\]\(((?:docs|config)/[^)#]*)", README)
    assert links
    missing = [link for link in links if not (REPO / link).exists()]
    assert not missing, f"README links to missing files: {missing}"


def test_readme_stays_a_few_hundred_lines():
    assert len(README.splitlines()) <= 300, "move reference material to docs/"
