"""Test helpers shared by the test modules (importable: test/ is on pytest's pythonpath)."""

from __future__ import annotations

import math
import struct

import numpy as np
from hypothesis import strategies as st

#: Initial configuration of the thesis satellite-observation scenario (section 4.2.2) [deg].
SATELLITE_OBSERVATION_DEG = (-90.0, -30.0, 0.0, -70.0, 180.0, -30.0, 0.0)
#: A short satellite-observation run for DDS tests: 30 deg roll about world x in 3 s, no wrist
#: term (scenario file contents; see rns_ros/control/scenario.py).
SHORT_ROLL_SCENARIO = {
    "name": "short_observation",
    "description": "30 deg roll about world x in 3 s",
    "initial_joint_positions_deg": list(SATELLITE_OBSERVATION_DEG),
    "frame": "world",
    "axis": [1, 0, 0],
    "angle_deg": 30.0,
    "duration": 3.0,
    "controller": {"wrist_gain": 0.0},
}


def unit_quaternions():
    """Uniformly distributed unit quaternions (x, y, z, w)."""
    return (
        st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4)
        .map(np.array)
        .filter(lambda v: np.linalg.norm(v) > 0.1)
        .map(lambda v: v / np.linalg.norm(v))
    )


def vectors(size: int, bound: float):
    return st.lists(st.floats(-bound, bound), min_size=size, max_size=size).map(np.array)


def configurations(robot_n: int = 7):
    """Random free-floating configurations: (base position, base quaternion, theta)."""
    return st.tuples(vectors(3, 5.0), unit_quaternions(), vectors(robot_n, np.pi))


class Recorder:
    """Keeps every message of a topic, keyed by header stamp when it has one."""

    def __init__(self, node, msg_type, topic, qos=50):
        self.messages = []
        node.create_subscription(msg_type, topic, self.messages.append, qos)

    def by_stamp(self):
        return {(m.header.stamp.sec, m.header.stamp.nanosec): m for m in self.messages}


def json_finite(value) -> bool:
    """Every number in a JSON value is finite (the report writes non-finite floats as strings)."""
    if isinstance(value, dict):
        return all(json_finite(v) for v in value.values())
    if isinstance(value, list):
        return all(json_finite(v) for v in value)
    if isinstance(value, str):
        return value not in ("inf", "-inf", "nan")
    if isinstance(value, float):
        return math.isfinite(value)
    return True


def quick_documents(identifiers, folder) -> dict:
    """{id: (JSON document, PNG path)} of registered reproductions run in quick mode into
    ``folder`` (results that share cached runs compute them once)."""
    import json

    from rns_ros.analysis.reproduce.registry import _REGISTRY, run_one

    written = {}
    for identifier in identifiers:
        record = run_one(_REGISTRY[identifier], folder, quick=True)
        written[identifier] = (json.loads(record.json_path.read_text()), record.png_path)
    return written


def quick_result_verdicts(document: dict, png, identifier: str) -> set[str]:
    """Check one quick result (its id, finite JSON, a real PNG) and return its verdicts, which
    must all be :class:`Verdict` values."""
    from rns_ros.analysis.reproduce.registry import Verdict

    assert document["id"] == identifier
    assert document["quick"] is True
    assert json_finite(document)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size > 10_000
    verdicts = {c["verdict"] for c in document["comparisons"]}
    assert verdicts <= {verdict.value for verdict in Verdict}
    return verdicts


def expected_verdict(thesis: float, ours: float, tolerance: float) -> str:
    """The verdict rule for one printed number, written out independently of the registry."""
    if abs(ours - thesis) <= tolerance:
        return "exact"
    return "close" if abs(ours - thesis) <= 0.1 * abs(thesis) else "different"


def comparison_rows(document) -> dict[str, dict]:
    """A result JSON's comparisons by key."""
    return {c["key"]: c for c in document["comparisons"]}


def assert_chapter_order(module: str, earlier: tuple[str, ...], identifiers) -> None:
    """Chapter ``module`` loads after each of the ``earlier`` chapter modules and registers
    ``identifiers``."""
    from rns_ros.analysis.reproduce import registry

    modules = [name.rsplit(".", 1)[1] for name in registry.CHAPTER_MODULES]
    for name in earlier:
        assert modules.index(name) < modules.index(module)
    assert set(identifiers) <= set(registry.load_all())


