"""rns_topic pub / rns_service call (rns_ros.apps.topic, .service): what the README's operator does
with ``ros2 topic pub`` / ``ros2 service call``, without ros2cli, against our own nodes.

rns_simulator and rns_ptp run on the wall clock in a Harness spun by a background thread; the
tools' main() runs in the main thread on its own Context, joining the domain of the environment
as the console scripts do. Domain: ROS_DOMAIN_ID + 2, loopback only.
"""

from __future__ import annotations

import os
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest

DOMAIN_ID = int(os.environ.get("ROS_DOMAIN_ID", "43")) + 2
ENV = {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_DOMAIN_ID": str(DOMAIN_ID)}
#: A goal 0.3 rad from the simulator's start on every joint [rad]: a plan of a few seconds.
GOAL_OFFSET = 0.3


@pytest.fixture(autouse=True)
def _environment(monkeypatch):
    for key, value in ENV.items():
        monkeypatch.setenv(key, value)
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)


@pytest.fixture(scope="module")
def stack():
    """``.simulator``, ``.ptp``; ``.joints`` / ``.status`` / ``.twists``: the latest
    joint_states, rns_ptp status values and every cmd_twist, as a probe received them."""
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
                yield SimpleNamespace(simulator=simulator, ptp=ptp, seen=seen)
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
    assert out.startswith("requester: making request: std_srvs.srv.Trigger_Request()")
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


def test_service_list_shows_our_services(stack, capsys):
    from rns_ros.apps.service import service_main

    code, out, _ = _run(capsys, service_main, "list")
    assert code == 0
    lines = out.splitlines()
    assert "/rns_simulator/reset [std_srvs/srv/Trigger]" in lines
    assert "/rns_ptp/cancel [std_srvs/srv/Trigger]" in lines


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
    got, out, err = _run(capsys, main, *argv, "--timeout", "0.3")
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
    code, _, err = _run(capsys, topic_main, "pub", "--once", "/nobody_listens", "std_msgs/msg/Bool",
                        "{data: true}", "--timeout", "0.3")  # fmt: skip
    assert code == 1
    assert "0 of 1 subscription(s) to /nobody_listens matched within 0.3 s" in err
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
