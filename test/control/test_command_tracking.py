"""CommandedAttitude: the operator's rate integrated over the command stamps, and the correction
that makes the camera follow it whatever ticks ran."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.control.command_tracking import CommandedAttitude, TrackingSettings
from rns_ros.control.controller import TwistFrame
from rns_ros.core.errors import ConfigError

AXIS = np.array([1.0, -2.0, 1.5]) / np.linalg.norm([1.0, -2.0, 1.5])
I3 = np.eye(3)


def angle_between(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(pin.log3(a @ b.T)))


def test_the_integral_follows_the_stamps_not_the_receipts():
    """Jittered receipts (up to 40 ms late) change nothing: each command counts over the
    interval between its stamp and the next one's."""
    rng = np.random.default_rng(3)
    tracker = CommandedAttitude(TrackingSettings())
    tracker.restart(I3, 0.0)
    omega, period, n = 0.2 * AXIS, 0.02, 250
    for k in range(n):
        stamp = k * period
        tracker.take(omega, TwistFrame.WORLD, stamp, stamp + rng.uniform(0, 0.04), I3)
    tracker.take(np.zeros(3), TwistFrame.WORLD, n * period, n * period + 0.03, I3)
    expected = pin.exp3(omega * n * period)
    assert angle_between(tracker.target(n * period + 10.0), expected) < 1e-12


def test_camera_axes_are_body_fixed():
    """A constant rate in camera axes turns R_cmd on the right: R0 exp(omega t)."""
    r0 = pin.exp3(np.array([0.3, -0.1, 0.7]))
    tracker = CommandedAttitude(TrackingSettings())
    tracker.restart(r0, 0.0)
    omega = np.array([0.0, 0.1, 0.3])
    for k in range(101):
        tracker.take(omega if k < 100 else np.zeros(3), TwistFrame.CAMERA, 0.01 * k, 0.01 * k, I3)
    assert angle_between(tracker.target(5.0), r0 @ pin.exp3(omega * 1.0)) < 1e-12
    # world axes would be another attitude: the frame matters
    assert angle_between(pin.exp3(omega * 1.0) @ r0, r0 @ pin.exp3(omega * 1.0)) > 1e-2


def test_base_axes_turn_with_the_base_rotation():
    base = pin.exp3(np.array([0.0, 0.0, np.pi / 2]))
    tracker = CommandedAttitude(TrackingSettings(max_interval=2.0))
    tracker.restart(I3, 0.0)
    tracker.take(np.array([0.1, 0.0, 0.0]), TwistFrame.BASE, 0.0, 0.0, base)
    tracker.take(np.zeros(3), TwistFrame.BASE, 1.0, 1.0, base)
    assert angle_between(tracker.target(2.0), pin.exp3(np.array([0.0, 0.1, 0.0]))) < 1e-12


def test_a_gap_counts_at_most_max_interval():
    """A stream that stops for longer than the command timeout adds no more than that."""
    tracker = CommandedAttitude(TrackingSettings(max_interval=0.5))
    tracker.restart(I3, 0.0)
    tracker.take(np.array([0.0, 0.0, 0.1]), TwistFrame.WORLD, 0.0, 0.0, I3)
    tracker.take(np.zeros(3), TwistFrame.WORLD, 3.0, 3.0, I3)
    assert angle_between(tracker.target(9.0), I3) == pytest.approx(0.05, abs=1e-12)
    # the newest command counts from its receipt, clipped the same way
    tracker.take(np.array([0.0, 0.0, 0.1]), TwistFrame.WORLD, 4.0, 4.0, I3)
    assert angle_between(tracker.target(100.0), I3) == pytest.approx(0.10, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-0.3, 0.3), st.floats(0.0, 0.2), st.floats(0.0, 0.1)),
        min_size=1,
        max_size=40,
    )
)
def test_rates_about_one_axis_add_up_over_the_clipped_stamp_intervals(commands):
    """About a fixed axis the integral is sum(omega_i clip(dt_i, 0, max_interval)), whatever
    the receipt delays (each (rate [rad/s], stamp step [s], receipt delay [s]))."""
    cap = 0.15
    tracker = CommandedAttitude(TrackingSettings(max_interval=cap))
    tracker.restart(I3, 0.0)
    stamp, angle, previous = 0.0, 0.0, None
    for rate, step, delay in commands:
        stamp += step
        if previous is not None:
            angle += previous * min(step, cap)
        tracker.take(rate * AXIS, TwistFrame.WORLD, stamp, stamp + delay, I3)
        previous = rate
    tracker.take(np.zeros(3), TwistFrame.WORLD, stamp + 0.1, stamp + 0.1, I3)
    angle += previous * 0.1
    expected = pin.exp3(angle * AXIS)
    assert angle_between(tracker.target(stamp + 5.0), expected) < 1e-9


