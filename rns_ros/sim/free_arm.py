r"""The free fixed-base arm of thesis Part II (no contact), and the joint brake of the simulator.

:class:`FreeArmSimulator` integrates eq. (6.2) without the contact force,

    M_l(q) q_ddot + c_l(q, q_dot) + g_l(q) = tau,                                    (F.1)

with RK4 under a held torque, behind the interface of :class:`rns_ros.sim.contact.
ContactSimulator` (contact force and wrenches 0). :class:`JointBrake` is the torque the robot's
own brakes apply when its controller has gone silent, gravity held and joints damped:

    tau_brake = g_l(q) - B(q) q_dot,   B = d M_l (M_l + dt d I)^-1                 (F.2)

(d [N m s/rad] the brake damping; why implicit: docs/part2_ros.md, "Stale or invalid torque").
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError
from rns_ros.core.fixed_base import FixedBaseModel
from rns_ros.core.validation import as_vector, positive
from rns_ros.sim.torque_driven import TorqueDrivenArm


class FreeArmSimulator(TorqueDrivenArm):
    """Torque-driven fixed-base arm without contact, eq. (F.1), RK4 at a fixed step.

    Args:
        robot: the fixed-base arm (its ``gravity`` flag decides g_l).
        initial_q: start configuration [rad] (n,); initial_v: start velocity [rad/s] (n,),
            default zero.
        dt: RK4 step [s], in (0, 0.1].
        clip_torque: clip every commanded torque to the URDF effort limits (limits <= 0 or
            non-finite count as absent).

    Attributes:
        time [s]; q [rad], v [rad/s]: (n,); torque: held over the next step [N m] (n,); work: the
        work of the held torques since reset, sum of tau . (q_{k+1} - q_k) [J]; constraint: None;
        pulling: always False; pulling_steps: always 0 (no contact to pull on).

    Raises:
        ConfigError: bad dt or a model with nq != nv. InputError: bad q/v.
    """

    constraint = None
    _KIND = "free-arm simulation"

    def __init__(
        self,
        robot: FixedBaseModel,
        *,
        initial_q,
        initial_v=None,
        dt: float = 1e-3,
        clip_torque: bool = False,
    ) -> None:
        if robot.model.nq != robot.model.nv:
            raise ConfigError(f"{robot.name}: nq != nv; the free-arm simulator needs 1-DoF joints")
        self._init_arm(robot, dt, clip_torque)
        self._init_start(initial_q, initial_v)
        self.reset()

    # --- state ---------------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to the initial state, zero torque, zero work."""
        self._reset_arm()
        self.pulling = False
        self.pulling_steps = 0

    @property
    def contact_force(self) -> float:
        """0 [N]: no environment."""
        return 0.0

    @property
    def acceleration(self) -> np.ndarray:
        """q_ddot = M_l^-1 (tau - c_l - g_l) [rad/s^2] (n,) at the current state, (F.1)."""
        return self._acceleration(self.q, self.v)

    def contact_normal(self) -> np.ndarray:
        """Zeros (3,): no environment."""
        return np.zeros(3)

    def ee_position(self) -> np.ndarray:
        """EE point [m] (3,), world."""
        pin.framesForwardKinematics(self._model, self._data, self.q)
        return self._data.oMf[self.robot.ee_frame_id].translation.copy()

    def contact_wrench(self) -> np.ndarray:
        """Zeros (6,) [N, N m]: nothing to push on."""
        return np.zeros(6)

    def wrist_wrench(self) -> np.ndarray:
        """Zeros (6,) [N, N m]: the EE touches nothing."""
        return np.zeros(6)

    def constraint_error(self) -> tuple[float, float]:
        """(0, 0): no constraint."""
        return 0.0, 0.0

    # --- stepping ------------------------------------------------------------------------------
    def step(self) -> None:
        """Advance by dt with the held torque (RK4 of (F.1)).

        Raises:
            SimulationDivergedError: a non-finite q or v (or a failing ABA); time, state and work
                are left as they were before the step (the last finite state).
        """
        self._guarded_step(self._advance, (ValueError, ArithmeticError, RuntimeError))

    def _acceleration(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return pin.aba(self._model, self._data, q, v, self.torque).copy()

    def _advance(self) -> tuple[str, None]:
        """One RK4 step; the failure text of a non-finite result ("" if none)."""
        self._rk4(self._acceleration(self.q, self.v), self._acceleration)
        bad = [name for name in ("q", "v") if not np.isfinite(getattr(self, name)).all()]
        return (f"non-finite {' and '.join(bad)}" if bad else ""), None


class JointBrake:
    """The robot's joint brakes with gravity hold, eq. (F.2): what a simulator applies when no
    valid torque command arrives.

    Args:
        robot: the fixed-base arm (its ``gravity`` flag decides the held g_l).
        damping: brake damping d [N m s/rad], > 0.
        dt: the simulator step [s] over which the brake torque is held, > 0.

    Raises:
        ConfigError: damping or dt not finite and > 0.
    """

    def __init__(self, robot: FixedBaseModel, damping: float, dt: float) -> None:
        self.robot = robot
        self.damping = positive(damping, "brake damping", "[N m s/rad]")
        self.dt = positive(dt, "dt", "[s]")
        self._model = robot.model
        self._data = robot.model.createData()
        self._lower = np.tril_indices(robot.n, -1)
        self._identity = np.eye(robot.n)

    def gain(self, q) -> np.ndarray:
        """B(q) = d M_l (M_l + dt d I)^-1 [N m s/rad] (n, n), symmetric positive definite."""
        q = as_vector(q, self.robot.n, "q")
        mass = pin.crba(self._model, self._data, q).copy()
        mass[self._lower] = mass.T[self._lower]  # crba fills the upper triangle
        d = self.damping
        # M (M + h I)^-1 = I - h (M + h I)^-1, h = dt d: symmetric by construction
        h = self.dt * d
        gain = d * (self._identity - h * np.linalg.inv(mass + h * self._identity))
        return 0.5 * (gain + gain.T)

    def torque(self, q, v) -> np.ndarray:
        """tau_brake = g_l(q) - B(q) q_dot [N m] (n,), eq. (F.2)."""
        q = as_vector(q, self.robot.n, "q")
        v = as_vector(v, self.robot.n, "v")
        hold = (
            pin.computeGeneralizedGravity(self._model, self._data, q).copy()
            if self.robot.gravity
            else np.zeros(self.robot.n)
        )
        return hold - self.gain(q) @ v

    def contraction(self, q) -> float:
        """Largest per-step speed-retention factor of the unconstrained brake, max over the
        modes of M_l of m / (m + dt d), in (0, 1)."""
        q = as_vector(q, self.robot.n, "q")
        mass = pin.crba(self._model, self._data, q).copy()
        mass[self._lower] = mass.T[self._lower]
        largest = float(np.linalg.eigvalsh(mass).max())
        return largest / (largest + self.dt * self.damping)


__all__ = ["FreeArmSimulator", "JointBrake"]
