"""rns_force_controller: operator twist + force setpoint in, joint torques out (thesis chapter 6).

RNS-C or OS-C on a fixed-base arm whose end effector (EE) touches a rigid surface: motion along
the surface from the operator twist, force along its normal from the force setpoint. The law is
:class:`rns_ros.control.force.controller.ForceTeleopController`; this node converts messages and
runs one step per received ``joint_states`` (event-driven). Contract: docs/part2_ros.md.

With ``await_commands`` (``use_sim_time`` only: lockstep with the simulator) the operator is in
the lockstep too: it publishes its samples ahead of simulated time, stamped with their instants
(``rns_operator``'s ``lead``), and the step of a state stamped t waits until the commands in
force at t are known on both streams (a cmd_twist and a force_setpoint stamped at or after t, or
a stream that has sent nothing yet), then applies the commands stamped up to t and runs
(:class:`rns_ros.control.ticks.AwaitedTicks`). A lockstep simulator waits for that step's
torque, so which command a step sees no longer depends on when the operator's process got a
core. A steady-clock watchdog of ``command_timeout`` gives up waiting (an operator that stopped
or stalled): the step runs with the newest commands, whose ages (simulated time) then stop the
motion as without ``await_commands``.

Subscribes:
    joint_states    sensor_msgs/JointState (by name, other joints ignored; position, velocity,
                    effort = the torque held over the step that ended there); reliable, depth
                    10; triggers the step
    wrist_wrench    geometry_msgs/WrenchStamped, EE axes (frame_id the EE frame, "" or "ee";
                    world_frame also accepted), the wrench the EE exerts on the environment;
                    reliable, depth 10; matched to the state of the same stamp
    cmd_twist       geometry_msgs/TwistStamped (world or EE axes); best effort, depth 1 (50 with
                    ``await_commands``)
    force_setpoint  geometry_msgs/WrenchStamped (world or EE axes, "" = EE); best effort, depth 1
                    (50 with ``await_commands``)
Publishes:
    joint_efforts   std_msgs/Float64MultiArray, torques [N m] in the ``joints`` order, one per
                    state; one zero torque when the state goes stale and at shutdown
    ~/errors        std_msgs/Float64MultiArray, layout label " ".join(ERROR_LABELS), one per step
    ~/status        diagnostic_msgs/DiagnosticArray at ``status_rate``
    /diagnostics    the newest status at 1 Hz
Service:
    ~/reset         std_srvs/Trigger: clears a latched safety stop, re-latches the reference at
                    the current pose (the force task waits for a new force setpoint)

Input ages (state_timeout, command_timeout, force_timeout) are receipt times on the node clock
under ``use_sim_time`` (simulated time: a delayed or paused simulation ages nothing), else
monotonic wall time (:class:`InputClock`). Under ``use_sim_time`` a /clock that stands still for
``clock_timeout`` of wall time with no joint_states meanwhile (a dead simulator) is a stale state.
"""

from __future__ import annotations

import time
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from std_srvs.srv import Trigger

from rns_ros.control.contact_topics import ERROR_LABELS
from rns_ros.control.force.commands import (
    JointMeasurement,
    WrenchSample,
    command_frames,
    validate_force_setpoint,
    validate_twist,
)
from rns_ros.control.force.controller import ForceTeleopController
from rns_ros.control.force.settings import CommandFrame, ForceControlSettings
from rns_ros.control.force.status import ForceControlState, ForceStep
from rns_ros.control.ticks import AwaitedTicks, ServedTick
from rns_ros.core.commands import ExtraJointsReport, joint_state_order, match_joint_state
from rns_ros.core.errors import ConfigError, InputError, RnsError
from rns_ros.core.fixed_base import load_fixed_base_model
from rns_ros.nodes import force_controller_parameters
from rns_ros.nodes.force_controller_parameters import DEFAULT_MODEL, await_commands_problem
from rns_ros.nodes.input_clock import InputClock, awaited_commands
from rns_ros.nodes.parameters import declare_parameters, from_parameters, velocity_joint_order
from rns_ros.nodes.runner import publish_last, run_node
from rns_ros.nodes.status import status_text
from rns_ros.resources import config_dir