def _closed_loop(gain: float, skip_every: int) -> float:
    """A camera that moves only on the ticks that run (one tick in ``skip_every`` is lost, its
    period not moved) and starts each command from rest through a ramp, commanded 0.2 rad/s
    for 5 s then zero; the angle [rad] it ends from the commanded turn after 7 s more."""
    tracker = CommandedAttitude(TrackingSettings(gain=gain, max_correction=0.05))
    camera = np.eye(3)
    tracker.restart(camera, 0.0)
    period, speed, accel = 0.01, 0.0, 1.0
    for k in range(1200):
        t = k * period
        rate = 0.2 if t < 5.0 else 0.0
        tracker.take(rate * AXIS, TwistFrame.WORLD, t, t, I3)
        speed = min(rate, speed + accel * period) if rate > 0 else 0.0
        omega = speed * AXIS + tracker.step(camera, t).correction
        if k % skip_every != skip_every - 1:
            camera = pin.exp3(omega * period) @ camera
    return angle_between(camera, pin.exp3(0.2 * 5.0 * AXIS))


def test_the_camera_ends_where_the_commands_add_up_despite_ramps_and_lost_ticks():
    untracked = _closed_loop(gain=0.0, skip_every=7)
    tracked = _closed_loop(gain=1.0, skip_every=7)
    assert untracked > 0.1  # one tick in seven lost: the camera falls ~0.14 rad short
    assert tracked < 1e-3


def test_the_correction_is_capped_and_a_runaway_error_restarts():
    tracker = CommandedAttitude(TrackingSettings(gain=2.0, max_correction=0.05, max_error=0.3))
    tracker.restart(pin.exp3(0.2 * AXIS), 0.0)
    step = tracker.step(I3, 0.0)
    assert np.linalg.norm(step.correction) == pytest.approx(0.05)
    assert step.correction @ AXIS > 0  # towards the commanded attitude
    camera = pin.exp3(-0.2 * AXIS)
    step = tracker.step(camera, 0.0)  # 0.4 rad off: cannot be closed
    assert step.restarted
    assert step.error == pytest.approx(0.4)
    assert angle_between(tracker.target(0.0), camera) < 1e-12
    assert not tracker.step(camera, 0.0).correction.any()  # exactly zero: joints at rest


def test_nothing_is_tracked_before_a_restart_or_after_a_stop():
    tracker = CommandedAttitude(TrackingSettings())
    tracker.take(AXIS, TwistFrame.WORLD, 0.0, 0.0, I3)
    assert tracker.target(1.0) is None
    assert not tracker.active
    assert not tracker.step(I3, 1.0).correction.any()
    tracker.restart(I3, 0.0)
    assert tracker.active
    tracker.stop(1.0)
    assert not tracker.active
    assert tracker.target(1.0) is None


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"gain": -1.0}, "tracking_gain"),
        ({"gain": float("nan")}, "tracking_gain"),
        ({"max_correction": 0.0}, "tracking_max_correction"),
        ({"max_error": float("inf")}, "tracking_max_error"),
        ({"max_interval": -0.1}, "command_timeout"),
    ],
)
def test_bad_settings_name_the_value(kwargs, name):
    with pytest.raises(ConfigError, match=name):
        TrackingSettings(**kwargs)


def test_a_restart_counts_the_held_command_from_its_receipt_or_the_stop():
    """A restart (the arm follows again) anchors R_cmd at the camera and keeps the newest
    command, counted from its receipt or from the stop, whichever came later: nothing is added
    twice or lost."""
    omega = 0.1 * AXIS
    fresh = CommandedAttitude(TrackingSettings(max_interval=5.0))
    fresh.take(omega, TwistFrame.WORLD, 10.0, 0.0, I3)  # sender's clock 10 s ahead
    fresh.restart(I3, 0.01)  # the first tick after the receipt
    assert angle_between(fresh.target(2.0), pin.exp3(omega * 2.0)) < 1e-12

    tracker = CommandedAttitude(TrackingSettings(max_interval=5.0))
    tracker.take(omega, TwistFrame.WORLD, 10.0, 0.0, I3)
    tracker.stop(0.5)
    assert tracker.target(1.0) is None
    tracker.restart(I3, 1.0)
    assert angle_between(tracker.target(2.0), pin.exp3(omega * 1.5)) < 1e-12
    tracker.take(np.zeros(3), TwistFrame.WORLD, 11.5, 1.5, I3)
    assert angle_between(tracker.target(9.0), pin.exp3(omega * 1.0)) < 1e-12
