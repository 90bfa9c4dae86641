r"""Motion/force teleoperation of a fixed-base arm in contact: one control step per joint state.

Pure logic (no ROS) under the ``rns_force_controller`` node (docs/part2_ros.md): operator twist
and force setpoint in, joint torque out, thesis chapter 6 (RNS-C or OS-C, motion along the
surface, force along its normal). One :meth:`ForceTeleopController.step` per measured state:

1. :meth:`FixedBaseState.compute` once (M, c, g, J_e, J_e_dot q_dot, EE pose).
2. Motion reference from the operator twist (:class:`TwistCommand`): latched at the first
   state, integrated with a first-order hold of the twist messages (acceleration feed-forward
   from consecutive message stamps), components along the force direction removed, too-fast
   commands scaled as whole vectors, rate limited to ``max_linear_acceleration``; a stale or
   rejected twist decelerates to rest and the reference holds.
3. Task :meth:`TaskSpace.from_contact` along the contact normal n (fixed, or the measured force
   direction on a curved surface).
4. Motion loop (6.33) and the normal (centripetal) feed-forward a_n = curvature |v_t|^2 [A-4.8].
5. RNS-C closed form (:func:`rns_control`) or OS-C (:func:`os_control`): the motion torque tau_0.
6. Force loop (6.34) with the **predicted** contact force (:class:`RigidContactModel`): over DDS
   the wrench that arrives with state k was measured under the torque held over the previous
   step, so (6.34) on it gives e_{k+1} = -k_f e_k (the thesis' k_f = 5 diverges,
   ``part2_runs.ForceMeasurement``). The rigid-contact force is affine in the torque,
   lambda(tau) = Lambda_n (n^T J_v M^-1 (tau - c - g) + n^T (J_dot v)_lin) + beta; beta (surface
   curvature, stabilization, model error) is estimated from the wrench and the held torque of the
   same stamp, and lambda_0 = lambda(tau_0) is the force the motion torque alone produces NOW,
   as the in-process loop reads it: f_ref = (f_des + k_f (f_des - lambda_0)) / (1 + k_f).
7. Safety monitor (:class:`SafetyMonitor`): wrench limit, contact lost / never made -> the force
   task stops and the arm holds its pose under pure motion control (latched until reset).
8. Torque clipped to the URDF effort limits; a non-finite result publishes nothing.

Signs: f is the force the EE exerts on the environment along n ([A-4.1]), n points from the EE
into the environment; every torque contains +J^T n f_ref. Times: stamps are integer nanoseconds
(header stamps; matched exactly between joint_states and wrist_wrench), receipt times monotonic
seconds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rns_ros.control.motion_force import (
    ROW_NAMES,
    ForceGains,
    MotionGains,
    OscVariant,
    ReversedModel,
    TaskSpace,
    force_loop,
    motion_loop,
    os_control,
    rns_control,
)
from rns_ros.core.errors import ConfigError, InputError, RnsError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState
from rns_ros.core.validation import Choice, positive

#: Layout of one ``~/errors`` sample (docs/part2_ros.md).
ERROR_LABELS = (
    "time",
    "position_error_x",
    "position_error_y",
    "position_error_z",
    "orientation_error",
    "force_desired",
    "force_measured",
    "force_error",
    "force_reference",
    "joint_speed",
    "normal_x",
    "normal_y",
    "normal_z",
    "force_active",
)
#: Longest step used to integrate the reference [s] (a gap in the states is not integrated over).
#: The first-order hold of a twist extrapolates it with its acceleration feed-forward for up
#: to this many of its message periods past its stamp: a twist usually reaches the controller a
#: control step after its stamp, so one period would drop the feed-forward every other step
#: (1.3 mm instead of 0.02 mm on the wall stroke); a stream that stops is held, not extrapolated.
EXTRAPOLATION_PERIODS = 2.0
MAX_STEP = 0.1
#: Wrench samples kept for matching by stamp.
WRENCH_HISTORY = 32
#: Removed or ignored command components smaller than this are not reported [m/s, rad/s, N].
REPORT_TOLERANCE = 1e-6
#: Frame-id aliases accepted besides the configured names.
WORLD_ALIAS, EE_ALIAS = "world", "ee"


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


class ForceControlState(Choice):
    """What the controller is doing (status level in brackets)."""

    WAITING_FOR_STATE = "WAITING_FOR_STATE"  # [WARN] no joint_states yet
    OK = "OK"  # [OK] following a fresh twist
    HOLDING = "HOLDING"  # [OK] no fresh twist: decelerating to rest / holding the pose
    SPEED_LIMITED = "SPEED_LIMITED"  # [WARN] twist scaled to max_linear/angular_speed
    FORCE_SETPOINT_STALE = "FORCE_SETPOINT_STALE"  # [WARN] setpoint older than force_timeout
    WRENCH_STALE = "WRENCH_STALE"  # [WARN] force task on, no fresh wrist wrench: push paused
    TORQUE_LIMITED = "TORQUE_LIMITED"  # [WARN] torque clipped to the URDF effort limits
    INVALID_COMMAND = "INVALID_COMMAND"  # [ERROR] the newest twist/setpoint was rejected
    WRENCH_LIMIT = "WRENCH_LIMIT"  # [ERROR, latched] measured wrench over the limit
    CONTACT_LOST = "CONTACT_LOST"  # [ERROR, latched] contact made, then lost
    NO_CONTACT = "NO_CONTACT"  # [ERROR, latched] the force task never made contact
    STALE_STATE = "STALE_STATE"  # [ERROR] no joint_states for state_timeout: zero torque
    NON_FINITE = "NON_FINITE"  # [ERROR] a non-finite torque: nothing published
    CONTROL_ERROR = "CONTROL_ERROR"  # [ERROR] the law failed (e.g. OS-C singular): nothing


#: Latched safety stops (cleared by :meth:`ForceTeleopController.reset`).
SAFETY_STOPS = (
    ForceControlState.WRENCH_LIMIT,
    ForceControlState.CONTACT_LOST,
    ForceControlState.NO_CONTACT,
)


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
        setter(
            self,
            "virtual_inertia",
            _number(self.virtual_inertia, "virtual_inertia", "[kg m^2]", 0.0),
        )
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
        setter(
            self,
            "surface_curvature",
            _number(self.surface_curvature, "surface_curvature", "[1/m]", -1e3, 1e3),
        )
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
            setter(self, name, _number(getattr(self, name), name, unit, low, high))

    @property
    def max_angular_acceleration(self) -> float:
        """Angular acceleration limit [rad/s^2]: the linear one's ramp time at max speed."""
        return self.max_linear_acceleration * self.max_angular_speed / self.max_linear_speed


