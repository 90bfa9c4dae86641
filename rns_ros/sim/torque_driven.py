"""What the torque-driven fixed-base arm simulators share: the held torque (zero-order hold),
energies, snapshots, the RK4 step and the restore on divergence."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError, SimulationDivergedError
from rns_ros.core.fixed_base import FixedBaseModel
from rns_ros.core.validation import as_vector, positive

#: Largest simulator step [s].
MAX_DT = 0.1


@dataclass(frozen=True)
class ContactState:
    """Snapshot after a step (copies; safe to keep).

    Attributes:
        time [s]; q [rad], v [rad/s], torque [N m]: (n,); contact_force lambda [N] (>= 0
        pushing); phi [m], phi_dot [m/s]: the constraint error.
    """

    time: float
    q: np.ndarray
    v: np.ndarray
    torque: np.ndarray
    contact_force: float
    phi: float
    phi_dot: float


class TorqueDrivenArm:
    """Base of the fixed-base arm simulators: joint state (q, v), the torque held over each
    RK4 step, the work it does, and its effort limits.

    Subclasses provide ``contact_force`` [N], ``constraint_error()`` -> (phi [m], phi_dot
    [m/s]) and their step, built from :meth:`_rk4` inside :meth:`_guarded_step`.
    """

    #: What a step changes (restored when it diverges); each step assigns new objects.
    _STEP_STATE: tuple[str, ...] = ("time", "q", "v", "work")
    #: The simulation's name in the divergence message.
    _KIND = "simulation"

    def _init_arm(self, robot: FixedBaseModel, dt: float, clip_torque: bool) -> None:
        """Robot, step dt [s] in (0, MAX_DT], torque clipping and the effort limits (limits
        <= 0 or non-finite count as absent)."""
        self.robot = robot
        self.dt = positive(dt, "dt", "[s]")
        if self.dt > MAX_DT:
            raise ConfigError(f"dt must be in (0, {MAX_DT:g}] s, got {dt!r}")
        self.clip_torque = bool(clip_torque)
        limits = np.array(robot.effort_limits, dtype=float)
        limits[~(np.isfinite(limits) & (limits > 0.0))] = np.inf
        self.effort_limits = limits
        self._model = robot.model
        self._data = robot.model.createData()  # own scratch: robot.data stays the caller's

    def _init_start(self, initial_q, initial_v) -> None:
        """The start state q [rad], v [rad/s] (n,) (v default zero)."""
        n = self.robot.n
        self._initial_q = as_vector(initial_q, n, "initial_q").copy()
        self._initial_v = (
            np.zeros(n) if initial_v is None else as_vector(initial_v, n, "initial_v").copy()
        )

    def _reset_arm(self) -> None:
        """Back to the initial state, zero torque, zero work."""
        self.time = 0.0
        self.q = self._initial_q.copy()
        self.v = self._initial_v.copy()
        self.torque = np.zeros(self.robot.n)
        self.work = 0.0

    def set_torque(self, tau) -> None:
        """Joint torques [N m] (n,), finite, held over the following steps (zero-order hold).

        With ``clip_torque`` each component is clipped to its URDF effort limit.

        Raises:
            InputError: wrong shape or non-finite.
        """
        tau = as_vector(tau, self.robot.n, "tau").copy()
        if self.clip_torque:
            tau = np.clip(tau, -self.effort_limits, self.effort_limits)
        self.torque = tau

    @property
    def torque_clipped(self) -> np.ndarray:
        """Joints whose held torque sits at its effort limit (bool (n,))."""
        return np.abs(self.torque) >= self.effort_limits

    def kinetic_energy(self) -> float:
        """1/2 q_dot^T M_l q_dot [J]."""
        return float(pin.computeKineticEnergy(self._model, self._data, self.q, self.v))

    def potential_energy(self) -> float:
        """Gravitational potential energy [J] (0 with gravity off)."""
        return float(pin.computePotentialEnergy(self._model, self._data, self.q))

    def power(self) -> float:
        """Joint power tau . q_dot [W] of the held torque at the current velocity."""
        return float(self.torque @ self.v)

    def snapshot(self) -> ContactState:
        """The current state with its contact force and constraint error."""
        phi, phi_dot = self.constraint_error()
        return ContactState(
            time=self.time,
            q=self.q.copy(),
            v=self.v.copy(),
            torque=self.torque.copy(),
            contact_force=self.contact_force,
            phi=phi,
            phi_dot=phi_dot,
        )

    def _rk4(self, k1v: np.ndarray, acceleration: Callable) -> None:
        """One classical RK4 step of (q, v) under the held torque: ``k1v`` = q_ddot at (q, v),
        ``acceleration(q, v)`` at the other stages; the work tau . (q_{k+1} - q_k) [J]."""
        q, v, dt = self.q, self.v, self.dt
        v2 = v + 0.5 * dt * k1v
        k2v = acceleration(q + 0.5 * dt * v, v2)
        v3 = v + 0.5 * dt * k2v
        k3v = acceleration(q + 0.5 * dt * v2, v3)
        v4 = v + dt * k3v
        k4v = acceleration(q + dt * v3, v4)
        new_q = q + dt / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4)
        self.v = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        self.work = self.work + float(self.torque @ (new_q - q))
        self.q = new_q
        self.time = self.time + dt

    def _guarded_step(self, advance: Callable, errors: tuple[type[Exception], ...]):
        """Run ``advance()`` -> (failure text, result) with floating-point warnings off; on a
        failure or one of ``errors`` restore the state before it and raise.

        Raises:
            SimulationDivergedError: naming the step's start time and the failure.
        """
        before = {name: getattr(self, name) for name in self._STEP_STATE}
        failure, result = "", None
        try:
            with np.errstate(all="ignore"):  # reported below, as SimulationDivergedError
                failure, result = advance()
        except errors as exc:
            failure = f"{type(exc).__name__}: {exc}"
        if failure:
            start = before["time"]
            for name, value in before.items():
                setattr(self, name, value)
            raise SimulationDivergedError(
                f"{self._KIND} diverged in the step from t = {start:.6g} s: {failure}; kept the "
                "last finite state"
            )
        return result


__all__ = ["MAX_DT", "ContactState", "TorqueDrivenArm"]
