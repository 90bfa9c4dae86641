"""rns_ros.apps.observer: argument errors are reported before any waiting (the DDS part is
covered by test_two_hosts.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from geometry_msgs.msg import TwistStamped
from sensor_msgs.msg import JointState

from rns_ros.apps import observer
from rns_ros.harness import Harness, TopicLog, ros_environment
from rns_ros.nodes.simulator import SimulatorNode

DOMAIN = int(os.environ.setdefault("ROS_DOMAIN_ID", "43"))


def test_unknown_scenario_is_reported_at_once(capsys):
    assert observer.main(["--scenario", "no_such_scenario", "--wait", "30"]) == 2
    assert "no_such_scenario" in capsys.readouterr().err


def test_bad_ros_arguments_are_reported(capsys):
    assert observer.main(["--wait", "1", "--ros-args", "-p", "no_value"]) == 2
    assert "invalid ROS arguments" in capsys.readouterr().err


def _twists(rates: list[float], period: float = 0.02, age: float = 1.0) -> TopicLog:
    """cmd_twist as the observer logs it: one twist per ``rates`` entry [rad/s] about x,
    stamped ``period`` [s] apart on simulated time, the last received ``age`` [s] ago."""
    log = TopicLog("/cmd_twist")
    for k, rate in enumerate(rates):
        msg = TwistStamped()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(
            10_000_000_000 + k * 20_000_000, 10**9
        )
        msg.twist.angular.x = rate
        log._append(msg)
    log.received[:] = [value - age for value in log.received]
    return log


def test_the_operator_is_done_after_its_profile_by_the_stamps_not_after_any_silence():
    """With --scenario the observer stops once the operator's twists have covered the profile
    (stamps) and are at rest, then silent for --idle: a loaded machine that holds the operator
    for a second mid-profile (lockstep) no longer ends the recording a third into a roll."""
    duration = 3.0  # [s] of the scenario, 150 samples at 50 Hz
    before, profile, after = [0.0], [0.17] * 150, [0.0] * 50
    assert observer._commands_done(_twists(before + profile + after), 0.5, duration)
    assert not observer._commands_done(_twists(before + profile[:50]), 0.5, duration)  # a stall
    paused = before + profile[:50] + [0.0] * 25  # a segment at rest mid-profile
    assert not observer._commands_done(_twists(paused), 0.5, duration)
    assert not observer._commands_done(_twists(before + profile + after, age=0.1), 0.5, duration)
    assert not observer._commands_done(_twists([0.0] * 300), 0.5, duration)  # never moved


def test_remapped_robot_topics_are_watched(tmp_path):
    """The robot publishes joint_states and base_odom under arm/; the observer's -r remaps make
    it watch those (without them it sees no robot and exits 1). A separate process, as on the
    operator's computer."""
    report_file = tmp_path / "report.json"
    command = [
        sys.executable, "-m", "rns_ros.apps.observer", "--wait", "15", "--duration", "1.0",
        "--json", str(report_file),
        "--ros-args", "-r", "joint_states:=arm/joint_states", "-r", "base_odom:=arm/base_odom",
    ]  # fmt: skip
    with Harness(DOMAIN) as ros:
        ros.add(
            SimulatorNode,
            remappings={"joint_states": "arm/joint_states", "base_odom": "arm/base_odom"},
        )
        watcher = subprocess.Popen(
            command, env=ros_environment(DOMAIN), stdout=subprocess.PIPE, text=True
        )
        try:
            ros.spin_until(lambda: watcher.poll() is not None, timeout=40.0)
        finally:
            if watcher.poll() is None:
                watcher.kill()
            output = watcher.communicate(timeout=10)[0]
    assert watcher.returncode == 0, output
    report = json.loads(report_file.read_text())
    assert report["robot_seen"]
    for topic in ("joint_states", "base_odom"):
        assert report["topics"][topic]["count"] >= 50, report["topics"]  # ~1 s at 100 Hz
        summary = report["topics"][topic]
        assert summary["rate_hz"] == pytest.approx(100.0, rel=0.2)  # the simulator's stamps
        assert summary["receipt_rate_hz"] > 0.0
        assert summary["max_receipt_gap_s"] > 0.0


def _joint_states(stamps: list[float]) -> list[JointState]:
    messages = []
    for stamp in stamps:
        msg = JointState()
        msg.header.stamp.sec, msg.header.stamp.nanosec = int(stamp), round(stamp % 1 * 1e9)
        messages.append(msg)
    return messages


def test_rate_is_the_publishers_when_arrivals_come_in_a_burst():
    """100 Hz stamps whose first half arrives as a backlog in 10 ms: the arrivals say 198 Hz
    over 0.5 s, the publisher's rate stays 100 Hz (the CI run that measured 132 Hz)."""
    log = TopicLog("joint_states")
    stamps = [100.0 + 0.01 * k for k in range(100)]
    log.messages = _joint_states(stamps)
    log.received = [5.0 + 0.0002 * k for k in range(50)] + [5.01 + 0.01 * k for k in range(50)]
    summary = observer._topic_summary(log)
    assert summary["rate_hz"] == pytest.approx(100.0, rel=1e-9)
    assert summary["receipt_rate_hz"] == pytest.approx(99 / 0.5, rel=1e-9)
    assert summary["max_receipt_gap_s"] == pytest.approx(0.01, rel=1e-9)


def test_rate_falls_back_to_arrivals_without_stamps():
    log = TopicLog("joint_references")
    log.messages = _joint_states([0.0] * 11)  # unstamped
    log.received = [1.0 + 0.02 * k for k in range(11)]
    assert observer._topic_summary(log)["rate_hz"] == pytest.approx(50.0, rel=1e-9)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--domain-id", "233"], "--domain-id: must be an integer in [0, 232]"),
        (["--idle", "-1"], "--idle"),
    ],
)
def test_bad_numbers_name_the_option(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        observer.parse_args(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_static_peer_environment_is_the_two_computer_recipe():
    env = observer.static_peer_environment(7, ["192.0.2.1", "robot.local"], base={})
    assert env["ROS_DOMAIN_ID"] == "7"
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert env["ROS_STATIC_PEERS"] == "192.0.2.1;robot.local"