# --------------------------------------------------------------------------------------------
# Inputs


class TwistCommand(NamedTuple):
    """One validated operator twist.

    Attributes:
        linear [m/s], angular [rad/s]: (3,), in ``frame`` axes, finite.
        frame: world or EE axes.
        stamp: header stamp [ns] (0: unstamped: no acceleration feed-forward).
        received: monotonic receipt time [s].
    """

    linear: np.ndarray
    angular: np.ndarray
    frame: CommandFrame
    stamp: int
    received: float


class ForceSetpoint(NamedTuple):
    """One validated force setpoint: force [N] and torque [N m] (3,) in ``frame`` axes (only the
    force along the contact normal is used), monotonic receipt time [s]."""

    force: np.ndarray
    torque: np.ndarray
    frame: CommandFrame
    received: float


class WrenchSample(NamedTuple):
    """The wrist wrench the EE exerts on the environment, EE axes [N, N m] (3,) each, at header
    stamp ``stamp`` [ns] (that of the joint state it belongs to)."""

    stamp: int
    force: np.ndarray
    torque: np.ndarray


class JointMeasurement(NamedTuple):
    """One joint state in model joint order: stamp [ns], q [rad], v [rad/s] (n,), effort [N m]
    (n,) = the torque held over the step that ended here, or None when not reported."""

    stamp: int
    q: np.ndarray
    v: np.ndarray
    effort: np.ndarray | None = None


def command_frames(world_frame: str, ee_frame: str) -> dict[str, CommandFrame]:
    """frame_id -> axes: ``world_frame`` and the alias ``world``; the EE frame's name and the
    alias ``ee``."""
    return {
        WORLD_ALIAS: CommandFrame.WORLD,
        world_frame: CommandFrame.WORLD,
        EE_ALIAS: CommandFrame.EE,
        ee_frame: CommandFrame.EE,
    }


def _finite3(vector, name: str) -> np.ndarray:
    array = np.asarray(vector, dtype=float)
    if array.shape != (3,) or not np.isfinite(array).all():
        raise InputError(f"{name} must be 3 finite numbers, got {array.tolist()}")
    return array


def _frame(frame_id: str, frames: Mapping[str, CommandFrame], default: CommandFrame):
    if frame_id == "":
        return default
    if frame_id not in frames:
        raise InputError(f"frame_id {frame_id!r} is not one of {sorted(frames)}")
    return frames[frame_id]


def validate_twist(
    linear,
    angular,
    frame_id: str,
    frames: Mapping[str, CommandFrame],
    default: CommandFrame,
    stamp: int,
    received: float,
) -> TwistCommand:
    """Check a ``cmd_twist`` message (finite, known frame; empty frame_id -> ``default``).

    Raises:
        InputError: non-finite values or an unknown frame (the message names them).
    """
    return TwistCommand(
        _finite3(linear, "cmd_twist linear velocity"),
        _finite3(angular, "cmd_twist angular velocity"),
        _frame(frame_id, frames, default),
        int(stamp),
        float(received),
    )


def validate_force_setpoint(
    force, torque, frame_id: str, frames: Mapping[str, CommandFrame], received: float
) -> ForceSetpoint:
    """Check a ``force_setpoint`` message (finite, known frame; empty frame_id -> EE).

    Raises:
        InputError: non-finite values or an unknown frame.
    """
    return ForceSetpoint(
        _finite3(force, "force_setpoint force"),
        _finite3(torque, "force_setpoint torque"),
        _frame(frame_id, frames, CommandFrame.EE),
        float(received),
    )


