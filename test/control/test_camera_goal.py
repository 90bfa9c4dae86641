"""The camera orientation goal: quaternion checks and the error-feedback law on an ideal camera
(R <- exp(omega T) R each period, what the reactionless law achieves away from singularities)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.control.camera_goal import (
    UNIT_NORM_TOLERANCE,
    CameraGoal,
    GoalSettings,
    goal_rotation,
)
from rns_ros.core.errors import ConfigError, InputError

T = 0.01  # control period [s]


def _rotation(axis, angle: float) -> np.ndarray:
    axis = np.asarray(axis, dtype=float)
    return pin.exp3(angle * axis / np.linalg.norm(axis))


@pytest.mark.parametrize(
    ("quaternion", "text"),
    [
        ((0.0, 0.0, 0.0, 0.0), "not a unit quaternion"),  # an unset orientation
        ((0.0, 0.0, 0.0, 1.0 + 2 * UNIT_NORM_TOLERANCE), "not a unit quaternion"),
        ((0.5, 0.5, 0.5, 0.5 * (1 - 10 * UNIT_NORM_TOLERANCE)), "not a unit quaternion"),
        ((math.nan, 0.0, 0.0, 1.0), "finite"),
        ((0.0, math.inf, 0.0, 1.0), "finite"),
        ((0.0, 0.0, 1.0), "finite"),
    ],
)
def test_non_finite_and_non_unit_quaternions_are_rejected(quaternion, text):
    with pytest.raises(InputError, match=text):
        goal_rotation(quaternion)


def test_a_unit_quaternion_is_its_rotation_in_xyzw_order():
    rotation = _rotation((1.0, -2.0, 0.5), 0.7)
    q = pin.Quaternion(rotation)
    x, y, z, w = q.x, q.y, q.z, q.w
    assert np.allclose(goal_rotation((x, y, z, w)), rotation, atol=1e-12)
    # within the tolerance: renormalized, still a rotation
    scaled = goal_rotation(np.array([x, y, z, w]) * (1.0 + 0.5 * UNIT_NORM_TOLERANCE))
    assert np.allclose(scaled @ scaled.T, np.eye(3), atol=1e-12)
    assert np.allclose(scaled, rotation, atol=1e-12)


def test_settings_must_be_positive():
    with pytest.raises(ConfigError, match="goal_gain"):
        GoalSettings(gain=0.0)
    with pytest.raises(ConfigError, match="goal_tolerance"):
        GoalSettings(tolerance=-1e-3)


def test_an_ideal_camera_turns_along_the_geodesic_at_the_bounded_speed_then_decays_as_exp():
    """From 1 rad away: |omega| = max_speed while k|e| > max_speed, about the fixed axis of the
    remaining rotation (the geodesic); then |e| decays as exp(-k t); reached once within the
    tolerance, with zero command from then on."""
    settings = GoalSettings(gain=2.0, max_speed=0.3, tolerance=1e-3)
    start = _rotation((0.2, 1.0, -0.4), 0.9)
    target = _rotation((1.0, 1.0, 1.0), 1.0) @ start
    axis = pin.log3(target @ start.T)
    axis /= np.linalg.norm(axis)
    goal = CameraGoal(settings)
    goal.set(target)
    camera, errors, reached_at = start, [], None
    for k in range(2000):
        step = goal.step(camera)
        errors.append(step.error)
        speed = float(np.linalg.norm(step.omega))
        assert speed <= settings.max_speed * (1 + 1e-12)
        if step.reached:
            reached_at = k
            assert speed == 0.0
            break
        assert np.allclose(step.omega / speed, axis, atol=1e-9)  # geodesic: a fixed axis
        camera = pin.exp3(step.omega * T) @ camera
    assert reached_at is not None
    assert not goal.active
    assert errors[-1] <= settings.tolerance < errors[-2]
    # cruise at max_speed down to |e| = max_speed / k ...
    cruise = next(k for k, e in enumerate(errors) if settings.gain * e <= settings.max_speed)
    assert errors[0] - errors[cruise - 1] == pytest.approx(settings.max_speed * T * (cruise - 1))
    # ... then each period multiplies |e| by (1 - k T), the discrete exp(-k t)
    ratios = np.array(errors[cruise + 1 : -1]) / np.array(errors[cruise:-2])
    assert np.allclose(ratios, 1.0 - settings.gain * T, rtol=1e-9)
    expected = cruise + math.log(settings.max_speed / settings.gain / settings.tolerance) / (
        -math.log(1.0 - settings.gain * T)
    )
    assert abs(reached_at - expected) <= 2


def test_a_cancelled_goal_is_inactive_and_stepping_it_is_an_error():
    goal = CameraGoal()
    goal.set(np.eye(3))
    goal.cancel()
    assert not goal.active
    with pytest.raises(InputError):
        goal.step(np.eye(3))
