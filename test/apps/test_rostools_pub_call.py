"""rns_topic pub / rns_service call (rns_ros.apps.topic, .service): what the README's operator does
with ``ros2 topic pub`` / ``ros2 service call``, without ros2cli, against our own nodes, with
ros2cli Jazzy's arguments, output and waits.

rns_simulator and rns_ptp run on the wall clock in a Harness spun by a background thread; the
tools' main() runs in the main thread on its own Context, joining the domain of the environment
as the console scripts do; the waits for a late peer run the installed executables. Domain:
ROS_DOMAIN_ID + 2, loopback only.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

DOMAIN_ID = int(os.environ.get("ROS_DOMAIN_ID", "43")) + 2
ENV = {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_DOMAIN_ID": str(DOMAIN_ID)}
#: A goal 0.3 rad from the simulator's start on every joint [rad]: a plan of a few seconds.
GOAL_OFFSET = 0.3
BIN = Path(sys.executable).parent


@pytest.fixture(autouse=True)
def _environment(monkeypatch):
    for key, value in ENV.items():
        monkeypatch.setenv(key, value)
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)


@pytest.fixture(scope="module")
def stack():
    """``.simulator``, ``.ptp``, ``.probe``; ``.joints`` / ``.status`` / ``.twists``: the latest
    joint_states, rns_ptp status values and every cmd_twist, as the probe received them."""
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import TwistStamped
    from sensor_msgs.msg import JointState

    from rns_ros.harness import Harness
    from rns_ros.nodes.ptp import PtpNode
    from rns_ros.nodes.simulator import SimulatorNode

    seen = SimpleNamespace(joints=None, status={}, twists=[])
    with pytest.MonkeyPatch.context() as patch:
        for key, value in ENV.items():
            patch.setenv(key, value)
        with Harness(domain_id=DOMAIN_ID) as harness:
            simulator = harness.add(SimulatorNode)
            ptp = harness.add(PtpNode, {"state_timeout": 0.3})
            probe = harness.probe("rns_pub_call_probe")

            def on_status(msg) -> None:
                seen.status = {kv.key: kv.value for kv in msg.status[0].values}

            probe.create_subscription(
                JointState, "joint_states", lambda m: setattr(seen, "joints", m), 10
            )
            probe.create_subscription(DiagnosticArray, "rns_ptp/status", on_status, 10)
            probe.create_subscription(TwistStamped, "cmd_twist", seen.twists.append, 10)
            stop = threading.Event()

            def spin() -> None:
                while not stop.is_set():
                    harness.executor.spin_once(timeout_sec=0.01)

            thread = threading.Thread(target=spin, daemon=True)
            thread.start()
            try:
                yield SimpleNamespace(simulator=simulator, ptp=ptp, probe=probe, seen=seen)
            finally:
                stop.set()
                thread.join(timeout=5.0)


def _wait(condition, timeout: float = 20.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.02)
    return bool(condition())


def _run(capsys, main, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _positions(stack) -> np.ndarray:
    return np.array(stack.seen.joints.position)


# --- against our nodes ----------------------------------------------------------------------------
def test_a_goal_moves_the_arm_cancel_stops_it_and_reset_puts_it_back(stack, capsys):
    """The operator's sequence of docs/ptp.md with the PyPI tools alone: publish a ptp_goal,
    cancel the motion (rns_ptp ~/cancel), reset the simulation (rns_simulator ~/reset)."""
    from rns_ros.apps.service import service_main
    from rns_ros.apps.topic import topic_main

    assert _wait(lambda: stack.seen.joints is not None and stack.seen.status.get("state") == "IDLE")
    start = _positions(stack)
    names = ", ".join(stack.seen.joints.name)
    goal = ", ".join(f"{value:.6f}" for value in start + GOAL_OFFSET)
    code, out, err = _run(
        capsys,
        topic_main,
        "pub",
        "--once",
        "/ptp_goal",
        "sensor_msgs/msg/JointState",
        f"{{name: [{names}], position: [{goal}]}}",
    )
    assert (code, err) == (0, ""), err
    assert "publishing #1: sensor_msgs.msg.JointState(" in out
    assert _wait(lambda: stack.seen.status.get("state") == "MOVING"), stack.seen.status
    assert _wait(lambda: np.abs(_positions(stack) - start).max() > 1e-3)

    code, out, err = _run(capsys, service_main, "call", "/rns_ptp/cancel", "std_srvs/srv/Trigger")
    assert (code, err) == (0, ""), err
    # ros2's line while the client is not yet matched (almost always: a new node)
    request = out.removeprefix("waiting for service to become available...\n")
    assert request.startswith("requester: making request: std_srvs.srv.Trigger_Request()")
    assert "response:\nstd_srvs.srv.Trigger_Response(success=True, message='decelerating" in out
    assert _wait(lambda: stack.seen.status.get("state") in ("IDLE", "CANCELLED", "DONE"))
    stopped = _positions(stack)
    assert np.abs(stopped - start).max() > 1e-3  # cancelled on the way
    assert np.abs(stopped - (start + GOAL_OFFSET)).max() > 1e-3

    # short form of the type, as ros2 accepts it
    code, out, err = _run(capsys, service_main, "call", "rns_simulator/reset", "std_srvs/Trigger")
    assert (code, err) == (0, ""), err
    assert "Trigger_Response(success=True" in out
    assert _wait(lambda: np.abs(_positions(stack) - start).max() < 1e-9)


def test_a_twist_at_a_rate_with_an_auto_header(stack, capsys):
    """`-t 3 -r 20`: three messages, each stamped anew (`header: auto`), message k not before
    k periods (50 ms) after the loop began. A busy machine only delays them, so no upper bound."""
    from rns_ros.apps.topic import topic_main

    before = len(stack.seen.twists)
    began = time.time()  # the loop begins after this
    code, out, err = _run(
        capsys,
        topic_main,
        "pub",
        "-t",
        "3",
        "-r",
        "20",
        "cmd_twist",
        "geometry_msgs/msg/TwistStamped",
        "{header: auto, twist: {angular: {z: -0.1}}}",  # z: an integer would be a float too
    )
    assert (code, err) == (0, ""), err
    assert out.count("publishing #") == 3
    assert _wait(lambda: len(stack.seen.twists) >= before + 3)
    twists = stack.seen.twists[before:]
    assert len(twists) == 3
    assert [t.twist.angular.z for t in twists] == [-0.1] * 3
    stamps = [t.header.stamp.sec + 1e-9 * t.header.stamp.nanosec for t in twists]
    assert abs(stamps[0] - time.time()) < 10.0
    assert np.all(np.diff(stamps) > 0.0), stamps  # each stamped when it was published
    assert stamps[2] - began >= 2 / 20 - 1e-3, (began, stamps)  # due at start + k / rate


def test_service_list_prints_names_and_with_t_types(stack, capsys):
    from rns_ros.apps.service import service_main

    code, out, _ = _run(capsys, service_main, "list")
    assert code == 0
    lines = out.splitlines()
    assert "/rns_simulator/reset" in lines
    assert "/rns_ptp/cancel" in lines
    assert not any("[" in line for line in lines)
    code, out, _ = _run(capsys, service_main, "list", "--show-types")
    lines = out.splitlines()
    assert "/rns_simulator/reset [std_srvs/srv/Trigger]" in lines
    assert "/rns_ptp/cancel [std_srvs/srv/Trigger]" in lines


def test_pub_qos_profile_and_node_name_leave_the_positionals_alone(stack, capsys):
    """`--qos-profile sensor_data -n NAME -t 3` before TOPIC TYPE YAML, as ros2 parses them: a
    best-effort publisher of that name, three messages, each received."""
    from rclpy.qos import QoSPresetProfiles, ReliabilityPolicy
    from std_msgs.msg import String

    from rns_ros.apps.topic import topic_main

    received = []

    def on_message(msg) -> None:
        publishers = stack.probe.get_publishers_info_by_topic("rns_pub_named")
        received.append((msg.data, {(p.node_name, p.qos_profile.reliability) for p in publishers}))

    stack.probe.create_subscription(
        String, "rns_pub_named", on_message, QoSPresetProfiles.SENSOR_DATA.value
    )
    code, out, err = _run(
        capsys, topic_main, "pub", "--qos-profile", "sensor_data", "-n", "rns_named_pub",
        "-t", "3", "-r", "20", "rns_pub_named", "std_msgs/msg/String", "{data: hi}",
    )  # fmt: skip
    assert (code, err) == (0, ""), err
    assert out.count("publishing #") == 3
    assert _wait(lambda: len(received) >= 3)
    assert [data for data, _ in received] == ["hi"] * 3
    assert ("rns_named_pub", ReliabilityPolicy.BEST_EFFORT) in received[-1][1]


def test_max_wait_time_without_a_wait_is_a_usage_error(capsys):
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(
        capsys, topic_main, "pub", "/x", "std_msgs/msg/Bool", "--max-wait-time-secs", "1"
    )
    assert (code, out) == (2, "")
    assert "only effective with --wait-matching-subscriptions, --once or --times" in err
    assert err.count("\n") == 1


# --- waiting for a late peer, as ros2 does (no 5 s limit) ---------------------------------------
def _start(*argv: str) -> subprocess.Popen:
    script = BIN / argv[0]
    if not script.exists():
        pytest.skip(f"{script} not installed (run `make venv`)")
    return subprocess.Popen(
        [str(script), *argv[1:]],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, **ENV},
    )


def _read_until(process: subprocess.Popen, line: str, times: int = 1) -> None:
    """Read ``process``'s stdout until ``line`` came ``times`` times (fails if it ends first)."""
    seen = 0
    while seen < times:
        got = process.stdout.readline()
        assert got, f"ended ({process.wait()}) before {line!r} x{times}: {process.stderr.read()}"
        seen += got.rstrip("\n") == line


