"""The programs in rns_ros/apps/ stand apart: none imports another, and no library imports one."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "rns_ros"


def _imports(path: Path) -> set[str]:
    """Every absolute module name ``path`` imports, ``from rns_ros.apps import x`` as
    ``rns_ros.apps.x``."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def test_no_program_imports_another():
    programs = {f"rns_ros.apps.{path.stem}" for path in (PACKAGE / "apps").glob("*.py")}
    for path in (PACKAGE / "apps").glob("*.py"):
        others = (_imports(path) & programs) - {f"rns_ros.apps.{path.stem}"}
        assert not others, f"{path.name} imports {sorted(others)}"


def test_no_library_imports_a_program():
    for path in PACKAGE.rglob("*.py"):
        if path.parent == PACKAGE / "apps":
            continue
        bad = [name for name in _imports(path) if name.startswith("rns_ros.apps")]
        assert not bad, f"{path.relative_to(PACKAGE.parent)} imports {bad}"
