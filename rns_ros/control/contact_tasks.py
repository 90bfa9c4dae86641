r"""The two chapter-6 motion/force tasks (thesis sections 6.2.1-6.2.2), resolved on their arms.

:class:`ArcScenario` (Figs. 6.3-6.4) and :class:`WallScenario` (Figs. 6.7-6.8) are validated
records; ``setup()`` resolves one into a :class:`Setup` (start configuration on the surface,
references, f_des, constraint). Geometry, timing and choices: docs/part2.md, "Chapter 6 runs".
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from rns_ros.control.motion_force.task_space import FULL_ROWS, PLANAR_ROWS, contact_frame
from rns_ros.core.contact_geometry import ArcConstraint, PlaneConstraint, project_onto_constraint
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState, load_fixed_base_model
from rns_ros.core.timing import quintic_profile
from rns_ros.core.validation import positive
from rns_ros.resources import config_dir

#: Half-cycle duration T_half of the planar arc [s] ([A-4.7]): chosen so that the RNS-C peak
#: joint speed is about the thesis' 0.73 rad/s (see docs/part2.md, "Chapter 6 runs").
PLANAR_HALF_CYCLE = 1.6
#: Stroke duration of the wall task [s] (thesis section 6.2.2: 2.5 s) and strokes ([A-4.11]).
WALL_STROKE, WALL_STROKES = 2.5, 4
#: Desired contact force [N] and its quintic ramp time [s] (both scenarios).
FORCE, FORCE_RAMP = 10.0, 1.0
#: Thesis x of the wall-task target [0.24, 0.43, 0.43] m: the stroke length is |0.24 - x0|.
WALL_TARGET_X = 0.24


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


def _check_timing(task, segment: str, segments: str) -> None:
    """Validate in place the segment duration [s] (> 0), the segment count (>= 1), the force
    [N] (>= 0) and its ramp [s] (> 0) of a frozen task record."""
    object.__setattr__(task, segment, positive(getattr(task, segment), segment, "[s]"))
    object.__setattr__(task, segments, _count(getattr(task, segments), segments))
    object.__setattr__(task, "force", _nonnegative(task.force, "force", "[N]"))
    object.__setattr__(task, "force_ramp", positive(task.force_ramp, "force_ramp", "[s]"))


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
        object.__setattr__(self, "seed_deg", _finite_tuple(self.seed_deg, 3, "seed_deg"))
        _check_timing(self, "half_cycle", "half_cycles")

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
        _check_timing(self, "stroke", "strokes")

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


def quick_scenarios() -> tuple[ArcScenario, WallScenario]:
    """Shortened scenarios for tests and ``--quick``: one half cycle, one stroke."""
    return ArcScenario(half_cycles=1), WallScenario(strokes=1)


__all__ = [
    "FORCE",
    "FORCE_RAMP",
    "PLANAR_HALF_CYCLE",
    "WALL_STROKE",
    "WALL_STROKES",
    "WALL_TARGET_X",
    "ArcScenario",
    "Reference",
    "Setup",
    "WallScenario",
    "back_and_forth",
    "force_profile",
    "quick_scenarios",
]
