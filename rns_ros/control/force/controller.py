"""The force controller step: operator motion/force teleoperation of a fixed-base arm in
contact, one control step per measured joint state (docs/part2_ros.md, "One step")."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin

from rns_ros.control.force.commands import (
    ForceSetpoint,
    JointMeasurement,
    TwistCommand,
    WrenchSample,
)
from rns_ros.control.force.contact_model import (
    RigidContactModel,
    force_reference,
    normal_acceleration,
)
from rns_ros.control.force.reference import (
    REPORT_TOLERANCE,
    TwistTrack,
    held_twist,
    in_world,
    limit_speed,
    rate_limit,
    remove_constrained,
)
from rns_ros.control.force.safety import SafetyMonitor
from rns_ros.control.force.settings import (
    MAX_STEP,
    ConstrainedFrame,
    ControlMethod,
    ForceControlSettings,
    ForceMeasurementMode,
    NormalMode,
)
from rns_ros.control.force.status import PRIORITY, ForceControlState, ForceStep
from rns_ros.control.motion_force.osc import os_control
from rns_ros.control.motion_force.outer_loops import (
    ForceGains,
    MotionGains,
    force_loop,
    motion_loop,
)
from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.rnsc import rns_control
from rns_ros.control.motion_force.task_space import TaskSpace
from rns_ros.core.errors import InputError, RnsError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState

#: Wrench samples kept for matching by stamp.
WRENCH_HISTORY = 32


class ForceTeleopController:
    """Operator motion/force control of a fixed-base arm in contact, thesis chapter 6.

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
            self._law = self._rns_law
        else:
            self._law = self._os_law
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
        self._twist: TwistTrack | None = None
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
        self._twist = TwistTrack.following(self._twist, command)
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
        self._latch_pose(state)

    def _latch_pose(self, state: FixedBaseState) -> None:
        """The motion reference at rest at the measured EE pose."""
        self._p_des = state.ee_position.copy()
        self._r_des = state.ee_rotation.copy()
        self._v_des = np.zeros(6)

    def _twist_target(self, state, stamp: int, now: float, notes: list[str], flags: set):
        """(v target (6,), feed-forward a (6,), size of the removed components) in world axes."""
        settings, track = self.settings, self._twist
        if self._twist_rejection is not None:
            flags.add(ForceControlState.INVALID_COMMAND)
            notes.append(f"cmd_twist rejected: {self._twist_rejection}")
            return np.zeros(6), np.zeros(6), 0.0
        if track is None or now - track.command.received > settings.command_timeout:
            age = "no cmd_twist yet" if track is None else "cmd_twist stale"
            flags.add(ForceControlState.HOLDING)
            notes.append(f"{age}: holding the pose")
            return np.zeros(6), np.zeros(6), 0.0
        v, a = held_twist(track, settings, state.ee_rotation, stamp)
        removed = remove_constrained(v, a, settings.rows, self._normal)
        ignored = float(np.linalg.norm(removed))
        if ignored > REPORT_TOLERANCE:
            notes.append(
                f"ignored {np.linalg.norm(removed[:3]):.3g} m/s, {np.linalg.norm(removed[3:]):.3g}"
                " rad/s of cmd_twist along the force direction / non-task axes"
            )
        limit_speed(v, settings, notes, flags)
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
        force = in_world(setpoint.force, setpoint.frame, state.ee_rotation)
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
        """One control step at a measured state (stages: docs/part2_ros.md, "One step").

        Args:
            measurement: the joint state (model order) with its stamp [ns] and held effort.
            now: time [s] on the clock of the commands' receipt times (command ages).

        Raises:
            InputError: non-finite or wrongly shaped q / v.
        """
        state = FixedBaseState.compute(self.robot, measurement.q, measurement.v)
        stamp = int(measurement.stamp)
        notes: list[str] = []
        flags: set[ForceControlState] = set()
        dt = self._advance_clock(state, stamp)
        self._rotation = state.ee_rotation
        exact = self._wrenches.get(stamp)
        latest = exact or self._latest_wrench
        force_world = None if latest is None else self._rotation @ latest.force
        n = self._update_normal(state, force_world)
        f_meas = 0.0 if force_world is None else float(n @ force_world)
        f_des = self._force_desired(state, now, notes, flags)
        if self._force_active and not self._wrench_fresh(latest, stamp):
            f_meas, f_des = self._pause_push(latest, stamp, f_des, notes, flags)
        fault = self._supervise(state, stamp, f_des, f_meas, latest)
        ignored = 0.0
        if fault is None:
            v_des, a_des, ignored = self._follow_twist(state, stamp, now, dt, notes, flags)
            task = self._contact_task(n)
        else:
            v_des, a_des = np.zeros(6), np.zeros(6)
            task = self._free_task
        error = task.pose_error(state, self._p_des, self._r_des)
        report = self._report(state, stamp, f_des, f_meas, n, ignored)
        try:
            a_ref = motion_loop(
                self.motion_gains,
                a_des[list(self.settings.rows)],
                v_des[list(self.settings.rows)],
                task.velocity(state),
                error,
            )
            torque, f_ref = self._torque(state, task, n, a_ref, f_des, f_meas, exact, measurement)
        except (RnsError, np.linalg.LinAlgError) as exc:
            return dataclasses.replace(
                report, state=ForceControlState.CONTROL_ERROR, detail=f"control step failed: {exc}"
            )
        return self._finish(report, torque, f_ref, fault, notes, flags)

    def _advance_clock(self, state: FixedBaseState, stamp: int) -> float:
        """The step length dt [s] since the previous state (stamps [ns]); the first state
        latches the reference (and the normal) and steps ``nominal_period``."""
        if self._p_des is None:
            self._activate(state)
            dt = self.settings.nominal_period
        else:
            dt = min(max((stamp - self._stamp) * 1e-9, 0.0), MAX_STEP)
        self._stamp = stamp
        return dt

    def _update_normal(self, state: FixedBaseState, force_world) -> np.ndarray:
        """The contact normal n (3,), world: the measured push direction (``wrench`` mode),
        else the surface model; unchanged when neither gives one."""
        settings = self.settings
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
        return self._normal

    def _pause_push(self, latest, stamp: int, f_des: float, notes: list[str], flags: set):
        """(f_meas, f_des) = (0, 0) without a fresh wrist wrench: neither push blind (into free
        space, maybe) nor count the missing force as "no contact" (a sensor stream that starts
        late is not a lost contact)."""
        flags.add(ForceControlState.WRENCH_STALE)
        age = "none yet" if latest is None else f"newest {(stamp - latest.stamp) * 1e-9:.3f} s old"
        notes.append(
            f"no fresh wrist_wrench ({age}, wrench_timeout {self.settings.wrench_timeout:g} s): "
            f"force task paused at f_des 0 N (setpoint {f_des:.3g} N)"
        )
        return 0.0, 0.0

    def _supervise(self, state, stamp: int, f_des: float, f_meas: float, latest):
        """The safety monitor's latched fault; on a new one the force task stops and the arm
        holds its pose under pure motion control."""
        fault = self.monitor.update(stamp, self._force_active, f_des, f_meas, latest)
        if fault is not None and not self._holding:
            self._force_active = False
            self._holding = True
            self._latch_pose(state)
        return fault

    def _follow_twist(self, state, stamp: int, now: float, dt: float, notes, flags):
        """(v_des (6,), a_des (6,), ignored): the reference rate limited toward the operator
        twist and integrated over dt (trapezoidal position, exponential-map rotation)."""
        settings = self.settings
        target, feedforward, ignored = self._twist_target(state, stamp, now, notes, flags)
        lin, lin_a = rate_limit(
            self._v_des[:3],
            target[:3],
            feedforward[:3],
            dt,
            settings.max_linear_acceleration,
        )
        ang, ang_a = rate_limit(
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
        n = self._normal
        tangent = v_des[:3] - float(n @ v_des[:3]) * n
        size = float(np.linalg.norm(tangent))
        if size > 1e-9:
            self._tangent = tangent / size
        return v_des, a_des, ignored

    def _report(self, state, stamp: int, f_des: float, f_meas: float, n, ignored: float):
        """The step's record before the torque: no torque, state OK, f_ref 0."""
        speed = float(np.max(np.abs(state.v)))
        self.peak_joint_speed = max(self.peak_joint_speed, speed)
        orientation_error = 0.0
        if self._orientation:
            orientation_error = float(np.linalg.norm(pin.log3(self._r_des @ self._rotation.T)))
        return ForceStep(
            None,
            ForceControlState.OK,
            "",
            stamp * 1e-9,
            self._p_des - state.ee_position,
            orientation_error,
            f_des,
            f_meas,
            0.0,
            speed,
            n.copy(),
            self._force_active,
            self.monitor.contact(f_meas),
            (),
            ignored,
        )

    def _rns_law(self, state, task, a_ref, a_n):
        return rns_control(state, task, self.reversed_model, a_ref, normal_acceleration=a_n)

    def _os_law(self, state, task, a_ref, a_n):
        variant = self.settings.os_variant
        return os_control(state, task, a_ref, variant=variant, normal_acceleration=a_n)

    def _torque(self, state, task, n, a_ref, f_des, f_meas, exact, measurement):
        """(tau (n,) [N m], f_ref [N]): the motion torque of the law (with the normal
        feed-forward a_n on a curved surface) plus J_v^T n f_ref of the force loop."""
        a_n = None
        if task.k:
            p_dot = state.jacobian[:3] @ state.v
            a_n = [normal_acceleration(self.settings.surface_curvature, n, p_dot)]
        command = self._law(state, task, a_ref, a_n)
        torque, f_ref = command.torque, 0.0
        if task.k:
            f_ref = self._force_loop(state, n, f_des, f_meas, exact, measurement, command)
            torque = torque + self._push * f_ref
        return torque, f_ref

    def _finish(self, report: ForceStep, torque, f_ref: float, fault, notes, flags) -> ForceStep:
        """The record with the torque clipped to the effort limits (nothing when non-finite)
        and the state of highest priority."""
        if not np.isfinite(torque).all() or not np.isfinite(f_ref):
            return dataclasses.replace(
                report,
                state=ForceControlState.NON_FINITE,
                detail="the law produced a non-finite torque: nothing published",
            )
        clipped = np.clip(torque, -self.effort_limits, self.effort_limits)
        saturated = [self.robot.joint_names[i] for i in np.flatnonzero(clipped != torque)]
        if saturated:
            flags.add(ForceControlState.TORQUE_LIMITED)
            notes.append(f"torque clipped to the effort limits of {', '.join(saturated)}")
        if fault is not None:
            notes.insert(0, fault[1] + "; force task stopped, holding the pose")
            state = fault[0]
        else:
            state = next((s for s in PRIORITY if s in flags), ForceControlState.OK)
        return dataclasses.replace(
            report,
            torque=clipped,
            state=state,
            detail="; ".join(notes),
            force_reference=f_ref,
            saturated=tuple(saturated),
        )

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


__all__ = ["WRENCH_HISTORY", "ForceTeleopController"]
