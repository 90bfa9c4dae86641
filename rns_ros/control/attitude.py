r"""Base attitude control with reaction wheels: the conventional practice of thesis chapter 5.

The arm moves by any law (e.g. the conventional wrist-only controller of eqs. 4.7-4.8) and the
wheels absorb its reaction. Eq. (5.14) gives the wheel torque that keeps the base attitude exactly:
the wheels take the coupling momentum h_c = M~_omega_m theta_dot_ref of the arm,

    tau_ff,world = -d/dt(M~_omega_m theta_dot_ref)                          [N m], (3,)

which this law differentiates numerically between two control periods. With the wheels'
absolute axial momenta H (base axes, gyrostat model of :mod:`rns_ros.sim.reaction_wheels`),
d/dt(R_b H) = R_b (tau + omega^B x H), so the motor torques in base axes are

    tau = R_b^T tau_ff,world - omega^B x H  +  tau_fb,
    tau_fb = M~_omega^B (omega_n^2 e + 2 zeta omega_n omega^B),   e = log(R_ref^T R_b),

the feedback a PD law on the attitude error e [rad] and the base rate omega^B [rad/s] (base
axes), scaled by the base's rotational inertia M~_omega in base axes so that the closed loop has
natural frequency omega_n and damping ratio zeta about every axis (the wheels push back on the base
with -tau, hence the + sign). The torque is clipped per wheel to ``torque_limit`` (what the wheels
can deliver) and the clipped wheels are reported: while a wheel is saturated the base turns.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import as_vector


@dataclass(frozen=True)
class AttitudeGains:
    """Attitude loop settings.

    Attributes:
        natural_frequency: omega_n of the attitude error dynamics [rad/s].
        damping_ratio: zeta [-].
        torque_limit: motor torque limit per wheel [N m] (ETS-VII: 0.1).
        feedforward: use the eq. (5.14) feed-forward (False: feedback only).
    """

    natural_frequency: float = 0.1
    damping_ratio: float = 1.0
    torque_limit: float = 0.1
    feedforward: bool = True

    def __post_init__(self) -> None:
        for name, unit in (
            ("natural_frequency", "rad/s"),
            ("damping_ratio", "-"),
            ("torque_limit", "N m"),
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"{name} must be finite and > 0 {unit}, got {value!r}")


class AttitudeCommand(NamedTuple):
    """One period's wheel command, base axes.

    Attributes:
        torque: motor torques to apply, clipped [N m], shape (3,).
        feedforward: eq. (5.14) part incl. the gyroscopic term, before clipping [N m], (3,).
        feedback: PD part before clipping [N m], (3,).
        saturated: wheels whose demand exceeded ``torque_limit``, bool (3,).
        attitude_error: |log(R_ref^T R_b)| [rad].
        coupling_momentum: h_c = M~_omega_m theta_dot_ref, world axes [kg m^2/s], (3,).
    """

    torque: np.ndarray
    feedforward: np.ndarray
    feedback: np.ndarray
    saturated: np.ndarray
    attitude_error: float
    coupling_momentum: np.ndarray


class AttitudeControlLaw:
    """Holds the base attitude at ``reference`` (world <- base rotation) with three wheels.

    Call :meth:`step` once per control period with the measured state; the first call has no
    previous coupling momentum, so its feed-forward is zero.
    """

    def __init__(self, reference: np.ndarray, gains: AttitudeGains | None = None) -> None:
        self.gains = gains or AttitudeGains()
        self.reference = np.array(reference, dtype=float).reshape(3, 3)
        self._previous: tuple[float, np.ndarray] | None = None  # (time [s], h_c world)
        self._rate = np.zeros(3)  # newest d/dt h_c, world axes [N m]

    def reset(self, reference: np.ndarray) -> None:
        """New attitude reference; forgets the previous coupling momentum."""
        self.reference = np.array(reference, dtype=float).reshape(3, 3)
        self._previous = None
        self._rate = np.zeros(3)

    def restart_rate(self) -> None:
        """Difference the coupling momentum anew from the next sample, holding the current rate
        until then: the samples of a new source or clock of theta_dot_ref (references stamped by
        their sender, measured rates timed by the node) are not differenced across the switch,
        where a jump divided by an arbitrary interval would be a torque spike."""
        self._previous = None

    def step(
        self,
        time: float,
        state: FreeFloatingState,
        theta_dot_ref,
        base_angular_velocity,
        wheel_momentum,
    ) -> AttitudeCommand:
        """The wheel torques for this period.

        Args:
            time: time of ``theta_dot_ref`` [s], e.g. its message stamp. The rate of h_c is
                updated when it advances and held while it does not (a reference that has not
                changed since the last period), so delivery jitter does not enter the
                numerical derivative.
            state: the measured state (base attitude, M~_omega_m, M~_omega).
            theta_dot_ref: the arm's joint velocity reference (or measured rates) [rad/s], (n,).
            base_angular_velocity: omega_b in base axes [rad/s], (3,).
            wheel_momentum: absolute axial wheel momenta H [N m s], base axes, (3,).
        """
        theta_dot = as_vector(theta_dot_ref, state.n, "theta_dot_ref")
        omega = as_vector(base_angular_velocity, 3, "base angular velocity")
        momentum = as_vector(wheel_momentum, 3, "wheel momentum")
        rotation = state.base_rotation
        coupling = state.coupling_angular_momentum_matrix @ theta_dot
        if self._previous is None:
            self._previous = (float(time), coupling)
        elif time > self._previous[0]:
            last_time, last_coupling = self._previous
            self._rate = (coupling - last_coupling) / (time - last_time)
            self._previous = (float(time), coupling)
        feedforward = np.zeros(3)
        if self.gains.feedforward:
            feedforward = -rotation.T @ self._rate - np.cross(omega, momentum)
        error = pin.log3(self.reference.T @ rotation)
        inertia_base_axes = rotation.T @ state.base_rotational_inertia @ rotation
        wn, zeta = self.gains.natural_frequency, self.gains.damping_ratio
        feedback = inertia_base_axes @ (wn**2 * error + 2.0 * zeta * wn * omega)
        demand = feedforward + feedback
        limit = self.gains.torque_limit
        torque = np.clip(demand, -limit, limit)
        return AttitudeCommand(
            torque=torque,
            feedforward=feedforward,
            feedback=feedback,
            saturated=np.abs(demand) > limit,
            attitude_error=float(np.linalg.norm(error)),
            coupling_momentum=coupling,
        )
