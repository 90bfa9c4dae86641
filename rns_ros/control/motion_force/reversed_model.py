"""The RNS-C control model: the arm re-rooted at its EE link, section 6.1.2, (6.14)-(6.32)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.control.motion_force.task_space import FULL_ROWS, TaskSpace
from rns_ros.core.errors import ConfigError, InputError, ModelError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState
from rns_ros.core.validation import as_vector, positive

#: Default virtual-link mass m_hat [kg] (thesis section 6.2.1: 1e5 kg).
DEFAULT_VIRTUAL_MASS = 1.0e5
#: Default virtual-link inertia per unit mass I_hat / m_hat [m^2] ([A-4.9]: I_hat = m_hat/12).
DEFAULT_INERTIA_PER_MASS = 1.0 / 12.0


def _skew(p: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]])


@dataclass(frozen=True)
class ReversedQuantities:
    """The control model's inertia at one configuration, in REAL joint coordinates.

    Coordinates q_hat_dot = [V_A; theta_dot] with V_A = [v_A; omega_A] the twist of the EE point
    A in world axes (same as V_e) and theta the REAL joints (the thesis' reversed, sign-flipped
    theta_hat of (6.28) is a signed permutation of them; row spaces and projectors carry over).

    Attributes:
        mass: M_hat (6 + n, 6 + n): rows/cols [V_A; theta]; momentum rows = [linear momentum;
            angular momentum about A] in world axes.
        root_mass: M_hat_A (6, 6). coupling: M_hat_Al (6, n).
        reduced_mass: M_red (m, m) = M_hat_A with the non-task root coordinates eliminated
            (eq. 6.24-6.25 generalized); = M_hat_A when all six rows are tasks.
        w: W = M_lred (m, n): M_hat_Al reduced the same way (the planar 2x3 of 6.25; the LWR 6x7).
    """

    mass: np.ndarray
    root_mass: np.ndarray
    coupling: np.ndarray
    reduced_mass: np.ndarray
    w: np.ndarray


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b of two 3-vectors (np.cross's axis handling dominates dynamics() otherwise)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def _cross_motion(twist: np.ndarray, motion: np.ndarray) -> np.ndarray:
    """Spatial motion cross product V x m, Pinocchio order [linear; angular]."""
    v, w = twist[:3], twist[3:]
    return np.concatenate([_cross(w, motion[:3]) + _cross(v, motion[3:]), _cross(w, motion[3:])])


def _cross_force(twist: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Spatial force cross product V x* f, Pinocchio order [force; moment]."""
    v, w = twist[:3], twist[3:]
    return np.concatenate([_cross(w, force[:3]), _cross(w, force[3:]) + _cross(v, force[:3])])


@dataclass(frozen=True)
class ReversedDynamics:
    """The control model's dynamics (6.21) M_hat q_hat_ddot + c_hat + g_hat = Q_hat +
    J_const^T F_B at the real state, real joint coordinates, q_hat = [V_A (6); theta (n)].

    Attributes:
        mass: M_hat (6 + n, 6 + n). bias: c_hat (6 + n,). gravity: g_hat (6 + n,) (B's weight
            included; zero with gravity off).
        constraint: J_const (6, 6 + n), maps q_hat_dot to B's spatial twist at the world origin
            (6.19); its root block is T_hat^T = X_A, its joint block J_B = -J_world.
        constraint_drift: J_const_dot q_hat_dot (6,) of (6.20).
        velocity: q_hat_dot = [J_e theta_dot; theta_dot].
    """

    mass: np.ndarray
    bias: np.ndarray
    gravity: np.ndarray
    constraint: np.ndarray
    constraint_drift: np.ndarray
    velocity: np.ndarray