# --------------------------------------------------------------------------------------------
# The predicted contact force


@dataclass(frozen=True)
class RigidContactModel:
    """The normal force of a rigid contact along n as an affine function of the joint torque.

    With the constraint n^T p_ddot = a_c (a_c torque-independent: curvature, stabilization),
    (C.1)-(C.2) of ``rns_ros.sim.contact`` give

        lambda(tau) = Lambda_n (n^T J_v M^-1 (tau - c - g) + n^T (J_dot v)_lin) + beta,
        Lambda_n = 1 / (n^T J_v M^-1 J_v^T n)  [kg],

    with beta torque-independent. lambda(tau + J_v^T n f) = lambda(tau) + f.

    Attributes:
        push: J_v^T n (n,) [m] (the torque per newton of f_ref).
        mobility: M^-1 J_v^T n (n,). inertia: Lambda_n [kg]. bias: c + g (n,) [N m].
        drift: n^T (J_dot v)_lin [m/s^2].
    """

    push: np.ndarray
    mobility: np.ndarray
    inertia: float
    bias: np.ndarray
    drift: float

    @classmethod
    def at(cls, state: FixedBaseState, normal) -> RigidContactModel:
        """The model at ``state`` along the unit ``normal`` (3,), world axes.

        Raises:
            InputError: the EE cannot move along n (n^T J_v M^-1 J_v^T n = 0).
        """
        n = np.asarray(normal, dtype=float)
        push = state.jacobian[:3].T @ n
        mobility = np.linalg.solve(state.mass_matrix, push)
        schur = float(push @ mobility)
        if not schur > 0.0:
            raise InputError(f"the end effector cannot move along the normal {n.tolist()}")
        return cls(
            push,
            mobility,
            1.0 / schur,
            state.coriolis + state.gravity,
            float(n @ state.jacobian_dot_v[:3]),
        )

    def force(self, torque) -> float:
        """lambda(tau) - beta [N] for the torque tau (n,) [N m]."""
        return self.inertia * (float(self.mobility @ (torque - self.bias)) + self.drift)


def predicted_contact_force(state: FixedBaseState, normal, torque, bias: float = 0.0) -> float:
    """lambda(tau) [N] of :class:`RigidContactModel` with the torque-independent part ``bias``."""
    return RigidContactModel.at(state, normal).force(np.asarray(torque, dtype=float)) + bias


def force_reference(f_des: float, lambda_0: float, k_f: float) -> float:
    """f_ref of (6.34) solved at the same instant: f = lambda_0 + f_ref gives
    f_ref = (f_des + k_f (f_des - lambda_0)) / (1 + k_f) [N] (then f - f_des = lambda_0/(1+k_f))."""
    return (f_des + k_f * (f_des - lambda_0)) / (1.0 + k_f)


def normal_acceleration(curvature: float, normal, ee_velocity) -> float:
    """a_n = curvature |v_t|^2 [m/s^2]: the normal acceleration that keeps the EE on a surface
    bending toward the environment with ``curvature`` [1/m], v_t = the EE velocity (3,) [m/s]
    tangent to the surface (world). Equals -kappa of ``ArcConstraint.curvature`` for motion
    across a cylinder of radius 1/curvature."""
    v = np.asarray(ee_velocity, dtype=float)
    n = np.asarray(normal, dtype=float)
    tangential = v - (n @ v) * n
    return float(curvature * (tangential @ tangential))


# --------------------------------------------------------------------------------------------
# Safety


class SafetyMonitor:
    """Latched wrench limit and contact supervision (cleared by :meth:`reset`).

    * WRENCH_LIMIT: measured |force| > ``max_force`` [N] or |torque| > ``max_torque`` [N m].
    * CONTACT_LOST / NO_CONTACT: while the force task is active and f_des >= 2 ``threshold``,
      the measured normal force stayed below ``threshold`` [N] for ``loss_time`` [s] or more
      (by state stamps); CONTACT_LOST when it had been >= threshold since the last reset.
    """

    def __init__(
        self, max_force: float, max_torque: float, threshold: float, loss_time: float
    ) -> None:
        self.max_force, self.max_torque = max_force, max_torque
        self.threshold, self.loss_time = threshold, loss_time
        self.reset()

    def reset(self) -> None:
        self.fault: tuple[ForceControlState, str] | None = None
        self.ever_in_contact = False
        self._below_since: int | None = None

    def contact(self, f: float) -> str:
        """in_contact | lost | none for the measured normal force f [N]."""
        if f >= self.threshold:
            return "in_contact"
        return "lost" if self.ever_in_contact else "none"

    def update(
        self, stamp: int, force_active: bool, f_des: float, f: float, wrench: WrenchSample | None
    ) -> tuple[ForceControlState, str] | None:
        """Check one step (stamp [ns], f_des and the measured normal f [N]); returns the latched
        fault, if any."""
        if self.fault is not None:
            return self.fault
        if wrench is not None:
            force, torque = np.linalg.norm(wrench.force), np.linalg.norm(wrench.torque)
            if force > self.max_force or torque > self.max_torque:
                self.fault = (
                    ForceControlState.WRENCH_LIMIT,
                    f"measured |force| {force:.4g} N / |torque| {torque:.4g} N m over the limits "
                    f"{self.max_force:g} N / {self.max_torque:g} N m",
                )
                return self.fault
        if f >= self.threshold:
            self.ever_in_contact = True
        if force_active and f_des >= 2.0 * self.threshold and f < self.threshold:
            if self._below_since is None:
                self._below_since = stamp
            elapsed = (stamp - self._below_since) * 1e-9
            if elapsed >= self.loss_time:
                lost = self.ever_in_contact
                self.fault = (
                    ForceControlState.CONTACT_LOST if lost else ForceControlState.NO_CONTACT,
                    f"{'contact lost' if lost else 'no contact made'}: measured force "
                    f"{f:.3g} N < contact_threshold {self.threshold:g} N for {elapsed:.3f} s "
                    f"while {f_des:.3g} N was desired",
                )
        else:
            self._below_since = None
        return self.fault


