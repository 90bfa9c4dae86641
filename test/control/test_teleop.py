"""Operator command gate: validation at the edge, receipt-time timeout, bounded ramp to zero."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.control.controller import TwistFrame
from rns_ros.control.teleop import (
    CommandGate,
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
