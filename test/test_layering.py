"""The package's floors: imports point down only, and nothing below nodes/ touches ROS or rerun.

Floors (README, "Using the core"): core < control, sim < analysis < everything else. A module may
import its own floor and the floors below; control and sim are side by side and do not import each
other.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "rns_ros"
#: floor -> the rns_ros subpackages its modules may import
ALLOWED = {
    "core": {"core"},
    "control": {"core", "control"},
    "sim": {"core", "sim"},
    # resources: where the shipped config/ files are (stdlib only), for the thesis scenarios
    "analysis": {"core", "control", "sim", "analysis", "resources"},
}
ROS_OR_VIEWER = ("rclpy", "rerun", "rcl_interfaces", "std_msgs", "sensor_msgs", "geometry_msgs")


def _imports(path: Path) -> set[str]:
    """Every absolute module name ``path`` imports (at any depth of the file)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def _modules(floor: str) -> list[Path]:
    return sorted((PACKAGE / floor).rglob("*.py"))


@pytest.mark.parametrize("floor", sorted(ALLOWED))
def test_imports_point_down_only(floor):
    assert _modules(floor), f"rns_ros/{floor} has no modules"
    for path in _modules(floor):
        for name in _imports(path):
            parts = name.split(".")
            if parts[0] == "rns_ros" and len(parts) > 1:
                assert parts[1] in ALLOWED[floor], (
                    f"{path.relative_to(PACKAGE.parent)} imports {name}: rns_ros.{floor} may "
                    f"only import {sorted(ALLOWED[floor])}"
                )


@pytest.mark.parametrize("floor", sorted(ALLOWED))
def test_nothing_below_nodes_imports_ros_or_rerun(floor):
    for path in _modules(floor):
        bad = [name for name in _imports(path) if name.split(".")[0] in ROS_OR_VIEWER]
        assert not bad, f"{path.relative_to(PACKAGE.parent)} imports {bad}"
