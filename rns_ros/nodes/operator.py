"""rns_operator: a scripted operator that plays a scenario file as twist (and force) commands.

Part I scenario files (no ``kind`` key, :mod:`rns_ros.control.scenario`): publishes
geometry_msgs/TwistStamped on ``cmd_twist`` at ``rate``: the scenario's angular velocity
omega(t) = angle * s_dot(t) * axis in the scenario's frame (``header.frame_id`` = ``world_frame``,
``base_frame`` or ``camera_frame``; the last two, left empty, are the base link and camera frame
of ``model_config``'s model, loaded only for a scenario in those frames), then zeros for
``zero_duration``, then nothing (a controller then stops on its own timeout). Time is the node
clock (sim time with ``use_sim_time``); the profile starts once ``cmd_twist`` has a subscriber
(``wait_for_subscriber``) plus ``start_delay``. With ``use_sim_time`` the samples come at the
period instants /clock passes (:class:`~rns_ros.nodes.clock_ticks.ClockTicks`), one each, not
from an rclpy timer; with ``lead`` each goes out that long before its instant, stamped with the
instant, for a controller that serves twists at their stamps (rns_controller's
``await_commands``; zeros from the start condition until the profile starts).

Part II scenario files (``kind: motion_force``, :mod:`rns_ros.control.contact_scenarios`,
docs/part2_ros.md): at ``rate`` (500 Hz suggested: the force controller runs at 1 kHz) BOTH
``force_setpoint`` (geometry_msgs/WrenchStamped, ``frame_id`` = ``world_frame``, force =
f_des(t) n(t), n the contact normal at the reference point, torque 0) and ``cmd_twist``
(``frame_id`` = ``world_frame``, linear = the EE reference velocity p_dot_des(t) of (6.33),
angular = 0), in that order, both stamped with the node clock at publication (with ``lead``: with
the instant they are for): the sample is evaluated at exactly that stamp (the controller
differentiates consecutive twist stamps for its acceleration feed-forward). After the profile:
zero twists for ``zero_duration`` and the force setpoint held at its final value for the same
time, then nothing (the controller holds the last setpoint). The profile starts once
``cmd_twist`` and ``force_setpoint`` both have ``min_subscribers`` (``wait_for_subscriber``). With
``lead`` (rns_force_controller's ``await_commands``) only zero twists go out from the start
condition until the profile starts (no force setpoint: it would start the force task); the
setpoint of a sample goes out before its twist, so a controller that awaits the twist stream
and has the twist stamped t has been sent the force task's first setpoint of t too.

Stopped while it plays (Ctrl-C, SIGTERM, ``destroy_node``), it publishes :data:`FINAL_ZEROS` zero
twists :data:`FINAL_ZERO_GAP` apart before it goes: the controller stops at once instead of
holding the last rate for its ``command_timeout`` and then ramping down. Commands are best effort
(no acknowledgement to wait for), so a few copies stand in for one. Stopped before the profile
starts or after it finished, it sends nothing (nothing of it is moving the arm). A motion/force
scenario stopped while it plays also sends, with each final zero twist, the CURRENT force
setpoint once more: nothing jumps, and the controller keeps pushing with it (it holds the last
setpoint) while the arm stops; releasing the push is the controller's business (its stop).
"""

from __future__ import annotations

import re

import numpy as np
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time

from rns_ros.control.contact_scenarios import (
    MotionForceScenario,
    OperatorSample,
    load_operator_scenario,
    operator_sample,
)
from rns_ros.control.controller import TwistFrame
from rns_ros.control.scenario import Scenario
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.nodes import operator_parameters
from rns_ros.nodes.cdr import (
    SerializedTemplate,
    TemplateError,
    split_stamp,
    twist_stamped_template,
)
from rns_ros.nodes.clock_ticks import ClockTicks
from rns_ros.nodes.operator_parameters import MOTION_FORCE_RATE
from rns_ros.nodes.parameters import declare_parameters, twist_frame_names
from rns_ros.nodes.runner import publish_copies, publish_last, run_node
from rns_ros.resources import scenario_path

#: Zero twists published when the node is stopped mid-profile, this far apart [s].
FINAL_ZEROS = 3
FINAL_ZERO_GAP = 0.02
#: Under use_sim_time: missed sample instants played at once after the process waited for a core
#: (the ten of a depth-10 /clock queue before; farther behind, the profile skips ahead).
OPERATOR_CATCH_UP = 10