def big_endian_joint_state(names: list[str], position: list[float]) -> bytes:
    """A JointState in big-endian CDR (rclpy writes little-endian only on this machine)."""
    out = bytearray(b"\x00\x00\x00\x00")  # CDR_BE

    def align(size):
        out.extend(b"\x00" * (-(len(out) - 4) % size))

    def string(text):
        align(4)
        raw = text.encode() + b"\x00"
        out.extend(struct.pack(">I", len(raw)) + raw)

    out.extend(struct.pack(">iI", 3, 4))
    string("")
    align(4)
    out.extend(struct.pack(">I", len(names)))
    for name in names:
        string(name)
    align(4)
    out.extend(struct.pack(">I", len(position)))
    align(8)
    out.extend(struct.pack(f">{len(position)}d", *position))
    for _ in range(2):
        align(4)
        out.extend(struct.pack(">I", 0))
    return bytes(out)


def status_values(msg) -> dict[str, str]:
    """The key values of a diagnostic_msgs/DiagnosticArray's first status."""
    return {kv.key: kv.value for kv in msg.status[0].values}


def caught_up(status, tolerance: float = 2e-3) -> bool:
    """rns_controller's newest status (a Recorder of ~/status) says the camera is within
    ``tolerance`` [rad] of the attitude the commands add up to (tracking_error): from then on
    it turns at the commanded rate itself, not at that rate plus a catch-up."""
    if not status.messages:
        return False
    return float(status_values(status.messages[-1]).get("tracking_error", "inf")) < tolerance


def caught_up_camera(ros, status, simulator, timeout: float = 30.0, tolerance: float = 2e-3):
    """The simulator's camera rotation in world (3, 3) at a moment this process saw the camera
    caught up with the attitude the commands add up to (:func:`caught_up`, ``tolerance`` [rad]),
    and that moment on this process's monotonic clock [s]: the snapshot lies between two
    consecutive caught-up statuses (a stall in between, which lets the camera fall behind,
    makes it try again), so the camera then is within ``tolerance`` of the commanded attitude
    whatever the machine's load. Fails the test after ``timeout`` [s]."""
    import time

    import pytest

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if not ros.spin_until(lambda: caught_up(status, tolerance), deadline - time.monotonic()):
            break
        seen = len(status.messages)
        moment, (_, camera) = time.monotonic(), simulated_camera(simulator)
        newer = ros.spin_until(
            lambda seen=seen: len(status.messages) > seen, deadline - time.monotonic()
        )
        if newer and caught_up(status, tolerance):
            return moment, camera
    pytest.fail(f"the camera did not catch up with the commands within {timeout} s")


class SimClock:
    """A simulated ``/clock`` a test publishes itself, for nodes under ``use_sim_time``: time
    stands still between :meth:`advance` calls, whatever the wall clock does.

    Args:
        node: the node that publishes (e.g. a harness probe).
        start: the first reading [s].
    """

    def __init__(self, node, start: float = 100.0) -> None:
        from rclpy.qos import QoSProfile
        from rosgraph_msgs.msg import Clock

        self._msg_type = Clock
        self._publisher = node.create_publisher(Clock, "/clock", QoSProfile(depth=1))
        self.seconds = start

    def advance(self, dt: float):
        """Publish the clock ``dt`` [s] later; returns its stamp (builtin_interfaces/Time)."""
        from rns_ros.nodes.sim_clock import stamp_from_seconds

        self.seconds += dt
        stamp = stamp_from_seconds(self.seconds)
        self._publisher.publish(self._msg_type(clock=stamp))
        return stamp


def six_joint_model(folder, wrist_frame: str | None = "wrist"):
    """A model YAML in ``folder`` for the default arm with joint_7 welded (a fixed joint): 6
    controlled joints; ``wrist_frame`` None writes ``wrist_frame: null``. Returns its path."""
    from rns_ros.core.config import load_model_config
    from rns_ros.resources import default_model_config

    urdf, _ = load_model_config(default_model_config())
    text = urdf.read_text()
    welded = text.replace(
        '<joint name="joint_7" type="revolute">', '<joint name="joint_7" type="fixed">'
    )
    assert welded != text
    (folder / "arm6.urdf").write_text(welded)
    model = folder / "arm6.yaml"
    wrist = "null" if wrist_frame is None else wrist_frame
    model.write_text(f"urdf: arm6.urdf\ncamera_frame: camera\nwrist_frame: {wrist}\n")
    return model