#: Period of the stale-state check [s] (wall clock; it judges ages on the input clock) and of
#: /diagnostics [s].
WATCHDOG_PERIOD, DIAGNOSTICS_PERIOD = 0.05, 1.0
#: Window of the step-time statistics [s] (wall clock: they measure the CPU cost of a step).
STEP_TIME_WINDOW = 1.0
#: The command streams a step waits for under await_commands (equal stamps apply in this order).
TWIST_STREAM, FORCE_STREAM = "cmd_twist", "force_setpoint"
#: cmd_twist and force_setpoint under await_commands: best effort (matches the operators'
#: best-effort publishers), deep enough for the samples an operator publishes ahead (each is one
#: instant of its profile: none may be overwritten before it is read).
SCHEDULED_COMMAND_QOS = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
#: await_commands: states waiting for their commands beyond this many are a simulation that no
#: longer waits for the torques (in lockstep one state waits: the simulator pauses for its
#: torque); waiting on would only pile up steps on old states, so it is given up at once.
MAX_WAITING_STEPS = 50
_ERROR = {
    ForceControlState.INVALID_COMMAND,
    ForceControlState.WRENCH_LIMIT,
    ForceControlState.CONTACT_LOST,
    ForceControlState.NO_CONTACT,
    ForceControlState.STALE_STATE,
    ForceControlState.NON_FINITE,
    ForceControlState.CONTROL_ERROR,
}
_OK = {ForceControlState.OK, ForceControlState.HOLDING}


def state_level(state: ForceControlState) -> bytes:
    """DiagnosticStatus level of a :class:`ForceControlState`."""
    if state in _ERROR:
        return DiagnosticStatus.ERROR
    return DiagnosticStatus.OK if state in _OK else DiagnosticStatus.WARN


def _model_path(name: str) -> Path:
    if not name:
        return config_dir() / DEFAULT_MODEL
    path = Path(name)
    if path.is_file() or path.is_absolute():
        return path
    return config_dir() / name


def _stamp_ns(stamp) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


