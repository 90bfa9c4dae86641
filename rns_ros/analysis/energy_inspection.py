r"""Energy of the camera inspection: reactionless motion vs conventional control plus reaction
wheels (thesis §5.2.1-5.2.2, Figs. 5.4-5.5).

Per control period: the kinetic energy split into arm (Lambda_m) and wheel (Lambda_r) parts
(:class:`EnergySeries`), the running costs C_max (5.12) and C_sum (5.13), the wheel torque (5.14);
:func:`random_conditions` draws the thesis' random start configurations and axes (A-3.6).
Bookkeeping and sampling: docs/chapter5_inspection.md.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from rns_ros.analysis.closed_loop import ClosedLoopResult, PeriodSample, run_scenario
from rns_ros.control.controller import TwistFrame
from rns_ros.control.scenario import Scenario, TimeScaling
from rns_ros.core.energy import WHEEL_INERTIA, EnergyCost, energy_metric
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import positive

#: ETS-VII reaction-wheel torque limit quoted by the thesis (§5.2.2) [N m].
ETS_VII_WHEEL_TORQUE_LIMIT = 0.1
#: Reject a random initial configuration when sigma_min(J-bar_omega_e) is below this [-]
#: (thesis_rest A-3.6).
SIGMA_MIN_THRESHOLD = 0.1
#: Seed of the random conditions 2-5 (numpy ``default_rng``).
CONDITION_SEED = 5
#: Rotation of every inspection condition: pi rad over 20 s, quintic (thesis_rest A-3.7).
CONDITION_ANGLE = np.pi
CONDITION_DURATION = 20.0
#: Default controller rate [Hz] and RK4 step [s] of the inspection runs.
CONTROL_RATE = 100.0
SIMULATION_STEP = 1e-3


# --------------------------------------------------------------------------- costs and torque


@dataclass(frozen=True)
class Costs:
    """Running costs of one energy series.

    Attributes:
        c_max: C_max = 1/2 max_t theta_dot^T Lambda theta_dot [J], eq. (5.12).
        c_sum: C_sum = 1/2 integral theta_dot^T Lambda theta_dot dt [J s], eq. (5.13)
            (trapezoidal between the first and the last sample).
    """

    c_max: float
    c_sum: float


def running_costs(t, energy) -> Costs:
    """C_max (5.12) and C_sum (5.13) of the kinetic energy ``energy`` [J] (N,) sampled at
    non-decreasing times ``t`` [s] (N,), through :class:`rns_ros.core.energy.EnergyCost`."""
    t = np.asarray(t, dtype=float)
    energy = np.asarray(energy, dtype=float)
    if t.shape != energy.shape or t.ndim != 1:
        raise ValueError(f"t and energy must be 1-D of one length, got {t.shape}, {energy.shape}")
    cost = EnergyCost()
    for time, value in zip(t, energy, strict=True):
        cost.add(float(time), float(value))
    return Costs(cost.c_max, cost.c_sum)


@dataclass(frozen=True)
class WheelTorque:
    """Reaction-wheel torque of eq. (5.14), tau_r = -d/dt (M~_omega_m theta_dot).

    Attributes:
        t: times of the torque samples [s], shape (N - 1,): midway between momentum samples.
        dt: the interval each torque sample spans [s], shape (N - 1,).
        torque: tau_r in world axes (the held base's axes) [N m], shape (N - 1, 3).
    """

    t: np.ndarray
    dt: np.ndarray
    torque: np.ndarray

    @property
    def magnitude(self) -> np.ndarray:
        """|tau_r| [N m], shape (N - 1,)."""
        return np.linalg.norm(self.torque, axis=1)

    def peak(self) -> float:
        """max_t |tau_r| [N m] (0 for an empty series)."""
        return float(self.magnitude.max(initial=0.0))

    def peak_component(self) -> float:
        """max_t max_i |tau_r,i| [N m]: the largest single-wheel torque (one wheel per axis)."""
        return float(np.abs(self.torque).max(initial=0.0))

    def time_above(self, limit: float = ETS_VII_WHEEL_TORQUE_LIMIT, *, per_wheel=False) -> float:
        """Total time [s] during which |tau_r| (or, ``per_wheel``, any |tau_r,i|) exceeds
        ``limit`` [N m]: the sum of the intervals ``dt`` of the samples above it."""
        value = np.abs(self.torque).max(axis=1) if per_wheel else self.magnitude
        return float(self.dt[value > limit].sum())


def wheel_torque(t, momentum) -> WheelTorque:
    """Eq. (5.14) by finite differences: tau_r = -(h_{k+1} - h_k) / (t_{k+1} - t_k).

    Args:
        t: sample times [s], shape (N,), strictly increasing.
        momentum: h = M~_omega_m theta_dot at those times, world axes [kg m^2/s], shape (N, 3).

    Returns:
        the torque at the midpoints, (N - 1) samples; by construction
        sum_k tau_k dt_k = -(h_{N-1} - h_0): the wheels take up the change of coupling momentum.
    """
    t = np.asarray(t, dtype=float)
    momentum = np.asarray(momentum, dtype=float)
    if t.ndim != 1 or momentum.shape != (t.shape[0], 3):
        raise ValueError(f"need t (N,) and momentum (N, 3), got {t.shape}, {momentum.shape}")
    dt = np.diff(t)
    if np.any(dt <= 0.0):
        raise ValueError("sample times must increase strictly")
    torque = -np.diff(momentum, axis=0) / dt[:, None]
    return WheelTorque(t=0.5 * (t[1:] + t[:-1]), dt=dt, torque=torque)


# --------------------------------------------------------------------------- energy series


@dataclass(frozen=True)
class EnergySeries:
    """Kinetic energy of one closed-loop run, one row per control period (N periods, n joints).

    Attributes:
        t: middle of each period [s], shape (N,).
        period: length of each period [s], shape (N,).
        theta: joint angles at the middle of each period [rad], shape (N, n).
        theta_dot: joint velocity held over each period [rad/s], shape (N, n).
        arm_energy: 1/2 theta_dot^T Lambda_m theta_dot, Lambda_m = M~_m [J], shape (N,) (5.3).
        wheel_energy: 1/2 theta_dot^T Lambda_r theta_dot, Lambda_r = M~_omega_m^T M~_omega_m / I_r
            [J], shape (N,) (5.3): what wheels absorbing the coupling momentum would hold.
        coupling_momentum: h = M~_omega_m theta_dot, world axes (base held at identity) [kg m^2/s],
            shape (N, 3).
        wheel_inertia: I_r [kg m^2].
    """

    t: np.ndarray
    period: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray
    arm_energy: np.ndarray
    wheel_energy: np.ndarray
    coupling_momentum: np.ndarray
    wheel_inertia: float

    @property
    def total_energy(self) -> np.ndarray:
        """1/2 theta_dot^T Lambda theta_dot [J], shape (N,) (5.3)."""
        return self.arm_energy + self.wheel_energy

    @property
    def wheel_rate(self) -> np.ndarray:
        """phi_dot = -M~_omega_r^{-1} M~_omega_m theta_dot = -h / I_r [rad/s], shape (N, 3)
        (eq. 5.2 with M~_omega_r = I_r E: three orthogonal wheels along the base axes)."""
        return -self.coupling_momentum / self.wheel_inertia

    def costs(self, part: str = "total") -> Costs:
        """C_max, C_sum (5.12-5.13) of ``part``: "total" (Lambda), "arm" (Lambda_m) or
        "wheels" (Lambda_r)."""
        energy = {
            "total": self.total_energy,
            "arm": self.arm_energy,
            "wheels": self.wheel_energy,
        }[part]
        return running_costs(self.t, energy)

    def wheel_torque(self) -> WheelTorque:
        """tau_r of eq. (5.14) along the run (see :func:`wheel_torque`) [N m]."""
        return wheel_torque(self.t, self.coupling_momentum)


def energy_series(
    robot: FreeFloatingModel,
    samples: Sequence[PeriodSample],
    wheel_inertia: float = WHEEL_INERTIA,
) -> EnergySeries:
    """The :class:`EnergySeries` of a kinematic closed-loop run from its ``on_period`` samples.

    Each period is evaluated at its middle configuration theta_end - T/2 theta_dot (exact in
    kinematic mode, where theta_dot is held) with the base at the origin, identity attitude
    (held by the wheels; see the module docstring).
    """
    wheel_inertia = positive(wheel_inertia, "wheel_inertia", "[kg m^2]")
    rows = list(samples)
    if not rows:
        raise ValueError("no samples")
    n = robot.n
    size = len(rows)
    theta = np.empty((size, n))
    theta_dot = np.empty((size, n))
    arm = np.empty(size)
    wheels = np.empty(size)
    momentum = np.empty((size, 3))
    for k, sample in enumerate(rows):
        rate = np.asarray(sample.step.joint_velocity, dtype=float)
        middle = np.asarray(sample.state.theta, dtype=float) - 0.5 * sample.period * rate
        state = FreeFloatingState.compute(robot, robot.configuration(middle))
        metric = energy_metric(state, wheel_inertia)
        theta[k], theta_dot[k] = middle, rate
        # quadratic forms of PSD matrices: clip rounding (~1e-24 J) below zero
        arm[k], wheels[k] = (max(part, 0.0) for part in metric.energy(rate))
        momentum[k] = state.coupling_angular_momentum_matrix @ rate
    period = np.array([s.period for s in rows])
    return EnergySeries(
        t=np.array([s.t for s in rows]) + 0.5 * period,
        period=period,
        theta=theta,
        theta_dot=theta_dot,
        arm_energy=arm,
        wheel_energy=wheels,
        coupling_momentum=momentum,
        wheel_inertia=wheel_inertia,
    )


@dataclass(frozen=True)
class EnergyRun:
    """One closed-loop inspection run and its energy.

    Attributes:
        method: controller method ("dls": reactionless, eq. 4.5; "conventional": eqs. 4.7-4.8).
        result: the closed loop's summary (base deviation, camera error, speed scaling...).
        series: the energy time series.
    """

    method: str
    result: ClosedLoopResult
    series: EnergySeries


def energy_run(
    robot: FreeFloatingModel,
    scenario: Scenario,
    method: str,
    *,
    rate: float = CONTROL_RATE,
    simulation_step: float = SIMULATION_STEP,
    wheel_inertia: float = WHEEL_INERTIA,
) -> EnergyRun:
    """Run ``scenario`` with ``method`` in the kinematic closed loop
    (:func:`rns_ros.analysis.closed_loop.run_scenario`, midpoint hold) and cost it.

    Args:
        rate: controller rate [Hz]; simulation_step: RK4 step [s] (1 / rate a multiple of it).
        wheel_inertia: I_r [kg m^2].
    """
    samples: list[PeriodSample] = []
    result = run_scenario(
        robot,
        scenario,
        method=method,
        rate=rate,
        simulation_step=simulation_step,
        on_period=samples.append,
    )
    return EnergyRun(str(method), result, energy_series(robot, samples, wheel_inertia))


# --------------------------------------------------------------------------- conditions


@dataclass(frozen=True)
class InspectionCondition:
    """One inspection condition of Fig. 5.5: where the arm starts and how the camera turns.

    Attributes:
        label: e.g. "condition 2".
        scenario: the inspection scenario (initial angles [rad] (n,), world axis (3,), angle
            [rad], duration [s], quintic).
        sigma_min: sigma_min of the restricted Jacobian J-bar_omega_e at the start [-].
        draws: configurations drawn to get this one (1 + rejected ones); 0 for a fixed one.
    """

    label: str
    scenario: Scenario
    sigma_min: float
    draws: int = 0


def restricted_sigma_min(state: FreeFloatingState) -> float:
    """Smallest singular value of J-bar_omega_e = J_omega_e P_RNS (eq. 4.5) [-]."""
    return float(np.linalg.svd(state.restricted_jacobian, compute_uv=False)[-1])


def fixed_condition(
    robot: FreeFloatingModel, scenario: Scenario, label: str
) -> InspectionCondition:
    """Wrap a given scenario (condition 1: the Fig. 4.3(a) satellite observation)."""
    state = FreeFloatingState.compute(robot, robot.configuration(scenario.initial_theta))
    return InspectionCondition(label, scenario, restricted_sigma_min(state), 0)


def random_conditions(
    robot: FreeFloatingModel,
    count: int,
    *,
    seed: int = CONDITION_SEED,
    sigma_threshold: float = SIGMA_MIN_THRESHOLD,
    first_index: int = 2,
    max_draws: int = 10_000,
) -> list[InspectionCondition]:
    """Seeded random inspection conditions (thesis_rest A-3.6).

    With ``rng = numpy.random.default_rng(seed)``, each candidate draws, in this order,
    theta0 ~ U(lower, upper) per joint (the URDF position limits, (n,) [rad]) and an axis
    a = g / |g|, g ~ N(0, E_3) (uniform on the unit sphere). A candidate is rejected when a joint is
    outside its limits or sigma_min(J-bar_omega_e(theta0)) < ``sigma_threshold``. No collision
    check is made (the arm may intersect the base). The command is
    omega_ref(t) = pi * s_dot(t) * a, world axes, quintic s over 20 s: a rotation by pi rad about
    a (the reading of the existing inspection scenarios, thesis_rest A-3.7).

    Args:
        count: conditions to return (>= 0).
        seed: numpy ``default_rng`` seed; the same seed gives the same conditions.
        sigma_threshold: rejection threshold on sigma_min [-].
        first_index: number of the first label ("condition {first_index}").
        max_draws: give up after this many candidates in total.

    Raises:
        RuntimeError: ``max_draws`` candidates did not give ``count`` conditions.
    """
    rng = np.random.default_rng(seed)
    lower, upper = robot.lower_limits, robot.upper_limits
    conditions: list[InspectionCondition] = []
    draws = total = 0
    while len(conditions) < count:
        if total >= max_draws:
            raise RuntimeError(f"{max_draws} draws gave only {len(conditions)} conditions")
        total += 1
        draws += 1
        theta = rng.uniform(lower, upper)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        if np.any(theta < lower) or np.any(theta > upper):
            continue
        state = FreeFloatingState.compute(robot, robot.configuration(theta))
        sigma = restricted_sigma_min(state)
        if sigma < sigma_threshold:
            continue
        index = first_index + len(conditions)
        scenario = Scenario(
            name=f"condition_{index}",
            initial_theta=theta,
            frame=TwistFrame.WORLD,
            axis=axis,
            angle=CONDITION_ANGLE,
            duration=CONDITION_DURATION,
            time_scaling=TimeScaling.QUINTIC,
            description=f"random inspection condition (seed {seed})",
        )
        conditions.append(InspectionCondition(f"condition {index}", scenario, sigma, draws))
        draws = 0
    return conditions


@dataclass(frozen=True)
class ConditionComparison:
    """Reactionless vs conventional + wheels for one condition.

    Attributes:
        condition: the condition.
        reactionless: the DLS run (eq. 4.5).
        conventional: the wrist-only inverse Jacobian run (4.7-4.8), costed with wheels.
        ratio: {"c_max": ..., "c_sum": ...} conventional + wheels over reactionless [-].
    """

    condition: InspectionCondition
    reactionless: EnergyRun
    conventional: EnergyRun
    ratio: dict = field(default_factory=dict)


def compare(
    robot: FreeFloatingModel,
    condition: InspectionCondition,
    *,
    rate: float = CONTROL_RATE,
    simulation_step: float = SIMULATION_STEP,
    wheel_inertia: float = WHEEL_INERTIA,
) -> ConditionComparison:
    """Run ``condition`` with both controllers and form the cost ratios (total Lambda each)."""
    runs = [
        energy_run(
            robot,
            condition.scenario,
            method,
            rate=rate,
            simulation_step=simulation_step,
            wheel_inertia=wheel_inertia,
        )
        for method in ("dls", "conventional")
    ]
    ratio = cost_ratio(runs[1].series.costs(), runs[0].series.costs())
    return ConditionComparison(condition, runs[0], runs[1], ratio)


def cost_ratio(numerator: Costs, denominator: Costs) -> dict:
    """{"c_max": ..., "c_sum": ...}: numerator / denominator [-] (inf over a zero cost)."""

    def divide(a: float, b: float) -> float:
        return a / b if b > 0.0 else float("inf")

    return {
        "c_max": divide(numerator.c_max, denominator.c_max),
        "c_sum": divide(numerator.c_sum, denominator.c_sum),
    }


def geometric_mean(values: Iterable[float]) -> float:
    """exp(mean(log v)) of positive values [-]."""
    values = np.asarray(list(values), dtype=float)
    return float(np.exp(np.mean(np.log(values))))
