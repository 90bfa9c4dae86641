"""The states of rns_ptp and their report: ``~/status`` every period, ``/diagnostics`` at 1 Hz,
and who else is in the graph (:mod:`rns_ros.nodes.ptp`)."""

from __future__ import annotations

import math

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node
from rclpy.qos import QoSProfile

from rns_ros.control.ptp import PtpMethod, PtpPlan
from rns_ros.control.ptp_playback import PlanPlayback
from rns_ros.core import FreeFloatingModel, FreeFloatingState
from rns_ros.core.validation import Choice
from rns_ros.nodes.status import CommanderWatch, level_rank, node_names, status_text

#: Period of the /diagnostics publication [s] (wall clock).
DIAGNOSTICS_PERIOD = 1.0


class PtpState(Choice):
    WAITING_FOR_STATE = "WAITING_FOR_STATE"
    IDLE = "IDLE"
    PLANNING = "PLANNING"
    MOVING = "MOVING"
    CANCELLING = "CANCELLING"
    HOLDING = "HOLDING"
    CLOCK_FAULT = "CLOCK_FAULT"
    SETTLING = "SETTLING"
    DONE = "DONE"
    GOAL_MISSED = "GOAL_MISSED"
    INVALID_GOAL = "INVALID_GOAL"
    STALE_STATE = "STALE_STATE"
    CONFLICTING_STATE = "CONFLICTING_STATE"


#: Level of each state; OK when not listed.
STATE_LEVELS = {
    PtpState.WAITING_FOR_STATE: DiagnosticStatus.WARN,
    PtpState.HOLDING: DiagnosticStatus.WARN,
    PtpState.CLOCK_FAULT: DiagnosticStatus.ERROR,
    PtpState.INVALID_GOAL: DiagnosticStatus.ERROR,
    PtpState.GOAL_MISSED: DiagnosticStatus.ERROR,
    PtpState.STALE_STATE: DiagnosticStatus.ERROR,
    PtpState.CONFLICTING_STATE: DiagnosticStatus.ERROR,
}

#: States in which each tick commands the joints from the plan.
PLAYING = (PtpState.MOVING, PtpState.CANCELLING)
#: States in which the arm is held at rest on the plan, which is kept (the state before the hold
#: returns when the input, or the clock, can be trusted again).
HELD = (PtpState.HOLDING, PtpState.CLOCK_FAULT)
#: States of a motion or a planning, which a lost input or a lasting clock fault abandons.
ACTIVE = (*PLAYING, PtpState.PLANNING)
#: States in which the measured state cannot be trusted (zero output, the plan abandoned).
FAULTS = (PtpState.STALE_STATE, PtpState.CONFLICTING_STATE)


def coupling_momentum(
    robot: FreeFloatingModel,
    theta: np.ndarray,
    base_position: np.ndarray,
    base_orientation: np.ndarray,
    theta_dot: np.ndarray,
) -> float:
    """||M~_omega_m theta_dot|| [kg m^2/s]: the base angular momentum the joint velocities
    ``theta_dot`` [rad/s] (n,) couple into at the joint angles ``theta`` [rad] (n,) and the base
    pose (position [m] (3,), quaternion x y z w (4,)); zero for a reactionless motion."""
    state = FreeFloatingState.compute(
        robot, robot.configuration(theta, base_position, base_orientation)
    )
    return float(np.linalg.norm(state.coupling_angular_momentum_matrix @ theta_dot))


