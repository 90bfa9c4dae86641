"""rns_operator: a scripted operator that plays a scenario file as camera twist commands.

Publishes geometry_msgs/TwistStamped on ``cmd_twist`` at ``rate``: the scenario's angular velocity
omega(t) = angle * s_dot(t) * axis in the scenario's frame (``header.frame_id`` = ``world_frame``,
``base_frame`` or ``camera_frame``), then zeros for ``zero_duration``, then nothing (a controller
then stops on its own timeout). Time is the node clock (sim time with ``use_sim_time``); the
profile starts once ``cmd_twist`` has a subscriber (``wait_for_subscriber``) plus ``start_delay``.

Stopped while it plays (Ctrl-C, SIGTERM, ``destroy_node``), it publishes :data:`FINAL_ZEROS` zero
twists :data:`FINAL_ZERO_GAP` apart before it goes: the controller stops at once instead of
holding the last rate for its ``command_timeout`` and then ramping down. Commands are best effort
(no acknowledgement to wait for), so a few copies stand in for one. Stopped before the profile
starts or after it finished, it sends nothing (nothing of it is moving the arm).
"""

from __future__ import annotations

import time

from geometry_msgs.msg import TwistStamped
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time

from rns_ros.control.controller import TwistFrame
from rns_ros.control.scenario import Scenario, load_scenario
from rns_ros.nodes.parameters import WORLD_FRAME, ParameterSpec, declare_parameters
from rns_ros.nodes.runner import run_node
from rns_ros.resources import scenario_path

NODE_NAME = "rns_operator"
#: Zero twists published when the node is stopped mid-profile, this far apart [s].
FINAL_ZEROS = 3
FINAL_ZERO_GAP = 0.02
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
    """Plays one :class:`~rns_ros.control.scenario.Scenario` (see the module docstring)."""

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
        # True while the last thing published was part of the profile (motion or its zeros).
        self._playing = False
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
                self._playing = False
                self.get_logger().info(f"scenario {self.scenario.name!r} finished")
            return
        self._playing = True
        self._publish(self.scenario.angular_velocity(t), now)

    def _publish(self, omega, stamp: Time) -> None:
        """One TwistStamped with angular velocity ``omega`` [rad/s], shape (3,)."""
        msg = TwistStamped()
        msg.header.stamp = stamp.to_msg()
        msg.header.frame_id = self._frame_id
        msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = (float(w) for w in omega)
        self._publisher.publish(msg)

    def destroy_node(self) -> None:
        """Stop the camera when the profile is playing: zero twists first (module docstring),
        then tear down. ``run_node`` calls this on Ctrl-C while the Context still runs."""
        if self._playing and self.context.ok():
            self._playing = False
            try:
                for i in range(FINAL_ZEROS):
                    if i:
                        time.sleep(FINAL_ZERO_GAP)
                    self._publish((0.0, 0.0, 0.0), self.get_clock().now())
            except Exception as exc:  # the Context may be going down (a second signal)
                self.get_logger().warn(f"could not publish the final zero twist: {exc}")
        super().destroy_node()


def main(args=None) -> int:
    return run_node(
        OperatorNode, executable=NODE_NAME, summary=SUMMARY, specs=PARAMETERS, args=args
    )


if __name__ == "__main__":
    raise SystemExit(main())
