"""Status of rns_controller: the newest state on ~/status and /diagnostics, and the graph check of
who publishes its inputs."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import TwistStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState

from rns_ros.control.controller import ControllerStep
from rns_ros.control.teleop import ControllerState, GateOutput
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import apart
from rns_ros.nodes.status import (
    CommanderWatch,
    level_rank,
    node_names,
    status_text,
    type_name,
)

#: Period of the /diagnostics publication and of the check of who publishes the inputs [s].
DIAGNOSTICS_PERIOD = 1.0
#: Status level of each state (diagnostic_msgs/DiagnosticStatus); the others warn.
STATE_LEVELS = {
    ControllerState.OK: DiagnosticStatus.OK,
    ControllerState.IDLE: DiagnosticStatus.OK,
    ControllerState.RAMPING: DiagnosticStatus.OK,
    ControllerState.PAUSED: DiagnosticStatus.OK,
    ControllerState.GOAL_ACTIVE: DiagnosticStatus.OK,
    ControllerState.GOAL_REACHED: DiagnosticStatus.OK,
    ControllerState.INVALID_COMMAND: DiagnosticStatus.ERROR,
    ControllerState.STALE_STATE: DiagnosticStatus.ERROR,
    ControllerState.CONFLICTING_STATE: DiagnosticStatus.ERROR,
    ControllerState.CLOCK_FAULT: DiagnosticStatus.ERROR,
}


def step_values(method: str, step: ControllerStep, gate: GateOutput) -> dict:
    """Key values of a served tick's status: the law's output (sigma_min, the determinants,
    damping lambda^2, speed scale), the unachieved twist [rad/s], [m/s] (3,) and the predicted
    coupling momentum (3,); zeros for a stopped output."""
    out = step.output
    unachieved = out.angular_residual if not gate.stopped else np.zeros(3)
    return {
        "method": method,
        "frame": gate.frame.value,
        "sigma_min": out.sigma_min,
        "det_kinematic": out.determinants.kinematic,
        "det_coupling": out.determinants.coupling,
        "det_algorithmic": out.determinants.algorithmic,
        "damping": out.damping,
        "speed_scale": out.speed_scale,
        "unachieved_angular": unachieved,
        "unachieved_linear": gate.linear,
        "coupling_momentum": out.coupling_momentum if not gate.stopped else np.zeros(3),
    }


def joint_limit_text(robot: FreeFloatingModel, theta: np.ndarray) -> str:
    """The warning of a joint limit stop: the joint closest to its limit at ``theta`` [rad] (n,)."""
    lower, upper = robot.lower_limits, robot.upper_limits
    margin = np.minimum(theta - lower, upper - theta)
    joint = int(np.argmin(margin))
    angle, low, high = apart(theta[joint], lower[joint], upper[joint])
    return (
        f"JOINT_LIMIT: {robot.joint_names[joint]} at {angle} rad is "
        f"{margin[joint]:.3g} rad from its limit [{low}, {high}]; "
        "the motion is slowed or stopped (choose another direction)"
    )


class JointLimitStop:
    """Whether the served outputs are in a joint-limit stop, judged over their holds.

    A stop begins with an output that a position limit scaled (the node warns then, once) and
    lasts until the outputs have run free of the limits for one control period of hold time,
    or until :meth:`end` (another state took over: the command ended, a fault). A late tick
    is followed by one on the timer's grid, so its output is held for a fraction of the period;
    over so short a hold the limit may not bind although the operator still pushes into it,
    and that is the same stop going on, not its end and a new one.

    Args:
        period: control period T [s], > 0.
    """

    def __init__(self, period: float) -> None:
        self._period = period
        # [s] of hold since the newest limited output, or None outside a stop
        self._free: float | None = None

    def update(self, limited: bool, hold: float) -> tuple[bool, bool]:
        """One served output held ``hold`` [s]; ``limited``: a position limit scaled it.

        Returns:
            (in a stop, the stop begins with this output).
        """
        if limited:
            began = self._free is None
            self._free = 0.0
            return True, began
        if self._free is None:
            return False, False
        self._free += hold
        if self._free < self._period:
            return True, False
        self._free = None
        return False, False

    def end(self) -> None:
        """Another state than the limit's was reported: a stop after it is a new one."""
        self._free = None


#: Status key: cmd_twist messages received (a scripted run starts once the controller has one).
TWISTS_RECEIVED = "twists_received"


