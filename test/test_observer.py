"""rns_ros.observer: argument errors are reported before any waiting (the DDS part is covered by
test_two_hosts.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from rns_ros import observer
from rns_ros.harness import Harness, ros_environment
from rns_ros.nodes.simulator import SimulatorNode

DOMAIN = int(os.environ.setdefault("ROS_DOMAIN_ID", "43"))


def test_unknown_scenario_is_reported_at_once(capsys):
    assert observer.main(["--scenario", "no_such_scenario", "--wait", "30"]) == 2
    assert "no_such_scenario" in capsys.readouterr().err


def test_bad_ros_arguments_are_reported(capsys):
    assert observer.main(["--wait", "1", "--ros-args", "-p", "no_value"]) == 2
    assert "invalid ROS arguments" in capsys.readouterr().err


def test_remapped_robot_topics_are_watched(tmp_path):
    """The robot publishes joint_states and base_odom under arm/; the observer's -r remaps make
    it watch those (without them it sees no robot and exits 1). A separate process, as on the
    operator's computer."""
    report_file = tmp_path / "report.json"
    command = [
        sys.executable, "-m", "rns_ros.observer", "--wait", "15", "--duration", "1.0",
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
        assert report["topics"][topic]["rate_hz"] == pytest.approx(100.0, rel=0.2)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--domain-id", "200"], "--domain-id: must be an integer in [0, 101]"),
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
