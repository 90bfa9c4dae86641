"""The launch-free harness: full stacks start and stop cleanly, parameters files and remappings
apply, installed executables run as subprocesses with --ros-args."""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState

from rns_ros.core import ConfigError
from rns_ros.harness import (
    CLAIM_PREFIX,
    STACK_NODES,
    DomainInUseError,
    Harness,
    ProcessStack,
    TopicLog,
    cdr_header_stamp,
    claim_domain,
    ros_environment,
    running_stack,
)
from rns_ros.nodes import (
    attitude_control_parameters,
    controller_parameters,
    force_controller_parameters,
    operator_parameters,
    ptp_parameters,
    rerun_logger_parameters,
    simulator_parameters,
)
from rns_ros.nodes.controller import ControllerNode
from rns_ros.nodes.operator import OperatorNode
from rns_ros.nodes.simulator import SimulatorNode
from rns_ros.resources import config_dir

DOMAIN = int(os.environ.setdefault("ROS_DOMAIN_ID", "43"))


def _state(log) -> str | None:
    msg = log.latest()
    return None if msg is None else {kv.key: kv.value for kv in msg.status[0].values}["state"]


def test_full_stack_starts_and_stops_repeatedly_without_leaks():
    baseline = {thread.name for thread in threading.enumerate()}
    for _ in range(3):
        with Harness(DOMAIN) as stack:
            stack.add(SimulatorNode)
            stack.add(ControllerNode)
            stack.add(OperatorNode, {"start_delay": 0.0})
            status = stack.record(DiagnosticArray, "rns_controller/status")
            assert stack.spin_until(lambda log=status: _state(log) == "OK", timeout=10.0)
            context = stack.context
        assert not context.ok()
        assert stack.nodes == []
        leaked = {thread.name for thread in threading.enumerate()} - baseline
        assert not leaked, f"threads left behind: {leaked}"


def test_teardown_happens_when_the_body_fails():
    started = {}

    def failing_test():
        with Harness(DOMAIN) as stack:
            started["stack"], started["simulator"] = stack, stack.add(SimulatorNode)
            raise RuntimeError("a failing test")

    with pytest.raises(RuntimeError, match="a failing test"):
        failing_test()
    assert not started["stack"].context.ok()
    assert not started["simulator"]._thread.is_alive()


def test_the_events_executor_runs_a_lockstep_stack_on_sim_time():
    """executor="events": sim-time timers fire on /clock and lockstep runs on, one controller
    tick (status, stamped on the period grid) per simulated period."""
    with Harness(DOMAIN, executor="events") as stack:
        simulator = stack.add(
            SimulatorNode,
            {"real_time_factor": 0.0, "publish_clock": True, "lockstep_period": 0.01},
        )
        stack.add(ControllerNode, {"use_sim_time": True, "state_timeout": 1.0})
        status = stack.record(DiagnosticArray, "rns_controller/status")
        assert stack.spin_until(lambda: simulator.simulator.time > 1.0, timeout=30.0)
        stamps = status.stamps()
    ticks = stamps[stamps > 0.2]  # lockstep from the first command on
    assert len(ticks) > 50
    assert np.allclose(np.diff(ticks), 0.01, atol=1e-9)


def test_an_unknown_executor_is_a_config_error():
    with pytest.raises(ConfigError, match="executor"):
        Harness(DOMAIN, executor="multi")


def test_params_file_remapping_and_name(tmp_path):
    with Harness(DOMAIN) as stack:
        controller = stack.add(
            ControllerNode,
            {"method": "sc"},
            params_file=config_dir() / "controller.yaml",
            remappings={"cmd_twist": "teleop/cmd"},
            name="arm_controller",
        )
        assert controller.get_name() == "arm_controller"
        assert controller.get_parameter("method").value == "sc"  # dict wins over the file
        assert controller.get_parameter("rate").value == 100.0
        stack.add(SimulatorNode)
        status = stack.record(DiagnosticArray, "arm_controller/status")
        publisher = stack.probe().create_publisher(
            TwistStamped,
            "teleop/cmd",
            QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT),
        )
        msg = TwistStamped()
        msg.header.frame_id = "camera"
        msg.twist.angular.z = 0.05

        def commanded():
            publisher.publish(msg)
            return _state(status) == "OK"

        assert stack.spin_until(commanded, timeout=10.0)
        with pytest.raises(ConfigError, match="params_file not found"):
            stack.add(ControllerNode, params_file=tmp_path / "missing.yaml")


def test_installed_executables_run_as_subprocesses_with_ros_args():
    with Harness(DOMAIN) as stack, ProcessStack(DOMAIN) as processes:
        joints = stack.record(JointState, "robot/joint_states")
        simulator = processes.start(
            "rns_simulator",
            {"publish_rate": 50.0, "initial_joint_positions": [0.1] * 7},
            remappings={"joint_states": "robot/joint_states"},
        )
        assert stack.spin_until(lambda: len(joints) >= 10, timeout=20.0), processes.output(
            simulator
        )
        assert list(joints.latest().position) == pytest.approx([0.1] * 7)
        assert processes.stop() == [0]
        assert "kinematic simulation" in processes.output(simulator)


