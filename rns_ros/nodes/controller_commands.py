"""rns_controller's operator commands: the twists on ``cmd_twist`` (message side; command safety
is :class:`rns_ros.control.teleop.CommandGate`, the checks
:func:`rns_ros.control.teleop.validate_twist`) and the camera attitude they add up to.

``cmd_twist`` is geometry_msgs/TwistStamped (``twist_stamped: true``, taken serialized and read
from the bytes, :mod:`rns_ros.nodes.cdr`) or geometry_msgs/Twist. Each twist is validated (finite,
a known frame, its angular speed scaled to ``max_angular_speed``) and handed to the node; a
rejected one is handed to the gate (INVALID_COMMAND). With ``await_commands`` (use_sim_time,
``output_lead`` > 0, stamped twists) the operator is in the lockstep: twists wait for their
stamps and each tick for the twist in force (:class:`rns_ros.control.ticks.AwaitedTicks`), given
up after ``await_timeout`` of wall time without a sample.

:class:`CommandTracking` integrates the commanded rates over their stamps
(:class:`rns_ros.control.command_tracking.CommandedAttitude`) and gives each tick the correction
that keeps the camera on that integral (``tracking_gain``, ``tracking_max_correction``,
``tracking_max_error``; status ``tracking_error``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from geometry_msgs.msg import Twist, TwistStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from rns_ros.control.command_tracking import CommandedAttitude, TrackingSettings
from rns_ros.control.controller import TwistFrame
from rns_ros.control.teleop import ControllerState, TwistCommand, validate_twist
from rns_ros.control.ticks import AwaitedTicks, CommandSchedule, ServedTick
from rns_ros.core.conventions import rotation_from_quaternion
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.nodes.cdr import MalformedMessageError, TwistFields, read_twist_stamped
from rns_ros.nodes.controller_parameters import time_tags
from rns_ros.nodes.controller_status import TWISTS_RECEIVED, StatusReporter
from rns_ros.nodes.input_clock import InputClock, awaited_commands

#: Inputs: only the newest message matters; best effort also matches reliable publishers.
INPUT_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
#: Stamped cmd_twist: best effort (matches the operators' best-effort publishers), deep enough
#: for 1 s of a 50 Hz stream: the samples an operator publishes ahead, or those that come while
#: this node waits for a core (each is one instant of the commanded profile).
STAMPED_COMMAND_QOS = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
NS_PER_S = 1_000_000_000  # nanoseconds per second (message stamps)
#: Time-tagged twists waiting for their execution time at most: 100 s of a 100 Hz stream (the
#: oldest is dropped beyond, so a flood cannot grow the queue).
MAX_PENDING = 10_000
#: Gate states in which the camera follows the integral of the commanded rate (a fresh
#: command); in the others nothing is tracked and the tracking restarts at the camera.
TRACKED_STATES = (ControllerState.OK, ControllerState.RAMPING, ControllerState.SPEED_LIMITED)
#: Gate states in which the commanded attitude runs on without a correction: a stale command
#: (a stream delayed or thinned out on a loaded machine, whose stamps still tell what was
#: commanded, each for at most command_timeout) is stopped, and the camera catches up once
#: commands are fresh again.
COASTING_STATES = (ControllerState.DECELERATING, ControllerState.IDLE)


class OperatorTwists:
    """The ``cmd_twist`` subscription of ``node`` and, with ``await_commands``, the ticks that
    wait for it (module docstring).

    Args:
        node: the controller node.
        params: its parameter values (``twist_stamped``, ``await_commands``,
            ``max_angular_speed``, ``command_timeout``).
        lead: ``output_lead`` in use [s] (0 when not: no awaited ticks).
        frames: the accepted frame ids and their twist axes
            (:func:`rns_ros.control.teleop.twist_frame_ids`).
        input_clock: the clock a twist's receipt time is read on.
        reporter: counts the twists received and names the malformed ones.
        on_command: called with each valid command and its stamp [s] on the sender's clock
            (its receipt time when unstamped).
        reject: called with the reason when a twist is rejected.
        serve_ready: called with the ticks whose twist in force is known (await_commands).
    """

    def __init__(
        self,
        node: Node,
        params: dict,
        lead: float,
        frames: dict[str, TwistFrame],
        input_clock: InputClock,
        reporter: StatusReporter,
        on_command: Callable[[TwistCommand, float], None],
        reject: Callable[[str], None],
        serve_ready: Callable[[list[ServedTick[TwistFields]]], None],
    ) -> None:
        self._node, self._frames, self._input_clock = node, frames, input_clock
        self._reporter, self._on_command = reporter, on_command
        self._reject, self._serve_ready = reject, serve_ready
        self.max_angular_speed = params["max_angular_speed"]  # [rad/s]; parameter changes
        self.command_timeout = params["command_timeout"]  # [s]; parameter changes
        self.await_timeout = params["await_timeout"]  # [s] of wall time (await_commands)
        #: with execution_delay > 0: when a twist acts, which stamps are refused; else None
        self.time_tags = time_tags(params)
        if self.time_tags is not None and not params["twist_stamped"]:
            raise ConfigError("execution_delay > 0 needs twist_stamped: true (the issue time)")
        #: with await_commands: ticks wait for the twist in force; None when not used
        self.awaited = self._awaited_ticks(params, lead)
        #: time-tagged twists waiting for their execution time (without await_commands)
        self.pending: CommandSchedule[TwistFields] = CommandSchedule(MAX_PENDING)
        self.message_type = TwistStamped if params["twist_stamped"] else Twist
        if params["twist_stamped"]:
            # each stamped twist is one sample of what was commanded (the tracked integral,
            # the awaited ticks, the time tags): none may be overwritten before it is read, not
            # while this node stalls, nor when a link hands on several at once
            node.create_subscription(
                TwistStamped, "cmd_twist", self._on_stamped, STAMPED_COMMAND_QOS, raw=True
            )
        else:
            node.create_subscription(Twist, "cmd_twist", self._on_twist, INPUT_QOS)
        self.topic = node.resolve_topic_name("cmd_twist")

    def _awaited_ticks(self, params: dict, lead: float) -> AwaitedTicks[TwistFields] | None:
        """await_commands: ticks wait for the twist in force, at most await_timeout of wall
        time after the operator's last sample; None when not used."""
        if not params["await_commands"]:
            return None
        if not (lead and params["twist_stamped"]):
            self._node.get_logger().warn(
                "await_commands needs use_sim_time, output_lead > 0 and twist_stamped: not used"
            )
            return None
        return awaited_commands(self._node, self.await_timeout, self._on_await_timeout)

    def _on_stamped(self, data: bytes) -> None:
        try:
            fields = read_twist_stamped(data)
        except MalformedMessageError as exc:
            self._reporter.reject(self.topic, exc)
            return
        self._reporter.count(TWISTS_RECEIVED)
        if self.time_tags is not None:
            fields = self._time_tagged(fields)
            if fields is None:
                return
            if self.awaited is None:
                sec, nanosec = fields.stamp
                self.pending.push(sec * NS_PER_S + nanosec, fields, True)
                return
        if self.awaited is None:
            self.take(fields.angular, fields.linear, fields.frame_id, fields.stamp)
            return
        sec, nanosec = fields.stamp
        moving = any(value != 0.0 for value in (*fields.angular, *fields.linear))
        dropped = self.awaited.schedule.dropped
        ready = self.awaited.push(sec * NS_PER_S + nanosec, fields, moving)
        if self.awaited.schedule.dropped > dropped:
            self._node.get_logger().warn(
                "too many cmd_twist stamped ahead are waiting for their stamps: the oldest was "
                "dropped (stamps far ahead of the clock?)",
                throttle_duration_sec=1.0,
            )
        self._serve_ready(ready)

    def _time_tagged(self, fields: TwistFields) -> TwistFields | None:
        """A time-tagged twist with its stamp moved to its execution time (stamp +
        execution_delay), or None after refusing it (late, from the future, unstamped)."""
        sec, nanosec = fields.stamp
        stamp = sec * NS_PER_S + nanosec
        now = self._node.get_clock().now().nanoseconds
        refusal = (
            "a time-tagged cmd_twist needs its issue time in header.stamp"
            if stamp == 0
            else self.time_tags.refusal(stamp * 1e-9, now * 1e-9)
        )
        if refusal is not None:
            self._reject(f"cmd_twist refused: {refusal}")
            self._node.get_logger().error(
                f"cmd_twist stamped {stamp * 1e-9:.3f} s refused at {now * 1e-9:.3f} s: {refusal}",
                throttle_duration_sec=1.0,
            )
            return None
        acts = stamp + round(self.time_tags.execution_delay * NS_PER_S)
        return fields._replace(stamp=divmod(acts, NS_PER_S))

    def release_due(self, tick: int) -> None:
        """Time-tagged twists (without await_commands) whose execution time is at or before
        ``tick`` [ns]: taken in stamp order, the last one in force from this tick on."""
        for fields in self.pending.due(tick):
            self.take(fields.angular, fields.linear, fields.frame_id, fields.stamp)

    def _on_await_timeout(self) -> None:
        """await_commands: no twist came for await_timeout (wall clock) while ticks waited:
        the operator stalled or its stream ended on a motion; serve with the newest (the gate
        then stops a stale command as usual)."""
        waiting = self.awaited.oldest_waiting
        if waiting is not None:
            self._node.get_logger().warn(
                f"no cmd_twist stamped at or after {waiting * 1e-9:.3f} s within "
                f"await_timeout ({self.await_timeout} s wall clock): served "
                "with the newest one",
                throttle_duration_sec=1.0,
            )
        self._serve_ready(self.awaited.give_up())

    def _on_twist(self, msg: Twist) -> None:
        self._reporter.count(TWISTS_RECEIVED)
        a, v = msg.angular, msg.linear
        self.take([a.x, a.y, a.z], [v.x, v.y, v.z], "")

    def take(self, angular, linear, frame_id: str, stamp: tuple[int, int] | None = None) -> None:
        """An operator twist: ``angular`` [rad/s] and ``linear`` [m/s] (3,) in ``frame_id``,
        stamped ``stamp`` (sec, nanosec) on the sender's clock (None or zero: unstamped, its
        receipt time counts)."""
        try:
            command = validate_twist(
                angular,
                linear,
                frame_id,
                self._frames,
                self.max_angular_speed,
                self._input_clock.now(),
            )
        except InputError as exc:
            self._reject(str(exc))
            self._node.get_logger().error(f"rejected cmd_twist: {exc}", throttle_duration_sec=1.0)
            return
        if command.requested_speed is not None:
            self._node.get_logger().warn(
                f"cmd_twist |angular| {command.requested_speed:.4g} rad/s is over "
                f"max_angular_speed {self.max_angular_speed:.4g} rad/s: scaled to it "
                "(axis kept)",
                throttle_duration_sec=1.0,
            )
        seconds = None if stamp is None else stamp[0] + 1e-9 * stamp[1]
        self._on_command(command, seconds or command.received)