class StatusReporter:
    """The newest status of ``node``: published on ~/status to a subscriber at each report, and
    on /diagnostics by :meth:`publish_diagnostics` (hardware_id = ``hardware_id``).

    The message and its key values are built only when someone reads them (a ~/status
    subscriber, /diagnostics): building them every tick would cost a good part of the tick.
    ``advisories`` (set by the graph check) raise the level to WARN and are appended to the
    message.
    """

    def __init__(self, node: Node, hardware_id: str) -> None:
        self._node, self._hardware_id = node, hardware_id
        self._status = node.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self._diagnostics = node.create_publisher(
            DiagnosticArray, "/diagnostics", QoSProfile(depth=10)
        )
        self.advisories: list[str] = []
        #: counts reported as key values in every status (e.g. ``twists_received``)
        self.counters: dict[str, int] = {}
        #: messages rejected as malformed, by topic (reported as ``rejected_messages``)
        self.rejected: dict[str, int] = {}
        self.last_state = ControllerState.WAITING_FOR_STATE
        self._last: tuple | None = None  # (level, message, state, values)

    def report(
        self, state: ControllerState, detail: str, values: dict | Callable[[], dict]
    ) -> None:
        """Keep the newest status (``values``: its key values, or what makes them, called only
        when a message is built) and publish it to a ~/status subscriber."""
        level = STATE_LEVELS.get(state, DiagnosticStatus.WARN)
        message = f"{state.value}: {detail}" if detail else state.value
        if self.advisories:
            level = max(level, DiagnosticStatus.WARN, key=level_rank)
            message = "; ".join([message, *self.advisories])
        self.last_state = state
        self._last = (level, message, state, values)
        if self._status.get_subscription_count():
            self._status.publish(self.message())

    def count(self, key: str) -> None:
        """One more of ``key`` (reported in every status from now on)."""
        self.counters[key] = self.counters.get(key, 0) + 1

    def reject(self, topic: str, error: Exception) -> None:
        """A message on ``topic`` that is not one (``error`` says why): counted in the status,
        logged (throttled); the node goes on."""
        self.rejected[topic] = self.rejected.get(topic, 0) + 1
        self._node.get_logger().error(
            f"rejected a message on {topic}: {error} ({self.rejected[topic]} so far)",
            throttle_duration_sec=1.0,
        )

    def message(self) -> DiagnosticArray:
        """The newest status as a DiagnosticArray stamped now."""
        level, message, state, values = self._last
        values = {"state": state.value, **(values() if callable(values) else values)}
        values.update(self.counters)
        if self.rejected:
            values["rejected_messages"] = ", ".join(f"{t}: {n}" for t, n in self.rejected.items())
        status = DiagnosticStatus(
            level=level,
            name=f"{self._node.get_name()}: reactionless control",
            message=message,
            hardware_id=self._hardware_id,
            values=[KeyValue(key=key, value=status_text(value)) for key, value in values.items()],
        )
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self._node.get_clock().now().to_msg()
        return msg

    def publish_diagnostics(self) -> None:
        """The newest status on /diagnostics (nothing before the first report)."""
        if self._last is not None:
            self._diagnostics.publish(self.message())


class InputPublishers:
    """Who publishes the controller's inputs, read from the graph.

    More than one joint_states source is a fault (two robots' states interleaved make the law
    reverse at every message); more than one command source, or a command publisher of the
    other message type (its messages never arrive), is an advisory.

    Another node commanding the joints on the controller's own output topic is an advisory
    too: the simulator takes each command as it comes, so the arm would follow both in turn.

    Args:
        node: the controller node.
        topics: resolved names of ``cmd_twist`` and ``joint_states``.
        command_type: TwistStamped or Twist, what cmd_twist is taken as.
        output_topic: resolved name of the controller's joint command output.
    """

    def __init__(
        self, node: Node, topics: dict[str, str], command_type: type, output_topic: str
    ) -> None:
        self._node, self._topics, self._command_type = node, topics, command_type
        self._output_topic = output_topic
        self._commanders = CommanderWatch(
            node,
            output_topic,
            "the simulator takes each command as it comes, so the arm follows both in turn; "
            "run one commander",
            publishes=True,
        )
        self._warned_types: set[str] = set()
        self.state_publishers: list[str] = []  # nodes publishing joint_states

    def check(self) -> list[str]:
        """Read the graph; update :attr:`state_publishers` and return the advisories."""
        node, topic = self._node, self._topics["cmd_twist"]
        expected = type_name(self._command_type)
        other = "false" if self._command_type is TwistStamped else "true"
        commands, others = [], []
        for info in node.get_publishers_info_by_topic(topic):
            (commands if info.topic_type == expected else others).append(info)
        advisories = []
        if len(commands) > 1:
            advisories.append(
                f"{len(commands)} publishers on {topic} "
                f"({', '.join(node_names(commands))}): their commands interleave"
            )
        for info in others:
            if info.topic_type not in self._warned_types:
                self._warned_types.add(info.topic_type)
                node.get_logger().warn(
                    f"{node_names([info])[0]} publishes {info.topic_type} on {topic}, but this "
                    f"controller takes {expected}: those commands are dropped; restart with "
                    f"-p twist_stamped:={other} (or make the teleop publish the other type)"
                )
            advisories.append(
                f"{node_names([info])[0]} publishes {info.topic_type}, ignored: set "
                f"twist_stamped:={other}"
            )
        self.state_publishers = node_names(
            info
            for info in node.get_publishers_info_by_topic(self._topics["joint_states"])
            if info.topic_type == type_name(JointState)
        )
        commanders = self._commanders.check()
        if commanders:
            advisories.append(
                f"{', '.join(commanders)} also command(s) the joints on {self._output_topic}"
            )
        return advisories
