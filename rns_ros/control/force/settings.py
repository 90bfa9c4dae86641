"""Settings of the force controller step: the node parameters, validated once."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rns_ros.control.motion_force.osc import OscVariant
from rns_ros.control.motion_force.outer_loops import ForceGains, MotionGains
from rns_ros.control.motion_force.task_space import ROW_NAMES
from rns_ros.core.errors import ConfigError
from rns_ros.core.validation import Choice, positive

#: Longest step used to integrate the reference [s] (a gap in the states is not integrated over).
MAX_STEP = 0.1


class ControlMethod(Choice):
    """``rns``: RNS-C closed form (section 6.1.2); ``os``: OS-C (section 6.1.1)."""

    __label__ = "method"
    RNS = "rns"
    OS = "os"


class ConstrainedFrame(Choice):
    """Axes of ``constrained_axis``: ``ee`` (taken at activation, then fixed in world) or
    ``world``."""

    __label__ = "constrained_frame"
    EE = "ee"
    WORLD = "world"


class NormalMode(Choice):
    """``fixed``: the surface known at activation: n = constrained_axis there, a plane for
    surface_curvature 0, else a sphere of radius 1/surface_curvature through that point (its
    trace in the task plane: the cylinder of the planar arc), n(p) toward (kappa > 0) or away
    from (kappa < 0) its centre; ``wrench``: the measured force direction while the EE pushes
    with |f| >= contact_threshold, else the ``fixed`` surface model (or the last normal, for
    a plane); for surfaces whose shape is only roughly known."""

    __label__ = "normal_mode"
    FIXED = "fixed"
    WRENCH = "wrench"


class ForceMeasurementMode(Choice):
    """The force f in (6.34): ``predicted`` (model-based, same instant, sensor-corrected) or
    ``sampled`` (the one-step-late wrench; only for k_f < 1)."""

    __label__ = "force_measurement"
    PREDICTED = "predicted"
    SAMPLED = "sampled"


class CommandFrame(Choice):
    """Axes of an operator command: world or the EE frame."""

    __label__ = "command frame"
    WORLD = "world"
    EE = "ee"


def _number(value, name: str, unit: str, low: float, high: float = math.inf) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number {unit}, got {value!r}") from None
    if not (math.isfinite(number) and low <= number <= high):
        raise ConfigError(f"{name} must be in [{low}, {high}] {unit}, got {value!r}")
    return number


def parse_task_axes(axes) -> tuple[int, ...]:
    """Task rows from axis names (``x y z wx wy wz``, world axes), in J_e row order.

    Raises:
        ConfigError: unknown or duplicated names, no linear axis (the force needs one).
    """
    names = [axes] if isinstance(axes, str) else list(axes)
    bad = [name for name in names if name not in ROW_NAMES]
    if bad or not names or len(set(names)) != len(names):
        raise ConfigError(
            f"task_axes must be distinct names among {list(ROW_NAMES)}, got {names!r}"
        )
    rows = tuple(sorted(ROW_NAMES.index(name) for name in names))
    if not any(r < 3 for r in rows):
        raise ConfigError(f"task_axes {names} has no linear axis: the force needs x, y or z")
    return rows


@dataclass(frozen=True)
class ForceControlSettings:
    """Everything the step needs besides the robot (node parameters, docs/part2_ros.md).

    Attributes:
        method: rns | os; os_variant: literal | kinematic ([A-4.2]).
        k_p [1/s^2], k_d [1/s]: motion loop (6.33) (thesis 100, 10); k_f [-]: force loop (6.34)
            (thesis 5).
        virtual_mass: m_hat [kg] (RNS-C); virtual_inertia: I_hat [kg m^2], 0 -> m_hat/12 [A-4.9].
        task_axes: task rows by name (world axes).
        constrained_frame, constrained_axis (3,), normal_mode: the contact normal n (see
            :class:`NormalMode`); surface_curvature [1/m] (> 0: the surface bends toward the
            environment, 1/R for a cylinder crossed perpendicular to its axis; 0: a plane).
        force_measurement: predicted | sampled (sampled needs k_f < 1).
        default_twist_frame: axes of a twist with an empty frame_id (world | ee).
        command_timeout [s]: an older twist decelerates to rest; force_timeout [s]: an older
            setpoint is held (WARN).
        max_linear_speed [m/s], max_angular_speed [rad/s]: whole-vector scaling of the twist;
            max_linear_acceleration [m/s^2]: feed-forward clip and rate limit of the linear
            reference (the angular one uses the same ramp time: max_linear_acceleration *
            max_angular_speed / max_linear_speed [rad/s^2]).
        max_force_setpoint [N]: f_des is clipped to [0, it].
        max_contact_force [N], max_contact_torque [N m]: measured wrench limits.
        contact_threshold [N]: in contact when the measured f >= it; contact_loss_time [s].
        wrench_timeout [s]: the wrist wrench is fresh while its newest stamp is at most this
            older than the state's; without a fresh one the force task pauses (WRENCH_STALE).
        nominal_period [s]: the first step's length.

    Raises:
        ConfigError: a value out of range; ``sampled`` with k_f >= 1.
    """

    method: ControlMethod | str = ControlMethod.RNS
    os_variant: OscVariant | str = OscVariant.LITERAL
    k_p: float = 100.0
    k_d: float = 10.0
    k_f: float = 5.0
    virtual_mass: float = 1.0e5
    virtual_inertia: float = 0.0
    task_axes: tuple[str, ...] = ROW_NAMES
    constrained_frame: ConstrainedFrame | str = ConstrainedFrame.EE
    constrained_axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    normal_mode: NormalMode | str = NormalMode.FIXED
    surface_curvature: float = 0.0
    force_measurement: ForceMeasurementMode | str = ForceMeasurementMode.PREDICTED
    default_twist_frame: CommandFrame | str = CommandFrame.EE
    command_timeout: float = 0.5
    force_timeout: float = 0.5
    max_linear_speed: float = 0.5
    max_angular_speed: float = 1.0
    max_linear_acceleration: float = 5.0
    max_force_setpoint: float = 30.0
    max_contact_force: float = 40.0
    max_contact_torque: float = 10.0
    contact_threshold: float = 1.0
    contact_loss_time: float = 0.02
    wrench_timeout: float = 0.05
    nominal_period: float = 1e-3
    rows: tuple[int, ...] = field(init=False)

    def __post_init__(self) -> None:
        setter = object.__setattr__
        setter(self, "method", ControlMethod.parse(self.method))
        setter(self, "os_variant", OscVariant.parse(self.os_variant))
        gains = MotionGains(k_p=self.k_p, k_d=self.k_d)
        setter(self, "k_p", gains.k_p)
        setter(self, "k_d", gains.k_d)
        setter(self, "k_f", ForceGains(k_f=self.k_f).k_f)
        setter(self, "virtual_mass", positive(self.virtual_mass, "virtual_mass", "[kg]"))
        self._check_number("virtual_inertia", "[kg m^2]", 0.0)
        setter(self, "rows", parse_task_axes(self.task_axes))
        setter(self, "task_axes", tuple(ROW_NAMES[r] for r in self.rows))
        setter(self, "constrained_frame", ConstrainedFrame.parse(self.constrained_frame))
        axis = np.asarray(self.constrained_axis, dtype=float)
        if axis.shape != (3,) or not np.isfinite(axis).all() or np.linalg.norm(axis) < 1e-9:
            raise ConfigError(
                "constrained_axis must be 3 finite numbers, not all 0, got "
                f"{self.constrained_axis!r}"
            )
        setter(self, "constrained_axis", tuple(float(x) for x in axis / np.linalg.norm(axis)))
        if self.constrained_frame is ConstrainedFrame.WORLD:
            off = [ROW_NAMES[i] for i in range(3) if i not in self.rows and abs(axis[i]) > 1e-9]
            if off:
                raise ConfigError(
                    f"constrained_axis {list(self.constrained_axis)} (world) has components "
                    f"along {off}, which are not task_axes {list(self.task_axes)}"
                )
        setter(self, "normal_mode", NormalMode.parse(self.normal_mode))
        self._check_number("surface_curvature", "[1/m]", -1e3, 1e3)
        mode = ForceMeasurementMode.parse(self.force_measurement)
        setter(self, "force_measurement", mode)
        if mode is ForceMeasurementMode.SAMPLED and self.k_f >= 1.0:
            raise ConfigError(
                f"force_measurement 'sampled' needs k_f < 1, got k_f = {self.k_f:g}: over DDS the "
                "wrench that arrives with a state was measured under the torque held over the "
                "previous step, and against a rigid contact (6.34) on it gives "
                "e_{k+1} = -k_f e_k, which diverges for k_f >= 1 (the thesis' k_f = 5 blows up "
                "in a few steps); use force_measurement 'predicted' (the force at the same "
                "instant from the contact model, corrected by the sensor)"
            )
        setter(self, "default_twist_frame", CommandFrame.parse(self.default_twist_frame))
        for name, unit, low, high in (
            ("command_timeout", "[s]", 1e-3, 60.0),
            ("force_timeout", "[s]", 1e-3, 60.0),
            ("max_linear_speed", "[m/s]", 1e-6, 10.0),
            ("max_angular_speed", "[rad/s]", 1e-6, 20.0),
            ("max_linear_acceleration", "[m/s^2]", 1e-6, 1e3),
            ("max_force_setpoint", "[N]", 0.0, 1e4),
            ("max_contact_force", "[N]", 1e-6, 1e5),
            ("max_contact_torque", "[N m]", 1e-6, 1e5),
            ("contact_threshold", "[N]", 1e-6, 1e4),
            ("contact_loss_time", "[s]", 0.0, 10.0),
            ("wrench_timeout", "[s]", 1e-4, 10.0),
            ("nominal_period", "[s]", 1e-6, MAX_STEP),
        ):
            self._check_number(name, unit, low, high)

    def _check_number(self, name: str, unit: str, low: float, high: float = math.inf) -> None:
        """Field ``name`` as a float in [low, high] ``unit``, or ConfigError naming it."""
        object.__setattr__(self, name, _number(getattr(self, name), name, unit, low, high))

    @property
    def max_angular_acceleration(self) -> float:
        """Angular acceleration limit [rad/s^2]: the linear one's ramp time at max speed."""
        return self.max_linear_acceleration * self.max_angular_speed / self.max_linear_speed


__all__ = [
    "MAX_STEP",
    "CommandFrame",
    "ConstrainedFrame",
    "ControlMethod",
    "ForceControlSettings",
    "ForceMeasurementMode",
    "NormalMode",
    "parse_task_axes",
]
