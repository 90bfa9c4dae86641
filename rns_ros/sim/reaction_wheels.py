r"""Three orthogonal reaction wheels on the base: a gyrostat model for the free-floating simulator.

Thesis chapter 5 (§5.1) puts three reaction wheels on the base, spin axes along the base x, y, z
axes, each of spin inertia I_r. rns_ros takes the wheels' *mass and locked inertia to be part of
the URDF base link* (a real satellite's mass properties include its wheel assemblies), so the model
the controller uses is unchanged and the plant with locked wheels is exactly that model. What the
wheels add is their spin relative to the base.

Each wheel is axisymmetric about its axis a_i (= e_i in base axes) through the base CoM. Its
absolute axial angular momentum

    H_i = I_r (phi_dot_i + a_i . omega_b^B)      [N m s]                        (gyrostat)

changes only with the motor torque tau_i that the base applies to it: dH_i/dt = tau_i. The
simulator therefore integrates the rigid system *without* the wheels' spin inertia (the base
rotational inertia reduced by I_r E, :func:`spin_reduced_model`) plus the 3-vector H:

* total angular momentum (world, about the system CoM) = A'_G(q) v (angular rows) + R_b H,
  conserved: in kinematic mode the base twist solves A'_b v_b = h_G - A'_m theta_dot - [0; R_b H];
* dynamic mode: the wheels act on the reduced base as the pure couple -(tau + omega_b^B x H) (base
  axes), the reaction of d/dt(R_b H) = R_b (tau + omega^B x H), in ABA's external forces;
* relative wheel speeds phi_dot = H / I_r - omega_b^B [rad/s] (base axes, one per wheel);
* kinetic energy = 1/2 v^T M' v + |H|^2 / (2 I_r) = locked-system energy (eq. 5.1 with phi_dot = 0)
  + 1/2 I_r |phi_dot|^2 + I_r phi_dot . omega_b^B (the wheel terms of eq. 5.1 with
  M~_r = M~_omega_r = I_r E).

Commanded wheel torques are clipped per wheel to ``torque_limit`` (a wheel is an independent
actuator; ETS-VII's was 0.1 N m) and set to zero on a wheel at ``speed_limit`` that would spin it
faster; both are reported as saturation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError, ModelError
from rns_ros.core.validation import as_vector

#: Wheel names in axis order (base x, y, z), as published on the wheel joint states.
WHEEL_NAMES = ("wheel_x", "wheel_y", "wheel_z")


@dataclass(frozen=True)
class ReactionWheels:
    """Parameters of the three wheels (same for each).

    Attributes:
        inertia: spin inertia I_r [kg m^2] (thesis: 0.11).
        mass: mass of one wheel [kg] (thesis: 10); informative here, it is part of the URDF base.
        torque_limit: largest motor torque per wheel [N m] (ETS-VII: 0.1).
        speed_limit: largest spin rate relative to the base per wheel [rad/s] (default 628.3 =
            6000 rpm).
    """

    inertia: float = 0.11
    mass: float = 10.0
    torque_limit: float = 0.1
    speed_limit: float = 200.0 * math.pi

    def __post_init__(self) -> None:
        for name, unit in (
            ("inertia", "kg m^2"),
            ("mass", "kg"),
            ("torque_limit", "N m"),
            ("speed_limit", "rad/s"),
        ):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise ConfigError(
                    f"reaction wheel {name} must be finite and > 0 {unit}, got {value!r}"
                )


def spin_reduced_model(model: pin.Model, wheels: ReactionWheels) -> pin.Model:
    """A copy of ``model`` whose base body lacks the wheels' spin inertia: its rotational inertia
    about the base CoM is reduced by I_r E (the wheel momentum state carries that part).

    Raises:
        ModelError: the base inertia minus I_r E is not positive definite (the URDF base cannot
            contain these wheels).
    """
    reduced = model.copy()
    base = reduced.inertias[1]
    rotational = np.array(base.inertia) - wheels.inertia * np.eye(3)
    smallest = float(np.linalg.eigvalsh(rotational)[0])
    if not smallest > 0.0:
        raise ModelError(
            f"the base inertia minus the wheels' spin inertia {wheels.inertia} kg m^2 per axis is "
            f"not positive definite (smallest moment {smallest:.4g} kg m^2): the URDF base must "
            "include the wheel assemblies"
        )
    reduced.inertias[1] = pin.Inertia(base.mass, base.lever, rotational)
    return reduced


def limit_wheel_torque(
    command, wheel_speeds: np.ndarray, wheels: ReactionWheels
) -> tuple[np.ndarray, np.ndarray]:
    """Wheel torques [N m] (3,) within the limits, and a bool (3,) per limited wheel.

    Clipped to +-``torque_limit``; zero on a wheel at or above ``speed_limit`` [rad/s] whose
    torque would spin it faster.

    Raises:
        InputError: ``command`` is not a finite 3-vector.
    """
    command = as_vector(command, 3, "wheel torque")
    applied = np.clip(command, -wheels.torque_limit, wheels.torque_limit)
    saturated = applied != command
    runaway = (np.abs(wheel_speeds) >= wheels.speed_limit) & (applied * wheel_speeds > 0.0)
    applied = np.where(runaway, 0.0, applied)
    return applied, saturated | runaway


def wheel_speeds(momentum: np.ndarray, base_angular_velocity: np.ndarray, inertia: float):
    """Relative spin rates phi_dot = H / I_r - omega_b^B [rad/s] (3,), from the absolute axial
    momenta H [N m s] (3,) and the base angular velocity in base axes [rad/s] (3,)."""
    return np.asarray(momentum) / inertia - np.asarray(base_angular_velocity)
