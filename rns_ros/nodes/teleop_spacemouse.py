"""rns_teleop_spacemouse: point the camera with a 3D mouse (3Dconnexion SpaceMouse).

Dead zone, scaling, buttons and the watchdog are :mod:`rns_ros.control.spacemouse` (pure logic);
the device is read through :mod:`rns_ros.nodes.spacemouse_device` (pyspacemouse, raw HID, no
driver or daemon) or any object with its protocol (tests script one). This module owns the ROS
side.

Publishes:
    cmd_twist   geometry_msgs/TwistStamped, best effort depth 1 (as rns_teleop_keyboard): while
                the cap is deflected beyond the dead zone, the twist at ``rate`` (angular: the
                cap's rotation, linear: its push, ROS axes x forward, y left, z up, in the
                frame shown by ``header.frame_id``: ``world_frame``, ``base_frame`` or
                ``camera_frame``; the latter two, left empty, the base link and camera frame of
                ``model_config``'s model); after it stops (released, paused, a frame change, a
                silent device), zeros at ``rate`` for ``zero_duration``; then nothing. A few
                zeros are also sent on the way out (Ctrl-C, SIGTERM).

Buttons: ``frame_button`` cycles camera -> world -> base, ``pause_button`` pauses / resumes; after
either the twist stays zero until the cap is back in the dead zone. A deflected cap that sends no
report for ``device_timeout`` gives zero twist. A device that goes away (unplugged) gives zeros
and is looked for again every second.

Start-up: no device, no permission, no hidapi or no pyspacemouse is one line on stderr with the
fix (the udev rule for the permission) and exit code 2.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from geometry_msgs.msg import TwistStamped
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from rns_ros.control.spacemouse import (
    Mode,
    SpaceMouseCommand,
    SpaceMouseReading,
    SpaceMouseSettings,
    SpaceMouseTeleop,
)
from rns_ros.nodes import teleop_spacemouse_parameters
from rns_ros.nodes.parameters import declare_parameters, from_parameters, twist_frame_names
from rns_ros.nodes.runner import publish_copies, run_node
from rns_ros.nodes.spacemouse_device import DeviceError, PySpaceMouseDevice, SpaceMouseDevice
from rns_ros.nodes.teleop_spacemouse_parameters import NODE_NAME

#: Zero twists sent on the way out, this far apart [s]: best effort may drop one.
EXIT_ZEROS = 3
EXIT_ZERO_GAP = 0.02
#: A lost device is looked for again this often [s].
REOPEN_PERIOD = 1.0

#: Opens the device at a path ("" = the first found); raises DeviceError.
DeviceFactory = Callable[[str], SpaceMouseDevice]


class TeleopSpaceMouseNode(Node):
    """Publishes the :class:`SpaceMouseTeleop` commands of a device (module docstring).

    Args:
        open_device: opens the device at ``device_path``; default pyspacemouse.
        clock: monotonic time [s], the clock of the device's report times.

    Raises:
        ConfigError: a parameter is out of range.
        DeviceError: the device does not open (the message says how to fix it).
    """

    def __init__(
        self,
        open_device: DeviceFactory = PySpaceMouseDevice,
        clock: Callable[[], float] = time.monotonic,
        **node_kwargs,
    ) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        params = declare_parameters(self, teleop_spacemouse_parameters.PARAMETERS)
        self.teleop = SpaceMouseTeleop(
            from_parameters(SpaceMouseSettings, params), params["initial_frame"]
        )
        self.frame_ids = twist_frame_names(params)
        self._open, self._path, self._monotonic = open_device, params["device_path"], clock
        self.device: SpaceMouseDevice | None = open_device(self._path)
        self._next_open = 0.0
        self._sent = False  # a twist was published: the way out ends with zeros
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._publisher = self.create_publisher(TwistStamped, "cmd_twist", qos)
        self.create_timer(1.0 / params["rate"], self.tick)
        self.get_logger().info(
            f"publishing on {self._publisher.topic_name} in the {self.teleop.frame.value} frame "
            f"(button {params['frame_button']}: frame, button {params['pause_button']}: pause)"
        )

    def _reading(self, now: float) -> SpaceMouseReading:
        """The device's newest state; a lost device reads as released (and is reopened)."""
        if self.device is None and now >= self._next_open:
            self._next_open = now + REOPEN_PERIOD
            try:
                self.device = self._open(self._path)
                self.get_logger().info("SpaceMouse found again")
            except DeviceError as exc:
                self.get_logger().warn(f"{exc}", throttle_duration_sec=10.0)
        if self.device is not None:
            try:
                return self.device.read()
            except DeviceError as exc:
                self.get_logger().error(
                    f"{exc}: zero twist; looking for it again", throttle_duration_sec=10.0
                )
                self._close()
        return SpaceMouseReading()

    def tick(self) -> None:
        """One period: read the device, publish what the teleop says."""
        now = self._monotonic()
        command = self.teleop.update(self._reading(now), now)
        for event in self.teleop.events:
            self.get_logger().info(event)
        if command is not None:
            self.publish(command)

    def publish(self, command: SpaceMouseCommand) -> None:
        """One command as TwistStamped stamped with the node clock."""
        msg = TwistStamped()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.header.frame_id = self.frame_ids[command.frame]
        msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = command.angular
        msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z = command.linear
        self._publisher.publish(msg)
        self._sent = True

    def _close(self) -> None:
        device, self.device = self.device, None
        if device is not None:
            try:
                device.close()
            except Exception as exc:  # a device gone mid-read may fail to close
                self.get_logger().warn(f"closing the SpaceMouse: {exc}")

    def destroy_node(self) -> None:
        """A few zero twists (when any twist was sent), the device closed, then tear down."""
        try:
            if self._sent:
                zero = SpaceMouseCommand(
                    (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), self.teleop.frame, Mode.CENTRED
                )
                publish_copies(lambda: self.publish(zero), EXIT_ZEROS, EXIT_ZERO_GAP)
        except Exception as exc:  # the Context may already be going down
            self.get_logger().warn(f"could not publish the final zero twist: {exc}")
        finally:
            self._close()
            super().destroy_node()


def main(args=None) -> int:
    return run_node(TeleopSpaceMouseNode, teleop_spacemouse_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