# --------------------------------------------------------------------------------------------
# The step


@dataclass(frozen=True)
class ForceStep:
    """One control step's result.

    Attributes:
        torque: joint torques [N m] (n,) in model order, clipped to the effort limits, finite;
            None: publish nothing new (non-finite or failed step).
        state, detail: status (detail = reasons and reports, '; '-joined).
        time: the state's stamp [s]. position_error: p_des - p, world [m] (3,).
        orientation_error: |log(R_des R^T)| [rad] (0 when the orientation is not a task).
        force_desired, force_measured, force_reference [N]: f_des, the measured f along n, f_ref.
        joint_speed: max |theta_dot_i| [rad/s]. normal: n (3,). force_active: the force task runs.
        contact: in_contact | lost | none. saturated: joint names clipped to their effort limit.
        ignored: size of the twist removed along constrained / non-task directions [m/s, rad/s].
    """

    torque: np.ndarray | None
    state: ForceControlState
    detail: str
    time: float
    position_error: np.ndarray
    orientation_error: float
    force_desired: float
    force_measured: float
    force_reference: float
    joint_speed: float
    normal: np.ndarray
    force_active: bool
    contact: str
    saturated: tuple[str, ...] = ()
    ignored: float = 0.0

    @property
    def force_error(self) -> float:
        """f_des - f [N]."""
        return self.force_desired - self.force_measured

    def error_sample(self) -> np.ndarray:
        """The ``~/errors`` sample, layout :data:`ERROR_LABELS`, (14,)."""
        return np.array(
            [
                self.time,
                *self.position_error,
                self.orientation_error,
                self.force_desired,
                self.force_measured,
                self.force_error,
                self.force_reference,
                self.joint_speed,
                *self.normal,
                float(self.force_active),
            ]
        )


class _Twist(NamedTuple):
    """An accepted twist with its feed-forward: accelerations (3,) in the command's axes
    [m/s^2, rad/s^2] and the message period [s] (0: none)."""

    command: TwistCommand
    linear_acceleration: np.ndarray
    angular_acceleration: np.ndarray
    period: float


def _limit(vector: np.ndarray, limit: float) -> tuple[np.ndarray, float | None]:
    """``vector`` scaled to norm ``limit`` if longer (and its original norm), else as is."""
    norm = float(np.linalg.norm(vector))
    if norm > limit:
        return vector * (limit / norm), norm
    return vector, None


def _rate_limit(previous, target, feedforward, step: float, limit: float):
    """(v, a): ``target`` reached from ``previous`` with at most ``limit`` * step change; the
    acceleration is the feed-forward when unconstrained, else the limiting one."""
    change = target - previous
    norm = float(np.linalg.norm(change))
    allowed = limit * step
    if norm <= allowed * (1.0 + 1e-9) + 1e-12:
        return target, feedforward
    direction = change / norm
    return previous + allowed * direction, limit * direction


