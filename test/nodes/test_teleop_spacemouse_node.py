"""rns_teleop_spacemouse over DDS (loopback, private Context) with a scripted device, its start-up
error without a device, and the spacenav driver's Twist stream (config/spacenav.yaml) turning the
camera through rns_controller in closed loop with rns_simulator."""

from __future__ import annotations

import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rns_testing import Recorder, caught_up_camera, status_values

from rns_ros.control.spacemouse import SpaceMouseReading
from rns_ros.core.integration import attitude_deviation
from rns_ros.harness import ros_environment
from rns_ros.nodes.controller import ControllerNode
from rns_ros.nodes.simulator import SimulatorNode
from rns_ros.nodes.spacemouse_device import UDEV_RULE, DeviceError, open_failure_text
from rns_ros.nodes.teleop_spacemouse import EXIT_ZEROS, TeleopSpaceMouseNode

REPO = Path(__file__).resolve().parents[2]
COMMAND = [sys.executable, "-m", "rns_ros.nodes.teleop_spacemouse"]


class ScriptedDevice:
    """A SpaceMouse whose state the test sets; ``reporting`` False: it stops sending reports
    (the reading keeps its last report time), ``lost`` True: reads fail as an unplugged one."""

    def __init__(self, clock) -> None:
        self.clock = clock
        self.rotation = (0.0, 0.0, 0.0)
        self.buttons = (False, False)
        self.reporting, self.lost, self.closed = True, False, False
        self.received = -math.inf

    def read(self) -> SpaceMouseReading:
        if self.lost:
            raise DeviceError("SpaceMouse read failed: [Errno 19] No such device")
        if self.reporting:
            self.received = self.clock()
        return SpaceMouseReading((0.0, 0.0, 0.0), self.rotation, self.buttons, self.received)

    def close(self) -> None:
        self.closed = True


def _twist_node(ros, device, **parameters):
    overrides = [Parameter(name, value=value) for name, value in parameters.items()]
    node = TeleopSpaceMouseNode(
        open_device=lambda _path: device, context=ros.context, parameter_overrides=overrides
    )
    return ros.add(node)


def _angular(msg: TwistStamped) -> tuple[float, float, float]:
    a = msg.twist.angular
    return (a.x, a.y, a.z)


def test_a_scripted_device_drives_cmd_twist_with_frame_button_and_watchdog(ros):
    """A full yaw twist gives angular_scale about z in the camera frame; the frame button gives
    zeros in the world frame until the cap centres; a cap that stops reporting while deflected
    gives zeros after device_timeout; an unplugged device gives zeros; the way out sends zeros."""
    device = ScriptedDevice(time.monotonic)
    twists = ros.record(TwistStamped, "cmd_twist")
    node = _twist_node(ros, device, angular_scale=0.3, device_timeout=0.3, rate=50.0)
    assert ros.spin_until(lambda: node._publisher.get_subscription_count() > 0, timeout=10.0)
    ros.spin_for(0.2)
    assert len(twists) == 0  # at rest: nothing

    device.rotation = (0.0, 0.0, 1.0)
    assert ros.spin_until(lambda: len(twists) >= 10, timeout=5.0)
    latest = twists.latest()
    assert _angular(latest) == pytest.approx((0.0, 0.0, 0.3))
    assert latest.header.frame_id == "camera"  # the default model's camera frame

    device.buttons = (True, False)
    assert ros.spin_until(lambda: twists.latest().header.frame_id == "world", timeout=5.0)
    ros.spin_for(0.2)
    assert _angular(twists.latest()) == (0.0, 0.0, 0.0)  # deflected through the change: zero
    device.rotation, device.buttons = (0.0, 0.0, 0.0), (False, False)
    ros.spin_for(0.1)
    device.rotation = (0.0, 0.5, 0.0)
    assert ros.spin_until(lambda: _angular(twists.latest())[1] > 0.0, timeout=5.0)
    assert twists.latest().header.frame_id == "world"

    device.reporting = False  # stalled while deflected
    stalled = time.monotonic()
    assert ros.spin_until(lambda: not any(_angular(twists.latest())), timeout=5.0)
    assert time.monotonic() - stalled >= 0.3 - 0.03  # device_timeout, one tick of slack
    device.reporting = True
    ros.spin_for(0.2)
    assert not any(_angular(twists.latest()))  # still deflected: waits for the cap to centre

    device.rotation = (0.0, 0.0, 0.0)
    ros.spin_for(0.1)
    device.rotation = (-1.0, 0.0, 0.0)
    assert ros.spin_until(lambda: _angular(twists.latest())[0] < 0.0, timeout=5.0)
    device.lost = True
    assert ros.spin_until(lambda: not any(_angular(twists.latest())), timeout=5.0)
    assert device.closed

    count = len(twists)
    ros.detach(node)
    node.destroy_node()
    ros.spin_for(0.3)
    exit_zeros = twists.messages[count:]
    assert 1 <= len(exit_zeros) <= EXIT_ZEROS
    assert all(not any(_angular(m)) for m in exit_zeros)


