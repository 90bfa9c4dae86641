r"""Kinetic energy of the arm and of reaction wheels that would cancel its reaction (thesis ch. 5).

With three orthogonal reaction wheels of spin inertia I_r on the base and the base held still
(omega_b = 0), the kinetic energy of a joint motion theta_dot is (eqs. 5.2-5.3)

    T = 1/2 theta_dot^T M~_m theta_dot  +  1/2 phi_dot^T M~_r phi_dot,
    phi_dot = -M~_omega_r^{-1} M~_omega_m theta_dot   (the wheels absorb the coupling momentum)
      = 1/2 theta_dot^T Lambda theta_dot,   Lambda = Lambda_m + Lambda_r,
    Lambda_m = M~_m,   Lambda_r = M~_omega_m^T M~_omega_m / I_r      (M~_r = M~_omega_r = I_r E).

M~_m = M_m - M_vm^T M_v^{-1} M_vm is the joint-space inertia with the base's linear motion folded
in (zero linear momentum; the thesis uses it without defining it, thesis_rest section 0). A
reactionless motion (M~_omega_m theta_dot = 0) has Lambda_r theta_dot = 0, so it costs only the arm
term; the cheapest unit joint speed of all costs sigma_min(Lambda) / 2 (eq. 5.4), and the ratio of
the two is C_ratio (eq. 5.5). Running costs of a motion: C_max (5.12), C_sum (5.13).

Eq. (5.11) is a schematic of Lambda_r (it drops the cross-link terms and the base translation):
Lambda_r is computed from its definition above.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rns_ros.core.inverses import kernel_basis
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import as_vector, positive

#: Spin inertia of one reaction wheel [kg m^2] (thesis section 5.2).
WHEEL_INERTIA = 0.11


def tilde_manipulator_inertia(state: FreeFloatingState) -> np.ndarray:
    """M~_m = M_m - M_vm^T M_v^{-1} M_vm [kg m^2], shape (n, n): the arm inertia seen with the
    base free to translate and zero linear momentum (M_v = m_C E, eq. 2.9)."""
    m_v = state.inertia_base[:3, :3]
    m_vm = state.coupling_inertia[:3]
    return state.manipulator_inertia - m_vm.T @ np.linalg.solve(m_v, m_vm)


class EnergyMetric(NamedTuple):
    """Lambda of eq. (5.3) split into its two parts, each (n, n) [kg m^2], symmetric.

    Attributes:
        manipulator: Lambda_m = M~_m, the arm's own kinetic-energy metric.
        wheels: Lambda_r = M~_omega_m^T M~_omega_m / I_r, the wheels cancelling the reaction.
    """

    manipulator: np.ndarray
    wheels: np.ndarray

    @property
    def total(self) -> np.ndarray:
        """Lambda = Lambda_m + Lambda_r, shape (n, n)."""
        return self.manipulator + self.wheels

    def energy(self, theta_dot) -> tuple[float, float]:
        """(arm, wheel) kinetic energy [J] of joint velocity theta_dot [rad/s] (n,), eq. (5.3)."""
        theta_dot = as_vector(theta_dot, self.manipulator.shape[0], "theta_dot")
        return (
            0.5 * float(theta_dot @ self.manipulator @ theta_dot),
            0.5 * float(theta_dot @ self.wheels @ theta_dot),
        )


def energy_metric(
    state: FreeFloatingState, wheel_inertia: float = WHEEL_INERTIA, joints=None
) -> EnergyMetric:
    """Lambda_m and Lambda_r of eq. (5.3) at ``state``.

    Args:
        state: the free-floating state.
        wheel_inertia: I_r [kg m^2], > 0.
        joints: indices of the joints that move (a subchain, e.g. the positioning joints of
            section 5.2's 4-DoF case); None: all n. The others are held (a rigid payload).

    Returns:
        the metric restricted to ``joints``, each part (k, k).
    """
    wheel_inertia = positive(wheel_inertia, "wheel_inertia", "[kg m^2]")
    index = np.arange(state.n) if joints is None else np.asarray(joints, dtype=int)
    tilde_m = tilde_manipulator_inertia(state)[np.ix_(index, index)]
    coupling = state.coupling_angular_momentum_matrix[:, index]
    return EnergyMetric(
        manipulator=0.5 * (tilde_m + tilde_m.T),
        wheels=coupling.T @ coupling / wheel_inertia,
    )


def c_ratio(metric: EnergyMetric, coupling: np.ndarray, rank_tolerance: float = 1e-9) -> float:
    """C_ratio = T_RNS / T_min of eq. (5.5) for unit joint speed [-], >= 1.

    T_min = sigma_min(Lambda) / 2 (eq. 5.4). T_RNS is the cheapest reactionless unit motion:
    sigma_min(N^T Lambda_m N) / 2 with N an orthonormal basis of ker(M~_omega_m) (for the thesis'
    cases, a 1-D kernel, that is n^T M~_m n with n the unit null vector). Where M~_omega_m
    vanishes, Lambda = Lambda_m and C_ratio = 1.

    Args:
        metric: Lambda_m, Lambda_r, (k, k).
        coupling: M~_omega_m of the same joints [kg m^2], shape (3, k).
        rank_tolerance: relative singular-value threshold for the kernel [-].

    Raises:
        ValueError: M~_omega_m has no kernel (no reactionless motion exists).
    """
    kernel, _, _ = kernel_basis(np.asarray(coupling, dtype=float), rank_tolerance)
    if kernel.shape[1] == 0:
        raise ValueError("M~_omega_m has full column rank: no reactionless motion")
    t_rns = np.linalg.eigvalsh(kernel.T @ metric.manipulator @ kernel)[0]
    t_min = np.linalg.eigvalsh(metric.total)[0]
    return float(t_rns / t_min)


class KineticEnergy(NamedTuple):
    """Kinetic energy of the system split as in eq. (5.1) [J].

    Attributes:
        base: 1/2 V_b^T M_b V_b, the base with the wheels locked in it.
        arm: 1/2 theta_dot^T M_m theta_dot.
        coupling: V_b^T M_bm theta_dot, the base-arm cross term.
        wheels: the wheels' spin relative to the base, 1/2 I_r |phi_dot|^2 + I_r phi_dot .
            omega_b (the M~_r and M~_omega_r terms of eq. 5.1 with both = I_r E); 0 without.
        total: the sum, = Pinocchio's kinetic energy of the locked system + the wheel term.
    """

    base: float
    arm: float
    coupling: float
    wheels: float
    total: float


def kinetic_energy(
    state: FreeFloatingState,
    base_twist,
    theta_dot,
    wheel_speeds=None,
    wheel_inertia: float = WHEEL_INERTIA,
) -> KineticEnergy:
    """Eq. (5.1) at ``state``.

    Args:
        state: the state (inertia blocks M_b, M_bm, M_m of eq. 2.7, thesis coordinates).
        base_twist: V_b = [v_b; omega_b] in world axes [m/s, rad/s], shape (6,).
        theta_dot: joint velocities [rad/s], shape (n,).
        wheel_speeds: spin rates of the three wheels relative to the base about the base x, y,
            z axes [rad/s], shape (3,); None: no wheels.
        wheel_inertia: I_r [kg m^2].
    """
    twist = as_vector(base_twist, 6, "base twist")
    theta_dot = as_vector(theta_dot, state.n, "theta_dot")
    base = 0.5 * float(twist @ state.inertia_base @ twist)
    arm = 0.5 * float(theta_dot @ state.manipulator_inertia @ theta_dot)
    coupling = float(twist @ state.coupling_inertia @ theta_dot)
    wheels = 0.0
    if wheel_speeds is not None:
        speeds = as_vector(wheel_speeds, 3, "wheel speeds")
        omega_base_axes = state.base_rotation.T @ twist[3:]
        inertia = positive(wheel_inertia, "wheel_inertia", "[kg m^2]")
        wheels = 0.5 * inertia * float(speeds @ speeds) + inertia * float(speeds @ omega_base_axes)
    return KineticEnergy(base, arm, coupling, wheels, base + arm + coupling + wheels)


class EnergyCost:
    """Running costs of a motion, eqs. (5.12)-(5.13): C_max = max_t T(t) [J] and
    C_sum = integral of T dt [J s] (trapezoidal), with T = 1/2 theta_dot^T Lambda theta_dot.

    Feed one sample per step with :meth:`add` (time [s], energy [J]); times must not decrease.
    """

    def __init__(self) -> None:
        self.peak = 0.0
        self.integral = 0.0
        self._last: tuple[float, float] | None = None

    def add(self, time: float, energy: float) -> None:
        energy = float(energy)
        if not np.isfinite(energy) or energy < 0.0:
            raise ValueError(f"kinetic energy must be finite and >= 0 J, got {energy}")
        if self._last is not None:
            last_time, last_energy = self._last
            if time < last_time:
                raise ValueError(f"time went back from {last_time} s to {time} s")
            self.integral += 0.5 * (energy + last_energy) * (time - last_time)
        self.peak = max(self.peak, energy)
        self._last = (float(time), energy)

    @property
    def c_max(self) -> float:
        """C_max = 1/2 max theta_dot^T Lambda theta_dot [J] (5.12)."""
        return self.peak

    @property
    def c_sum(self) -> float:
        """C_sum = 1/2 integral theta_dot^T Lambda theta_dot dt [J s] (5.13)."""
        return self.integral