class ReversedModel:
    """The RNS-C control model (Fig. 6.2 b) of a real fixed-base serial arm, section 6.1.2.

    The real arm is re-rooted at its EE link A (6-DoF virtual joint to the inertial frame); the
    ground becomes the virtual constrained link B at the real base: mass m_hat, rotational inertia
    I_hat about its CoM, length l_hat = 0, i.e. its CoM at the origin of real joint 1.

    Construction (thesis_rest 4.4 generalized to 3-D): with A as root, body k (real link k) moves
    with the twist V_k = X_A V_A - sum_{j > k} S_j theta_dot_j (spatial twists at the world origin;
    S_j the world Jacobian column of joint j, X_A shifts V_A from the EE point to the origin):
    increasing theta_j turns the base side of joint j by -theta_j. B moves with
    X_A V_A - sum_{all j} S_j theta_dot_j. Then M_hat = sum_k J_k^T I_k J_k with I_k the spatial
    inertia of body k in world axes. The real ground body (Pinocchio's universe inertia) is
    replaced by B.

    Args:
        robot: the real :class:`FixedBaseModel` (a serial chain; the EE frame on the last link).
        rows: task rows (non-task root coordinates are eliminated, [A-4.9]-style reduction).
        virtual_mass: m_hat [kg] > 0 (default 1e5).
        virtual_inertia: I_hat [kg m^2]: None -> m_hat/12 E ([A-4.9]), a number -> that times E,
            or an SPD (3, 3) matrix in world axes.

    Raises:
        ConfigError: m_hat not > 0, I_hat not SPD, bad rows. ModelError: not a serial chain or
            the EE is not on the last link.
    """

    def __init__(
        self,
        robot: FixedBaseModel,
        rows=FULL_ROWS,
        *,
        virtual_mass: float = DEFAULT_VIRTUAL_MASS,
        virtual_inertia=None,
    ) -> None:
        self.robot = robot
        self.rows = TaskSpace.free(rows).rows
        self.free_rows = tuple(i for i in range(6) if i not in self.rows)
        self.virtual_mass = positive(virtual_mass, "virtual_mass m_hat", "[kg]")
        if virtual_inertia is None:
            inertia = DEFAULT_INERTIA_PER_MASS * self.virtual_mass * np.eye(3)
        elif np.ndim(virtual_inertia) == 0:
            inertia = positive(virtual_inertia, "virtual_inertia I_hat", "[kg m^2]") * np.eye(3)
        else:
            inertia = np.asarray(virtual_inertia, dtype=float)
            if inertia.shape != (3, 3) or not np.isfinite(inertia).all():
                raise ConfigError(f"virtual_inertia must be a number or (3, 3), got {inertia!r}")
            if not np.allclose(inertia, inertia.T) or np.linalg.eigvalsh(inertia)[0] <= 0.0:
                raise ConfigError(
                    f"virtual_inertia must be symmetric positive definite, got {inertia.tolist()}"
                )
        self.virtual_inertia = inertia
        model = robot.model
        for j in range(1, model.njoints):
            if model.parents[j] != j - 1:
                raise ModelError(f"{robot.name}: RNS-C needs a serial chain (joint {j})")
        if model.frames[robot.ee_frame_id].parentJoint != model.njoints - 1:
            raise ModelError(f"{robot.name}: the EE frame must be on the last link")
        self._data = model.createData()
        base = model.jointPlacements[1].translation.copy()  # l_hat = 0: B's CoM at joint 1
        self._b_inertia = pin.Inertia(self.virtual_mass, base, inertia).matrix()

    def evaluate(self, q) -> ReversedQuantities:
        """M_hat, M_hat_A, M_hat_Al, M_red and W at the real configuration q [rad], (n,)."""
        robot, model, data = self.robot, self.robot.model, self._data
        n = robot.n
        q = as_vector(q, n, "q")
        pin.computeJointJacobians(model, data, q)  # also forward kinematics
        pin.updateFramePlacements(model, data)
        joint_twists = data.J  # (6, n) spatial axes at the world origin
        p_a = data.oMf[robot.ee_frame_id].translation
        shift = np.eye(6)
        shift[:3, 3:] = _skew(p_a)  # V^O = X_A V_A: v_O = v_A + p_A x omega
        mass = np.zeros((6 + n, 6 + n))
        for k in range(n + 1):  # real links 1..n (k = 1..n), then B (k = 0 slot)
            jac = np.zeros((6, 6 + n))
            jac[:, :6] = shift
            if k == 0:
                jac[:, 6:] = -joint_twists
                inertia = self._b_inertia
            else:
                jac[:, 6 + k :] = -joint_twists[:, k:]  # joints k+1..n lie between A and body k
                inertia = data.oMi[k].act(model.inertias[k]).matrix()
            mass += jac.T @ inertia @ jac
        mass = 0.5 * (mass + mass.T)
        root, coupling = mass[:6, :6], mass[:6, 6:]
        rows, free = list(self.rows), list(self.free_rows)
        reduced, w = root[np.ix_(rows, rows)], coupling[rows]
        if free:
            solve = np.linalg.solve(
                root[np.ix_(free, free)], np.hstack([root[free][:, rows], coupling[free]])
            )
            reduced = reduced - root[np.ix_(rows, free)] @ solve[:, : len(rows)]
            w = w - root[np.ix_(rows, free)] @ solve[:, len(rows) :]
        return ReversedQuantities(mass, root, coupling, 0.5 * (reduced + reduced.T), w)

    def dynamics(
        self, state: FixedBaseState, *, momentum_approximation: bool = False
    ) -> ReversedDynamics:
        """The control model's equation of motion (6.21) at the REAL state (B at rest).

        ``momentum_approximation`` replaces the exact C_hat_A (the root rows of c_hat) by the
        approximation C_hat_A ~ M_hat_A_dot V_A + M_hat_Al_dot theta_dot that momentum
        conservation uses (section 6.1.2 warns against it): :meth:`momentum_bias`. The linear
        rows agree exactly; the angular rows (about the moving point A) differ by v_A x p.

        Coordinates q_hat_dot = [V_A; theta_dot] with V_A = J_e theta_dot. With spatial twists
        V_k = J_k q_hat_dot at the world origin and world-axes spatial inertias I_k (Featherstone):
        c_hat = sum_k J_k^T (I_k J_k_dot q_hat_dot + V_k x* I_k V_k), g_hat = -sum_k J_k^T I_k a_g,
        J_k_dot q_hat_dot = [v_A x omega_A; 0] - sum_{j>k} (V_j x S_j) theta_dot_j. The constraint
        of (6.19) is V_B = J_const q_hat_dot = 0 with J_const = [X_A, -J_world] (= [T_hat^T J_B]).
        """
        robot, model, data = self.robot, self.robot.model, self._data
        n = robot.n
        if state.n != n:
            raise InputError(f"state has {state.n} joints, the model {n}")
        pin.computeJointJacobians(model, data, state.q)
        pin.updateFramePlacements(model, data)
        joint_twists = data.J.copy()
        p_a = data.oMf[robot.ee_frame_id].translation.copy()
        v_a = state.jacobian @ state.v  # (6,) [v_A; omega_A] at the EE point
        velocity = np.concatenate([v_a, state.v])
        shift = np.eye(6)
        shift[:3, 3:] = _skew(p_a)
        root_drift = np.concatenate([_cross(v_a[:3], v_a[3:]), np.zeros(3)])
        twist_a = shift @ v_a
        # body twists V_j (j = 1..n), spatial at the origin, of the hat model at the real state
        tail = np.cumsum((joint_twists * state.v)[:, ::-1], axis=1)[:, ::-1]  # sum_{i>=j}
        tail = np.hstack([tail, np.zeros((6, 1))])  # tail[:, j] = sum_{i>j} (0-based j+1..)
        gravity_acc = np.concatenate([np.asarray(model.gravity.linear, float), np.zeros(3)])
        mass = np.zeros((6 + n, 6 + n))
        bias, weight = np.zeros(6 + n), np.zeros(6 + n)
        constraint = drift_b = None
        for k in range(n + 1):
            jac = np.zeros((6, 6 + n))
            jac[:, :6] = shift
            first = 0 if k == 0 else k  # 0-based index of the first joint between k and A
            jac[:, 6 + first :] = -joint_twists[:, first:]
            drift = root_drift.copy()
            for j in range(first, n):  # 0-based joint j, child body twist V = X_A V_A - tail
                body_twist = twist_a - tail[:, j + 1]
                drift -= _cross_motion(body_twist, joint_twists[:, j]) * state.v[j]
            twist = twist_a - tail[:, first]
            inertia = self._b_inertia if k == 0 else data.oMi[k].act(model.inertias[k]).matrix()
            mass += jac.T @ inertia @ jac
            bias += jac.T @ (inertia @ drift + _cross_force(twist, inertia @ twist))
            weight -= jac.T @ (inertia @ gravity_acc)
            if k == 0:
                constraint, drift_b = jac, drift
        if momentum_approximation:
            bias[:6] = self.momentum_bias(state.q, state.v)
        return ReversedDynamics(0.5 * (mass + mass.T), bias, weight, constraint, drift_b, velocity)

    def momentum_bias(self, q, v, step: float = 1e-6) -> np.ndarray:
        """The momentum approximation of C_hat_A: M_hat_A_dot V_A + M_hat_Al_dot theta_dot =
        (M_hat_dot q_hat_dot)[:6] along the real motion (B at rest, V_A = J_e theta_dot), M_hat_dot
        by a central difference of M_hat(q +- h theta_dot), h = ``step`` [s]; (6,) [N, N m].
        """
        step = positive(step, "step", "[s]")
        q = as_vector(q, self.robot.n, "q")
        v = as_vector(v, self.robot.n, "v")
        rate = (self.evaluate(q + step * v).mass - self.evaluate(q - step * v).mass) / (2 * step)
        state = FixedBaseState.compute(self.robot, q, v)
        return rate[:6] @ np.concatenate([state.jacobian @ v, v])

    def w(self, q) -> np.ndarray:
        """W (m, n) at q."""
        return self.evaluate(q).w

    def w_rate(self, q, v, step: float = 1e-6) -> np.ndarray:
        """W_dot = dW/dq theta_dot by a central difference along theta_dot.

        Args:
            step: time step h of W(q +- h theta_dot) [s] (> 0; error O(h^2)).
        """
        step = positive(step, "step", "[s]")
        q = as_vector(q, self.robot.n, "q")
        v = as_vector(v, self.robot.n, "v")
        return (self.w(q + step * v) - self.w(q - step * v)) / (2.0 * step)