def test_pub_once_waits_for_a_late_subscriber_then_delivers(stack):
    """`pub --once` with nobody subscribed says it waits, once a second, past the 5 s an older
    version gave up after; a subscription made then gets the message and pub exits 0."""
    from std_msgs.msg import String

    process = _start("rns_topic", "pub", "--once", "rns_pub_late", "std_msgs/msg/String",
                     "{data: late}")  # fmt: skip
    try:
        _read_until(process, "Waiting for at least 1 matching subscription(s)...", times=7)
        assert process.poll() is None  # still waiting, 6 s after the first line
        received = []
        stack.probe.create_subscription(String, "rns_pub_late", received.append, 10)
        out, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert (process.returncode, err) == (0, ""), err
    assert "publishing #1: std_msgs.msg.String(data='late')" in out
    assert _wait(lambda: len(received) == 1)
    assert received[0].data == "late"


def test_service_call_waits_for_a_late_service(stack):
    from std_srvs.srv import Trigger

    process = _start("rns_service", "call", "/rns_late_service", "std_srvs/srv/Trigger")
    try:
        _read_until(process, "waiting for service to become available...")
        time.sleep(6.0)  # longer than the 5 s an older version waited
        assert process.poll() is None

        def answer(_request, response):
            response.success, response.message = True, "late"
            return response

        stack.probe.create_service(Trigger, "rns_late_service", answer)
        out, err = process.communicate(timeout=60)
    finally:
        process.kill()
    assert (process.returncode, err) == (0, ""), err
    assert out.startswith("requester: making request: std_srvs.srv.Trigger_Request()\n\n")
    assert "response:\nstd_srvs.srv.Trigger_Response(success=True, message='late')\n" in out


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        (["rns_topic", "pub", "--once", "/rns_nobody", "std_msgs/msg/Bool"],
         "Waiting for at least 1 matching subscription(s)..."),
        (["rns_service", "call", "/rns_nobody", "std_srvs/srv/Trigger"],
         "waiting for service to become available..."),
    ],
)  # fmt: skip
def test_ctrl_c_ends_a_wait_quietly_with_exit_0(argv, line):
    process = _start(*argv)
    try:
        _read_until(process, line)
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=20)
    finally:
        process.kill()
    assert (process.returncode, err) == (0, "")
    assert "publishing" not in out
    assert "requester" not in out


