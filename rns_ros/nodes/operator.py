"""rns_operator: a scripted operator that plays a scenario file as camera twist commands.

Publishes geometry_msgs/TwistStamped on ``cmd_twist`` at ``rate``: the scenario's angular velocity
omega(t) = angle * s_dot(t) * axis in the scenario's frame (``header.frame_id`` = ``world_frame``,
``base_frame`` or ``camera_frame``), then zeros for ``zero_duration``, then nothing (a controller
then stops on its own timeout). Time is the node clock (sim time with ``use_sim_time``); the
profile starts once ``cmd_twist`` has a subscriber (``wait_for_subscriber``) plus ``start_delay``.
"""

from __future__ import annotations

from geometry_msgs.msg import TwistStamped
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time

from rns_ros.core.controller import TwistFrame
from rns_ros.core.scenario import Scenario, load_scenario
from rns_ros.nodes.parameters import WORLD_FRAME, ParameterSpec, declare_parameters
from rns_ros.nodes.runner import run_node
from rns_ros.resources import scenario_path

NODE_NAME = "rns_operator"
SUMMARY = "Scripted operator: plays a scenario file (config/scenarios/*.yaml) as TwistStamped."

PARAMETERS = (
    ParameterSpec(
        "scenario",
        "satellite_observation",
        "Scenario file path, or the name of a shipped one in config/scenarios/",
    ),
    ParameterSpec("rate", 50.0, "Command publishing rate", "[Hz]", 1.0, 1000.0),
    ParameterSpec(
        "start_delay",
        0.5,
        "Wait after the start condition before the profile begins",
        "[s]",
        0.0,
        3600.0,
    ),
    ParameterSpec("wait_for_subscriber", True, "Start only once cmd_twist has a subscriber"),
    ParameterSpec(
        "zero_duration", 1.0, "Publish zero twists this long after the profile", "[s]", 0.0, 3600.0
    ),
    WORLD_FRAME,
    ParameterSpec("base_frame", "base_link", "frame_id used for base-frame scenarios"),
    ParameterSpec("camera_frame", "camera", "frame_id used for camera-frame scenarios"),
)


class OperatorNode(Node):
    """Plays one :class:`~rns_ros.core.scenario.Scenario` (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        params = declare_parameters(self, PARAMETERS)
        self.scenario: Scenario = load_scenario(scenario_path(params["scenario"]))
        self._frame_id = {
            TwistFrame.WORLD: params["world_frame"],
            TwistFrame.BASE: params["base_frame"],
            TwistFrame.CAMERA: params["camera_frame"],
        }[self.scenario.frame]
        self._start_delay = params["start_delay"]
        self._zero_duration = params["zero_duration"]
        self._wait = params["wait_for_subscriber"]
        self._start: Time | None = None
        self.finished = False
        # Commands: best effort, depth 1 - a late twist is worth nothing (same QoS as the
        # controller's subscription).
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._publisher = self.create_publisher(TwistStamped, "cmd_twist", qos)
        self._timer = self.create_timer(1.0 / params["rate"], self._on_tick)
        self.get_logger().info(
            f"scenario {self.scenario.name!r}: {self.scenario.description or 'no description'} "
            f"({self.scenario.duration} s, frame {self._frame_id})"
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

    def _on_tick(self) -> None:
        now = self.get_clock().now()
        if self._start is None:
            if self._wait and self._publisher.get_subscription_count() == 0:
                return
            self._start = now + Duration(nanoseconds=round(self._start_delay * 1e9))
            self.get_logger().info(f"starting in {self._start_delay} s")
        t = (now - self._start).nanoseconds * 1e-9
        if t < 0.0:
            return
        end = self.scenario.duration + self._zero_duration
        if t > end:
            if not self.finished:
                self.finished = True
                self.get_logger().info(f"scenario {self.scenario.name!r} finished")
            return
        omega = self.scenario.angular_velocity(t)
        msg = TwistStamped()
        msg.header.stamp = now.to_msg()
        msg.header.frame_id = self._frame_id
        msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = (float(w) for w in omega)
        self._publisher.publish(msg)


def main(args=None) -> int:
    return run_node(
        OperatorNode, executable=NODE_NAME, summary=SUMMARY, specs=PARAMETERS, args=args
    )


if __name__ == "__main__":
    raise SystemExit(main())
