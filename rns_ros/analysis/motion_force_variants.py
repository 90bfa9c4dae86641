r"""Labelled variants of the chapter-6 set-up: the same arm with gravity in its plane or with a
payload, and the planar arm's start configuration chosen on its self-motion.

They feed :func:`~rns_ros.analysis.motion_force_runs.run_closed_loop` (a gravity arm as the
scenario's robot, a payload arm as its ``plant``) for the cause sweeps of ``fig6.3``/``fig6.4`` and
the remarks of sections 6.1.2 and 6.2.1.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin

from rns_ros.control.contact_tasks import Setup
from rns_ros.core.errors import ConfigError
from rns_ros.core.fixed_base import FixedBaseModel
from rns_ros.core.validation import as_vector, positive

#: Gravity of the labelled gravity runs [m/s^2] (the thesis gives no value).
GRAVITY = 9.81
#: The planar arm's vertical: y of our x-y plane (the thesis' x-z plane, z up) (3,).
PLANAR_UP = (0.0, 1.0, 0.0)


def _copy(robot: FixedBaseModel) -> tuple[pin.Model, str]:
    model = robot.model.copy()
    return model, robot.model.frames[robot.ee_frame_id].name


def with_gravity(robot: FixedBaseModel, acceleration) -> FixedBaseModel:
    """A copy of ``robot`` with the gravity acceleration ``acceleration`` [m/s^2] (3,), world
    axes (the model's own, used by g_l, c_hat and the simulator alike)."""
    gravity = as_vector(acceleration, 3, "gravity acceleration")
    model, frame = _copy(robot)
    copy = FixedBaseModel(model, frame, name=f"{robot.name}+gravity")
    model.gravity = pin.Motion(gravity, np.zeros(3))
    copy.gravity = bool(np.any(gravity != 0.0))
    return copy


def planar_gravity(robot: FixedBaseModel, magnitude: float = GRAVITY) -> FixedBaseModel:
    """``robot`` with gravity ``magnitude`` [m/s^2] along -y (the plane's vertical, y up: the
    thesis' x-z plane with z up mapped to our x-y)."""
    magnitude = positive(magnitude, "gravity", "[m/s^2]")
    return with_gravity(robot, -magnitude * np.asarray(PLANAR_UP))


def with_payload(robot: FixedBaseModel, mass: float) -> FixedBaseModel:
    """A copy of ``robot`` carrying a point mass ``mass`` [kg] (> 0) at the EE point (on the last
    link): the plant of a model error the controllers do not know."""
    mass = positive(mass, "payload mass", "[kg]")
    model, frame = _copy(robot)
    ee = model.frames[robot.ee_frame_id]
    point = pin.Inertia(mass, ee.placement.translation.copy(), np.zeros((3, 3)))
    model.inertias[ee.parentJoint] = model.inertias[ee.parentJoint] + point
    copy = FixedBaseModel(model, frame, name=f"{robot.name}+payload")
    model.gravity = robot.model.gravity
    copy.gravity = robot.gravity
    return copy


def gravity_setup(setup: Setup, magnitude: float = GRAVITY) -> Setup:
    """``setup`` on the planar arm with gravity along -y (:func:`planar_gravity`): controllers
    and simulator see it (every controller compensates it with its own g_l / G_e)."""
    return dataclasses.replace(setup, robot=planar_gravity(setup.robot, magnitude))


def planar_lengths(robot: FixedBaseModel) -> tuple[float, float, float]:
    """Link lengths l_1, l_2, l_3 [m] of a planar 3R arm: joint-to-joint and joint 3 to EE."""
    model = robot.model
    if robot.n != 3:
        raise ConfigError(f"{robot.name}: a planar 3R arm is needed, got {robot.n} joints")
    ee = model.frames[robot.ee_frame_id]
    return (
        float(np.linalg.norm(model.jointPlacements[2].translation)),
        float(np.linalg.norm(model.jointPlacements[3].translation)),
        float(np.linalg.norm(ee.placement.translation)),
    )


def planar_ik(robot: FixedBaseModel, point, psi: float, elbow: int) -> np.ndarray:
    r"""Joint angles [rad] (3,) of the planar 3R arm with its EE at ``point`` (x, y) [m] and the
    last link at absolute angle ``psi`` [rad] (psi = theta_1 + theta_2 + theta_3): the wrist
    w = p - l_3 (cos psi, sin psi), then cos theta_2 = (|w|^2 - l_1^2 - l_2^2) / (2 l_1 l_2),
    theta_2 of the sign of ``elbow`` (+1 / -1). Parametrizes the self-motion at ``point``.

    Raises:
        ConfigError: the wrist is out of reach for this psi, or elbow is not +-1.
    """
    if elbow not in (-1, 1):
        raise ConfigError(f"elbow must be +1 or -1, got {elbow!r}")
    l1, l2, l3 = planar_lengths(robot)
    p = as_vector(point, 2, "point")
    w = p - l3 * np.array([math.cos(psi), math.sin(psi)])
    cosine = (w @ w - l1**2 - l2**2) / (2.0 * l1 * l2)
    if abs(cosine) > 1.0:
        raise ConfigError(f"psi = {math.degrees(psi):.4g} deg puts the wrist out of reach")
    theta2 = elbow * math.acos(cosine)
    theta1 = math.atan2(w[1], w[0]) - math.atan2(l2 * math.sin(theta2), l1 + l2 * math.cos(theta2))
    return np.array([theta1, theta2, psi - theta1 - theta2])


__all__ = [
    "GRAVITY",
    "PLANAR_UP",
    "gravity_setup",
    "planar_gravity",
    "planar_ik",
    "planar_lengths",
    "with_gravity",
    "with_payload",
]