def plan_values(
    state: PtpState,
    method: PtpMethod,
    plan: PtpPlan | None,
    playback: PlanPlayback | None,
    momentum: float,
    rejected: str,
) -> dict:
    """The key values of a status in ``state``: the method, where the plan stands (phase,
    progress, duration, playback rate, folds reached, notes), the coupling momentum
    [kg m^2/s] and why the newest goal was rejected (when it was)."""
    values = {"method": method.value}
    moving = state in PLAYING
    if plan is not None:
        s = playback.s if playback is not None else 0.0
        reference = plan.sample(s)
        on_path = moving or (state in HELD and reference.phase != "done")
        values["plan_method"] = str(plan.method)
        values["phase"] = reference.phase if on_path else "done"
        values["progress"] = float(reference.progress)
        values["duration"] = float(plan.duration)
        values["playback_rate"] = playback.rate if moving else 0.0
        folds = [
            f"{p.name}: {math.degrees(p.fold_reached):.4g} deg"
            for p in plan.phases
            if p.fold_reached is not None
        ]
        values["fold_reached"] = ", ".join(folds) if folds else "none"
        values["notes"] = "; ".join(plan.notes) if plan.notes else "none"
    values["coupling_momentum"] = momentum
    if rejected:
        values["rejected_goal"] = rejected
    return values


class PtpStatus:
    """The status of rns_ptp: published on ``~/status`` at each :meth:`publish`, the newest on
    ``/diagnostics`` at :meth:`publish_diagnostics` (hardware_id = ``hardware_id``). Other
    commanders on the output topic ``output_topic`` (read by :meth:`check_graph`) raise the
    level to WARN and are named in the message.

    Attributes:
        rejected: why the newest goal was rejected ('' when it was not); in every status.
        last: the newest status, None before the first.
    """

    def __init__(self, node: Node, hardware_id: str, output_topic: str) -> None:
        self._node, self._hardware_id, self._output_topic = node, hardware_id, output_topic
        self._commanders = CommanderWatch(
            node,
            output_topic,
            "only one of rns_controller / rns_ptp may command the joints at a time",
            publishes=True,
        )
        self._status = node.create_publisher(DiagnosticArray, "~/status", QoSProfile(depth=10))
        self._diagnostics = node.create_publisher(
            DiagnosticArray, "/diagnostics", QoSProfile(depth=10)
        )
        self.rejected = ""
        self.last: DiagnosticStatus | None = None

    def check_graph(self, state_topic: str) -> list[str]:
        """Read the graph: who else commands the joints on the output topic (two commanders
        make the arm jerk between them; reported) and who publishes JointState on
        ``state_topic`` (returned: more than one source is a fault, the plan would start from
        one robot's angles and the watchdog be fed by another)."""
        self._commanders.check()
        return node_names(
            info
            for info in self._node.get_publishers_info_by_topic(state_topic)
            if info.topic_type == "sensor_msgs/msg/JointState"
        )

    def publish(self, state: PtpState, detail: str, values: dict) -> None:
        """The status in ``state`` (``detail``: why, ''; ``values``: :func:`plan_values`) on
        ~/status, stamped now."""
        level = STATE_LEVELS.get(state, DiagnosticStatus.OK)
        message = f"{state.value}: {detail}" if detail else state.value
        if self.rejected and state is not PtpState.INVALID_GOAL:
            message += f"; last goal rejected: {self.rejected}"
        others = self._commanders.others
        if others:
            level = max(level, DiagnosticStatus.WARN, key=level_rank)
            message += (
                f"; {', '.join(others)} also publish(es) on {self._output_topic}: "
                "run only one of rns_controller / rns_ptp"
            )
        self.last = DiagnosticStatus(
            level=level,
            name=f"{self._node.get_name()}: point-to-point motion",
            message=message,
            hardware_id=self._hardware_id,
            values=[
                KeyValue(key=key, value=status_text(value))
                for key, value in {"state": state.value, **values}.items()
            ],
        )
        self._status.publish(self._stamped(self.last))

    def publish_diagnostics(self) -> None:
        """The newest status on /diagnostics, stamped now (nothing before the first)."""
        if self.last is not None:
            self._diagnostics.publish(self._stamped(self.last))

    def _stamped(self, status: DiagnosticStatus) -> DiagnosticArray:
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self._node.get_clock().now().to_msg()
        return msg