class ForceTeleopController:
    """Operator motion/force control of a fixed-base arm in contact (module docstring).

    Args:
        robot: the arm; settings: :class:`ForceControlSettings`.

    Feed it with :meth:`set_twist` / :meth:`reject_twist`, :meth:`set_force` /
    :meth:`reject_force`, :meth:`add_wrench`, and call :meth:`step` once per joint state.

    Raises:
        ConfigError: task rows exceed the joints, or the RNS-C model cannot be built.
    """

    def __init__(self, robot: FixedBaseModel, settings: ForceControlSettings) -> None:
        self.robot = robot
        self.settings = settings
        TaskSpace.free(settings.rows).check(robot)
        self.reversed_model = None
        if settings.method is ControlMethod.RNS:
            self.reversed_model = ReversedModel(
                robot,
                settings.rows,
                virtual_mass=settings.virtual_mass,
                virtual_inertia=settings.virtual_inertia or None,
            )
        self.motion_gains = MotionGains(k_p=settings.k_p, k_d=settings.k_d)
        self.force_gains = ForceGains(k_f=settings.k_f)
        limits = np.array(robot.effort_limits, dtype=float)
        limits[~(np.isfinite(limits) & (limits > 0.0))] = np.inf
        self.effort_limits = limits
        self.monitor = SafetyMonitor(
            settings.max_contact_force,
            settings.max_contact_torque,
            settings.contact_threshold,
            settings.contact_loss_time,
        )
        self._orientation = any(r >= 3 for r in settings.rows)
        self._twist: _Twist | None = None
        self._twist_rejection: str | None = None
        self._setpoint: ForceSetpoint | None = None
        self._force_rejection: str | None = None
        self._wrenches: dict[int, WrenchSample] = {}
        self._latest_wrench: WrenchSample | None = None
        self._normal: np.ndarray | None = None
        # fixed mode on a curved surface: the centre of curvature, latched at activation (3,)
        self._center: np.ndarray | None = None
        self._tangent: np.ndarray | None = None
        self._beta = 0.0
        self._f_des = 0.0
        self._force_active = False
        self._p_des: np.ndarray | None = None
        self._r_des: np.ndarray | None = None
        self._v_des = np.zeros(6)
        self._stamp: int | None = None
        self._holding = False  # a safety stop holds the pose
        self._task: tuple | None = None  # (TaskSpace, normal, tangent) of the last step
        self._free_task = TaskSpace.free(settings.rows)
        self._push = np.zeros(robot.n)
        self._rotation: np.ndarray | None = None
        self.peak_joint_speed = 0.0

    # --- inputs ---------------------------------------------------------------------------------
    def set_twist(self, command: TwistCommand) -> None:
        """A valid twist; its acceleration feed-forward is the difference to the previous one
        over their stamps (0 for equal/zero stamps or another frame)."""
        previous = self._twist
        zero = np.zeros(3)
        lin_acc, ang_acc, period = zero, zero, 0.0
        if previous is not None and previous.command.frame is command.frame:
            step = (command.stamp - previous.command.stamp) * 1e-9
            if command.stamp and previous.command.stamp and step > 0.0:
                lin_acc = (command.linear - previous.command.linear) / step
                ang_acc = (command.angular - previous.command.angular) / step
                period = min(step, MAX_STEP)
        self._twist = _Twist(command, lin_acc, ang_acc, period)
        self._twist_rejection = None

    def reject_twist(self, reason: str) -> None:
        """An invalid twist: the reference decelerates to rest (INVALID_COMMAND)."""
        self._twist_rejection = reason

    def set_force(self, setpoint: ForceSetpoint) -> None:
        """A valid force setpoint: the force task is active from now on (until a safety stop)."""
        self._setpoint, self._force_rejection = setpoint, None
        if self.monitor.fault is None:
            self._force_active = True

    def reject_force(self, reason: str) -> None:
        """An invalid setpoint: the previous one is kept (INVALID_COMMAND)."""
        self._force_rejection = reason

    def add_wrench(self, sample: WrenchSample) -> None:
        """A wrist wrench sample (kept by stamp; the newest stamp is the latest measurement)."""
        self._wrenches[sample.stamp] = sample
        if len(self._wrenches) > WRENCH_HISTORY:
            del self._wrenches[min(self._wrenches)]
        if self._latest_wrench is None or sample.stamp >= self._latest_wrench.stamp:
            self._latest_wrench = sample

    def reset(self) -> None:
        """Clear a latched safety stop and re-latch the motion reference at the next state's
        pose; the force task waits for a new force setpoint."""
        self.monitor.reset()
        self._force_active = False
        self._holding = False
        self._f_des = 0.0
        self.resync()

    def resync(self) -> None:
        """Re-latch the motion reference at the next state (after a gap in the states)."""
        self._p_des = None
        self._v_des = np.zeros(6)
        self._stamp = None

    @property
    def fault(self) -> tuple[ForceControlState, str] | None:
        """The latched safety stop (state, reason), or None."""
        return self.monitor.fault

    @property
    def ee_rotation(self) -> np.ndarray | None:
        """The EE rotation world <- EE (3, 3) at the newest state, or None."""
        return self._rotation

    @property
    def normal(self) -> np.ndarray | None:
        """The contact normal n in use (3,), world, or None before the first state."""
        return None if self._normal is None else self._normal.copy()

    # --- helpers --------------------------------------------------------------------------------
    def _project_normal(self, direction: np.ndarray) -> np.ndarray | None:
        """``direction`` with its non-task linear components removed, unit; None if little is
        left (a direction the task cannot push along)."""
        n = direction.copy()
        for i in range(3):
            if i not in self.settings.rows:
                n[i] = 0.0
        norm = float(np.linalg.norm(n))
        original = float(np.linalg.norm(direction))
        if not norm > 0.5 * original or not original > 0.0:
            return None
        return n / norm

    def _activate(self, state: FixedBaseState) -> None:
        if self._normal is None:
            axis = np.array(self.settings.constrained_axis)
            if self.settings.constrained_frame is ConstrainedFrame.EE:
                axis = state.ee_rotation @ axis
            normal = self._project_normal(axis)
            if normal is None:
                raise InputError(
                    f"constrained_axis {list(self.settings.constrained_axis)} in the EE frame is "
                    f"{axis.round(4).tolist()} in world: not along the task axes "
                    f"{list(self.settings.task_axes)}"
                )
            self._normal = normal
            curvature = self.settings.surface_curvature
            if curvature != 0.0:
                self._center = state.ee_position + normal / curvature
        self._p_des = state.ee_position.copy()
        self._r_des = state.ee_rotation.copy()
        self._v_des = np.zeros(6)

    def _hold(self, state: FixedBaseState) -> None:
        self._p_des = state.ee_position.copy()
        self._r_des = state.ee_rotation.copy()
        self._v_des = np.zeros(6)

    def _in_world(self, vector: np.ndarray, frame: CommandFrame, rotation: np.ndarray):
        return rotation @ vector if frame is CommandFrame.EE else vector

    def _twist_target(self, state, stamp: int, now: float, notes: list[str], flags: set):
        """(v target (6,), feed-forward a (6,), size of the removed components) in world axes."""
        settings, rows = self.settings, self.settings.rows
        track = self._twist
        if self._twist_rejection is not None:
            flags.add(ForceControlState.INVALID_COMMAND)
            notes.append(f"cmd_twist rejected: {self._twist_rejection}")
            return np.zeros(6), np.zeros(6), 0.0
        if track is None or now - track.command.received > settings.command_timeout:
            age = "no cmd_twist yet" if track is None else "cmd_twist stale"
            flags.add(ForceControlState.HOLDING)
            notes.append(f"{age}: holding the pose")
            return np.zeros(6), np.zeros(6), 0.0
        command, rotation = track.command, state.ee_rotation
        hold, horizon = 0.0, EXTRAPOLATION_PERIODS * track.period
        if track.period > 0.0:
            hold = min(max((stamp - command.stamp) * 1e-9, 0.0), horizon)
        lin_acc = self._in_world(track.linear_acceleration, command.frame, rotation)
        ang_acc = self._in_world(track.angular_acceleration, command.frame, rotation)
        lin_acc = _limit(lin_acc, settings.max_linear_acceleration)[0]
        ang_acc = _limit(ang_acc, settings.max_angular_acceleration)[0]
        linear = self._in_world(command.linear, command.frame, rotation) + lin_acc * hold
        angular = self._in_world(command.angular, command.frame, rotation) + ang_acc * hold
        if track.period == 0.0 or hold >= horizon:
            lin_acc, ang_acc = np.zeros(3), np.zeros(3)
        v, a = np.concatenate([linear, angular]), np.concatenate([lin_acc, ang_acc])
        removed = np.zeros(6)
        for i in range(6):
            if i not in rows:
                removed[i], v[i], a[i] = v[i], 0.0, 0.0
        n = self._normal  # the normal is force-controlled: its motion is not commanded
        along = float(n @ v[:3])
        removed[:3] += along * n
        v[:3] -= along * n
        a[:3] -= float(n @ a[:3]) * n
        ignored = float(np.linalg.norm(removed))
        if ignored > REPORT_TOLERANCE:
            notes.append(
                f"ignored {np.linalg.norm(removed[:3]):.3g} m/s, {np.linalg.norm(removed[3:]):.3g}"
                " rad/s of cmd_twist along the force direction / non-task axes"
            )
        v[:3], requested_linear = _limit(v[:3], settings.max_linear_speed)
        v[3:], requested_angular = _limit(v[3:], settings.max_angular_speed)
        if requested_linear is not None or requested_angular is not None:
            flags.add(ForceControlState.SPEED_LIMITED)
            asked = [
                f"{value:.4g} {unit} scaled to {limit:g}"
                for value, unit, limit in (
                    (requested_linear, "m/s", settings.max_linear_speed),
                    (requested_angular, "rad/s", settings.max_angular_speed),
                )
                if value is not None
            ]
            notes.append("cmd_twist " + ", ".join(asked))
        return v, a, ignored

    def _force_desired(self, state, now: float, notes: list[str], flags: set) -> float:
        settings, setpoint = self.settings, self._setpoint
        if self._force_rejection is not None:
            flags.add(ForceControlState.INVALID_COMMAND)
            notes.append(f"force_setpoint rejected (previous kept): {self._force_rejection}")
        if setpoint is None or not self._force_active:
            return 0.0
        if now - setpoint.received > settings.force_timeout:
            flags.add(ForceControlState.FORCE_SETPOINT_STALE)
            notes.append(
                f"force_setpoint {now - setpoint.received:.2f} s old (force_timeout "
                f"{settings.force_timeout:g} s): holding f_des {self._f_des:.3g} N"
            )
            return self._f_des
        force = self._in_world(setpoint.force, setpoint.frame, state.ee_rotation)
        f_des = float(self._normal @ force)
        other = float(np.linalg.norm(force - f_des * self._normal))
        torque = float(np.linalg.norm(setpoint.torque))
        if other > REPORT_TOLERANCE or torque > REPORT_TOLERANCE:
            notes.append(
                f"ignored {other:.3g} N of force_setpoint off the normal and {torque:.3g} N m "
                "of torque"
            )
        clipped = min(max(f_des, 0.0), settings.max_force_setpoint)
        if clipped != f_des:
            notes.append(
                f"f_des {f_des:.4g} N clipped to [0, {settings.max_force_setpoint:g}] N "
                "(a surface cannot be pulled)"
            )
        self._f_des = clipped
        return clipped

    # --- the step -------------------------------------------------------------------------------
    def step(self, measurement: JointMeasurement, now: float) -> ForceStep:
        """One control step at a measured state (see the module docstring).

        Args:
            measurement: the joint state (model order) with its stamp [ns] and held effort.
            now: monotonic time [s] (command ages by receipt time).

        Raises:
            InputError: non-finite or wrongly shaped q / v.
        """
        settings = self.settings
        state = FixedBaseState.compute(self.robot, measurement.q, measurement.v)
        stamp = int(measurement.stamp)
        notes: list[str] = []
        flags: set[ForceControlState] = set()
        if self._p_des is None:
            self._activate(state)
            dt = settings.nominal_period
        else:
            dt = min(max((stamp - self._stamp) * 1e-9, 0.0), MAX_STEP)
        self._stamp = stamp
        rotation = self._rotation = state.ee_rotation
        exact = self._wrenches.get(stamp)
        latest = exact or self._latest_wrench
        force_world = None if latest is None else rotation @ latest.force
        normal = None
        if settings.normal_mode is NormalMode.WRENCH and force_world is not None:
            size = float(np.linalg.norm(force_world))
            # only a push gives the normal: a (bilateral) pull points the other way
            if size >= settings.contact_threshold and float(self._normal @ force_world) > 0.0:
                normal = self._project_normal(force_world / size)
        if normal is None and self._center is not None:
            # the surface model: a sphere of radius 1/kappa through the activation point
            toward = np.sign(settings.surface_curvature) * (self._center - state.ee_position)
            normal = self._project_normal(toward / max(float(np.linalg.norm(toward)), 1e-12))
        if normal is not None:
            self._normal = normal
        n = self._normal
        f_meas = 0.0 if force_world is None else float(n @ force_world)
        f_des = self._force_desired(state, now, notes, flags)
        if self._force_active and not self._wrench_fresh(latest, stamp):
            # no force sensing: neither push blind (into free space, maybe) nor count the missing
            # force as "no contact" (a sensor stream that starts late is not a lost contact)
            flags.add(ForceControlState.WRENCH_STALE)
            age = (
                "none yet"
                if latest is None
                else f"newest {(stamp - latest.stamp) * 1e-9:.3f} s old"
            )
            notes.append(
                f"no fresh wrist_wrench ({age}, wrench_timeout {settings.wrench_timeout:g} s): "
                f"force task paused at f_des 0 N (setpoint {f_des:.3g} N)"
            )
            f_meas, f_des = 0.0, 0.0
        fault = self.monitor.update(stamp, self._force_active, f_des, f_meas, latest)
        if fault is not None and not self._holding:
            self._force_active = False  # the force task stops; pure motion control holds
            self._holding = True
            self._hold(state)
        ignored = 0.0
        if fault is None:
            target, feedforward, ignored = self._twist_target(state, stamp, now, notes, flags)
            lin, lin_a = _rate_limit(
                self._v_des[:3],
                target[:3],
                feedforward[:3],
                dt,
                settings.max_linear_acceleration,
            )
            ang, ang_a = _rate_limit(
                self._v_des[3:],
                target[3:],
                feedforward[3:],
                dt,
                settings.max_angular_acceleration,
            )
            v_des, a_des = np.concatenate([lin, ang]), np.concatenate([lin_a, ang_a])
            mean = 0.5 * (self._v_des + v_des)
            self._p_des = self._p_des + mean[:3] * dt
            self._r_des = pin.exp3(mean[3:] * dt) @ self._r_des
            self._v_des = v_des
            tangent = v_des[:3] - float(n @ v_des[:3]) * n
            size = float(np.linalg.norm(tangent))
            if size > 1e-9:
                self._tangent = tangent / size
            task = self._contact_task(n)
        else:
            v_des, a_des = np.zeros(6), np.zeros(6)
            task = self._free_task
        rows = list(settings.rows)
        error = task.pose_error(state, self._p_des, self._r_des)
        speed = float(np.max(np.abs(state.v)))
        self.peak_joint_speed = max(self.peak_joint_speed, speed)
        position_error = self._p_des - state.ee_position
        orientation_error = (
            float(np.linalg.norm(pin.log3(self._r_des @ rotation.T))) if self._orientation else 0.0
        )
        contact = self.monitor.contact(f_meas)

        def result(torque, state_, detail, f_ref=0.0, saturated=()):
            return ForceStep(
                torque,
                state_,
                detail,
                stamp * 1e-9,
                position_error,
                orientation_error,
                f_des,
                f_meas,
                f_ref,
                speed,
                n.copy(),
                self._force_active,
                contact,
                tuple(saturated),
                ignored,
            )

        try:
            a_ref = motion_loop(
                self.motion_gains, a_des[rows], v_des[rows], task.velocity(state), error
            )
            a_n = None
            if task.k:
                p_dot = state.jacobian[:3] @ state.v
                a_n = [normal_acceleration(settings.surface_curvature, n, p_dot)]
            if self.reversed_model is not None:
                command = rns_control(
                    state, task, self.reversed_model, a_ref, normal_acceleration=a_n
                )
            else:
                command = os_control(
                    state, task, a_ref, variant=settings.os_variant, normal_acceleration=a_n
                )
            torque, f_ref = command.torque, 0.0
            if task.k:
                f_ref = self._force_loop(state, n, f_des, f_meas, exact, measurement, command)
                torque = torque + self._push * f_ref
        except (RnsError, np.linalg.LinAlgError) as exc:
            return result(None, ForceControlState.CONTROL_ERROR, f"control step failed: {exc}")
        if not np.isfinite(torque).all() or not np.isfinite(f_ref):
            return result(
                None,
                ForceControlState.NON_FINITE,
                "the law produced a non-finite torque: nothing published",
            )
        clipped = np.clip(torque, -self.effort_limits, self.effort_limits)
        saturated = [self.robot.joint_names[i] for i in np.flatnonzero(clipped != torque)]
        if saturated:
            flags.add(ForceControlState.TORQUE_LIMITED)
            notes.append(f"torque clipped to the effort limits of {', '.join(saturated)}")
        if fault is not None:
            notes.insert(0, fault[1] + "; force task stopped, holding the pose")
            state_ = fault[0]
        else:
            state_ = next((s for s in _PRIORITY if s in flags), ForceControlState.OK)
        return result(clipped, state_, "; ".join(notes), f_ref, saturated)

    def _contact_task(self, n: np.ndarray) -> TaskSpace:
        """TaskSpace.from_contact along n with the current tangent, rebuilt only when n or the
        tangent direction changed (building it costs as much as the rest of the task code)."""
        t = self._tangent
        if t is not None:
            t = t - float(n @ t) * n
            t = t / np.linalg.norm(t) if np.linalg.norm(t) > 1e-9 else None
        cached = self._task
        if (
            cached is not None
            and np.array_equal(cached[1], n)
            and (t is None or (cached[2] is not None and np.abs(cached[2] - t).max() < 1e-9))
        ):
            return cached[0]
        task = TaskSpace.from_contact(self.settings.rows, n, t)
        self._task = (task, n.copy(), None if t is None else t.copy())
        return task

    def _wrench_fresh(self, latest: WrenchSample | None, stamp: int) -> bool:
        """The wrist wrench watchdog, by stamps: a sample at most wrench_timeout [s] older than
        the state (stamp [ns])."""
        timeout_ns = self.settings.wrench_timeout * 1e9
        return latest is not None and stamp - latest.stamp <= timeout_ns

    def _force_loop(self, state, n, f_des, f_meas, exact, measurement, command) -> float:
        """f_ref of (6.34) (predicted or sampled); sets self._push = J_v^T n."""
        model = RigidContactModel.at(state, n)
        self._push = model.push
        k_f = self.force_gains.k_f
        if self.settings.force_measurement is ForceMeasurementMode.SAMPLED:
            return float(force_loop(self.force_gains, [f_des], [f_meas])[0])
        held = measurement.effort
        if exact is not None and held is not None and np.isfinite(held).all():
            measured = float(n @ (state.ee_rotation @ exact.force))
            self._beta = measured - model.force(np.asarray(held, dtype=float))
        lambda_0 = model.force(command.torque) + self._beta
        f_ref = force_reference(f_des, lambda_0, k_f)
        if f_meas < self.settings.contact_threshold:
            # approach: no contact measured, the rigid-contact prediction does not hold in free
            # space; push with at most the setpoint (the feed-forward) until contact is made
            f_ref = min(f_ref, f_des)
        return f_ref


#: Which state to report when several apply (highest first; safety stops come before these).
_PRIORITY = (
    ForceControlState.INVALID_COMMAND,
    ForceControlState.TORQUE_LIMITED,
    ForceControlState.WRENCH_STALE,
    ForceControlState.FORCE_SETPOINT_STALE,
    ForceControlState.SPEED_LIMITED,
    ForceControlState.HOLDING,
)


__all__ = [
    "ERROR_LABELS",
    "SAFETY_STOPS",
    "CommandFrame",
    "ConstrainedFrame",
    "ControlMethod",
    "ForceControlSettings",
    "ForceControlState",
    "ForceMeasurementMode",
    "ForceSetpoint",
    "ForceStep",
    "ForceTeleopController",
    "JointMeasurement",
    "NormalMode",
    "RigidContactModel",
    "SafetyMonitor",
    "TwistCommand",
    "WrenchSample",
    "command_frames",
    "force_reference",
    "normal_acceleration",
    "parse_task_axes",
    "predicted_contact_force",
    "validate_force_setpoint",
    "validate_twist",
]
