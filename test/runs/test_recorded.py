"""rns_ros.runs.recorded: the robot's arrays from recorded topics, within the run's stamps."""

from __future__ import annotations

import pytest

from rns_ros.runs.recorded import robot_arrays


def test_figures_cover_the_run_up_to_the_settling_time_on_the_stamps_clock():
    """The run ends SETTLE after the operator on the stamps' clock: samples stamped later (a
    lockstep run goes on at its own pace while the stack stops) are not part of the figures."""
    from geometry_msgs.msg import TwistStamped, WrenchStamped
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import JointState

    from rns_ros.harness import TopicLog
    from rns_ros.nodes.sim_clock import stamp_from_seconds

    logs = {name: TopicLog(name) for name in ("joints", "odom", "momentum", "commands")}
    for k in range(100):
        stamp = stamp_from_seconds(0.01 * k)
        joints = JointState(position=[0.0] * 7, velocity=[0.0] * 7)
        odom, momentum, twist = Odometry(), WrenchStamped(), TwistStamped()
        odom.pose.pose.orientation.w = 1.0
        for msg, name in ((joints, "joints"), (odom, "odom"), (momentum, "momentum")):
            msg.header.stamp = stamp
            logs[name]._append(msg)
        if k % 2 == 0:
            twist.header.stamp = stamp
            logs["commands"]._append(twist)
    data = robot_arrays(logs, until=0.5)
    assert data["times"][-1] == pytest.approx(0.5)
    assert len(data["times"]) == len(data["angular_momentum"]) == 51
    assert data["command_times"].max() <= 0.5
    assert len(robot_arrays(logs)["times"]) == 100
