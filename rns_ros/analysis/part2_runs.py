r"""Thesis chapter 6 closed loops: the two motion/force scenarios and a torque-level runner.

Two scenarios (``shared/spec/thesis_rest.md`` sections 4.4-4.5, choices documented in
``docs/part2.md``, "Chapter 6 runs"):

* :class:`ArcScenario` (section 6.2.1, Figs. 6.3-6.4): the planar 3-DoF arm slides its end
  effector (EE) along the rigid cylinder of radius 0.707 m about (1.91, 1.91) m, circle angle
  180 deg -> 270 deg -> 180 deg (the arc facing the base, 225 +- 45 deg, [A-4.6]) in two quintic
  half cycles of :data:`PLANAR_HALF_CYCLE` each, stopping at the half cycle; it pushes toward the
  cylinder axis with a force rising along a quintic from 0 to 10 N over the first 1 s.
* :class:`WallScenario` (section 6.2.2, Figs. 6.7-6.8): the 7-DoF LWR4-class arm from
  [20, -20, 0, 100, 0, 10, 0] deg pushes 10 N into a wall through its start flange point, normal
  to the start flange z axis, and strokes back and forth along a horizontal line in the wall
  (2.5 s per stroke, 4 strokes), orientation held.

:func:`run_closed_loop` runs one controller on one scenario: every control period (= the
simulator step ``dt``, 1 ms by default) it computes the :class:`FixedBaseState`, the task
references, the motion loop (6.33) and the force loop (6.34) with the contact force measured at
that instant, the controller torque (RNS-C closed form, OS-C literal or OS-C kinematic) and holds
that torque over the next :class:`~rns_ros.sim.contact.ContactSimulator` RK4 step (zero-order
hold). The result is an immutable :class:`ClosedLoopRun`.

Errors and signs: position error = p_des - p, force error = f_des - f, f the normal force the EE
exerts on the environment ([A-4.1], the simulator's lambda). The contact frame {E} has x_E along
the motion (planar: direction of increasing circle angle; wall: the stroke direction), z_E along
the contact normal into the environment, y_E = z_E x x_E.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from rns_ros.control.motion_force.osc import OscVariant, os_control
from rns_ros.control.motion_force.outer_loops import (
    ForceGains,
    MotionGains,
    force_loop,
    motion_loop,
)
from rns_ros.control.motion_force.projectors import kernel_projector
from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.rnsc import rns_control
from rns_ros.control.motion_force.task_space import FULL_ROWS, PLANAR_ROWS, TaskSpace, contact_frame
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState, load_fixed_base_model
from rns_ros.core.validation import Choice, positive
from rns_ros.resources import config_dir
from rns_ros.sim.contact import (
    ArcConstraint,
    ContactSimulator,
    PlaneConstraint,
    project_onto_constraint,
)

#: Half-cycle duration T_half of the planar arc [s] ([A-4.7]): chosen so that the RNS-C peak
#: joint speed is about the thesis' 0.73 rad/s (see docs/part2.md, "Chapter 6 runs").
PLANAR_HALF_CYCLE = 1.6
#: Stroke duration of the wall task [s] (thesis section 6.2.2: 2.5 s) and strokes ([A-4.11]).
WALL_STROKE, WALL_STROKES = 2.5, 4
#: Desired contact force [N] and its quintic ramp time [s] (both scenarios).
FORCE, FORCE_RAMP = 10.0, 1.0
#: Thesis x of the wall-task target [0.24, 0.43, 0.43] m: the stroke length is |0.24 - x0|.
WALL_TARGET_X = 0.24
#: Control model's virtual-link mass m_hat [kg] (thesis section 6.2.1; I_hat = m_hat / 12).
VIRTUAL_MASS = 1.0e5
#: Default control period = simulator step [s] (thesis_rest 4.7: RK4 at 1 ms).
CONTROL_PERIOD = 1e-3
#: Thesis gains (section 6.2.1): k_p = 100 1/s^2, k_d = 10 1/s (6.33); k_f = 5 (6.34). Frozen.
THESIS_MOTION_GAINS, THESIS_FORCE_GAINS = MotionGains(k_p=100.0, k_d=10.0), ForceGains(k_f=5.0)


class Controller(Choice):
    """The controllers compared in chapter 6 (labels as in the JSON of ``fig6.*``)."""

    __label__ = "controller"
    RNS_C = "RNS-C"
    OSC = "OS-C"
    OSC_KINEMATIC = "OS-C-kinematic"


class ForceMeasurement(Choice):
    """The contact force f in the force loop (6.34) f_ref = f_des + k_f (f_des - f).

    * ``same-instant`` (default): f is the force at the same instant. Against a rigid surface the
      contact force answers the torque at once: every controller's torque is tau_0 + J^T n f_ref
      and gives f = lambda_0 + f_ref, lambda_0 being the force of tau_0 alone (read from the
      simulator at the current state). (6.34) is solved with it:
      f_ref = (f_des + k_f (f_des - lambda_0)) / (1 + k_f), i.e. f - f_des = lambda_0 / (1 + k_f).
    * ``previous-step``: f is the force at the current state under the torque held over the
      previous period (a sampled sensor, one period late). With a rigid contact the error then
      obeys e_{k+1} = -k_f e_k: unstable for k_f > 1 (the thesis' k_f = 5 diverges).
    """

    __label__ = "force measurement"
    SAME_INSTANT = "same-instant"
    PREVIOUS_STEP = "previous-step"


#: Report order.
CONTROLLERS = (Controller.RNS_C, Controller.OSC, Controller.OSC_KINEMATIC)


def quintic_profile(t: float, duration: float) -> tuple[float, float, float]:
    """Rest-to-rest quintic s = 10 tau^3 - 15 tau^4 + 6 tau^5, tau = t / T clamped to [0, 1].

    Returns:
        (s [-], s_dot [1/s], s_ddot [1/s^2]).
    """
    tau = min(max(t / duration, 0.0), 1.0)
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    s_dot = 30.0 * tau**2 * (1.0 - tau) ** 2 / duration
    s_ddot = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / duration**2
    return s, s_dot, s_ddot


def back_and_forth(t: float, segment: float, segments: int) -> tuple[float, float, float]:
    """Progress sigma in [0, 1] along a path run forth, back, forth... in ``segments`` quintic
    segments of ``segment`` [s] each, stopping at rest between them; held after the last one.

    Returns:
        (sigma, sigma_dot [1/s], sigma_ddot [1/s^2]).
    """
    index = min(int(t // segment), segments - 1) if t > 0.0 else 0
    s, s_dot, s_ddot = quintic_profile(t - index * segment, segment)
    if index % 2:
        return 1.0 - s, -s_dot, -s_ddot
    return s, s_dot, s_ddot


def force_profile(t: float, force: float, ramp: float) -> float:
    """f_des(t) [N]: a quintic from 0 to ``force`` over ``ramp`` [s], then constant."""
    return force * quintic_profile(t, ramp)[0]


@dataclass(frozen=True)
class Reference:
    """Desired EE motion at one instant (world axes).

    Attributes:
        position [m], velocity [m/s], acceleration [m/s^2]: (3,).
        rotation: desired EE orientation world <- EE (3, 3), or None (orientation free).
    """

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    rotation: np.ndarray | None = None


@dataclass(frozen=True)
class Setup:
    """A scenario resolved on its arm: what :func:`run_closed_loop` needs.

    Attributes:
        name: "planar_arc" or "lwr_wall".
        robot: the fixed-base arm; constraint: the rigid surface.
        initial_q: start configuration on the surface [rad] (n,).
        rows: task rows of J_e; duration: full run [s].
        reference: t -> :class:`Reference`; force: t -> f_des [N].
        tangent: EE point (3,) -> the unit motion direction x_E of {E} (3,).
        normal_feedforward: command the constraint-consistent normal acceleration -kappa
            (the centripetal term on a curved surface, [A-4.8]).
        description: the resolved geometry, JSON-able (start/end points, normal, ...).
    """

    name: str
    robot: FixedBaseModel
    constraint: ArcConstraint | PlaneConstraint
    initial_q: np.ndarray
    rows: tuple[int, ...]
    duration: float
    reference: Callable[[float], Reference] = field(repr=False)
    force: Callable[[float], float] = field(repr=False)
    tangent: Callable[[np.ndarray], np.ndarray] = field(repr=False)
    normal_feedforward: bool = False
    description: dict = field(default_factory=dict)


@functools.cache
def _load(config: str) -> FixedBaseModel:
    return load_fixed_base_model(config_dir() / config)


def _count(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ConfigError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def _nonnegative(value, name: str, unit: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number {unit}, got {value!r}") from None
    if not math.isfinite(number) or number < 0.0:
        raise ConfigError(f"{name} must be finite and >= 0 {unit}, got {value!r}")
    return number


def _finite_tuple(value, size: int, name: str) -> tuple[float, ...]:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be {size} numbers, got {value!r}") from None
    if array.shape != (size,) or not np.isfinite(array).all():
        raise ConfigError(f"{name} must be {size} finite numbers, got {value!r}")
    return tuple(float(x) for x in array)


def _point_ik(robot: FixedBaseModel, q, target, *, iterations: int = 50) -> np.ndarray:
    """Minimum-norm Gauss-Newton on the EE position (x, y rows) from ``q`` to ``target``."""
    q = np.asarray(q, dtype=float).copy()
    for _ in range(iterations):
        state = FixedBaseState.compute(robot, q, np.zeros(robot.n))
        error = (np.asarray(target) - state.ee_position)[:2]
        if np.linalg.norm(error) < 1e-14:
            return q
        q = q + np.linalg.lstsq(state.jacobian[:2], error, rcond=None)[0]
    raise ConfigError(f"the arc start point {np.asarray(target).tolist()} is out of reach")


@dataclass(frozen=True)
class ArcScenario:
    """Planar 3-DoF arm on the cylinder (thesis section 6.2.1, thesis_rest 4.4 [R] choices).

    Attributes:
        center: cylinder axis point (x, y) [m]; radius [m] (> 0).
        start_angle_deg, end_angle_deg: circle angles of the arc ends [deg] (the EE starts at the
            first), different.
        half_cycle: T_half [s] (> 0) of each quintic half cycle; half_cycles: how many (>= 1;
            2 = one full cycle start -> end -> start, stopping at rest in between).
        seed_deg: configuration [deg] (3,) moved by minimum-norm IK to put the EE exactly at the
            arc start.
        force: desired push [N] (>= 0) reached by a quintic over ``force_ramp`` [s] (> 0).
        centripetal: command the constraint-consistent normal acceleration |v_t|^2 / R toward
            the axis ([A-4.8]); False: the thesis S V_dot (the constraint supplies it).
        model: model YAML in config/.

    Raises:
        ConfigError: any value out of range (at construction).
    """

    center: tuple[float, float] = (1.91, 1.91)
    radius: float = 0.707
    start_angle_deg: float = 180.0
    end_angle_deg: float = 270.0
    half_cycle: float = PLANAR_HALF_CYCLE
    half_cycles: int = 2
    seed_deg: tuple[float, float, float] = (106.4, -45.7, -56.2)
    force: float = FORCE
    force_ramp: float = FORCE_RAMP
    centripetal: bool = True
    model: str = "planar_3dof.yaml"

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _finite_tuple(self.center, 2, "arc center"))
        object.__setattr__(self, "radius", positive(self.radius, "arc radius", "[m]"))
        start, end = _finite_tuple(
            (self.start_angle_deg, self.end_angle_deg), 2, "arc start/end angles"
        )
        if start == end:
            raise ConfigError(f"arc start and end angles must differ, both are {start} deg")
        object.__setattr__(self, "half_cycle", positive(self.half_cycle, "half_cycle", "[s]"))
        object.__setattr__(self, "half_cycles", _count(self.half_cycles, "half_cycles"))
        object.__setattr__(self, "seed_deg", _finite_tuple(self.seed_deg, 3, "seed_deg"))
        object.__setattr__(self, "force", _nonnegative(self.force, "force", "[N]"))
        object.__setattr__(self, "force_ramp", positive(self.force_ramp, "force_ramp", "[s]"))

    @property
    def duration(self) -> float:
        """Whole motion [s]."""
        return self.half_cycle * self.half_cycles

    def setup(self) -> Setup:
        robot = _load(self.model)
        center = np.array([*self.center, 0.0])
        radius = self.radius
        constraint = ArcConstraint(center, radius)
        start, end = np.radians([self.start_angle_deg, self.end_angle_deg])

        def circle(angle: float) -> np.ndarray:
            return np.array([math.cos(angle), math.sin(angle), 0.0])

        def reference(t: float) -> Reference:
            sigma, sigma_dot, sigma_ddot = back_and_forth(t, self.half_cycle, self.half_cycles)
            angle = start + sigma * (end - start)
            rate, accel = sigma_dot * (end - start), sigma_ddot * (end - start)
            radial, tangent = circle(angle), circle(angle + 0.5 * math.pi)
            return Reference(
                center + radius * radial,
                radius * rate * tangent,
                radius * accel * tangent - radius * rate**2 * radial,
            )

        def tangent(p: np.ndarray) -> np.ndarray:
            d = p - center
            t = np.array([-d[1], d[0], 0.0])  # direction of increasing circle angle
            return np.sign(end - start) * t / np.linalg.norm(t)

        q0 = _point_ik(robot, np.radians(self.seed_deg), center + radius * circle(start))
        q0, _ = project_onto_constraint(robot, constraint, q0)
        return Setup(
            "planar_arc",
            robot,
            constraint,
            q0,
            PLANAR_ROWS,
            self.duration,
            reference,
            functools.partial(force_profile, force=self.force, ramp=self.force_ramp),
            tangent,
            self.centripetal,
            {
                "initial_joint_positions_deg": np.degrees(q0).round(4).tolist(),
                "start_point_m": (center + radius * circle(start))[:2].round(6).tolist(),
                "end_point_m": (center + radius * circle(end))[:2].round(6).tolist(),
                "arc_center_m": list(self.center),
                "arc_radius_m": radius,
                "arc_angles_deg": [self.start_angle_deg, self.end_angle_deg],
                "half_cycle_s": self.half_cycle,
                "half_cycles": self.half_cycles,
                "centripetal_feedforward": self.centripetal,
            },
        )


@dataclass(frozen=True)
class WallScenario:
    """7-DoF LWR4-class arm against a wall (thesis section 6.2.2, thesis_rest 4.5).

    Attributes:
        initial_deg: start configuration [deg] (7,) (thesis [20, -20, 0, 100, 0, 10, 0]).
        normal: wall normal into the wall, world (3,); None: the start flange z axis (the tool
            pushes along its axis; the wall passes through the start flange point).
        direction: stroke direction, world (3,), projected into the wall plane; None: the
            default tangent of ``contact_frame`` (z_world x normal, horizontal in the wall).
        length: stroke length [m] (> 0); None: |0.24 - x0| with x0 the start flange x.
        stroke: duration of one stroke [s] (> 0); strokes: how many (>= 1), back and forth.
        force: push [N] (>= 0), quintic ramp over ``force_ramp`` [s] (> 0).
        model: model YAML in config/.

    Raises:
        ConfigError: any value out of range (at construction; a direction along the normal at
            :meth:`setup`).
    """

    initial_deg: tuple[float, ...] = (20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0)
    normal: tuple[float, float, float] | None = None
    direction: tuple[float, float, float] | None = None
    length: float | None = None
    stroke: float = WALL_STROKE
    strokes: int = WALL_STROKES
    force: float = FORCE
    force_ramp: float = FORCE_RAMP
    model: str = "lwr_7dof.yaml"

    def __post_init__(self) -> None:
        object.__setattr__(self, "initial_deg", _finite_tuple(self.initial_deg, 7, "initial_deg"))
        for name in ("normal", "direction"):
            value = getattr(self, name)
            if value is not None:
                vector = _finite_tuple(value, 3, f"wall {name}")
                if np.linalg.norm(vector) < 1e-9:
                    raise ConfigError(f"wall {name} must be non-zero, got {value!r}")
                object.__setattr__(self, name, vector)
        if self.length is not None:
            object.__setattr__(self, "length", positive(self.length, "stroke length", "[m]"))
        object.__setattr__(self, "stroke", positive(self.stroke, "stroke", "[s]"))
        object.__setattr__(self, "strokes", _count(self.strokes, "strokes"))
        object.__setattr__(self, "force", _nonnegative(self.force, "force", "[N]"))
        object.__setattr__(self, "force_ramp", positive(self.force_ramp, "force_ramp", "[s]"))

    @property
    def duration(self) -> float:
        """Whole motion [s]."""
        return self.stroke * self.strokes

    def setup(self) -> Setup:
        robot = _load(self.model)
        q0 = np.radians(self.initial_deg)
        start = FixedBaseState.compute(robot, q0, np.zeros(robot.n))
        p0, rotation = start.ee_position, start.ee_rotation
        normal = rotation[:, 2] if self.normal is None else np.asarray(self.normal)
        normal = normal / np.linalg.norm(normal)
        try:
            frame = contact_frame(normal, self.direction)
        except InputError as exc:
            raise ConfigError(f"wall stroke direction: {exc}") from None
        direction = frame[:, 0]
        length = abs(WALL_TARGET_X - p0[0]) if self.length is None else self.length
        constraint = PlaneConstraint(p0, normal)

        def reference(t: float) -> Reference:
            sigma, sigma_dot, sigma_ddot = back_and_forth(t, self.stroke, self.strokes)
            return Reference(
                p0 + sigma * length * direction,
                sigma_dot * length * direction,
                sigma_ddot * length * direction,
                rotation,
            )

        return Setup(
            "lwr_wall",
            robot,
            constraint,
            q0,
            FULL_ROWS,
            self.duration,
            reference,
            functools.partial(force_profile, force=self.force, ramp=self.force_ramp),
            lambda p: direction,
            False,
            {
                "initial_joint_positions_deg": list(self.initial_deg),
                "start_point_m": p0.round(6).tolist(),
                "end_point_m": (p0 + length * direction).round(6).tolist(),
                "wall_normal": normal.round(6).tolist(),
                "stroke_direction": direction.round(6).tolist(),
                "stroke_length_m": round(float(length), 6),
                "stroke_s": self.stroke,
                "strokes": self.strokes,
            },
        )


def _readonly(array) -> np.ndarray:
    array = np.array(array, dtype=float)
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class ClosedLoopRun:
    """One controller on one scenario: k = N + 1 samples at t_k = k dt (k = 0..N), arrays
    read-only. Sample k holds the state at t_k, the torque computed there (held over
    [t_k, t_k + dt]) and the contact force the controller measured at t_k (the state reached,
    under the torque held over the previous period; 0 at t = 0).

    Attributes:
        scenario: "planar_arc" or "lwr_wall"; controller: :class:`Controller` value.
        dt: control period = simulator step [s].
        t: (k,) [s]. q [rad], v [rad/s], tau [N m]: (k, n).
        position_error: p_des - p in {E} axes [m], (k, 3): x_E along the motion, y_E the second
            in-plane direction, z_E the normal (the surface holds it; for the arc it is the
            chord between the desired and actual points).
        orientation_error: log(R_des R^T) in world axes [rad], (k, r); r = 3 when the
            orientation is a task (wall), 0 when it is free (planar).
        force_desired: f_des (k,) [N]; force_reference: f_ref of (6.34) (k,) [N].
        contact_force: lambda over [t_k, t_k + dt) at t_k, under the torque of sample k (k,) [N];
        force_error: force_desired - contact_force (k,) [N].
        joint_speed: max_i |v_i| (k,) [rad/s] ([A-4.5]).
        null_space_velocity: ||P_hat_RNS v|| (k,) [rad/s] (7.14, m_hat of the run);
        null_space_velocity_jacobian: ||P_J v|| (k,) [rad/s].
        phi: constraint error (k,) [m] (> 0: penetration).
        pulling_steps: simulator steps that ended with the bilateral contact pulling.
        wall_time: seconds the run took.
        description: the resolved scenario (:attr:`Setup.description`).
    """

    scenario: str
    controller: str
    dt: float
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    force_desired: np.ndarray
    force_reference: np.ndarray
    contact_force: np.ndarray
    force_error: np.ndarray
    joint_speed: np.ndarray
    null_space_velocity: np.ndarray
    null_space_velocity_jacobian: np.ndarray
    phi: np.ndarray
    pulling_steps: int
    wall_time: float
    description: dict = field(default_factory=dict, compare=False)

    @property
    def tangential_error(self) -> np.ndarray:
        """In-plane position error ||(e_x, e_y)|| in {E} [m], (k,)."""
        return np.hypot(self.position_error[:, 0], self.position_error[:, 1])

    @property
    def peak_joint_speed(self) -> float:
        """max over joints and time of |theta_dot_i| [rad/s] ([A-4.5])."""
        return float(self.joint_speed.max())

    @property
    def max_position_error(self) -> float:
        """max over time of the in-plane position error [m]."""
        return float(self.tangential_error.max())

    @property
    def max_orientation_error(self) -> float:
        """max over time of ||orientation error|| [rad] (0 when the orientation is free)."""
        if self.orientation_error.shape[1] == 0:
            return 0.0
        return float(np.linalg.norm(self.orientation_error, axis=1).max())

    @property
    def max_force_error(self) -> float:
        """max over time of |f_des - f| [N]."""
        return float(np.abs(self.force_error).max())

    @property
    def max_constraint_error(self) -> float:
        """max |phi| [m]."""
        return float(np.abs(self.phi).max())

    def summary(self) -> dict:
        """The scalar results, JSON-able."""
        return {
            "peak_joint_speed_rad_s": self.peak_joint_speed,
            "max_position_error_m": self.max_position_error,
            "max_orientation_error_rad": self.max_orientation_error,
            "max_force_error_N": self.max_force_error,
            "final_force_error_N": float(self.force_error[-1]),
            "final_position_error_m": float(self.tangential_error[-1]),
            "max_null_space_velocity_rad_s": float(self.null_space_velocity.max()),
            "max_constraint_error_m": self.max_constraint_error,
            "pulling_steps": self.pulling_steps,
            "wall_time_s": self.wall_time,
        }


def run_closed_loop(
    scenario: ArcScenario | WallScenario | Setup,
    controller: Controller | str,
    *,
    dt: float = CONTROL_PERIOD,
    duration: float | None = None,
    motion_gains: MotionGains = THESIS_MOTION_GAINS,
    force_gains: ForceGains = THESIS_FORCE_GAINS,
    virtual_mass: float = VIRTUAL_MASS,
    force_measurement: ForceMeasurement | str = ForceMeasurement.SAME_INSTANT,
) -> ClosedLoopRun:
    """Run ``controller`` on ``scenario`` (see the module docstring for one period).

    Args:
        scenario: :class:`ArcScenario`, :class:`WallScenario` or a resolved :class:`Setup`.
        controller: :class:`Controller` or its label ("RNS-C", "OS-C", "OS-C-kinematic").
        dt: control period = RK4 step [s] (> 0, <= 0.1).
        duration: simulated time [s]; default the scenario's; rounded to whole periods.
        motion_gains, force_gains: (6.33)-(6.34), thesis k_p = 100, k_d = 10, k_f = 5.
        virtual_mass: m_hat [kg] of the RNS-C control model (and of P_hat_RNS in the log).
        force_measurement: which contact force f the force loop (6.34) sees
            (:class:`ForceMeasurement`).

    Raises:
        ConfigError: bad controller, dt, duration or scenario. SimulationDivergedError: the
            closed loop blew up (the message names the step). InputError: a task singularity
            (OS-C: J M^-1 J^T singular).
    """
    controller = Controller.parse(controller)
    measurement = ForceMeasurement.parse(force_measurement)
    setup = scenario if isinstance(scenario, Setup) else scenario.setup()
    dt = positive(dt, "dt", "[s]")
    duration = setup.duration if duration is None else positive(duration, "duration", "[s]")
    steps = max(1, round(duration / dt))
    robot, constraint = setup.robot, setup.constraint
    rows = setup.rows
    reversed_model = ReversedModel(robot, rows, virtual_mass=virtual_mass)
    sim = ContactSimulator(robot, constraint, initial_q=setup.initial_q, dt=dt)
    orientation_rows = [i for i, r in enumerate(rows) if r >= 3]
    n, k = robot.n, steps + 1
    log = {
        name: np.zeros((k, width))
        for name, width in (
            ("q", n),
            ("v", n),
            ("tau", n),
            ("position_error", 3),
            ("orientation_error", len(orientation_rows)),
        )
    }
    scalars = {
        name: np.zeros(k)
        for name in (
            "force_desired",
            "force_reference",
            "contact_force",
            "rns",
            "jacobian",
            "phi",
        )
    }
    fixed_task = None
    if isinstance(constraint, PlaneConstraint):
        fixed_task = TaskSpace.from_contact(rows, constraint.normal, setup.tangent(None))
    variant = {
        Controller.OSC: OscVariant.LITERAL,
        Controller.OSC_KINEMATIC: OscVariant.KINEMATIC,
    }.get(controller)
    started = time.perf_counter()
    for i in range(k):
        t = i * dt
        state = FixedBaseState.compute(robot, sim.q, sim.v)
        p = state.ee_position
        p_dot = state.jacobian[:3] @ state.v
        normal = constraint.gradient(p)
        task = fixed_task or TaskSpace.from_contact(rows, normal, setup.tangent(p))
        ref = setup.reference(t)
        full_accel = np.concatenate([ref.acceleration, np.zeros(3)])
        full_vel = np.concatenate([ref.velocity, np.zeros(3)])
        error = task.pose_error(state, ref.position, ref.rotation)
        a_ref = motion_loop(
            motion_gains,
            full_accel[list(rows)],
            full_vel[list(rows)],
            task.velocity(state),
            error,
        )
        f_des = setup.force(t)
        a_n = None
        if setup.normal_feedforward:
            a_n = [-constraint.curvature(p, p_dot)]  # n . p_ddot keeping phi_ddot = 0
        w = reversed_model.w(state.q)
        if variant is None:
            command = rns_control(state, task, reversed_model, a_ref, normal_acceleration=a_n, w=w)
        else:
            command = os_control(state, task, a_ref, variant=variant, normal_acceleration=a_n)
        # the force term of every controller is J^T N f_ref, added to the motion torque tau_0
        push = task.jacobian(state).T @ task.force_wrench([1.0])
        if measurement is ForceMeasurement.SAME_INSTANT:
            sim.set_torque(command.torque)
            motion_force = sim.contact_force  # lambda_0: the force tau_0 alone produces now
            # (6.34) with f = lambda_0 + f_ref (rigid contact: f answers the torque at once)
            f_ref = (f_des + force_gains.k_f * (f_des - motion_force)) / (1.0 + force_gains.k_f)
        else:
            f_ref = force_loop(force_gains, [f_des], [sim.contact_force])[0]
        torque = command.torque + push * f_ref
        sim.set_torque(torque)
        log["q"][i], log["v"][i], log["tau"][i] = state.q, state.v, torque
        log["position_error"][i] = task.contact_rotation.T @ (ref.position - p)
        log["orientation_error"][i] = error[orientation_rows]
        scalars["force_desired"][i], scalars["contact_force"][i] = f_des, sim.contact_force
        scalars["force_reference"][i] = f_ref
        scalars["rns"][i] = np.linalg.norm(kernel_projector(w) @ state.v)
        scalars["jacobian"][i] = np.linalg.norm(kernel_projector(task.jacobian(state)) @ state.v)
        scalars["phi"][i] = constraint.phi(p)
        if i < steps:
            sim.step()
    wall = time.perf_counter() - started
    return ClosedLoopRun(
        scenario=setup.name,
        controller=controller.value,
        dt=dt,
        t=_readonly(np.arange(k) * dt),
        q=_readonly(log["q"]),
        v=_readonly(log["v"]),
        tau=_readonly(log["tau"]),
        position_error=_readonly(log["position_error"]),
        orientation_error=_readonly(log["orientation_error"]),
        force_desired=_readonly(scalars["force_desired"]),
        force_reference=_readonly(scalars["force_reference"]),
        contact_force=_readonly(scalars["contact_force"]),
        force_error=_readonly(scalars["force_desired"] - scalars["contact_force"]),
        joint_speed=_readonly(np.abs(log["v"]).max(axis=1)),
        null_space_velocity=_readonly(scalars["rns"]),
        null_space_velocity_jacobian=_readonly(scalars["jacobian"]),
        phi=_readonly(scalars["phi"]),
        pulling_steps=sim.pulling_steps,
        wall_time=wall,
        description=dict(setup.description),
    )


def quick_scenarios() -> tuple[ArcScenario, WallScenario]:
    """Shortened scenarios for tests and ``--quick``: one half cycle, one stroke."""
    return ArcScenario(half_cycles=1), WallScenario(strokes=1)


#: Control period of the quick runs [s] (the simulator's Baumgarte rate allows it).
QUICK_PERIOD = 2e-3


__all__ = [
    "CONTROLLERS",
    "CONTROL_PERIOD",
    "FORCE",
    "FORCE_RAMP",
    "PLANAR_HALF_CYCLE",
    "QUICK_PERIOD",
    "THESIS_FORCE_GAINS",
    "THESIS_MOTION_GAINS",
    "VIRTUAL_MASS",
    "WALL_STROKE",
    "WALL_STROKES",
    "ArcScenario",
    "ClosedLoopRun",
    "Controller",
    "ForceMeasurement",
    "Reference",
    "Setup",
    "WallScenario",
    "back_and_forth",
    "force_profile",
    "quick_scenarios",
    "quintic_profile",
    "run_closed_loop",
]