# --- errors: one line, exit 1 (not found, refused) or 2 (the command line is wrong) ----------
@pytest.mark.parametrize(
    ("argv", "code", "words"),
    [
        (["pub", "/x", "std_msgs/msg/Nope", "{}"], 1, "not installed"),
        (["pub", "/x", "nope", "{}"], 2, "cannot interpret 'nope'"),
        (["pub", "/x", "std_msgs/msg/Bool", "{data: ["], 2, "cannot parse"),
        (["pub", "/x", "std_msgs/msg/Bool", "[true]"], 2, "YAML mapping"),
        (["pub", "/x", "std_msgs/msg/Bool", "{dat: true}"], 2, "no field 'dat'"),
        (["pub", "/x", "std_msgs/msg/Bool", "{data: 3}"], 2, "field 'data'"),
        (["pub", "/x", "geometry_msgs/msg/Twist", "{linear: 1}"], 2, "field 'linear'"),
        (["pub", "/x", "sensor_msgs/msg/JointState", "{position: [a]}"], 2, "'position[0]'"),
        (["pub", "/x", "diagnostic_msgs/msg/DiagnosticStatus", "{level: 300}"], 2, "[0, 255]"),
        (["pub", "/x", "geometry_msgs/msg/PoseWithCovariance", "{covariance: [1]}"], 2, "36"),
        (["pub", "/x", "std_msgs/msg/String", "{data: [1]}"], 2, "give a string"),
        (["pub", "/x", "std_msgs/msg/Bool", "-r", "0"], 2, "rate > 0"),
        (["pub", "/x", "std_msgs/msg/Bool", "--once", "-t", "2"], 2, "not allowed with"),
        (["call", "/x", "std_srvs/srv/Nope"], 1, "not installed"),
        (["call", "/x", "std_srvs/msg/Trigger"], 2, "as a srv type"),
        (["call", "/x", "std_srvs/srv/SetBool", "{value: true}"], 2, "no field 'value'"),
    ],
)
def test_bad_requests_are_one_line(argv, code, words, capsys):
    from rns_ros.apps.service import service_main
    from rns_ros.apps.topic import topic_main

    main, program = (topic_main, "rns_topic") if argv[0] == "pub" else (service_main, "rns_service")
    # pub waits for a subscription with --once only, and never past --max-wait-time-secs
    extra = (
        ["--once", "--max-wait-time-secs", "0.3"] if main is topic_main else ["--timeout", "0.3"]
    )
    got, out, err = _run(capsys, main, *argv, *extra)
    assert (got, out) == (code, ""), err
    assert err.startswith(f"{program}: "), err
    assert err.count("\n") == 1, err
    assert words in err, err


