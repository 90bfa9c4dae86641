r"""Contact simulation of thesis Part II: a fixed-base arm whose end effector touches a rigid body.

One scalar holonomic constraint phi(p_e) = 0 on the EE point, held by a Lagrange multiplier with
Baumgarte stabilization, integrated with RK4 under a held torque:

    M_l q_ddot + c_l + g_l = tau - J_c^T lambda,      J_c = n^T J_v                  (C.1)
    J_c q_ddot = -J_c_dot q_dot - K_v phi_dot - K_p phi                              (C.2)

lambda [N] is the normal force the EE exerts ON the environment along n (>= 0 pushing, [A-4.1]);
the constraint is bilateral. Model, signs and tolerances: docs/part2.md, "Contact simulation".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.contact_geometry import Constraint, ee_point_jacobian, is_numeric
from rns_ros.core.errors import ConfigError
from rns_ros.core.fixed_base import FixedBaseModel
from rns_ros.core.validation import positive
from rns_ros.sim.torque_driven import TorqueDrivenArm

#: Default largest |phi| [m] of a start configuration, and |phi_dot| [m/s] of a start velocity.
START_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Baumgarte:
    """Baumgarte gains of the constraint error dynamics phi_ddot + K_v phi_dot + K_p phi = 0.

    Attributes:
        position_gain: K_p [1/s^2], >= 0.
        velocity_gain: K_v [1/s], >= 0.

    Defaults: critical damping at omega_n = 50 rad/s (K_p = omega_n^2, K_v = 2 omega_n).
    """

    position_gain: float = 2500.0
    velocity_gain: float = 100.0

    def __post_init__(self) -> None:
        for name, unit in (("position_gain", "1/s^2"), ("velocity_gain", "1/s")):
            value = getattr(self, name)
            if not (
                is_numeric(value) and np.ndim(value) == 0 and math.isfinite(value) and value >= 0
            ):
                raise ConfigError(f"Baumgarte {name} must be finite and >= 0 {unit}, got {value!r}")

    @classmethod
    def critically_damped(cls, natural_frequency: float) -> Baumgarte:
        """K_p = omega_n^2, K_v = 2 omega_n; omega_n [rad/s] > 0."""
        omega = positive(natural_frequency, "Baumgarte natural_frequency", "[rad/s]")
        return cls(position_gain=omega**2, velocity_gain=2.0 * omega)

    def fastest_rate(self) -> float:
        """Largest |root| [1/s] of s^2 + K_v s + K_p (0 when both gains are 0)."""
        roots = np.roots([1.0, self.velocity_gain, self.position_gain])
        return float(np.max(np.abs(roots))) if roots.size else 0.0


#: Largest |eigenvalue| * dt of the Baumgarte error dynamics accepted (RK4 is stable up to about
#: 2.78 on the negative real axis; half of it keeps the decay well resolved).
_MAX_BAUMGARTE_RATE_DT = 1.4


@dataclass(frozen=True)
class _Terms:
    """The torque-independent part of (C.1)-(C.2) at one (q, v).

    Attributes:
        inverse_mass: M_l^-1 [1/(kg m^2)] (n, n); bias: c_l + g_l [N m] (n,);
        mobility: M_l^-1 J_c^T (n,); schur: J_c M_l^-1 J_c^T (> 0 unless singular);
        target: the constrained normal acceleration J_c q_ddot demanded by (C.2) [m/s^2];
        J_c: n^T J_v (n,).
    """

    inverse_mass: np.ndarray
    bias: np.ndarray
    mobility: np.ndarray
    schur: float
    target: float
    J_c: np.ndarray

    def solve(self, tau: np.ndarray) -> tuple[np.ndarray, float]:
        """(q_ddot [rad/s^2] (n,), lambda [N]) under the torque tau; NaN when singular."""
        free = self.inverse_mass @ (tau - self.bias)  # M^-1 (tau - c - g)
        if not self.schur > 0.0:
            return np.full(free.shape, np.nan), math.nan
        force = (float(self.J_c @ free) - self.target) / self.schur
        return free - self.mobility * force, force


class ContactSimulator(TorqueDrivenArm):
    """Torque-driven fixed-base arm with its end effector held on a rigid surface (RK4).

    See the module docstring for the model (C.1)-(C.2) and the sign of ``lambda``.

    Args:
        robot: the fixed-base arm (:func:`rns_ros.core.fixed_base.load_fixed_base_model`).
        constraint: :class:`ArcConstraint` or :class:`PlaneConstraint` on the EE point.
        initial_q: start configuration [rad] (n,): must be on the constraint within
            ``tolerance`` (see :func:`project_onto_constraint`).
        initial_v: start joint velocity [rad/s] (n,), default zero: its normal EE velocity must
            be below ``velocity_tolerance``.
        dt: RK4 step [s], in (0, 0.1]; default 1 ms (thesis_rest 4.7).
        stabilization: :class:`Baumgarte` gains; None: no stabilization (phi_ddot = 0 only).
        clip_torque: clip every commanded torque to the URDF effort limits (limits <= 0 or
            non-finite count as absent); default off (the torque is applied as given).
        tolerance: largest |phi| [m] of the start configuration; velocity_tolerance: largest
            |phi_dot| [m/s] of the start velocity.

    Attributes:
        time [s]; q [rad], v [rad/s]: (n,); torque: the torque held over the next step [N m];
        work: the work of the joint torques since reset, sum of tau . (q_{k+1} - q_k) [J] (exact
        for the held torque); pulling: the last step ended with contact_force < 0 (the bilateral
        constraint pulled); pulling_steps: steps since reset that ended pulling.

    Raises:
        ConfigError: bad dt, gains, or a start state off the constraint. InputError: bad q/v.
    """

    _STEP_STATE = ("time", "q", "v", "work", "pulling", "pulling_steps", "_cache")
    _KIND = "contact simulation"

    def __init__(
        self,
        robot: FixedBaseModel,
        constraint: Constraint,
        *,
        initial_q,
        initial_v=None,
        dt: float = 1e-3,
        stabilization: Baumgarte | None = Baumgarte(),  # frozen: safe to share
        clip_torque: bool = False,
        tolerance: float = START_TOLERANCE,
        velocity_tolerance: float = START_TOLERANCE,
    ) -> None:
        for method in ("phi", "gradient", "curvature", "evaluate"):
            if not callable(getattr(constraint, method, None)):
                raise ConfigError(
                    "constraint must be an ArcConstraint or PlaneConstraint (methods phi, "
                    f"gradient, curvature, evaluate), got {constraint!r}"
                )
        if robot.model.nq != robot.model.nv:
            raise ConfigError(f"{robot.name}: nq != nv; the contact simulator needs 1-DoF joints")
        self._init_arm(robot, dt, clip_torque)
        self.constraint = constraint
        if stabilization is not None and not isinstance(stabilization, Baumgarte):
            raise ConfigError(f"stabilization must be a Baumgarte or None, got {stabilization!r}")
        self.stabilization = stabilization
        gains = stabilization or Baumgarte(0.0, 0.0)
        self._k_p, self._k_v = gains.position_gain, gains.velocity_gain
        rate = gains.fastest_rate()
        if rate * self.dt > _MAX_BAUMGARTE_RATE_DT:
            raise ConfigError(
                f"Baumgarte gains too stiff for dt = {self.dt} s: fastest error rate "
                f"{rate:.4g} 1/s gives rate * dt = {rate * self.dt:.3g}, must be <= "
                f"{_MAX_BAUMGARTE_RATE_DT}"
            )
        tolerance = positive(tolerance, "tolerance", "[m]")
        velocity_tolerance = positive(velocity_tolerance, "velocity_tolerance", "[m/s]")
        self._zero = np.zeros(robot.n)
        self._lower = np.tril_indices(robot.n, -1)
        self._init_start(initial_q, initial_v)
        self.q, self.v = self._initial_q, self._initial_v
        phi, phi_dot = self.constraint_error()
        if abs(phi) > tolerance:
            raise ConfigError(
                f"initial_q puts the end effector {abs(phi):.3g} m off the surface "
                f"({'inside' if phi > 0 else 'outside'} the environment) of {constraint!r} "
                f"(|phi| must be <= {tolerance:g} m); use project_onto_constraint"
            )
        if abs(phi_dot) > velocity_tolerance:
            raise ConfigError(
                f"initial_v moves the end effector along the contact normal at {phi_dot:.3g} m/s "
                f"(|phi_dot| must be <= {velocity_tolerance:g} m/s); use project_onto_constraint"
            )
        self.reset()

    # --- state ---------------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to the initial state, zero torque, zero work, no pulling count."""
        self._reset_arm()
        self._cache: _Terms | None = None
        self.pulling = False
        self.pulling_steps = 0

    def _current_terms(self) -> _Terms:
        if self._cache is None:
            self._cache = self._terms(self.q, self.v)
        return self._cache

    @property
    def contact_force(self) -> float:
        """lambda [N]: the normal force the EE exerts on the environment, along the gradient n,
        at the current state under the held torque (after a step: the state the step reached,
        the torque held over it). >= 0 pushing, < 0 pulling (bilateral constraint)."""
        return self._current_terms().solve(self.torque)[1]

    @property
    def acceleration(self) -> np.ndarray:
        """q_ddot [rad/s^2] (n,) at the current state under the held torque, (C.1)-(C.2)."""
        return self._current_terms().solve(self.torque)[0]

    def constraint_jacobian(self) -> np.ndarray:
        """J_c = n^T J_v [m/rad] (n,) at the current configuration: phi_dot = J_c q_dot, and
        tau = J_c^T f pushes on the environment with f [N] (at rest, without gravity)."""
        return self._current_terms().J_c.copy()

    def contact_normal(self) -> np.ndarray:
        """The unit contact normal n at the current EE point, into the environment (3,)."""
        return self.constraint.gradient(self.ee_position())

    def ee_position(self) -> np.ndarray:
        """EE point [m] (3,), world."""
        return ee_point_jacobian(self.robot, self._data, self.q)[0]

    def contact_wrench(self) -> np.ndarray:
        """[f; m] (6,) the EE exerts on the environment, world axes, about the EE point [N, N m]:
        f = lambda n, m = 0 (point contact). The arm feels the opposite: (C.1) reads
        M q_ddot + c + g = tau - J_e^T contact_wrench()."""
        wrench = np.zeros(6)
        wrench[:3] = self.contact_force * self.contact_normal()
        return wrench

    def wrist_wrench(self) -> np.ndarray:
        """The same wrench in the EE frame's axes [N, N m] (6,): what a force/torque sensor at the
        EE frame reports when it reads the wrench its tool side applies to the environment
        (a sensor reporting the wrench acting on the tool reads the negative). The contact point
        is the EE frame origin, so the moment is zero."""
        rotation = self._placement().rotation
        wrench = self.contact_wrench()
        return np.concatenate((rotation.T @ wrench[:3], rotation.T @ wrench[3:]))

    def _placement(self) -> pin.SE3:
        pin.framesForwardKinematics(self._model, self._data, self.q)
        return self._data.oMf[self.robot.ee_frame_id]

    def constraint_error(self) -> tuple[float, float]:
        """(phi [m], phi_dot [m/s]) at the current state (0, 0 on the surface)."""
        p, J_v = ee_point_jacobian(self.robot, self._data, self.q)
        p_dot = J_v @ self.v
        return self.constraint.phi(p), float(self.constraint.gradient(p) @ p_dot)

    # --- stepping ------------------------------------------------------------------------------
    def step(self) -> None:
        """Advance by dt with the held torque (RK4); then evaluate the contact force.

        Raises:
            SimulationDivergedError: the step produced a non-finite q, v, acceleration or force,
                or met a singular constraint (J_c M^-1 J_c^T = 0); time, state, work and the
                pulling count are left as they were before the step (the last finite state).
        """
        errors = (ValueError, ArithmeticError, np.linalg.LinAlgError)
        force = self._guarded_step(self._advance_checked, errors)
        self.pulling = force < 0.0
        self.pulling_steps += int(self.pulling)

    def _advance_checked(self) -> tuple[str, float]:
        """One RK4 step and the contact force it reaches; the failure text ("" if none)."""
        self._advance()
        force = self.contact_force  # the state reached, under the held torque
        if self._cache is not None and not self._cache.schur > 0.0:
            failure = (
                "a singular constraint (J_c M^-1 J_c^T = 0: the end effector cannot move "
                "along the contact normal)"
            )
            return failure, force
        values = (("q", self.q), ("v", self.v), ("contact force", force))
        bad = [name for name, value in values if not np.isfinite(value).all()]
        return (f"non-finite {' and '.join(bad)}" if bad else ""), force

    def _advance(self) -> None:
        """One RK4 step of (q, v) with the held torque."""
        tau = self.torque
        k1v = self._current_terms().solve(tau)[0]
        self._rk4(k1v, lambda q, v: self._terms(q, v).solve(tau)[0])
        self._cache = None

    def _terms(self, q: np.ndarray, v: np.ndarray) -> _Terms:
        """The torque-independent terms of (C.1)-(C.2) at (q, v) (one Pinocchio pass)."""
        model, data, frame = self._model, self._data, self.robot.ee_frame_id
        mass = pin.crba(model, data, q).copy()
        mass[self._lower] = mass.T[self._lower]  # crba fills the upper triangle
        bias = pin.nonLinearEffects(model, data, q, v).copy()  # c_l + g_l [N m]
        pin.forwardKinematics(model, data, q, v, self._zero)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        J_v = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)[:3]
        drift = pin.getFrameClassicalAcceleration(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
        p_dot = J_v @ v
        phi, normal, kappa = self.constraint.evaluate(data.oMf[frame].translation, p_dot)
        J_c = normal @ J_v
        J_c_dot_v = float(normal @ drift.linear) + kappa
        target = -J_c_dot_v - self._k_v * float(normal @ p_dot) - self._k_p * phi
        inverse_mass = np.linalg.inv(mass)
        mobility = inverse_mass @ J_c
        return _Terms(inverse_mass, bias, mobility, float(J_c @ mobility), target, J_c)