#: How often a waiting operator says what it waits for [s] (wall time).
WAIT_REPORT_PERIOD = 5.0
#: A ROS node's base name: letters, digits and underscores, not starting with a digit.
NODE_NAME_PATTERN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def node_names(text: str) -> frozenset[str]:
    """The node base names of ``subscriber_nodes`` (comma-separated, blanks ignored); a
    :class:`ConfigError` names one that no ROS node can have."""
    names = frozenset(name.strip() for name in text.split(",") if name.strip())
    for name in sorted(names):
        if not NODE_NAME_PATTERN.fullmatch(name):
            raise ConfigError(
                f"subscriber_nodes: {name!r} is no node name (letters, digits and underscores, "
                "not starting with a digit; the base name, without a namespace)"
            )
    return names


class OperatorNode(Node):
    """Plays one :class:`~rns_ros.control.scenario.Scenario` or
    :class:`~rns_ros.control.contact_scenarios.MotionForceScenario` (module docstring).

    Attributes:
        scenario: the loaded scenario; motion_force: True for a ``kind: motion_force`` file.
        finished: True once the profile and its zeros were published.
    """

    def __init__(self, **node_kwargs) -> None:
        super().__init__(operator_parameters.NODE_NAME, **node_kwargs)
        params = declare_parameters(self, operator_parameters.PARAMETERS)
        self._thread_priority = params["thread_priority"]
        self.scenario: Scenario | MotionForceScenario = load_operator_scenario(
            scenario_path(params["scenario"])
        )
        self.motion_force = isinstance(self.scenario, MotionForceScenario)
        if self.motion_force or self.scenario.frame is TwistFrame.WORLD:
            self._frame_id = params["world_frame"]
        else:
            self._frame_id = twist_frame_names(params)[self.scenario.frame]
        self._start_delay = params["start_delay"]
        sim_time = bool(self.get_parameter("use_sim_time").value)
        # [ns] each sample goes out ahead of its instant (lockstep with an awaiting controller)
        self._lead = round(params["lead"] * 1e9) if sim_time else 0
        self._start_grid = round(params["start_grid"] * 1e9) if sim_time else 0
        if params["lead"] and not self._lead:
            self.get_logger().warn("lead is for use_sim_time only: not used")
        self._period_ns = round(1e9 / params["rate"])
        # lead: the newest sample's instant [ns], and whether a sample asked for motion (or, in
        # a motion/force scenario, started the force task) yet
        self._last_instant: int | None = None
        self._moved = False
        self._last_tick: int | None = None  # without lead: the previous tick [ns], node clock
        self._zero_duration = params["zero_duration"]
        self._wait = params["wait_for_subscriber"]
        self._min_subscribers = params["min_subscribers"]
        self._subscriber_nodes = node_names(params["subscriber_nodes"])
        self._start: Time | None = None
        self.finished = False
        # True while the last thing published was part of the profile (motion or its zeros).
        self._playing = False
        # motion_force: the newest force setpoint published [N] (3,), world axes.
        self._force = np.zeros(3)
        # Commands: best effort, depth 1 - a late twist is worth nothing (same QoS as the
        # controller's subscription).
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._publisher = self.create_publisher(TwistStamped, "cmd_twist", qos)
        try:  # pre-serialized (rns_ros.nodes.cdr): in lockstep a twist goes out every 20 ms
            self._twist_template: SerializedTemplate | None = twist_stamped_template(self._frame_id)
        except TemplateError as exc:
            self.get_logger().warn(f"{exc}: publishing TwistStamped messages")
            self._twist_template = None
        self._force_publisher = (
            self.create_publisher(WrenchStamped, "force_setpoint", qos)
            if self.motion_force
            else None
        )
        if sim_time:
            # one sample per period instant of /clock: the events executor's sim-time timer
            # skipped and repeated samples in a fast lockstep run (rns_ros.nodes.clock_ticks)
            # a process that waited for a core up to OPERATOR_CATCH_UP periods plays every sample
            # it missed, in order (rclpy's /clock keeps only the newest reading)
            self._ticks = ClockTicks(
                self, 1.0 / params["rate"], self._play, max_ticks=OPERATOR_CATCH_UP
            )
        else:
            self.create_timer(1.0 / params["rate"], self._on_tick)
        self.get_logger().info(
            f"scenario {self.scenario.name!r}: {self.scenario.description or 'no description'} "
            f"({self.scenario.duration} s, frame {self._frame_id})"
        )
        if self.motion_force and params["rate"] < MOTION_FORCE_RATE:
            self.get_logger().info(
                f"motion/force scenario at {params['rate']} Hz; {MOTION_FORCE_RATE:g} Hz is "
                "suggested (the controller runs at 1 kHz)"
            )

    @property
    def started(self) -> bool:
        """True once the profile clock runs."""
        return self._start is not None

    def elapsed(self) -> float:
        """Seconds since the profile started (node clock), or 0 before [s]."""
        if self._start is None:
            return 0.0
        return (self.get_clock().now() - self._start).nanoseconds * 1e-9

    def _waiting_for(self) -> str:
        """What the profile still waits for, "" for nothing: cmd_twist (motion_force: and
        force_setpoint) to have ``min_subscribers`` subscribers, ``subscriber_nodes`` among
        those of cmd_twist (a stranger's subscriber, a plot or an echo, is not the one the run
        waits for)."""
        publishers = (self._publisher, self._force_publisher)
        counted = all(
            publisher.get_subscription_count() >= self._min_subscribers
            for publisher in publishers
            if publisher is not None
        )
        missing = self.missing_subscriber_nodes()
        if counted and not missing:
            return ""
        count = self._publisher.get_subscription_count()
        return (
            f"subscribers of {self._publisher.topic_name}: {count} of min_subscribers "
            f"{self._min_subscribers}"
            + (f"; not yet subscribed: {', '.join(missing)}" if missing else "")
        )

    def missing_subscriber_nodes(self) -> list[str]:
        """The ``subscriber_nodes`` not (yet) subscribed to cmd_twist, sorted."""
        if not self._subscriber_nodes:
            return []
        infos = self.get_subscriptions_info_by_topic(self._publisher.topic_name)
        return sorted(self._subscriber_nodes - {info.node_name for info in infos})

    def _on_tick(self) -> None:
        self._play(self.get_clock().now())

    def _play(self, now: Time) -> None:
        """The sample of the instant ``now`` (node clock) plus ``lead``, published stamped with
        that instant."""
        if self._start is None:
            waiting_for = self._waiting_for() if self._wait else ""
            if waiting_for:
                # every WAIT_REPORT_PERIOD of wall time: a misspelt name in subscriber_nodes
                # would otherwise wait in silence
                self.get_logger().info(
                    f"waiting for {waiting_for}", throttle_duration_sec=WAIT_REPORT_PERIOD
                )
                if self._lead:
                    # zeros from the first tick on: a controller awaiting the stream waits on
                    # every tick from the first sample it holds, long before the profile starts
                    self._publish((0.0, 0.0, 0.0), now + Duration(nanoseconds=self._lead))
                return
            delay = max(self._start_delay, self._lead * 1e-9)
            self._start = self._on_grid(now + Duration(nanoseconds=round(delay * 1e9)))
            self.get_logger().info(f"starting in {delay} s")
        if self._lead:
            now = now + Duration(nanoseconds=self._lead)
            self._resume_after_a_stall(now)
        else:
            self._start_after_a_stall(now)
        t = (now - self._start).nanoseconds * 1e-9
        if t < 0.0:
            if self._lead:  # zeros until the profile starts: a controller awaits them
                self._publish((0.0, 0.0, 0.0), now)
            return
        end = self.scenario.duration + self._zero_duration
        if t > end:
            if not self.finished:
                self.finished = True
                self._playing = False
                self.get_logger().info(f"scenario {self.scenario.name!r} finished")
            return
        self._playing = True
        if not self.motion_force:
            self._publish(self.scenario.angular_velocity(t), now)
            return
        # after the profile: zero twists, the force held at its final value
        try:
            sample = operator_sample(self.scenario.setup, min(t, self.scenario.duration))
        except InputError as exc:  # never publish a non-finite value
            self.get_logger().error(f"t = {t:.3f} s: {exc}; nothing published")
            return
        moving = t <= self.scenario.duration
        self._publish_motion_force(sample if moving else None, sample.force_vector, now)

    def _on_grid(self, start: Time) -> Time:
        """``start`` rounded up to a multiple of ``start_grid`` (simulated time): the profile's
        samples then fall on the same instants of the controller's period in every run, however
        late the start condition was met."""
        if not self._start_grid:
            return start
        ns = -(-start.nanoseconds // self._start_grid) * self._start_grid
        return Time(nanoseconds=ns, clock_type=start.clock_type)

    def _resume_after_a_stall(self, instant: Time) -> None:
        """lead: samples skipped before any motion (this process waited for a core while the
        simulation ran on, before an awaiting controller had a sample to wait on) shift the
        profile instead of cutting its start off: the robot is at rest until then, so the
        shift is exact. Once a sample moves, the controller awaits each one and the clock
        cannot run ahead of this node."""
        if self._moved or self._last_instant is None:
            return
        skipped = instant.nanoseconds - self._last_instant - self._period_ns
        if skipped > self._period_ns // 2:
            self._start = self._on_grid(self._start + Duration(nanoseconds=skipped))
            self.get_logger().warn(
                f"waited {skipped * 1e-9:.3f} s (simulated) for a core before the profile "
                "moved: it starts that much later"
            )

    def _start_after_a_stall(self, now: Time) -> None:
        """Without lead (the wall clock): ticks that came late before any motion was published
        (this process waited for a core while the nodes started) shift the profile's start by
        the time skipped instead of cutting its start off (the first sample played would be
        one from mid-profile); the robot is at rest until then, so the shift is exact."""
        previous, self._last_tick = self._last_tick, now.nanoseconds
        if self._moved or previous is None:
            return
        skipped = now.nanoseconds - previous - self._period_ns
        if skipped >= self._period_ns and now > self._start:  # a sample's instant was missed
            late = min(skipped, (now - self._start).nanoseconds)
            self._start = self._start + Duration(nanoseconds=late)
            self.get_logger().warn(
                f"waited {late * 1e-9:.3f} s for a core as the profile was to start: it "
                "starts that much later"
            )

    def _publish(self, omega, stamp: Time) -> None:
        """One TwistStamped with angular velocity ``omega`` [rad/s], shape (3,)."""
        self._moved = self._moved or any(float(w) != 0.0 for w in omega)
        if self._lead:
            self._last_instant = stamp.nanoseconds
        if self._twist_template is not None:
            values = {"twist": np.concatenate((np.zeros(3), omega))}
            self._publisher.publish(
                self._twist_template.serialize(values, split_stamp(stamp.nanoseconds))
            )
            return
        msg = TwistStamped()
        msg.header.stamp = stamp.to_msg()
        msg.header.frame_id = self._frame_id
        msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = (float(w) for w in omega)
        self._publisher.publish(msg)

    def _publish_motion_force(self, sample: OperatorSample | None, force, stamp: Time) -> None:
        """One WrenchStamped (``force`` [N] (3,), torque 0) and then one TwistStamped (the
        sample's linear/angular velocity, zeros for None), both world-framed, both at ``stamp``.

        The setpoint first: a controller awaiting both streams (``await_commands``) waits on
        the twists from the first zero on but cannot wait on a force stream that has not
        started; the twist of an instant, published after its setpoint, then makes the
        controller wait until that setpoint has been sent."""
        # the force task is on from here: a stall is no longer a shift of a robot at rest
        self._moved = True
        if self._lead:
            self._last_instant = stamp.nanoseconds
        twist = TwistStamped()
        twist.header.stamp = stamp.to_msg()
        twist.header.frame_id = self._frame_id
        if sample is not None:
            v, w = sample.linear, sample.angular
            twist.twist.linear.x, twist.twist.linear.y, twist.twist.linear.z = (float(x) for x in v)
            twist.twist.angular.x, twist.twist.angular.y, twist.twist.angular.z = (
                float(x) for x in w
            )
        wrench = WrenchStamped()
        wrench.header = twist.header
        wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z = (
            float(f) for f in force
        )
        self._force = np.array(force, dtype=float)
        self._force_publisher.publish(wrench)
        self._publisher.publish(twist)

    def realtime_scheduling(self) -> tuple[int, bool]:
        """(thread_priority, whether it applies: on the wall clock, where its samples are the
        operator's timing), for :func:`rns_ros.nodes.runner.run_node`."""
        return self._thread_priority, not self.get_parameter("use_sim_time").value

    def destroy_node(self) -> None:
        """Stop the camera / EE when the profile is playing: zero twists first (motion_force:
        each with the current force setpoint; module docstring),
        then tear down. ``run_node`` calls this on Ctrl-C while the Context still runs."""
        if self._playing and self.context.ok():
            self._playing = False
            publish_last(
                self,
                lambda: publish_copies(self._publish_zero, FINAL_ZEROS, FINAL_ZERO_GAP),
                "zero twist",
            )
        super().destroy_node()

    def _publish_zero(self) -> None:
        """A zero twist (motion_force: with the current force setpoint once more)."""
        if self.motion_force:
            self._publish_motion_force(None, self._force, self.get_clock().now())
        else:
            self._publish((0.0, 0.0, 0.0), self.get_clock().now())


def main(args=None) -> int:
    return run_node(OperatorNode, operator_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