class ForceControllerNode(Node):
    """ROS 2 wrapper of :class:`ForceTeleopController` (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(force_controller_parameters.NODE_NAME, **node_kwargs)
        params = declare_parameters(self, force_controller_parameters.PARAMETERS)
        self._params = params
        self.robot = load_fixed_base_model(_model_path(params["model_config"]))
        self.settings = from_parameters(ForceControlSettings, params)
        self.controller = ForceTeleopController(self.robot, self.settings)
        # ros2_control convention: data[p[i]] is model joint i
        self._order = velocity_joint_order(params["joints"], self.robot.joint_names)
        self._ee_frame = self.robot.model.frames[self.robot.ee_frame_id].name
        self._frames = command_frames(params["world_frame"], self._ee_frame)
        self._state_timeout = params["state_timeout"]
        problem = await_commands_problem(
            params["await_commands"], bool(self.get_parameter("use_sim_time").value)
        )
        if problem is not None:
            raise ConfigError(problem)
        self._input_clock = InputClock(self, params["clock_timeout"], self._on_clock_stopped)
        # receipt time of the newest joint state [s] on the input clock (simulated time under
        # use_sim_time), and monotonic [s] (the /clock watch)
        self._state_received: float | None = None
        self._state_received_wall = -np.inf
        self._stepped_wall = -np.inf  # monotonic time of the newest control step [s]
        self._stale = False  # the zero torque of a stale state was published
        self._published = False  # any torque published (then shutdown publishes zero)
        self._step: ForceStep | None = None
        self._step_times: deque[tuple[float, float]] = deque()  # (monotonic, duration [s])
        self._status_override: tuple[ForceControlState, str] | None = None
        self._last_status: DiagnosticStatus | None = None
        self._last_state: ForceControlState | None = None

        # await_commands: the steps waiting for their commands, and the states they step on
        self._awaited = self._awaited_steps(params)
        self._pending: deque[JointMeasurement] = deque()
        self._moving_twist = False  # the newest cmd_twist scheduled asks for motion

        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        command_qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        if self._awaited is not None:
            command_qos = SCHEDULED_COMMAND_QOS
        self._extra_joints = ExtraJointsReport()  # joint_states names beyond the model's
        self.create_subscription(JointState, "joint_states", self._on_joint_state, reliable)
        self.create_subscription(WrenchStamped, "wrist_wrench", self._on_wrench, reliable)
        self.create_subscription(TwistStamped, "cmd_twist", self._on_twist, command_qos)
        self.create_subscription(WrenchStamped, "force_setpoint", self._on_setpoint, command_qos)
        self._torque_pub = self.create_publisher(Float64MultiArray, "joint_efforts", command_qos)
        self._errors_pub = self.create_publisher(Float64MultiArray, "~/errors", reliable)
        self._status_pub = self.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self._diagnostics = self.create_publisher(
            DiagnosticArray, "/diagnostics", QoSProfile(depth=10)
        )
        self.create_service(Trigger, "~/reset", self._on_reset)
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.create_timer(WATCHDOG_PERIOD, self._on_watchdog, clock=steady)
        self.create_timer(1.0 / params["status_rate"], self._publish_status, clock=steady)
        self.create_timer(DIAGNOSTICS_PERIOD, self._on_diagnostics, clock=steady)
        self._state_topic = self.resolve_topic_name("joint_states")
        self.get_logger().info(
            f"{self.settings.method.value} motion/force control of {self.robot.name} "
            f"(task {list(self.settings.task_axes)}, normal {self.settings.normal_mode.value}, "
            f"force {self.settings.force_measurement.value}, k_f {self.settings.k_f:g}"
            f"{', awaiting the commands' if self._awaited is not None else ''}); "
            f"waiting for {self._state_topic}"
        )

    def _awaited_steps(self, params: dict) -> AwaitedTicks[Any] | None:
        """await_commands: the steps waiting for both command streams, at most command_timeout
        of wall time after the operator's last sample; None when not used."""
        if not params["await_commands"]:
            return None
        return awaited_commands(
            self,
            params["command_timeout"],
            self._on_await_timeout,
            streams=(TWIST_STREAM, FORCE_STREAM),
        )

    # --- inputs ---------------------------------------------------------------------------------
    def _on_twist(self, msg: TwistStamped) -> None:
        if self._awaited is not None:
            self._moving_twist = any(
                value != 0.0
                for vector in (msg.twist.linear, msg.twist.angular)
                for value in (vector.x, vector.y, vector.z)
            )
            self._schedule(TWIST_STREAM, msg)
            return
        self._take_twist(msg, self._input_clock.now())

    def _on_setpoint(self, msg: WrenchStamped) -> None:
        if self._awaited is not None:
            self._schedule(FORCE_STREAM, msg)
            return
        self._take_setpoint(msg, self._input_clock.now())

    def _take_twist(self, msg: TwistStamped, now: float) -> None:
        """A cmd_twist received (taken to act) at ``now`` [s] on the input clock."""
        lin, ang = msg.twist.linear, msg.twist.angular
        self._command(
            "cmd_twist",
            lambda: validate_twist(
                [lin.x, lin.y, lin.z],
                [ang.x, ang.y, ang.z],
                msg.header.frame_id,
                self._frames,
                self.settings.default_twist_frame,
                _stamp_ns(msg.header.stamp),
                now,
            ),
            self.controller.set_twist,
            self.controller.reject_twist,
        )

    def _take_setpoint(self, msg: WrenchStamped, now: float) -> None:
        """A force_setpoint received (taken to act) at ``now`` [s] on the input clock."""
        f, m = msg.wrench.force, msg.wrench.torque
        self._command(
            "force_setpoint",
            lambda: validate_force_setpoint(
                [f.x, f.y, f.z],
                [m.x, m.y, m.z],
                msg.header.frame_id,
                self._frames,
                now,
            ),
            self.controller.set_force,
            self.controller.reject_force,
        )

    def _schedule(self, stream: str, msg: TwistStamped | WrenchStamped) -> None:
        """await_commands: a command held until its stamp; runs the steps it makes ready.

        Every command counts as moving (:meth:`CommandSchedule.ready`): nothing ends a
        motion/force stream but its silence (a held force setpoint is an order, and a zero
        twist between two strokes is a sample like any other), so each is waited for and the
        end of a scenario is found by the watchdog, once."""
        dropped = sum(schedule.dropped for schedule in self._awaited.schedules.values())
        ready = self._awaited.push(_stamp_ns(msg.header.stamp), msg, moving=True, stream=stream)
        if sum(schedule.dropped for schedule in self._awaited.schedules.values()) > dropped:
            self.get_logger().warn(
                f"too many {stream} stamped ahead are waiting for their stamps: the oldest was "
                "dropped (stamps far ahead of the clock?)",
                throttle_duration_sec=1.0,
            )
        self._serve_ready(ready)

    def _on_await_timeout(self) -> None:
        """await_commands: no command came for command_timeout (wall clock) on a stream a step
        waits for: the operator stopped (its scenario ended) or stalled; the waiting steps run
        with the newest commands (whose ages then stop the motion as usual)."""
        waiting = self._awaited.oldest_waiting
        if waiting is not None:
            streams = " / ".join(self._awaited.awaited_streams())
            text = (
                f"no {streams} stamped at or after {waiting * 1e-9:.3f} s within command_timeout "
                f"({self._params['command_timeout']} s wall clock): stepping on with the newest"
            )
            if self._moving_twist:
                self.get_logger().warn(f"{text} (the operator stalled?)", throttle_duration_sec=1.0)
            else:
                self.get_logger().info(f"{text} (the operator's twists ended at rest)")
        self._serve_ready(self._awaited.give_up())

    def _serve_ready(self, steps: list[ServedTick[Any]]) -> None:
        """await_commands: the steps whose commands in force are known, in order, each after
        the commands stamped up to its state, taken to act at its stamp (the simulated instant
        the torque acts at in lockstep; a command's age then counts from there)."""
        for served in steps:
            measurement = self._pending.popleft()
            now = served.instant * 1e-9
            for msg in served.commands:
                if isinstance(msg, TwistStamped):
                    self._take_twist(msg, now)
                else:
                    self._take_setpoint(msg, now)
            self._control_step(measurement, now)

    def _command(self, topic: str, validate, accept, reject) -> None:
        """``accept(validate())``; an InputError goes to ``reject`` (the status) and the log."""
        try:
            command = validate()
        except InputError as exc:
            reject(str(exc))
            self.get_logger().error(f"rejected {topic}: {exc}", throttle_duration_sec=1.0)
            return
        accept(command)

    def _on_wrench(self, msg: WrenchStamped) -> None:
        f, m = msg.wrench.force, msg.wrench.torque
        force, torque = np.array([f.x, f.y, f.z]), np.array([m.x, m.y, m.z])
        frame = msg.header.frame_id
        if not (np.isfinite(force).all() and np.isfinite(torque).all()):
            self.get_logger().error("ignored wrist_wrench: not finite", throttle_duration_sec=1.0)
            return
        if frame in ("", self._ee_frame) or self._frames.get(frame) is CommandFrame.EE:
            pass
        elif self._frames.get(frame) is CommandFrame.WORLD:
            if self.controller.ee_rotation is None:
                return
            rotation = self.controller.ee_rotation  # the newest state's EE rotation
            force, torque = rotation.T @ force, rotation.T @ torque
        else:
            self.get_logger().error(
                f"ignored wrist_wrench in frame {frame!r}: expected the EE frame "
                f"{self._ee_frame!r}",
                throttle_duration_sec=1.0,
            )
            return
        self.controller.add_wrench(WrenchSample(_stamp_ns(msg.header.stamp), force, torque))

    def _on_joint_state(self, msg: JointState) -> None:
        try:
            state, extras = match_joint_state(
                msg.name, self.robot.joint_names, positions=msg.position, velocities=msg.velocity
            )
            if state.positions is None or state.velocities is None:
                raise InputError(
                    f"joint_states needs positions and velocities of {self.robot.n} joints, got "
                    f"{len(msg.position)} and {len(msg.velocity)} values"
                )
            order, _ = joint_state_order(msg.name, self.robot.joint_names)
            effort = np.asarray(msg.effort, dtype=float)
            effort = effort[order] if effort.size == len(msg.name) else None
        except InputError as exc:
            self.get_logger().error(f"ignored joint_states: {exc}", throttle_duration_sec=1.0)
            return
        note = self._extra_joints.note(extras)
        if note is not None:
            self.get_logger().info(note)
        stamp = _stamp_ns(msg.header.stamp)
        now = self._input_clock.receipt_time(stamp * 1e-9)
        if self._stale:
            self.get_logger().info("joint_states resumed: reference re-latched at the pose")
            self.controller.resync()
        self._stale = False
        self._state_received, self._state_received_wall = now, time.monotonic()
        measurement = JointMeasurement(stamp, state.positions, state.velocities, effort)
        if self._awaited is None:
            self._control_step(measurement, now)
            return
        self._pending.append(measurement)
        self._serve_ready(self._awaited.tick(stamp))
        if len(self._pending) > MAX_WAITING_STEPS:
            self.get_logger().warn(
                f"{len(self._pending)} joint_states wait for their commands: the simulation "
                "does not wait for the torques (no lockstep?); stepping on with the newest",
                throttle_duration_sec=1.0,
            )
            self._serve_ready(self._awaited.give_up())

    def _control_step(self, measurement: JointMeasurement, now: float) -> None:
        """One control step on ``measurement``: the torque, ~/errors, the step time; ``now``
        [s] on the input clock (command ages)."""
        wall = self._stepped_wall = time.monotonic()
        started = time.perf_counter()
        try:
            step = self.controller.step(measurement, now)
        except RnsError as exc:
            self._status_override = (ForceControlState.CONTROL_ERROR, str(exc))
            self.get_logger().error(f"control step failed: {exc}", throttle_duration_sec=1.0)
            return
        if step.torque is not None:
            self._publish_torque(step.torque)
        self._step_times.append((wall, time.perf_counter() - started))
        while self._step_times and self._step_times[0][0] < wall - STEP_TIME_WINDOW:
            self._step_times.popleft()
        self._step, self._status_override = step, None
        self._publish_errors(step)
        if step.state is not self._last_state:
            self._log_transition(step)
        self._last_state = step.state

    def _log_transition(self, step: ForceStep) -> None:
        text = f"{step.state.value}: {step.detail}" if step.detail else step.state.value
        level = state_level(step.state)
        if level == DiagnosticStatus.ERROR:
            self.get_logger().error(text)
        elif level == DiagnosticStatus.WARN:
            self.get_logger().warn(text)
        elif step.detail:
            self.get_logger().info(text)

    # --- outputs --------------------------------------------------------------------------------
    def _publish_torque(self, torque: np.ndarray) -> None:
        data = np.empty(torque.size)
        data[self._order] = torque
        if not np.isfinite(data).all():  # never publish a non-finite value
            return
        self._torque_pub.publish(Float64MultiArray(data=data.tolist()))
        self._published = True

    def _publish_errors(self, step: ForceStep) -> None:
        values = step.error_sample()
        if not np.isfinite(values).all():
            return
        msg = Float64MultiArray(data=values.tolist())
        msg.layout.dim = [
            MultiArrayDimension(label=" ".join(ERROR_LABELS), size=len(values), stride=len(values))
        ]
        self._errors_pub.publish(msg)

    def _on_watchdog(self) -> None:
        if self._state_received is None or self._stale:
            return
        age = self._input_clock.now() - self._state_received
        if age <= self._state_timeout:
            return
        self._motors_off(
            f"{self._state_topic} {age:.3f} s old (state_timeout {self._state_timeout} s)"
        )

    def _motors_off(self, reason: str) -> None:
        """A stale state (``reason``): one zero torque, STALE_STATE, one error log."""
        self._stale = True
        detail = f"{reason}: one zero torque published (motors off)"
        self._status_override = (ForceControlState.STALE_STATE, detail)
        self.get_logger().error(f"STALE_STATE: {detail}")
        self._publish_torque(np.zeros(self.robot.n))
        self._publish_status()

    def _on_clock_stopped(self, still: float) -> None:
        """use_sim_time: /clock has stood still for ``still`` [s] of wall time. When no joint
        state came and no step ran for as long either (a dead simulator) after torques were
        published, the
        motors go off as on a stale state: with simulated time standing still, the state's age
        does not grow. Later calls while it stands still only update the status. A step that
        waits for the operator's commands (await_commands) holds the clock itself: that wait
        has its own watchdog, and the quiet counts from its end (the simulator has not had the
        step's torque before)."""
        if self._awaited is not None and self._awaited.oldest_waiting is not None:
            return
        quiet = time.monotonic() - max(self._state_received_wall, self._stepped_wall)
        if not self._published or quiet < self._input_clock.timeout:
            return
        reason = (
            f"/clock stood still for {still:.3f} s (clock_timeout "
            f"{self._params['clock_timeout']} s wall time)"
        )
        if not self._stale:
            self._motors_off(reason)
            return
        override = self._status_override
        if override is not None and override[1].startswith("/clock"):
            self._status_override = (override[0], f"{reason}: motors off")

    def _validate_parameters(self, parameters) -> SetParametersResult:
        """On set: refuse a use_sim_time (or await_commands) that leaves await_commands on the
        wall clock (the reason says why)."""
        values = {parameter.name: parameter.value for parameter in parameters}
        problem = await_commands_problem(
            bool(values.get("await_commands", self._params["await_commands"])),
            bool(values.get("use_sim_time", self.get_parameter("use_sim_time").value)),
        )
        if problem is not None:
            return SetParametersResult(successful=False, reason=problem)
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters) -> None:
        """After a set: the run-time parameters (clock_timeout) take their new values."""
        for parameter in parameters:
            if parameter.name == "clock_timeout":
                self._params["clock_timeout"] = parameter.value
                self._input_clock.set_clock_timeout(parameter.value)

    def _step_time_stats(self) -> tuple[float, float]:
        if not self._step_times:
            return 0.0, 0.0
        durations = np.array([d for _, d in self._step_times]) * 1e6
        return float(np.median(durations)), float(np.percentile(durations, 99))

    def _publish_status(self) -> None:
        step = self._step
        values: dict = {"method": self.settings.method.value}
        if self._status_override is not None:
            state, detail = self._status_override
        elif step is None:
            state, detail = ForceControlState.WAITING_FOR_STATE, f"waiting for {self._state_topic}"
        else:
            state, detail = step.state, step.detail
        if step is not None:
            median, p99 = self._step_time_stats()
            values.update(
                position_error_m=float(np.linalg.norm(step.position_error)),
                orientation_error_rad=step.orientation_error,
                force_error_N=step.force_error,
                force_desired_N=step.force_desired,
                force_measured_N=step.force_measured,
                force_reference_N=step.force_reference,
                force_active=step.force_active,
                contact=step.contact,
                normal=step.normal,
                peak_joint_speed_rad_s=self.controller.peak_joint_speed,
                step_time_us=median,
                step_time_p99_us=p99,
            )
        level = state_level(state)
        status = DiagnosticStatus(
            level=level,
            name=f"{self.get_name()}: motion/force control",
            message=f"{state.value}: {detail}" if detail else state.value,
            hardware_id=self.robot.name,
            values=[
                KeyValue(key=key, value=status_text(value))
                for key, value in {"state": state.value, "detail": detail, **values}.items()
            ],
        )
        self._last_status = status
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._status_pub.publish(msg)

    def _on_diagnostics(self) -> None:
        if self._last_status is None:
            return
        msg = DiagnosticArray(status=[self._last_status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics.publish(msg)

    def _on_reset(self, _request, response):
        fault = self.controller.fault
        self.controller.reset()
        response.success = True
        response.message = (
            f"cleared {fault[0].value}; reference re-latched at the next state, the force task "
            "waits for a new force_setpoint"
            if fault
            else "no safety stop latched; reference re-latched at the next state"
        )
        self.get_logger().info(f"~/reset: {response.message}")
        return response

    def destroy_node(self) -> None:
        """Motors off: one zero torque (when torques were published), then tear down."""
        if self._published:
            publish_last(
                self,
                lambda: self._torque_pub.publish(Float64MultiArray(data=[0.0] * self.robot.n)),
                "zero torque",
                acked_by=self._torque_pub,
                timeout=0.2,
            )
        super().destroy_node()


def main(args=None) -> int:
    return run_node(ForceControllerNode, force_controller_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
