"""An inspection run with the operator on the ground, behind a delayed space link
(``rns_demo --link-delay``).

The scripted operator publishes on the ground's ``/ground/cmd_twist``; ``rns_link`` carries the
twists up and the telemetry (``joint_states``, ``base_odom``, the controller's status) down,
each way ``delay`` + up to ``jitter`` later, losing ``loss`` of them; ``rns_controller`` acts
each twist at its stamp + :attr:`LinkOptions.execution_delay` (time tags); ``rns_predictor`` in
``/ground`` shows the arm as the commands will move it. The prediction error is measured here,
apart from the predictor's own report: each predicted state against the spacecraft's state of
the same stamp, both as recorded.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from rns_ros.core import FreeFloatingModel, FreeFloatingState
from rns_ros.core.integration import attitude_deviation
from rns_ros.harness import ProcessStack, TopicLog
from rns_ros.nodes import predictor_parameters
from rns_ros.nodes.sim_clock import stamp_from_seconds

GROUND = "ground"
#: The execution delay's margin over the link's worst delay [s]: a twist is handed on at the
#: link's next release (2 ms) and served at the controller's next tick (one period).
EXECUTION_MARGIN = 0.05
#: Largest --link-loss: a link that loses nearly everything carries no teleoperation.
MAX_LINK_LOSS = 0.5
#: The operator's topic on the ground.
GROUND_TWISTS = f"/{GROUND}/cmd_twist"


@dataclass(frozen=True)
class LinkOptions:
    """The link of a run: one-way ``delay`` [s] each way, ``jitter`` [s], ``loss`` [-]."""

    delay: float
    jitter: float = 0.0
    loss: float = 0.0

    @property
    def execution_delay(self) -> float:
        """D [s]: every twist acts at its stamp + D on board, the link's worst case and a margin."""
        return self.delay + self.jitter + EXECUTION_MARGIN


def link_options(args) -> LinkOptions | None:
    """The run's link from ``--link-delay``, ``--link-jitter``, ``--link-loss`` (None: no link)."""
    if getattr(args, "link_delay", None) is None:
        return None
    return LinkOptions(args.link_delay, args.link_jitter, args.link_loss)


def controller_parameters(link: LinkOptions, lead: float) -> dict[str, object]:
    """rns_controller's time tags for ``link``: D, and a future tolerance that admits the
    operator's ``lead`` (it publishes each sample that far ahead of its stamp)."""
    return {"execution_delay": link.execution_delay, "future_tolerance": lead + EXECUTION_MARGIN}


def start_link_nodes(
    processes: ProcessStack,
    link: LinkOptions,
    controller: dict[str, object],
    timing: dict[str, object],
    ros_args: list[str],
) -> None:
    """Start ``rns_link`` and ``rns_predictor`` (in /ground, with the law and gate parameters
    of ``controller``, rns_controller's)."""
    processes.start(
        "rns_link",
        {
            "uplink_delay": link.delay,
            "downlink_delay": link.delay,
            "uplink_jitter": link.jitter,
            "downlink_jitter": link.jitter,
            "uplink_loss": link.loss,
            "downlink_loss": link.loss,
            **timing,
        },
        ros_args=ros_args,
    )
    shared = {key: value for key, value in controller.items() if key in predictor_parameters.SHARED}
    # a lockstep controller's output acts one output_lead after its tick: so does each twist
    delay = link.execution_delay + float(controller.get("output_lead", 0.0))
    processes.start(
        "rns_predictor",
        {**shared, "execution_delay": delay, **timing},
        remappings={"__ns": f"/{GROUND}"},
        ros_args=ros_args,
    )


def prediction_error_deg(
    robot: FreeFloatingModel,
    predicted: dict[str, TopicLog],
    measured: dict[str, TopicLog],
    since: float,
    until: float,
) -> float:
    """The largest angle [deg] between the predicted and the spacecraft's camera attitude at
    the stamps in [``since``, ``until``] [s] both have (joint_states and base_odom paired by
    stamp on each side, stamps matched to the microsecond: the predictor sums its periods);
    NaN when no stamp is shared."""

    def key_of(msg) -> int:
        return round((msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec) * 1e6)

    def states(logs: dict[str, TopicLog]) -> dict[int, np.ndarray]:
        poses = {key_of(m): m.pose.pose for m in logs["odom"].messages}
        configurations = {}
        for msg in logs["joints"].messages:
            key = key_of(msg)
            if key in poses and since <= key * 1e-6 <= until:
                p, o = poses[key].position, poses[key].orientation
                by_name = dict(zip(msg.name, msg.position, strict=False))
                theta = [by_name[name] for name in robot.joint_names]
                configurations[key] = robot.configuration(
                    theta, [p.x, p.y, p.z], [o.x, o.y, o.z, o.w]
                )
        return configurations

    ours, theirs = states(predicted), states(measured)
    shared = sorted(set(ours) & set(theirs))
    if not shared:
        return math.nan
    worst = 0.0
    for key in shared:
        a = FreeFloatingState.compute(robot, ours[key]).camera.rotation
        b = FreeFloatingState.compute(robot, theirs[key]).camera.rotation
        worst = max(worst, attitude_deviation(a, b))
    return math.degrees(worst)


def acting(commands: TopicLog, delay: float) -> TopicLog:
    """The twists of ``commands`` stamped when they act on board: their issue stamp + ``delay``
    [s] (the figures compare the robot with the command in force on board)."""
    shifted = TopicLog(commands.topic, commands.msg_type)
    messages = []
    for msg in commands.messages:
        stamp = msg.header.stamp
        moved = copy.deepcopy(msg)
        moved.header.stamp = stamp_from_seconds(stamp.sec + 1e-9 * stamp.nanosec + delay)
        messages.append(moved)
    shifted.messages = messages
    shifted.received = list(commands.received)  # aligned once the log has decoded them all
    return shifted
