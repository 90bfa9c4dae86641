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


@pytest.mark.parametrize(
    ("dropped", "missed"), [((), 0), ((5,), 1), ((5, 6, 7), 3), ((5, 9), 2), ((1, 98), 2)]
)
def test_missed_samples_counts_the_holes_in_a_periodic_stream(dropped, missed):
    """A 500 Hz grid of stamps with the samples ``dropped`` (indices) taken out."""
    from rns_ros.runs.recorded import missed_samples

    stamps = [100.0 + 0.002 * k for k in range(100) if k not in dropped]
    assert missed_samples(stamps) == missed


def test_missed_samples_reads_a_jittered_stream_as_complete():
    """Spacings within 1.5 periods are no hole (stamps off their grid by up to 20 %)."""
    import numpy as np

    from rns_ros.runs.recorded import missed_samples

    rng = np.random.default_rng(0)
    stamps = 0.01 * np.arange(200) + rng.uniform(-0.002, 0.002, 200)
    assert missed_samples(stamps) == 0
    assert missed_samples(np.delete(stamps, [50, 51])) == 2
