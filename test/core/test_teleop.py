"""Operator command gate: validation at the edge, receipt-time timeout, bounded ramp to zero."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.core import ConfigError, InputError
from rns_ros.core.controller import TwistFrame
from rns_ros.core.teleop import CommandGate, ControllerState, validate_twist

FRAMES = {"world": TwistFrame.WORLD, "base_link": TwistFrame.BASE, "": TwistFrame.CAMERA}


def _command(angular, received=0.0, frame="world"):
    return validate_twist(angular, [0.1, 0.0, 0.0], frame, FRAMES, 1.0, received)


@pytest.mark.parametrize(
    ("angular", "frame", "message"),
    [
        ([math.nan, 0.0, 0.0], "world", "finite"),
        ([math.inf, 0.0, 0.0], "world", "finite"),
        ([0.9, 0.9, 0.0], "world", "over max_angular_speed"),
        ([0.1, 0.0, 0.0], "map", "'map' is not one of \\['base_link', 'world'\\]"),
    ],
)
def test_bad_twists_are_rejected_by_name(angular, frame, message):
    with pytest.raises(InputError, match=message):
        validate_twist(angular, [0.0] * 3, frame, FRAMES, 1.0, 0.0)


def test_empty_frame_takes_the_default_axes():
    assert _command([0.1, 0, 0], frame="").frame is TwistFrame.CAMERA


def test_fresh_command_passes_then_ramps_down_at_the_deceleration():
    gate = CommandGate(timeout=0.5, deceleration=1.0)
    assert gate.update(0.0, 0.01).state is ControllerState.STALE_COMMAND
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
    assert out.state is ControllerState.STALE_COMMAND
    assert np.array_equal(out.angular, np.zeros(3))
    assert np.array_equal(out.linear, np.zeros(3))


def test_rejection_ramps_down_and_a_valid_command_recovers():
    gate = CommandGate(timeout=0.5, deceleration=10.0)
    gate.accept(_command([0.2, 0.0, 0.0]))
    gate.reject("angular velocity must be 3 finite numbers")
    out = gate.update(0.01, 0.01)
    assert out.state is ControllerState.INVALID_COMMAND
    assert np.linalg.norm(out.angular) == pytest.approx(0.1)
    out = gate.update(0.02, 0.01)
    assert out.stopped
    assert out.state is ControllerState.INVALID_COMMAND
    gate.accept(_command([0.0, 0.1, 0.0], received=0.03))
    assert gate.update(0.04, 0.01).state is ControllerState.OK


def test_gate_rejects_bad_settings():
    with pytest.raises(ConfigError, match="command_timeout"):
        CommandGate(timeout=0.0, deceleration=1.0)