def test_process_warnings_are_collected_after_stop():
    """ProcessStack.problems(): the WARN / ERROR lines of every process started, also once it
    has been stopped (rns_demo prints them under each run: a watchdog that stopped the arm)."""
    with ProcessStack(DOMAIN) as processes:
        controller = processes.start("rns_controller", {"output_lead": 0.01})  # wall clock
        deadline = time.monotonic() + 20.0
        while "waiting for" not in processes.output(controller) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert processes.stop() == [0]
        problems = processes.problems()
    assert len(problems) == 1, problems
    assert problems[0].startswith("rns_controller: [WARN]")
    assert "output_lead is for use_sim_time" in problems[0]


def test_stop_waits_for_a_process_its_own_stop_timeout_and_names_one_it_killed(tmp_path):
    """ProcessStack.stop(): SIGINT, then a process gets its own ``stop_timeout`` (a recorder
    writing out what it holds as it closes: killed at the default, its file would lack its
    footer); one still running past its timeout is killed and said so among the problems."""
    closing = tmp_path / "closing"  # exits 1 s after SIGINT, as a recorder closing its file
    closing.write_text(
        "#!/bin/sh\ntrap 'sleep 1; exit 0' INT\n"
        f": > {tmp_path}/ready.$$\nwhile :; do sleep 0.05; done\n"
    )
    closing.chmod(0o755)
    with ProcessStack(DOMAIN, bin_dir=tmp_path) as processes:
        processes.start("closing")
        processes.start("closing", stop_timeout=60.0)
        deadline = time.monotonic() + 60.0
        while len(list(tmp_path.glob("ready.*"))) < 2:  # both have set their trap
            assert time.monotonic() < deadline
            time.sleep(0.05)
        codes = processes.stop(timeout=0.2)
        problems = processes.problems()
    assert codes == [-9, 0]
    assert problems == ["closing: [ERROR] still running 0.2 s after SIGINT: killed"]


