"""The package's rooms: imports point down only, no import circles, no ROS below nodes/.

Rooms (docs/architecture.md): core < control, sim < analysis, ground < viz and the libraries (cli,
resources, harness, keyboard, tool_session, tool_qos, ros_messages, bag) < nodes < runs < apps (the
programs).
A module may import its own room and the rooms listed for it; control and sim are side by side
and do not import each other.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "rns_ros"
#: room -> the rns_ros rooms (subpackages or top-level modules) its modules may import
ALLOWED = {
    "core": set(),
    "control": {"core", "resources"},
    "sim": {"core"},
    "cli": {"core"},
    "resources": {"core"},
    "analysis": {"core", "control", "sim", "resources"},
    "ground": {"core", "control", "sim", "resources"},
    "viz": {"core", "control", "sim", "resources"},
    "harness": {"core", "cli", "resources"},
    "keyboard": {"core", "control"},
    "nodes": {"core", "control", "sim", "ground", "viz", "cli", "resources", "keyboard", "bag"},
    "tool_session": {"core", "cli", "resources"},
    "tool_qos": {"tool_session"},
    "ros_messages": {"core", "cli", "resources", "tool_session"},
    "bag": {"core", "cli", "resources"},
    "runs": {
        "core",
        "control",
        "sim",
        "analysis",
        "ground",
        "viz",
        "cli",
        "resources",
        "harness",
        "nodes",
        "bag",
    },
}
#: the programs may import every room; test/apps/test_apps_apart.py keeps them apart
ALLOWED["apps"] = set(ALLOWED) | {"tool_session", "runs"}
#: rooms whose modules never import ROS 2 or the viewer
ROS_FREE = ("core", "control", "sim", "analysis", "ground", "resources")
ROS_OR_VIEWER = ("rclpy", "rerun", "rcl_interfaces", "std_msgs", "sensor_msgs", "geometry_msgs")


def _imports(path: Path) -> set[str]:
    """Every absolute module name ``path`` imports (at any depth of the file)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def _room(path: Path) -> str:
    parts = path.relative_to(PACKAGE).parts
    return parts[0] if len(parts) > 1 else parts[0].removesuffix(".py")


def _modules(room: str) -> list[Path]:
    folder = PACKAGE / room
    return sorted(folder.rglob("*.py")) if folder.is_dir() else [PACKAGE / f"{room}.py"]


def _is_room(name: str) -> bool:
    return (PACKAGE / name).is_dir() or (PACKAGE / f"{name}.py").exists()


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def test_every_room_has_a_rule():
    rooms = {_room(path) for path in PACKAGE.rglob("*.py")} - {"__init__"}
    assert rooms <= set(ALLOWED), f"rooms without a layering rule: {sorted(rooms - set(ALLOWED))}"


@pytest.mark.parametrize("room", sorted(ALLOWED))
def test_imports_point_down_only(room):
    assert all(path.exists() for path in _modules(room)), f"rns_ros/{room} is missing"
    allowed = ALLOWED[room] | {room}
    for path in _modules(room):
        for name in _imports(path):
            parts = name.split(".")
            if parts[0] == "rns_ros" and len(parts) > 1 and _is_room(parts[1]):
                assert parts[1] in allowed, (
                    f"{path.relative_to(PACKAGE.parent)} imports {name}: rns_ros.{room} may "
                    f"only import {sorted(allowed)}"
                )


@pytest.mark.parametrize("room", ROS_FREE)
def test_nothing_below_nodes_imports_ros_or_rerun(room):
    for path in _modules(room):
        bad = [name for name in _imports(path) if name.split(".")[0] in ROS_OR_VIEWER]
        assert not bad, f"{path.relative_to(PACKAGE.parent)} imports {bad}"


def _import_graph() -> dict[str, set[str]]:
    """module -> the rns_ros modules it imports; ``from package import module`` is an arrow to
    the module, not to the package's ``__init__``."""
    modules = {_module_name(path): path for path in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = defaultdict(set)
    for name, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                targets = [
                    f"{node.module}.{alias.name}"
                    if f"{node.module}.{alias.name}" in modules
                    else node.module
                    for alias in node.names
                ]
            else:
                continue
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name:
                    graph[name].add(target)
    return graph


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in graph.get(node, ()):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_the_import_graph_has_no_circles():
    assert _circles(_import_graph()) == []


def test_the_circle_finder_finds_a_circle():
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_program_imports_another():
    """The programs stand apart: what two of them share lives in a library (``rns_ros.runs``)."""
    programs = {_module_name(path) for path in _modules("apps")} - {"rns_ros.apps"}
    graph = _import_graph()
    for program in sorted(programs):
        others = (graph.get(program, set()) & programs) - {program}
        assert not others, f"{program} imports {sorted(others)}"
