"""rns_ros.runs.inspection: when the operator's profile started, from the recorded twists."""

from __future__ import annotations

import math

import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import TwistStamped
from rns_testing import SHORT_ROLL_SCENARIO

from rns_ros.control.scenario import load_scenario
from rns_ros.core import RnsError
from rns_ros.harness import TopicLog
from rns_ros.nodes.sim_clock import stamp_from_seconds
from rns_ros.resources import scenario_path
from rns_ros.runs import inspection
from rns_ros.runs.inspection import profile_start


def _twists(samples) -> TopicLog:
    log = TopicLog("cmd_twist")
    for stamp, omega in samples:
        msg = TwistStamped()
        msg.header.stamp = stamp_from_seconds(stamp)
        msg.twist.angular.x = omega
        log.messages.append(msg)
    return log


@pytest.mark.parametrize(
    ("samples", "start"),
    [
        ([(10.78, 0.0), (10.80, 0.01), (10.82, 0.02)], 10.78),  # a profile from rest
        # the operator waited for a core after its first sample (a rest): the profile moved on
        # 1.45 s later (rns_operator lead), so the twist of 10.78 is not its start
        ([(10.78, 0.0), (12.25, 0.01), (12.27, 0.02)], 12.23),
    ],
)
def test_the_profile_starts_a_sample_before_its_first_motion(samples, start):
    scenario = load_scenario(scenario_path("satellite_observation"))  # quintic: 0 at t = 0
    assert profile_start(_twists(samples), scenario, 50.0) == pytest.approx(start, abs=1e-9)


def test_a_profile_that_starts_moving_starts_at_its_first_twist(tmp_path):
    path = tmp_path / "step.yaml"
    path.write_text(yaml.safe_dump({**SHORT_ROLL_SCENARIO, "time_scaling": "constant"}))
    log = _twists([(3.0, 0.1), (3.02, 0.1)])
    assert profile_start(log, load_scenario(path), 50.0) == pytest.approx(3.0, abs=1e-9)
    with pytest.raises(RnsError, match="asks for motion"):
        profile_start(_twists([(3.0, 0.0)]), load_scenario(path), 50.0)


def test_a_partial_recording_is_an_error_naming_what_was_missed():
    """Figures never come from a recording with holes: robot states always, and on simulated
    time the operator's twists (on their fixed grid) too."""
    import numpy as np

    from rns_ros.runs.inspection import _check_complete
    from rns_ros.runs.recorded import PartialRecordingError

    times = 0.01 * np.arange(300)
    commands = 0.002 * np.arange(1500)
    _check_complete({"times": times, "command_times": commands}, "dls", sim_time=True)
    with pytest.raises(PartialRecordingError, match=r"dls: this process missed 3 robot states"):
        _check_complete(
            {"times": np.delete(times, [7, 8, 9]), "command_times": commands}, "dls", True
        )
    holes = {"times": times, "command_times": np.delete(commands, [100])}
    with pytest.raises(PartialRecordingError, match=r"missed 1 cmd_twist samples"):
        _check_complete(holes, "sc", sim_time=True)
    _check_complete(holes, "sc", sim_time=False)  # wall-clock twists jitter: not checked


def test_a_twist_stream_recorded_from_mid_profile_is_a_partial_recording():
    """Leading on simulated time the operator's stream opens with zeros: a first recorded twist
    that moves means the recorder missed the profile's start. Off lockstep, or without the lead,
    a profile may move from its first sample."""
    import argparse

    from rns_ros.runs.inspection import _check_recorded_from_the_start
    from rns_ros.runs.recorded import PartialRecordingError

    moving, resting = TwistStamped(), TwistStamped()
    moving.header.stamp = stamp_from_seconds(3.25)
    moving.twist.angular.x = 0.1
    lockstep = argparse.Namespace(wall_clock=False, real_time_factor=1.0, output_lead=True)
    with pytest.raises(PartialRecordingError, match=r"dls: .* only from 3\.250 s, after the"):
        _check_recorded_from_the_start(moving, lockstep, "dls")
    _check_recorded_from_the_start(resting, lockstep, "dls")
    for other in ({"output_lead": False}, {"wall_clock": True}):
        _check_recorded_from_the_start(
            moving, argparse.Namespace(**{**vars(lockstep), **other}), "dls"
        )


def test_an_arm_already_moving_at_the_first_recorded_twist_is_a_partial_recording():
    """On the wall clock a starved recorder may lose the operator's first moving twists: the
    task would then start mid-roll, and the camera's target count from where it had turned to
    (a loaded run showed 29 deg 'off' a 30 deg roll). An arm that moves before the first moving
    twist recorded gives it away."""
    import numpy as np

    from rns_ros.runs.inspection import AT_REST, _check_at_rest_before
    from rns_ros.runs.recorded import PartialRecordingError

    times = 0.01 * np.arange(100)
    speeds = np.zeros((100, 7))
    speeds[30:, 2] = 0.17  # the arm moves from 0.30 s on, when the first command acts
    data = {"times": times, "joint_velocities": speeds}
    _check_at_rest_before(data, 0.295, "dls")  # recorded from the profile's start
    with pytest.raises(PartialRecordingError, match=r"dls: the arm moved at 0\.17 rad/s before"):
        _check_at_rest_before(data, 0.60, "dls")  # the first 0.3 s of twists were lost
    speeds[:30, 2] = 0.5 * AT_REST  # rounding at rest
    _check_at_rest_before(data, 0.295, "dls")


def _status(state: str, seconds: float) -> DiagnosticArray:
    values = [KeyValue(key="state", value=state)]
    msg = DiagnosticArray(status=[DiagnosticStatus(name="rns_controller", values=values)])
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(seconds), round(seconds % 1 * 1e9)
    return msg


def test_the_joint_limit_watch_takes_the_first_stop_whenever_it_looks():
    """However many statuses arrived between two looks (a busy machine looks seldom), the stop
    is the first JOINT_LIMIT status: the figures end at the same instant."""
    from rclpy.serialization import serialize_message

    from rns_ros.runs.inspection import JointLimitWatch

    log = TopicLog("rns_controller/status", DiagnosticArray)
    watch = JointLimitWatch(log)
    for k in range(5):
        log._append_raw(serialize_message(_status("OK", 0.5 + 0.01 * k)))
    assert watch.at == math.inf
    log._append_raw(b"\x00\x01\x00\x00JOINT_LIMIT but not a message")  # anyone may send bytes
    for k in range(5):
        log._append_raw(serialize_message(_status("JOINT_LIMIT", 1.0 + 0.01 * k)))
    assert watch.at == pytest.approx(1.0)
    log._append_raw(serialize_message(_status("JOINT_LIMIT", 2.0)))
    assert watch.at == pytest.approx(1.0)


def test_behind_a_link_the_task_waits_for_a_predicting_predictor():
    """rns_predictor starts from its first telemetry and knows nothing of a motion already
    under way (a predictor that got its first telemetry mid-roll, late on a busy machine,
    re-anchored every second: 13.7 deg of prediction error): the task waits until its newest
    status says PREDICTING; without a link there is nothing to wait for."""

    def status(message: str) -> DiagnosticArray:
        return DiagnosticArray(status=[DiagnosticStatus(message=message)])

    log = TopicLog("/ground/rns_predictor/status")
    assert inspection._predicts(None)
    assert not inspection._predicts(log)
    log._append(status("WAITING_FOR_TELEMETRY"))
    assert not inspection._predicts(log)
    log._append(status("PREDICTING"))
    assert inspection._predicts(log)