def test_not_found_and_wrong_types_in_the_graph_are_exit_1(stack, capsys):
    from rns_ros.apps.service import service_main
    from rns_ros.apps.topic import topic_main

    code, _, err = _run(capsys, service_main, "call", "/nobody/reset", "std_srvs/srv/Trigger",
                        "--timeout", "0.3")  # fmt: skip
    assert code == 1
    assert "service /nobody/reset not found within 0.3 s" in err
    code, _, err = _run(
        capsys, service_main, "call", "/rns_simulator/reset", "std_srvs/srv/SetBool"
    )
    assert code == 1
    assert "has type std_srvs/srv/Trigger, not std_srvs/srv/SetBool" in err
    argv = ["pub", "--once", "/nobody_listens", "std_msgs/msg/Bool", "{data: true}"]
    code, out, err = _run(capsys, topic_main, *argv, "--max-wait-time-secs", "0.3")
    assert code == 1
    assert out == "Waiting for at least 1 matching subscription(s)...\n"
    assert err.startswith(
        "rns_topic: Timed out waiting for subscribers: Expected 1 subscribers but only got 0"
    )
    assert err.count("\n") == 1
    code, _, err = _run(capsys, topic_main, "pub", "--once", "/joint_states", "std_msgs/msg/String")
    assert code == 1
    assert "has type sensor_msgs/msg/JointState, not std_msgs/msg/String" in err
    assert err.count("\n") == 1


# --- the YAML -> message converter ------------------------------------------------------------
def test_message_from_yaml_fills_nested_arrays_and_times():
    from builtin_interfaces.msg import Time
    from diagnostic_msgs.msg import DiagnosticStatus
    from geometry_msgs.msg import PoseArray, TwistStamped
    from sensor_msgs.msg import JointState

    from rns_ros.ros_messages import message_from_yaml

    def now():
        return Time(sec=7, nanosec=5)

    msg = message_from_yaml("{header: auto, twist: {linear: {x: 1}}}", TwistStamped, now)
    assert msg.header.stamp == Time(sec=7, nanosec=5)
    assert msg.twist.linear.x == 1.0
    assert isinstance(msg.twist.linear.x, float)
    msg = message_from_yaml("{header: {stamp: now, frame_id: base}}", TwistStamped, now)
    assert (msg.header.stamp.sec, msg.header.frame_id) == (7, "base")
    msg = message_from_yaml("{name: [a, b], position: [1, 2.5]}", JointState, now)
    assert list(msg.name) == ["a", "b"]
    assert list(msg.position) == [1.0, 2.5]
    assert message_from_yaml("{level: 2}", DiagnosticStatus, now).level == b"\x02"
    msg = message_from_yaml("{poses: [{position: {z: 2}}, {}]}", PoseArray, now)
    assert [p.position.z for p in msg.poses] == [2.0, 0.0]
    assert message_from_yaml("", JointState, now) == JointState()


def test_message_from_yaml_refuses_an_alias_bomb_and_cuts_bad_values():
    from builtin_interfaces.msg import Time
    from rns_testing import alias_bomb_flow
    from sensor_msgs.msg import JointState

    from rns_ros.ros_messages import message_from_yaml
    from rns_ros.tool_session import UsageError

    def now():
        return Time()

    with pytest.raises(UsageError, match=r"^the message: more than \d+ YAML nodes"):
        message_from_yaml(f"{{name: {alias_bomb_flow()}}}", JointState, now)
    with pytest.raises(UsageError) as caught:
        message_from_yaml(f"{{position: [[{', '.join(['1'] * 5000)}]]}}", JointState, now)
    message = str(caught.value)
    assert message.startswith("bad value [1, 1, ")
    assert "(list of 5000 items) for field 'position[0]'" in message
    assert len(message) < 300