def simulated_camera(simulator):
    """An in-process rns_simulator's simulated time [s] and its camera's rotation in world (3, 3)
    at that time (one snapshot: the arm as the simulation has integrated it)."""
    import pinocchio as pin

    with simulator._lock:
        state = simulator.simulator.snapshot()
    robot = simulator.robot
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, state.q)
    return state.time, data.oMf[robot.camera_frame_id].rotation.copy()


def assert_commands_bounded(commands, robot, near: float) -> None:
    """Every joint command of ``commands``, (measured angles [rad] (n,), commanded positions
    [rad] (n,)) pairs, is finite, within ``robot``'s URDF position limits and within ``near``
    [rad] of the angles measured when it was received."""
    assert commands
    for measured, command in commands:
        assert np.all(np.isfinite(command))
        assert np.all(command >= robot.lower_limits)
        assert np.all(command <= robot.upper_limits)
        worst = np.abs(command - measured).max()
        assert worst <= near, f"command {worst:.4g} rad from the measured angles"


def assert_one_clock_fault_logged(capfd) -> None:
    """The node's log (stderr captured by ``capfd``) has exactly one CLOCK_FAULT error line and
    blames no stale state: the clock, not joint_states, is named."""
    log = capfd.readouterr().err
    assert log.count("CLOCK_FAULT:") == 1, log
    assert "STALE_STATE" not in log


#: The model YAML keys the alias-bomb tests fill (the value of each is read and checked).
BOMB_KEYS = ("urdf", "camera_frame", "held_joints", "initial_joint_positions")


def alias_bomb_model(key: str, urdf, levels: int = 9, width: int = 9) -> str:
    """A model YAML (text) naming ``urdf`` whose ``key`` holds a "billion laughs": anchors nested
    inside the value, each level ``width`` aliases of the one before, ``width ** levels``
    strings in all once expanded. Mapping keys (``held_joints``, ``initial_joint_positions``)
    get it as joint name: value; the others as a list."""
    mapping = key in ("held_joints", "initial_joint_positions")
    entry = "  joint_{i}: " if mapping else "  - "
    lines = [entry.format(i=1) + "&a0 [" + ", ".join(['"lol"'] * width) + "]"]
    for level in range(1, levels):
        aliases = ", ".join([f"*a{level - 1}"] * width)
        lines.append(entry.format(i=level + 1) + f"&a{level} [{aliases}]")
    head = "" if key == "urdf" else f"urdf: {urdf}\n"
    return head + f"{key}:\n" + "\n".join(lines) + "\n"


def alias_bomb_flow(levels: int = 9, width: int = 9) -> str:
    """A YAML flow list holding a "billion laughs" (``width ** levels`` strings once expanded),
    as one command-line value: ``[&a0 [x, ...], &a1 [*a0, ...], ...]``."""
    items = ["&a0 [" + ", ".join(["x"] * width) + "]"]
    items += [f"&a{i} [" + ", ".join([f"*a{i - 1}"] * width) + "]" for i in range(1, levels)]
    return "[" + ", ".join(items) + "]"


def chain_urdf(links: int) -> str:
    """URDF text of a serial chain of ``links`` links (1 kg cubes, 0.1 m apart) joined by
    revolute joints about z: ``l0`` ... ``l{links-1}``, ``j1`` ... ``j{links-1}``."""
    inertial = (
        '<inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" '
        'izz="0.01"/></inertial>'
    )
    parts = ['<robot name="chain">']
    for i in range(links):
        parts.append(f'<link name="l{i}">{inertial}</link>')
        if i:
            parts.append(
                f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/>'
                f'<child link="l{i}"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
                '<limit lower="-3" upper="3" effort="10" velocity="1"/></joint>'
            )
    parts.append("</robot>")
    return "\n".join(parts)


def run_with_file_size_limit(script: str, limit: int, timeout: float):
    """``script`` run by this Python in a child process whose files may not grow past ``limit``
    bytes (``ulimit -f``: writes beyond fail with EFBIG, Python ignores SIGXFSZ); the
    CompletedProcess, output as text. The child joins no ROS graph beyond localhost."""
    import os
    import resource
    import subprocess
    import sys

    def limited() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return subprocess.run(
        [sys.executable, "-c", script],
        preexec_fn=limited,
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"},
    )
