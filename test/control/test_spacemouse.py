"""SpaceMouse teleop logic: dead zone, scaling, buttons with re-centring, watchdog, zero phase."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rns_ros.control.controller import TwistFrame
from rns_ros.control.spacemouse import (
    Mode,
    SpaceMouseReading,
    SpaceMouseSettings,
    SpaceMouseTeleop,
    dead_zone,
)
from rns_ros.core.errors import ConfigError

SETTINGS = SpaceMouseSettings(angular_scale=0.2, linear_scale=0.05, dead_zone=0.1)
T = 0.02  # tick [s]


def _reading(rotation=(0.0, 0.0, 0.0), translation=(0.0, 0.0, 0.0), buttons=(0, 0), at=0.0):
    return SpaceMouseReading(translation, rotation, tuple(bool(b) for b in buttons), at)


@given(st.floats(0.0, 0.9), st.floats(-1.5, 1.5))
def test_the_dead_zone_is_zero_inside_continuous_at_its_edge_and_full_at_full_scale(width, a):
    out = dead_zone(a, width)
    if abs(a) <= width:
        assert out == 0.0
    else:
        assert math.copysign(1.0, out) == math.copysign(1.0, a)
    assert abs(out) <= 1.0
    assert abs(dead_zone(width + 1e-9, width)) < 1e-8  # continuous at the edge
    assert dead_zone(1.0, width) == pytest.approx(1.0)
    assert dead_zone(-1.0, width) == pytest.approx(-1.0)


def test_a_full_twist_is_angular_scale_and_combined_axes_are_bounded_as_a_vector():
    teleop = SpaceMouseTeleop(SETTINGS)
    command = teleop.update(_reading(rotation=(0.0, 0.0, 1.0)), 0.0)
    assert command.mode is Mode.MOVING
    assert command.angular == pytest.approx((0.0, 0.0, 0.2))
    half = teleop.update(_reading(rotation=(0.55, 0.0, 0.0), at=T), T)
    assert half.angular[0] == pytest.approx(0.2 * (0.55 - 0.1) / 0.9)
    both = teleop.update(_reading(rotation=(1.0, -1.0, 0.0), translation=(1.0, 1.0, 1.0)), 0.0)
    assert np.linalg.norm(both.angular) == pytest.approx(0.2)
    assert both.angular[0] == pytest.approx(-both.angular[1])  # direction kept
    assert np.linalg.norm(both.linear) == pytest.approx(0.05)
    assert both.frame is TwistFrame.CAMERA


def test_release_sends_zeros_for_zero_duration_then_nothing():
    teleop = SpaceMouseTeleop(SETTINGS)
    assert teleop.update(_reading(), 0.0) is None  # nothing before any motion
    assert teleop.update(_reading(rotation=(0.0, 0.5, 0.0), at=1.0), 1.0).moving
    sent = [teleop.update(_reading(at=1.0 + k * T), 1.0 + k * T) for k in range(1, 40)]
    zeros = [c for c in sent if c is not None]
    assert all(not c.moving and c.mode is Mode.CENTRED for c in zeros)
    assert len(zeros) == pytest.approx(SETTINGS.zero_duration / T, abs=1)
    assert sent[-1] is None


def test_the_frame_button_cycles_the_frame_and_waits_for_the_cap_to_centre():
    teleop = SpaceMouseTeleop(SETTINGS)
    yaw = (0.0, 0.0, 0.8)
    assert teleop.update(_reading(yaw), 0.0).frame is TwistFrame.CAMERA
    pressed = teleop.update(_reading(yaw, buttons=(1, 0)), T)
    assert pressed.frame is TwistFrame.WORLD
    assert not pressed.moving
    assert pressed.mode is Mode.RECENTRE
    assert teleop.events == ["frame world"]
    # still deflected, button still held (no new press): zero
    held = teleop.update(_reading(yaw, buttons=(1, 0)), 2 * T)
    assert held.mode is Mode.RECENTRE
    assert teleop.frame is TwistFrame.WORLD
    teleop.update(_reading(buttons=(0, 0)), 3 * T)  # centred and released
    again = teleop.update(_reading(yaw), 4 * T)
    assert again.moving
    assert again.frame is TwistFrame.WORLD
    teleop.update(_reading(buttons=(1, 0)), 5 * T)
    teleop.update(_reading(), 6 * T)
    teleop.update(_reading(buttons=(1, 0)), 7 * T)
    assert teleop.frame is TwistFrame.CAMERA  # camera -> world -> base -> camera


def test_the_pause_button_zeroes_until_pressed_again_and_the_cap_centres():
    teleop = SpaceMouseTeleop(SETTINGS)
    pitch = (0.0, 0.6, 0.0)
    assert teleop.update(_reading(pitch), 0.0).moving
    paused = teleop.update(_reading(pitch, buttons=(0, 1)), T)
    assert paused.mode is Mode.PAUSED
    assert not paused.moving
    for k in range(2, 10):  # button held, then released: still paused, nothing moves
        command = teleop.update(_reading(pitch, buttons=(0, int(k < 6))), k * T)
        assert command is None or not command.moving
    assert teleop.paused  # pressed again: resumed ...
    teleop.update(_reading(pitch, buttons=(0, 1)), 10 * T)
    assert not teleop.paused
    assert teleop.update(_reading(pitch, buttons=(0, 0)), 11 * T).mode is Mode.RECENTRE
    teleop.update(_reading(), 12 * T)
    assert teleop.update(_reading(pitch), 13 * T).moving  # ... moving once centred


def test_a_silent_device_gives_zero_until_it_reports_centred():
    """Deflected with the newest report older than device_timeout: zero (as released); a later
    report still deflected does not restart the motion, a centred one re-arms it."""
    settings = SpaceMouseSettings(device_timeout=0.5)
    teleop = SpaceMouseTeleop(settings)
    roll = (0.7, 0.0, 0.0)
    assert teleop.update(_reading(roll, at=0.0), 0.4).moving
    silent = teleop.update(_reading(roll, at=0.0), 0.51)
    assert silent.mode is Mode.DEVICE_SILENT
    assert not silent.moving
    assert teleop.events == ["device silent while deflected: zero twist"]
    assert teleop.update(_reading(roll, at=0.6), 0.61).mode is Mode.RECENTRE
    teleop.update(_reading(at=0.7), 0.71)
    assert teleop.update(_reading(roll, at=0.8), 0.81).moving


def test_buttons_must_differ():
    with pytest.raises(ConfigError, match="both 2"):
        SpaceMouseSettings(frame_button=2, pause_button=2)
    SpaceMouseSettings(frame_button=-1, pause_button=-1)  # neither used
