"""Operator command gate: validation at the edge, receipt-time timeout, bounded ramp to zero."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rns_ros.control.controller import TwistFrame
from rns_ros.control.teleop import (
    CommandGate,
    CommandSchedule,
    ControllerState,
    twist_frame_ids,
    validate_twist,
)
from rns_ros.core import ConfigError, InputError

FRAMES = {"world": TwistFrame.WORLD, "base_link": TwistFrame.BASE, "": TwistFrame.CAMERA}


def _command(angular, received=0.0, frame="world"):
    return validate_twist(angular, [0.1, 0.0, 0.0], frame, FRAMES, 1.0, received)


@pytest.mark.parametrize(
    ("angular", "frame", "message"),
    [
        ([math.nan, 0.0, 0.0], "world", "finite"),
        ([math.inf, 0.0, 0.0], "world", "finite"),
        ([0.1, 0.0, 0.0], "map", "'map' is not one of \\['base_link', 'world'\\]"),
    ],
)
def test_bad_twists_are_rejected_by_name(angular, frame, message):
    with pytest.raises(InputError, match=message):
        validate_twist(angular, [0.0] * 3, frame, FRAMES, 1.0, 0.0)


def test_empty_frame_takes_the_default_axes():
    assert _command([0.1, 0, 0], frame="").frame is TwistFrame.CAMERA


def test_fresh_command_passes_then_ramps_down_at_the_deceleration():
    gate = CommandGate(timeout=0.5, deceleration=1.0, acceleration=1e3)
    assert gate.update(0.0, 0.01).state is ControllerState.IDLE
    gate.accept(_command([0.3, 0.0, 0.4], received=0.0))  # |omega| = 0.5 rad/s
    out = gate.update(0.5, 0.01)  # age 0.5 s: still fresh
    assert out.state is ControllerState.OK
    assert np.array_equal(out.angular, [0.3, 0.0, 0.4])
    assert np.array_equal(out.linear, [0.1, 0.0, 0.0])
    speeds, t = [], 0.5
    while True:
        t += 0.01
        out = gate.update(t, 0.01)
        speeds.append(np.linalg.norm(out.angular))
        if out.stopped:
            break
        assert out.state is ControllerState.DECELERATING
        assert np.allclose(np.cross(out.angular, [0.3, 0.0, 0.4]), 0.0)  # same direction
    # |omega| / deceleration = 0.5 s of ramp, 0.5 rad/s less every second
    assert len(speeds) == pytest.approx(50, abs=1)
    assert np.allclose(-np.diff(speeds[:-1]), 0.01, atol=1e-12)
    assert out.state is ControllerState.IDLE
    assert np.array_equal(out.angular, np.zeros(3))
    assert np.array_equal(out.linear, np.zeros(3))


def test_rejection_ramps_down_and_a_valid_command_recovers():
    gate = CommandGate(timeout=0.5, deceleration=10.0)
    gate.accept(_command([0.2, 0.0, 0.0]))
    assert gate.update(0.0, 0.01).state is ControllerState.RAMPING  # 0.1 of 0.2 rad/s
    assert gate.update(0.0, 0.01).state is ControllerState.OK
    gate.reject("angular velocity must be 3 finite numbers")
    out = gate.update(0.01, 0.01)
    assert out.state is ControllerState.INVALID_COMMAND
    assert np.linalg.norm(out.angular) == pytest.approx(0.1)
    out = gate.update(0.02, 0.01)
    assert out.stopped
    assert out.state is ControllerState.INVALID_COMMAND
    gate.accept(_command([0.0, 0.1, 0.0], received=0.03))
    assert gate.update(0.04, 0.01).state is ControllerState.OK  # 10 rad/s^2: 0.1 in one period


def test_gate_rejects_bad_settings():
    with pytest.raises(ConfigError, match="command_timeout"):
        CommandGate(timeout=0.0, deceleration=1.0)


def test_above_limit_commands_are_scaled_to_the_limit_with_their_axis_kept():
    """MoveIt Servo style: a finite command over max_angular_speed keeps its direction."""
    command = validate_twist([0.9, 0.9, 0.0], [0.0] * 3, "world", FRAMES, 1.0, 0.0)
    assert np.linalg.norm(command.angular) == pytest.approx(1.0)
    assert np.allclose(np.cross(command.angular, [1.0, 1.0, 0.0]), 0.0)
    assert command.requested_speed == pytest.approx(math.hypot(0.9, 0.9))
    assert validate_twist([0.6, 0.0, 0.0], [0.0] * 3, "", FRAMES, 1.0, 0.0).requested_speed is None
    gate = CommandGate(timeout=0.5, deceleration=1.0, acceleration=1e3)
    gate.accept(command)
    out = gate.update(0.0, 0.01)
    assert out.state is ControllerState.SPEED_LIMITED
    assert not out.stopped
    assert np.linalg.norm(out.angular) == pytest.approx(1.0)


@pytest.mark.parametrize("speed", [0.05, 0.2, 0.8])
def test_start_from_rest_ramps_at_the_acceleration_then_follows_at_once(speed):
    """The first command (a restarted controller, after a stop) rises at start_acceleration:
    |omega| after k periods is min(speed, k a T); once there, changes pass unramped."""
    accel, period = 2.0, 0.01
    gate = CommandGate(timeout=0.5, deceleration=1.0, acceleration=accel)
    gate.accept(_command([0.0, speed, 0.0]))
    speeds = []
    for k in range(1, 200):
        out = gate.update(0.0, period)
        speeds.append(np.linalg.norm(out.angular))
        assert speeds[-1] == pytest.approx(min(speed, k * accel * period), abs=1e-12)
        assert np.allclose(np.cross(out.angular, [0.0, 1.0, 0.0]), 0.0)
        if out.state is ControllerState.OK:
            break
    assert speeds[-1] == pytest.approx(speed)
    assert len(speeds) == math.ceil(speed / (accel * period) - 1e-9)
    gate.accept(_command([0.0, -speed, 0.0]))  # a reversal while moving: served at once
    assert np.allclose(gate.update(0.0, period).angular, [0.0, -speed, 0.0])
    gate.stop()  # e.g. the joint state went stale: from rest again
    assert np.linalg.norm(gate.update(0.0, period).angular) == pytest.approx(
        min(speed, accel * period)
    )


def test_a_zero_command_means_the_next_one_starts_from_rest():
    gate = CommandGate(timeout=0.5, deceleration=1.0, acceleration=1.0)
    gate.accept(_command([0.5, 0.0, 0.0]))
    while gate.update(0.0, 0.01).state is not ControllerState.OK:
        pass
    gate.accept(_command([0.0, 0.0, 0.0]))
    assert gate.update(0.0, 0.01).state is ControllerState.OK
    gate.accept(_command([0.5, 0.0, 0.0]))
    out = gate.update(0.0, 0.01)
    assert out.state is ControllerState.RAMPING
    assert np.linalg.norm(out.angular) == pytest.approx(0.01)


def test_frame_names_accept_the_base_alias_and_the_urdf_names(robot):
    """header.frame_id and default_twist_frame take the same names: base / the base link,
    camera / the camera frame, world / world_frame."""
    frames = twist_frame_ids(robot, "world", "base")
    assert frames["base"] is frames[robot.base_link] is frames[""] is TwistFrame.BASE
    assert frames["camera"] is TwistFrame.CAMERA
    assert frames["world"] is TwistFrame.WORLD
    assert twist_frame_ids(robot, "world", robot.base_link)[""] is TwistFrame.BASE
    assert twist_frame_ids(robot, "map", "map")[""] is TwistFrame.WORLD
    with pytest.raises(ConfigError, match=r"default_twist_frame.*'base_link'.*got 'odom'"):
        twist_frame_ids(robot, "world", "odom")


def test_every_state_has_a_plot_code():
    from rns_ros.viz.paths import CONTROLLER_STATE_CODES

    assert set(CONTROLLER_STATE_CODES) == {state.value for state in ControllerState}
    assert len(set(CONTROLLER_STATE_CODES.values())) == len(ControllerState)


# --- CommandSchedule: twists stamped ahead, released at their stamps -------------------------


def test_a_schedule_releases_each_command_at_its_stamp_and_waits_for_the_next_one():
    schedule = CommandSchedule()
    assert schedule.ready(10)  # no stream: nothing to wait for
    assert schedule.due(10) == []
    schedule.push(0, "zero", moving=False)
    schedule.push(20, "a", moving=True)
    schedule.push(40, "b", moving=True)
    assert schedule.ready(10)
    assert schedule.due(10) == ["zero"]
    assert schedule.ready(30)
    assert schedule.due(30) == ["a"]
    assert schedule.ready(40)
    assert schedule.due(40) == ["b"]
    # b asks for motion and nothing stamped at or after 50 came: the command in force is unknown
    assert not schedule.ready(50)
    schedule.push(60, "c", moving=True)
    assert schedule.ready(50)  # b is still in force at 50
    assert schedule.due(50) == []


def test_a_schedule_waits_on_a_resting_start_but_not_on_a_stop_and_can_give_up_waiting():
    schedule = CommandSchedule()
    schedule.push(0, "rest", moving=False)  # a profile starts at rest: its next sample matters
    assert not schedule.ready(10)
    schedule.push(10, "a", moving=True)
    assert not schedule.ready(20)
    schedule.release_all()  # the stream stalled or ended: serve with what there is
    assert schedule.ready(20)
    assert schedule.ready(1000)
    schedule.push(20, "b", moving=True)  # a newer command: waiting resumes
    assert not schedule.ready(30)
    schedule.push(40, "stop", moving=False)
    assert schedule.ready(10**9)  # the operator's stream may end on a stop


def test_a_command_stamped_back_replaces_the_waiting_ones():
    schedule = CommandSchedule()
    for stamp in (100, 120, 140):
        schedule.push(stamp, stamp, moving=True)
    schedule.push(90, "final stop", moving=False)  # e.g. an operator stopped, stamped now
    assert schedule.newest == 90
    assert schedule.due(200) == ["final stop"]


def test_a_schedule_holds_at_most_max_waiting_commands():
    schedule = CommandSchedule(max_waiting=3)
    for stamp in range(5):  # e.g. a publisher stamping years ahead
        schedule.push(10**18 + stamp, stamp, moving=True)
    assert schedule.dropped == 2
    assert schedule.due(10**19) == [2, 3, 4]
    with pytest.raises(ConfigError, match="max_waiting"):
        CommandSchedule(max_waiting=0)


@given(
    gaps=st.lists(st.integers(1, 40), min_size=1, max_size=40),
    leads=st.lists(st.integers(0, 60), min_size=40, max_size=40),
    period=st.integers(1, 30),
)
def test_a_ready_tick_always_serves_the_newest_command_stamped_before_it(gaps, leads, period):
    """Commands stamped on any increasing grid, each published any time before its stamp up to
    a lead (an operator's process that gets the core late publishes late), ticks on another
    grid: whenever a tick is ready, the command in force is the newest stamped at or before it,
    whatever the arrival times."""
    stamps = list(np.cumsum(gaps))
    # one publisher: commands go out in stamp order, each no earlier than the one before
    published = np.maximum.accumulate(
        [stamp - lead for stamp, lead in zip(stamps, leads, strict=False)]
    )
    arrivals = list(zip(published.tolist(), stamps, strict=True))
    schedule, in_force, k = CommandSchedule(), None, 0
    for tick in range(0, stamps[-1] + 2 * period, period):
        while k < len(arrivals) and arrivals[k][0] <= tick:
            schedule.push(arrivals[k][1], arrivals[k][1], moving=True)
            k += 1
        while not schedule.ready(tick):  # the tick waits for the next command to arrive
            if k == len(arrivals):
                schedule.release_all()  # the stream ended (a controller's wait times out)
                break
            schedule.push(arrivals[k][1], arrivals[k][1], moving=True)
            k += 1
        released = schedule.due(tick)
        if released:
            in_force = released[-1]
        expected = max((s for s in stamps if s <= tick), default=None)
        assert in_force == expected
