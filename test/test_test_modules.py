"""The test tree: every test module's file name is unique. The test folders are not packages, so
pytest imports each module by its base name, and a second file of the same name under another
folder stops the whole run at collection ("import file mismatch")."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def test_every_test_module_name_is_unique():
    folders = defaultdict(list)
    for path in TESTS.rglob("test_*.py"):
        folders[path.name].append(str(path.parent.relative_to(TESTS)))
    clashes = {name: places for name, places in folders.items() if len(places) > 1}
    assert not clashes, f"test modules of the same name in several folders: {clashes}"