class CommandTracking:
    """The camera attitude the operator's commanded rates add up to, and each tick's correction
    toward it (module docstring).

    Args:
        node: the controller node (its log).
        settings: the tracking settings (parameter changes replace :attr:`settings`).
    """

    def __init__(self, node: Node, settings: TrackingSettings) -> None:
        self._node = node
        self.attitude = CommandedAttitude(settings)
        self.error = 0.0  # the last gap between the camera and the commanded attitude [rad]

    @property
    def settings(self) -> TrackingSettings:
        return self.attitude.settings

    @settings.setter
    def settings(self, settings: TrackingSettings) -> None:
        self.attitude.settings = settings

    def take(self, command: TwistCommand, stamp: float, base_orientation: np.ndarray) -> None:
        """A valid operator ``command`` stamped ``stamp`` [s] (the sender's clock, else its
        receipt time), its frame's axes taken at the base orientation (unit quaternion x y z w
        (4,)) of now."""
        self.attitude.take(
            command.angular,
            command.frame,
            stamp,
            command.received,
            rotation_from_quaternion(base_orientation),
        )

    def stop(self, now: float) -> None:
        """Nothing is tracked from ``now`` [s] (input clock) until the next restart."""
        self.attitude.stop(now)

    def correction(
        self,
        camera_rotation: np.ndarray,
        gate_state: ControllerState,
        goal: bool,
        now: float,
        lead: float,
    ) -> np.ndarray:
        """omega_corr [rad/s] (3,), world axes, that turns the camera (``camera_rotation``
        (3, 3) in world) toward the commanded attitude at the instant the output acts (``now``
        [s] on the input clock plus ``lead`` [s]); zero while the gate (``gate_state``) stops a
        stale command (the commanded attitude runs on), zero and not tracked while the command
        is rejected or a camera ``goal`` drives the camera: the tracking then restarts at the
        measured camera when the gate follows again."""
        if gate_state in COASTING_STATES and not goal:
            self.error = 0.0
            return np.zeros(3)
        if goal or gate_state not in TRACKED_STATES:
            self.attitude.stop(now)
            self.error = 0.0
            return np.zeros(3)
        at = now + lead
        if not self.attitude.active:
            self.attitude.restart(camera_rotation, at)
        tracked = self.attitude.step(camera_rotation, at)
        self.error = tracked.error
        if tracked.restarted:
            self._node.get_logger().warn(
                f"the camera is {np.degrees(tracked.error):.3g} deg from the attitude the "
                f"commands add up to (tracking_max_error "
                f"{np.degrees(self.settings.max_error):.3g} deg: a joint limit or a "
                "singular region): the commanded attitude restarts at the camera",
                throttle_duration_sec=1.0,
            )
        return tracked.correction