def test_environment_stays_on_localhost():
    base = {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET", "ROS_STATIC_PEERS": "192.0.2.7"}
    env = ros_environment(12, base=base)
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert "ROS_STATIC_PEERS" not in env  # static peers would reach other machines
    assert env["ROS_DOMAIN_ID"] == "12"
    with pytest.raises(ConfigError, match=r"domain_id must be an integer in \[0, 232\], got 250"):
        Harness(domain_id=250)


def test_a_bad_ros_domain_id_in_the_environment_is_a_config_error(monkeypatch):
    monkeypatch.setenv("ROS_DOMAIN_ID", "abc")
    with pytest.raises(ConfigError, match="got 'abc'"):
        Harness()


def test_process_parameters_override_the_params_file(tmp_path):
    """rcl applies ROS arguments in order: the params file must come before the -p overrides,
    or the file silently wins (a demo run asked for method os and ran rns)."""
    params = tmp_path / "params.yaml"
    params.write_text("/**:\n  ros__parameters:\n    method: rns\n")
    argv = ProcessStack(DOMAIN).command(
        "rns_force_controller",
        {"method": "os"},
        params_file=params,
        ros_args=["-r", "a:=b"],
    )
    ros = argv[argv.index("--ros-args") + 1 :]
    assert ros.index("--params-file") < ros.index("method:=os") < ros.index("a:=b")


@pytest.mark.parametrize("msg_type", [JointState, Odometry, TwistStamped])
def test_cdr_header_stamp_reads_what_serialization_wrote(msg_type):
    msg = msg_type()
    msg.header.stamp.sec, msg.header.stamp.nanosec = 1_796_217_188, 669_995_390
    msg.header.frame_id = "world"
    assert cdr_header_stamp(serialize_message(msg)) == 1_796_217_188 + 1e-9 * 669_995_390
    assert cdr_header_stamp(b"\x00\x07" + bytes(10)) is None  # not plain CDR
    assert cdr_header_stamp(b"\x00\x01\x00") is None  # too short


def test_a_raw_log_reads_back_the_recorded_messages():
    """Recorded serialized (Harness.record(raw=True)), the log gives the same messages, stamps
    and latest message as a deserializing one."""
    log = TopicLog("joint_states", JointState)
    sent = []
    for k in range(3):
        msg = JointState(name=["a"], position=[0.1 * k], velocity=[float(k)])
        msg.header.stamp.sec, msg.header.stamp.nanosec = 7, 10_000_000 * k
        sent.append(msg)
        log._append_raw(serialize_message(msg))
    assert len(log) == 3
    assert log.latest_stamp() == pytest.approx(7.02)
    assert log.latest() == sent[-1]
    assert log.messages == sent
    assert log.stamps() == pytest.approx([7.0, 7.01, 7.02])
    log._append_raw(serialize_message(sent[0]))  # decoded on the next read, in order
    assert len(log) == 4
    assert log.messages == [*sent, sent[0]]


def test_a_raw_recording_over_dds_matches_the_deserializing_one():
    with Harness(DOMAIN) as ros:
        ros.add(SimulatorNode)
        raw = ros.record(JointState, "joint_states", raw=True)
        decoded = ros.record(JointState, "joint_states")
        assert ros.spin_until(lambda: len(raw) >= 20 and len(decoded) >= 20, timeout=10.0)
    common = {m.header.stamp.sec * 10**9 + m.header.stamp.nanosec: m for m in decoded.messages}
    matched = [
        m for m in raw.messages if m.header.stamp.sec * 10**9 + m.header.stamp.nanosec in common
    ]
    assert len(matched) >= 15
    assert all(m == common[m.header.stamp.sec * 10**9 + m.header.stamp.nanosec] for m in matched)


@pytest.mark.parametrize("executor", ["events", "single_threaded"])
def test_spin_until_checks_a_costly_condition_at_most_every_check_every(executor):
    """With check_every the callbacks run in between the checks (a 2 ms timer fires more often
    than the condition is tested); without it the condition is tested after each callback;
    spin_for runs them for its duration, at least, in one executor call. (Counts and bounds
    that a slow machine can only move the asserted way: fewer checks, no early return.)"""
    with Harness(DOMAIN, executor=executor) as stack:
        fired = []
        stack.probe().create_timer(0.002, lambda: fired.append(time.monotonic()))
        checks = []
        assert not stack.spin_until(lambda: checks.append(1) and False, 0.3, check_every=0.1)
        assert len(checks) <= 5  # 0.3 s / 0.1 s, plus the first and the last
        assert len(fired) > len(checks)
        fired.clear()
        checks.clear()
        assert not stack.spin_until(lambda: checks.append(1) and False, 0.1)
        assert len(checks) >= len(fired) >= 1
        fired.clear()
        spins = []
        spin = stack._spin
        stack._spin = lambda duration: (spins.append(duration), spin(duration))
        start = time.monotonic()
        stack.spin_for(0.2)
        end = time.monotonic()
        assert end - start >= 0.2
        assert 0.0 < spins[0] <= 0.2
        assert len(spins) <= 2  # the whole duration in one call (a second for a rounding rest)
        assert fired
        assert all(start <= t <= end for t in fired)


def test_a_raw_log_drops_and_counts_bytes_that_are_not_its_type():
    """Anyone on the domain may send bytes that do not deserialize: the recorder of a run
    drops them (with their receipt times) and counts them, never raises."""
    log = TopicLog("/joint_states", JointState)
    good = serialize_message(JointState(name=["a"], position=[1.0]))
    for data in (good, good[:9], good):
        log._append_raw(data)
    assert log.latest().position.tolist() == [1.0]
    assert len(log.messages) == 2
    assert len(log.received) == 2
    assert log.rejected == 1
    log._append_raw(b"\x00\x01\x00\x00\xff")
    assert log.latest().name == ["a"]  # the newest that is a message


def test_a_claim_names_the_stack_already_on_the_domain_and_a_later_claim_sees_it():
    """A node named as a stack's node or publishing a stack topic takes the domain; the claim's
    own node does not; an open claim takes it for the next one."""
    with Harness(DOMAIN) as other:
        other.add(rclpy.create_node("teleop", context=other.context))
        other.nodes[-1].create_publisher(TwistStamped, "cmd_twist", 1)
        other.add(rclpy.create_node("rns_operator", context=other.context))
        with pytest.raises(DomainInUseError) as error:
            claim_domain(DOMAIN, f"{CLAIM_PREFIX}_test_a")
    assert error.value.stack == "/rns_operator, /teleop publishing /cmd_twist"
    assert str(error.value).startswith(f"domain {DOMAIN} already has a running stack (")
    with claim_domain(DOMAIN, f"{CLAIM_PREFIX}_test_a") as first:
        assert running_stack(first.nodes[0]) is None
        with pytest.raises(DomainInUseError, match=rf"\(/{CLAIM_PREFIX}_test_a\)"):
            claim_domain(DOMAIN, f"{CLAIM_PREFIX}_test_b")


def test_the_stack_node_names_are_the_executables_node_names():
    names = {
        module.NODE_NAME
        for module in (
            attitude_control_parameters,
            controller_parameters,
            force_controller_parameters,
            operator_parameters,
            ptp_parameters,
            rerun_logger_parameters,
            simulator_parameters,
        )
    }
    assert names == set(STACK_NODES)
