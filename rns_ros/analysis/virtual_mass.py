r"""Thesis chapter 7: the virtual-link mass of RNS-C and the velocity-level null-space term.

The planar 3-DoF arm of section 7.1.1 follows a circular arc without contact, integrated with RK4
(thesis_rest 4.7) under one of the :class:`Variant` joint-acceleration solutions; :class:`ArmRun`
records it, :func:`rms_difference` is RMS[Delta theta] of (7.7)-(7.8) and :func:`mass_sweep` runs
RNS-C for several m_hat. Variants and integration: docs/part2_chapter7.md, "The runs".
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from rns_ros.analysis.arrays import read_only
from rns_ros.control.motion_force.null_space import (
    DEFAULT_DAMPER_GAIN,
    VelocityTermForm,
    damper_term,
    free_floating_acceleration,
    null_space_velocity,
    resolved_acceleration,
    velocity_level_term,
)
from rns_ros.control.motion_force.outer_loops import MotionGains, motion_loop
from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.rnsc import rns_control
from rns_ros.control.motion_force.task_space import PLANAR_ROWS, TaskSpace
from rns_ros.core.errors import ConfigError, InputError, SimulationDivergedError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState
from rns_ros.core.timing import quintic_shape
from rns_ros.core.validation import Choice, as_vector, positive

#: Arc of section 7.1.1 / 6.2.1: centre [m] and radius [m] (thesis_rest 4.4, 4.6).
ARC_CENTER = (1.91, 1.91)
ARC_RADIUS = 0.707
#: [A-4.6]/[A-4.13] [R]: circle angles 180 deg -> 270 deg -> 180 deg (the arc facing the base).
ARC_START_ANGLE = np.pi
ARC_SWEEP = 0.5 * np.pi
#: [A-4.7]/[A-4.13]: duration of one half cycle [s] (the spec's [V] table uses 2.5 s).
HALF_PERIOD = 2.5
#: IK seed of the start configuration [deg] (thesis_rest A-4.6: the thesis "shape").
START_SEED_DEG = (106.4, -45.7, -56.2)
#: Thesis RK4 step [s] (thesis_rest 4.7).
THESIS_STEP = 1e-3
#: Damper gain per unit step: k_d = DAMPER_GAIN_STEP / step [-] (2770 1/s at 1 ms).
DAMPER_GAIN_STEP = DEFAULT_DAMPER_GAIN * THESIS_STEP
#: A run has diverged once max |theta_dot| exceeds this [rad/s] (or a value is not finite).
SPEED_LIMIT = 1.0e3


class Variant(Choice):
    """The joint-acceleration solutions compared in chapter 7."""

    __label__ = "chapter 7 variant"
    RNS = "rns"
    RESOLVED = "resolved"
    DAMPER = "damper"
    VELOCITY = "velocity"
    FREE_FLOATING = "free_floating"


@dataclass(frozen=True)
class ArcPath:
    """EE reference on a circle: phi(t) = start + sweep sigma(t), ``halves`` quintic half cycles
    of ``half_period`` each, alternately forward (sigma = s) and back (sigma = 1 - s); the EE pauses
    instantaneously between them. After the last half the reference is held.

    Attributes:
        center [m] (2,), radius [m] > 0, start_angle [rad], sweep [rad] (non-zero),
        half_period [s] > 0, halves >= 1 (2 = one full cycle, the thesis' 180 -> 270 -> 180 deg).
    """

    center: tuple[float, float] = ARC_CENTER
    radius: float = ARC_RADIUS
    start_angle: float = ARC_START_ANGLE
    sweep: float = ARC_SWEEP
    half_period: float = HALF_PERIOD
    halves: int = 2

    def __post_init__(self) -> None:
        center = as_vector(self.center, 2, "arc center")
        object.__setattr__(self, "center", (float(center[0]), float(center[1])))
        object.__setattr__(self, "radius", positive(self.radius, "arc radius", "[m]"))
        object.__setattr__(self, "half_period", positive(self.half_period, "half_period", "[s]"))
        for name in ("start_angle", "sweep"):
            value = float(getattr(self, name))
            if not np.isfinite(value):
                raise ConfigError(f"{name} must be finite [rad], got {value!r}")
            object.__setattr__(self, name, value)
        if self.sweep == 0.0:
            raise ConfigError("sweep must be non-zero [rad]")
        if int(self.halves) != self.halves or self.halves < 1:
            raise ConfigError(f"halves must be an integer >= 1, got {self.halves!r}")
        object.__setattr__(self, "halves", int(self.halves))

    @property
    def duration(self) -> float:
        """halves * half_period [s]."""
        return self.halves * self.half_period

    def angle(self, t: float) -> tuple[float, float, float]:
        """phi [rad], phi_dot [rad/s], phi_ddot [rad/s^2] at time t [s]."""
        index = min(int(max(t, 0.0) // self.half_period), self.halves - 1)
        s, ds, dds = quintic_shape((t - index * self.half_period) / self.half_period)
        sign = 1.0 if index % 2 == 0 else -1.0
        sigma = s if sign > 0 else 1.0 - s
        scale = self.sweep / self.half_period
        return (
            self.start_angle + self.sweep * sigma,
            sign * scale * ds,
            sign * scale * dds / self.half_period,
        )

    def reference(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """p_des [m], v_des [m/s], a_des [m/s^2] of the EE in x-y, each (2,)."""
        phi, rate, accel = self.angle(t)
        radial = np.array([np.cos(phi), np.sin(phi)])
        tangent = np.array([-np.sin(phi), np.cos(phi)])
        position = np.asarray(self.center) + self.radius * radial
        velocity = self.radius * rate * tangent
        acceleration = self.radius * (accel * tangent - rate**2 * radial)
        return position, velocity, acceleration


@dataclass(frozen=True)
class RunSettings:
    """Integrator and controller settings of one run.

    Attributes:
        step: RK4 step [s] > 0 (thesis 1 ms).
        gains: motion loop (6.33) gains (k_p = 100 1/s^2, k_d = 10 1/s).
        damper_gain: k_d of the ``damper`` variant [1/s]; None -> DAMPER_GAIN_STEP / step
            (2770 at 1 ms).
        velocity_form: form of (7.13) for the ``velocity`` variant (default ``velocity``).
        speed_limit: divergence threshold on max |theta_dot| [rad/s].
    """

    step: float = THESIS_STEP
    gains: MotionGains = field(default_factory=MotionGains)
    damper_gain: float | None = None
    velocity_form: VelocityTermForm = VelocityTermForm.VELOCITY
    speed_limit: float = SPEED_LIMIT

    def __post_init__(self) -> None:
        object.__setattr__(self, "step", positive(self.step, "step", "[s]"))
        if self.damper_gain is not None:
            object.__setattr__(
                self, "damper_gain", positive(self.damper_gain, "damper_gain", "[1/s]")
            )
        object.__setattr__(self, "velocity_form", VelocityTermForm.parse(self.velocity_form))
        object.__setattr__(
            self, "speed_limit", positive(self.speed_limit, "speed_limit", "[rad/s]")
        )
        if not isinstance(self.gains, MotionGains):
            raise ConfigError(f"gains must be MotionGains, got {self.gains!r}")

    @property
    def damper(self) -> float:
        """The damper gain in use [1/s]."""
        return self.damper_gain if self.damper_gain is not None else DAMPER_GAIN_STEP / self.step


@dataclass(frozen=True)
class ArmRun:
    """One chapter-7 run, sampled at every RK4 step (N = steps + 1 samples, n = 3 joints).

    Attributes:
        variant: :class:`Variant`.
        virtual_mass: m_hat [kg] of the control model (for ``resolved`` only used to measure
            ||P_hat_RNS theta_dot||).
        step: RK4 step [s]. damper_gain: k_d [1/s] of the ``damper`` variant, else None.
        t: time [s], (N,). q: joint angles [rad], (N, n). v: theta_dot [rad/s], (N, n).
        ee: EE position in x-y [m], (N, 2). ee_reference: p_des [m], (N, 2).
        null_space_rns: ||P_hat_RNS theta_dot|| [rad/s], (N,). null_space_jacobian:
            ||P_J theta_dot|| [rad/s], (N,).
        path: the :class:`ArcPath` followed.

    All arrays are read-only.
    """

    variant: Variant
    virtual_mass: float
    step: float
    damper_gain: float | None
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    ee: np.ndarray
    ee_reference: np.ndarray
    null_space_rns: np.ndarray
    null_space_jacobian: np.ndarray
    path: ArcPath

    @property
    def joint_speed(self) -> np.ndarray:
        """|theta_dot_i| [rad/s], (N, n)."""
        return np.abs(self.v)

    @property
    def peak_joint_speed(self) -> float:
        """max over joints and time of |theta_dot_i| [rad/s] ([A-4.5])."""
        return float(np.abs(self.v).max())

    @property
    def tracking_error(self) -> np.ndarray:
        """||p - p_des|| [m], (N,)."""
        return np.linalg.norm(self.ee - self.ee_reference, axis=1)

    @property
    def radial_error(self) -> np.ndarray:
        """| |p - c| - R | [m], (N,): distance of the EE from the circle."""
        distance = np.linalg.norm(self.ee - np.asarray(self.path.center), axis=1)
        return np.abs(distance - self.path.radius)

    @property
    def label(self) -> str:
        if self.variant is Variant.RESOLVED:
            return "J+ (resolved acceleration)"
        return f"{self.variant.value}, m_hat = {self.virtual_mass:g} kg"


def arc_start_configuration(
    robot: FixedBaseModel, path: ArcPath | None = None, seed_deg=START_SEED_DEG
) -> np.ndarray:
    """Joint angles [rad] (n,) putting the EE at the start of ``path`` ([A-4.6] [R]).

    Newton iterations with the minimum-norm J^+ step on x-y from ``seed_deg`` [deg].

    Raises:
        InputError: no convergence to 1e-12 m within 50 iterations.
    """
    path = ArcPath() if path is None else path
    q = np.deg2rad(as_vector(seed_deg, robot.n, "seed_deg"))
    target = path.reference(0.0)[0]
    for _ in range(50):
        state = FixedBaseState.compute(robot, q, np.zeros(robot.n))
        error = target - state.ee_position[:2]
        if np.linalg.norm(error) < 1e-12:
            return q
        q = q + np.linalg.lstsq(state.jacobian[list(PLANAR_ROWS)], error, rcond=None)[0]
    raise InputError(f"IK from {list(seed_deg)} deg did not reach the arc start {target.tolist()}")


class _Controller:
    """theta_ddot_ref(t, q, v) of one variant, plus the per-sample record."""

    def __init__(self, robot, variant, virtual_mass, path, settings):
        self.robot, self.variant, self.path, self.settings = robot, variant, path, settings
        self.task = TaskSpace.free(PLANAR_ROWS)
        self.model = ReversedModel(robot, PLANAR_ROWS, virtual_mass=virtual_mass)

    def __call__(self, t, q, v, *, record=False):
        state = FixedBaseState.compute(self.robot, q, v)
        task, model, settings = self.task, self.model, self.settings
        p_des, v_des, a_des = self.path.reference(t)
        error = task.pose_error(state, np.array([p_des[0], p_des[1], 0.0]))
        a_ref = motion_loop(settings.gains, a_des, v_des, task.velocity(state), error)
        w = model.w(q)
        if self.variant is Variant.RESOLVED:
            accel = resolved_acceleration(state, task, a_ref).joint_acceleration
        elif self.variant is Variant.FREE_FLOATING:
            accel = free_floating_acceleration(state, task, model, a_ref).joint_acceleration
        else:
            extra = None
            if self.variant is Variant.DAMPER:
                extra = damper_term(v, settings.damper)
            elif self.variant is Variant.VELOCITY:
                extra = velocity_level_term(state, task, model, form=settings.velocity_form)
            accel = rns_control(
                state, task, model, a_ref, null_space_acceleration=extra, w=w
            ).joint_acceleration
        if not record:
            return accel
        nsv = null_space_velocity(state, task, w)
        return accel, (state.ee_position[:2].copy(), p_des, nsv.rns, nsv.jacobian)


def _check(t, q, v, limit):
    if not (np.isfinite(q).all() and np.isfinite(v).all()):
        raise SimulationDivergedError(f"non-finite state at t = {t:.6g} s (last finite kept)")
    speed = float(np.abs(v).max())
    if speed > limit:
        raise SimulationDivergedError(
            f"max |theta_dot| = {speed:.3g} rad/s > {limit:g} rad/s at t = {t:.6g} s"
        )


def simulate(
    robot: FixedBaseModel,
    variant: Variant | str,
    *,
    virtual_mass: float = 1.0e4,
    path: ArcPath | None = None,
    settings: RunSettings | None = None,
    q0=None,
    v0=None,
    duration: float | None = None,
) -> ArmRun:
    """Integrate one chapter-7 run with RK4 and record it.

    Args:
        robot: the planar 3-DoF :class:`FixedBaseModel` (plane x-y).
        variant: :class:`Variant`.
        virtual_mass: m_hat [kg] > 0 (I_hat = m_hat / 12).
        path: default :class:`ArcPath` () (180 -> 270 -> 180 deg, 2 x 2.5 s).
        settings: default :class:`RunSettings` () (RK4 at 1 ms).
        q0: initial joint angles [rad] (n,); default :func:`arc_start_configuration`.
        v0: initial theta_dot [rad/s] (n,); default rest.
        duration: simulated time [s]; default path.duration. It must be a whole number of steps
            (to 1e-9 relative).

    Raises:
        SimulationDivergedError: a non-finite state or max |theta_dot| > settings.speed_limit
            (the RK4 damper beyond k_d step ~ 2.785 does this).
        ConfigError / InputError: bad settings or initial state.
    """
    variant = Variant.parse(variant)
    path = ArcPath() if path is None else path
    settings = RunSettings() if settings is None else settings
    virtual_mass = positive(virtual_mass, "virtual_mass", "[kg]")
    n = robot.n
    q = arc_start_configuration(robot, path) if q0 is None else as_vector(q0, n, "q0").copy()
    v = np.zeros(n) if v0 is None else as_vector(v0, n, "v0").copy()
    duration = path.duration if duration is None else positive(duration, "duration", "[s]")
    h = settings.step
    steps = round(duration / h)
    if steps < 1 or abs(steps * h - duration) > 1e-9 * max(duration, 1.0):
        raise ConfigError(f"duration {duration} s is not a whole number of {h} s steps")
    control = _Controller(robot, variant, virtual_mass, path, settings)
    t_all = np.arange(steps + 1) * h
    qs, vs = np.empty((steps + 1, n)), np.empty((steps + 1, n))
    ee, ref = np.empty((steps + 1, 2)), np.empty((steps + 1, 2))
    ns_rns, ns_jac = np.empty(steps + 1), np.empty(steps + 1)

    def stage(t, qq, vv):
        _check(t, qq, vv, settings.speed_limit)
        return control(t, qq, vv)

    for k in range(steps + 1):
        t = t_all[k]
        a1, (ee[k], ref[k], ns_rns[k], ns_jac[k]) = control(t, q, v, record=True)
        qs[k], vs[k] = q, v
        if k == steps:
            break
        a2 = stage(t + 0.5 * h, q + 0.5 * h * v, v + 0.5 * h * a1)
        v2 = v + 0.5 * h * a1
        a3 = stage(t + 0.5 * h, q + 0.5 * h * v2, v + 0.5 * h * a2)
        v3 = v + 0.5 * h * a2
        a4 = stage(t + h, q + h * v3, v + h * a3)
        v4 = v + h * a3
        q_next = q + h / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4)
        v_next = v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        _check(t + h, q_next, v_next, settings.speed_limit)
        q, v = q_next, v_next
    return ArmRun(
        variant,
        virtual_mass,
        h,
        settings.damper if variant is Variant.DAMPER else None,
        read_only(t_all),
        read_only(qs),
        read_only(vs),
        read_only(ee),
        read_only(ref),
        read_only(ns_rns),
        read_only(ns_jac),
        path,
    )


def rms_difference(run: ArmRun, reference: ArmRun) -> float:
    """RMS[Delta theta] of (7.7)-(7.8) [rad]: sqrt(1/(t_f - t_0) int ||theta_run - theta_ref||^2
    dt), trapezoidal over the common samples.

    Raises:
        InputError: the runs have different time grids.
    """
    if run.t.shape != reference.t.shape or not np.allclose(run.t, reference.t, atol=1e-12):
        raise InputError("RMS[Delta theta] needs two runs on the same time grid")
    if run.t.size < 2:
        raise InputError("RMS[Delta theta] needs at least two samples")
    squared = np.sum((run.q - reference.q) ** 2, axis=1)
    integral = float(np.sum(0.5 * (squared[1:] + squared[:-1]) * np.diff(run.t)))
    return float(np.sqrt(integral / (run.t[-1] - run.t[0])))


@dataclass(frozen=True)
class MassSweep:
    """RNS-C runs for several virtual masses against one J^+ run (Fig. 7.3).

    Attributes:
        masses: m_hat [kg], (k,), increasing. runs: the RNS-C :class:`ArmRun` per mass (k).
        reference: the J^+ run. rms: RMS[Delta theta] of each run against it [rad], (k,).
    """

    masses: np.ndarray
    runs: tuple[ArmRun, ...]
    reference: ArmRun
    rms: np.ndarray

    def slope(self) -> float:
        """Least-squares slope of log10 RMS against log10 m_hat [-] (the spec's [V]: -1 above
        about 100 kg)."""
        if self.masses.size < 2:
            raise InputError("a slope needs at least two masses")
        return float(np.polyfit(np.log10(self.masses), np.log10(self.rms), 1)[0])


def mass_sweep(
    robot: FixedBaseModel,
    masses: Iterable[float],
    *,
    path: ArcPath | None = None,
    settings: RunSettings | None = None,
    reference: ArmRun | None = None,
    runs: dict[float, ArmRun] | None = None,
) -> MassSweep:
    """RNS-C (theta_ddot_a = 0) for each m_hat and RMS[Delta theta] against J^+.

    Args:
        masses: m_hat values [kg] > 0, distinct (sorted here).
        reference: an existing J^+ run on the same grid (else simulated).
        runs: already simulated RNS-C runs keyed by m_hat (reused, e.g. those of Fig. 7.1).
    """
    masses = np.array(sorted({positive(m, "virtual mass", "[kg]") for m in masses}))
    if masses.size == 0:
        raise ConfigError("mass_sweep needs at least one virtual mass")
    runs = {} if runs is None else dict(runs)
    if reference is None:
        reference = simulate(robot, Variant.RESOLVED, path=path, settings=settings)
    out = []
    for mass in masses:
        run = runs.get(float(mass))
        if run is None:
            run = simulate(robot, Variant.RNS, virtual_mass=mass, path=path, settings=settings)
        out.append(run)
    rms = read_only([rms_difference(run, reference) for run in out])
    return MassSweep(read_only(masses), tuple(out), reference, rms)


__all__ = [
    "ARC_CENTER",
    "ARC_RADIUS",
    "DAMPER_GAIN_STEP",
    "HALF_PERIOD",
    "SPEED_LIMIT",
    "START_SEED_DEG",
    "THESIS_STEP",
    "ArcPath",
    "ArmRun",
    "MassSweep",
    "RunSettings",
    "Variant",
    "arc_start_configuration",
    "mass_sweep",
    "rms_difference",
    "simulate",
]