def test_no_device_is_one_line_with_the_fix_and_exit_2(ros):
    """On this machine there is no SpaceMouse (and maybe no hidapi): one line on stderr naming
    the fix, exit code 2, no traceback."""
    result = subprocess.run(
        COMMAND,
        env=ros_environment(ros.domain_id),
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rns_teleop_spacemouse: ")
    assert "libhidapi-hidraw0" in lines[0] or UDEV_RULE in lines[0]


@pytest.mark.parametrize(
    ("reason", "path", "fix"),
    [
        ("No connected or supported devices found.", "", UDEV_RULE),
        ("Failed to open device", "", UDEV_RULE),
        ("Device path '/dev/hidraw9' does not exist.", "/dev/hidraw9", UDEV_RULE),
        ("HID API is probably not installed. See ...", "", "apt-get install libhidapi-hidraw0"),
    ],
)
def test_each_open_failure_names_its_fix_in_one_line(reason, path, fix):
    text = open_failure_text(reason, path)
    assert fix in text
    assert "\n" not in text


def test_the_spacenav_twist_stream_turns_the_camera_through_the_controller(ros):
    """What spacenav_node publishes with config/spacenav.yaml while the cap is twisted about
    its z axis: plain Twist on spacenav/twist, reliable depth 10, ~32 Hz (one message per
    static_count_threshold ms), angular z = angular_scale/z at full deflection. The controller
    started with the same file and the remap of the file's comment turns the camera about its
    own z at that rate of simulated time once it has caught up with the attitude the commands add
    up to; the base stays within the DLS level."""

    config = REPO / "config" / "spacenav.yaml"
    driver = yaml.safe_load(config.read_text())["spacenav"]["ros__parameters"]
    rate = driver["angular_scale/z"]  # full deflection [rad/s]
    simulator = ros.add(SimulatorNode, {})
    ros.add(
        ControllerNode,
        {"state_timeout": 0.5},
        params_file=config,
        remappings={"cmd_twist": "spacenav/twist"},
    )
    probe = ros.probe()
    odom = Recorder(probe, Odometry, "base_odom")
    status = Recorder(probe, DiagnosticArray, "rns_controller/status")
    spacenav = probe.create_publisher(Twist, "spacenav/twist", 10)
    twist = Twist()
    twist.angular.z = rate
    probe.create_timer(0.031, lambda: spacenav.publish(twist))
    assert ros.spin_until(
        lambda: status.messages and status_values(status.messages[-1])["state"] == "OK",
        timeout=10.0,
    )
    # The start ramps the joint speed up; the controller then closes the gap between the camera
    # and the attitude the commands add up to (tracking_gain), after which the camera turns at
    # the commanded rate itself.
    # Measured between two such moments, the turn is the commanded rate's over the time between
    # them, however late the ticks ran meanwhile.
    time_0, camera_0 = caught_up_camera(ros, status, simulator)
    ros.spin_for(2.0)
    time_1, camera_1 = caught_up_camera(ros, status, simulator)
    assert status_values(status.messages[-1])["frame"] == "camera"
    turned = pin.log3(camera_0.T @ camera_1)  # in the first camera's axes
    print(f"turned {turned[2]:.5f} rad in {time_1 - time_0:.4f} s")
    assert turned[2] == pytest.approx(rate * (time_1 - time_0), rel=0.05)
    assert np.abs(turned[:2]).max() < 0.05 * turned[2]

    def rotation(msg):
        o = msg.pose.pose.orientation
        return pin.Quaternion(o.w, o.x, o.y, o.z).toRotationMatrix()

    first = rotation(odom.messages[0])
    deviation = max(attitude_deviation(first, rotation(m)) for m in odom.messages)
    assert math.degrees(deviation) < 1e-3