__all__ = [
    "DEFAULT_INERTIA_PER_MASS",
    "DEFAULT_VIRTUAL_MASS",
    "ReversedDynamics",
    "ReversedModel",
    "ReversedQuantities",
]


def reduce_to_rows(
    mass: np.ndarray, residual: np.ndarray, rows: list[int], free: list[int]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The root equations of (6.21) on the task ``rows`` once the ``free`` root rows are
    eliminated: M_A V_dot_A + M_Al theta_ddot = residual, the free components of V_dot_A solved
    from their own rows. Returns the reduced residual (m,), M_A on the rows (m, m) and W (m, n).

    ``mass`` is the control model's M_hat (6 + n, 6 + n), ``residual`` the root rows' right-hand
    side (6,).
    """
    root, coupling = mass[:6, :6], mass[:6, 6:]
    reduced_residual, reduced_mass, w = residual[rows], root[np.ix_(rows, rows)], coupling[rows]
    if free:
        solve = np.linalg.solve(
            root[np.ix_(free, free)],
            np.column_stack([residual[free], root[free][:, rows], coupling[free]]),
        )
        cross = root[np.ix_(rows, free)]
        reduced_residual = reduced_residual - cross @ solve[:, 0]
        reduced_mass = reduced_mass - cross @ solve[:, 1 : 1 + len(rows)]
        w = w - cross @ solve[:, 1 + len(rows) :]
    return reduced_residual, reduced_mass, w
