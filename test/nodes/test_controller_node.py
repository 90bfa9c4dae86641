"""rns_controller over real DDS (loopback, private Context) in closed loop with rns_simulator."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rns_testing import Recorder
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from rns_ros.core import ConfigError
from rns_ros.core.integration import attitude_deviation
from rns_ros.nodes.controller import PARAMETERS, ControllerNode
from rns_ros.nodes.simulator import SimulatorNode

REPO = Path(__file__).resolve().parents[2]
JOINTS = [f"joint_{i}" for i in range(1, 8)]
COMMAND_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


def _node(ros, cls, **overrides):
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(cls(context=ros.context, parameter_overrides=parameters))


def _state(msg: DiagnosticArray) -> dict[str, str]:
    return {kv.key: kv.value for kv in msg.status[0].values}


class Operator:
    """Publishes one twist at a fixed rate from a timer on the probe node (like a joystick)."""

    def __init__(self, probe, rate=50.0, stamped=True):
        msg_type = TwistStamped if stamped else Twist
        self.publisher = probe.create_publisher(msg_type, "cmd_twist", COMMAND_QOS)
        self.stamped, self.probe = stamped, probe
        self.angular, self.frame, self.active = (0.0, 0.0, 0.0), "world", False
        probe.create_timer(1.0 / rate, self._tick)

    def _tick(self):
        if not self.active:
            return
        twist = Twist()
        twist.angular.x, twist.angular.y, twist.angular.z = self.angular
        if self.stamped:
            msg = TwistStamped(twist=twist)
            msg.header.frame_id = self.frame
            msg.header.stamp = self.probe.get_clock().now().to_msg()
        else:
            msg = twist
        self.publisher.publish(msg)


@pytest.fixture
def stack(ros):
    """Simulator + controller + probe recorders on one executor."""
    simulator = _node(ros, SimulatorNode)
    controller = _node(ros, ControllerNode)
    probe = ros.probe()
    streams = {
        "references": Recorder(probe, JointTrajectory, "joint_references"),
        "status": Recorder(probe, DiagnosticArray, "rns_controller/status"),
        "odom": Recorder(probe, Odometry, "base_odom"),
    }
    return SimpleNamespace(simulator=simulator, controller=controller, probe=probe, streams=streams)


def _latest_state(streams):
    messages = streams["status"].messages
    return _state(messages[-1])["state"] if messages else None


def test_closed_loop_turns_the_camera_and_leaves_the_base_alone(ros, stack):
    controller, probe, streams = stack.controller, stack.probe, stack.streams
    operator = Operator(probe)
    operator.angular, operator.active = (0.1, 0.0, 0.0), True
    assert ros.spin_until(lambda: _latest_state(streams) == "OK", timeout=10.0)
    start = len(streams["references"].messages)
    t0 = time.monotonic()
    camera_0 = _camera_rotation(controller)
    ros.spin_for(1.5)
    elapsed = time.monotonic() - t0
    references = streams["references"].messages[start:]
    rate = len(references) / elapsed
    print(f"joint_references at {rate:.1f} Hz")
    assert rate == pytest.approx(100.0, rel=0.15)
    assert np.abs(references[-1].points[0].velocities).max() > 0.01
    states = {_state(m)["state"] for m in streams["status"].messages[-100:]}
    assert states == {"OK"}
    status = _state(streams["status"].messages[-1])
    assert float(status["sigma_min"]) > 0.2
    assert np.abs([float(x) for x in status["coupling_momentum"].split()]).max() < 1e-9
    # the camera turned about world x at ~0.1 rad/s; the base did not turn
    turned = pin.log3(_camera_rotation(controller) @ camera_0.T)
    assert turned[0] == pytest.approx(0.1 * elapsed, rel=0.3)
    assert np.abs(turned[1:]).max() < 0.2 * abs(turned[0])
    odom = streams["odom"].messages
    deviation = max(attitude_deviation(_odom_rotation(odom[0]), _odom_rotation(m)) for m in odom)
    print(f"base attitude deviation over DDS: {math.degrees(deviation):.2e} deg")
    assert math.degrees(deviation) < 1e-3

    # the operator lets go: the output ramps down and stops within timeout + ramp
    operator.active = False
    released = time.monotonic()
    assert ros.spin_until(lambda: _latest_state(streams) == "STALE_COMMAND", timeout=3.0)
    stopped_after = time.monotonic() - released
    assert stopped_after < 0.5 + 0.1 + 0.3  # timeout 0.5 s, ramp 0.1 rad/s / 1 rad/s^2
    seen = [_state(m)["state"] for m in streams["status"].messages]
    assert "DECELERATING" in seen
    ros.spin_for(0.1)
    assert np.all(np.array(streams["references"].messages[-1].points[0].velocities) == 0.0)


def test_nan_twist_is_invalid_and_nothing_moves(ros, stack):
    probe, streams = stack.probe, stack.streams
    joints = Recorder(probe, JointState, "joint_states")
    operator = Operator(probe)
    operator.angular, operator.active = (math.nan, 0.0, 0.0), True
    assert ros.spin_until(lambda: _latest_state(streams) == "INVALID_COMMAND", timeout=10.0)
    ros.spin_for(0.5)
    status = streams["status"].messages[-1]
    assert status.status[0].level == status.status[0].ERROR
    assert "finite" in status.status[0].message
    for msg in streams["references"].messages:
        assert np.all(np.array(msg.points[0].velocities) == 0.0)
    positions = np.array([m.position for m in joints.messages])
    assert np.ptp(positions, axis=0).max() < 1e-12


def test_unknown_frame_and_excessive_speed_are_rejected(ros, stack):
    probe, streams = stack.probe, stack.streams
    operator = Operator(probe)
    operator.angular, operator.frame, operator.active = (0.1, 0.0, 0.0), "map", True
    assert ros.spin_until(lambda: _latest_state(streams) == "INVALID_COMMAND", timeout=10.0)
    assert "'map' is not one of" in streams["status"].messages[-1].status[0].message
    operator.angular, operator.frame = (5.0, 0.0, 0.0), "camera"
    ros.spin_for(0.3)
    assert "max_angular_speed" in streams["status"].messages[-1].status[0].message
    operator.angular = (0.0, 0.05, 0.0)
    assert ros.spin_until(lambda: _latest_state(streams) == "OK", timeout=3.0)
    assert _state(streams["status"].messages[-1])["frame"] == "camera"


def test_nothing_is_published_before_the_first_joint_state(ros):
    controller = _node(ros, ControllerNode, twist_stamped=False, default_twist_frame="world")
    probe = ros.probe()
    references = Recorder(probe, JointTrajectory, "joint_references")
    status = Recorder(probe, DiagnosticArray, "rns_controller/status")
    ros.spin_for(0.5)
    assert references.messages == []
    assert status.messages == []
    # one joint state (names shuffled) starts the controller; a plain Twist is accepted
    names = list(controller.robot.joint_names)[::-1]
    probe.create_publisher(JointState, "joint_states", 10).publish(
        JointState(name=names, position=[0.3] * 7)
    )
    operator = Operator(probe, stamped=False)
    operator.angular, operator.active = (0.0, 0.0, 0.05), True
    assert ros.spin_until(lambda: status.messages and _state(status.messages[-1])["state"] == "OK")
    assert _state(status.messages[-1])["frame"] == "world"
    point = references.messages[-1].points[0]
    assert np.allclose(point.positions, 0.3, atol=0.05)
    # the reactionless output carries no coupling momentum at the reported configuration
    assert float(_state(status.messages[-1])["sigma_min"]) > 0.0


def test_teleop_twist_keyboard_style_input_turns_the_camera_about_its_own_z(ros):
    """What teleop_twist_keyboard sends when 'j' is held: plain Twist, angular z, on cmd_vel,
    reliable QoS, no frame. The README's remap and twist_stamped:=false make it a camera-frame
    yaw command; the camera turns about its own z axis and the base stays put."""
    _node(ros, SimulatorNode)
    controller = ros.add(
        ControllerNode,
        {"twist_stamped": False, "default_twist_frame": "camera"},
        remappings={"cmd_twist": "cmd_vel"},
    )
    probe = ros.probe()
    odom = Recorder(probe, Odometry, "base_odom")
    status = Recorder(probe, DiagnosticArray, "rns_controller/status")
    keyboard = probe.create_publisher(Twist, "cmd_vel", 10)  # rclpy's default: reliable
    yaw = Twist()
    yaw.angular.z = 0.1
    probe.create_timer(0.05, lambda: keyboard.publish(yaw))  # key auto-repeat, ~20 Hz
    assert ros.spin_until(lambda: status.messages and _state(status.messages[-1])["state"] == "OK")
    camera_0 = _camera_rotation(controller)
    t0 = time.monotonic()
    ros.spin_for(1.0)
    elapsed = time.monotonic() - t0
    assert _state(status.messages[-1])["frame"] == "camera"
    # the rotation between the two camera attitudes, in the first camera's axes
    turned = pin.log3(camera_0.T @ _camera_rotation(controller))
    assert turned[2] == pytest.approx(0.1 * elapsed, rel=0.3)
    assert np.abs(turned[:2]).max() < 0.05 * turned[2]
    messages = odom.messages
    deviation = max(
        attitude_deviation(_odom_rotation(messages[0]), _odom_rotation(m)) for m in messages
    )
    assert math.degrees(deviation) < 1e-3


def test_shipped_teleop_twist_files_fit_the_controller():
    """config/teleop_twist_{joy,keyboard}.yaml: stamped, a frame the controller accepts, turbo
    rates below max_angular_speed, no linear axes on the joystick."""
    defaults = yaml.safe_load((REPO / "config" / "controller.yaml").read_text())
    limit = defaults["/**"]["ros__parameters"]["max_angular_speed"]
    accepted = {"world", "base_link", "camera"}
    joy = yaml.safe_load((REPO / "config" / "teleop_twist_joy.yaml").read_text())
    joy = joy["/**"]["ros__parameters"]
    assert joy["publish_stamped_twist"] is True
    assert joy["frame"] in accepted
    for axis in ("roll", "pitch", "yaw"):
        assert isinstance(joy[f"axis_angular.{axis}"], int)
        assert joy[f"axis_angular.{axis}"] >= 0
        assert 0.0 < joy[f"scale_angular.{axis}"] <= joy[f"scale_angular_turbo.{axis}"] < limit
    assert all(joy[f"axis_linear.{axis}"] == -1 for axis in "xyz")
    keyboard = yaml.safe_load((REPO / "config" / "teleop_twist_keyboard.yaml").read_text())
    keyboard = keyboard["/**"]["ros__parameters"]
    assert keyboard["stamped"] is True
    assert keyboard["frame_id"] in accepted


def test_a_changed_command_is_served_at_once_and_restarts_the_period(ros):
    """immediate_reaction: at 2 Hz a new command does not wait up to 0.5 s for the next tick; it
    gets its own reference between ticks, and the period restarts from there."""
    _node(ros, ControllerNode, rate=2.0, command_timeout=5.0, wrist_gain=0.0)
    probe = ros.probe()
    references = Recorder(probe, JointTrajectory, "joint_references")
    state_pub = probe.create_publisher(JointState, "joint_states", 10)
    state = JointState(name=JOINTS, position=np.deg2rad([-90, -30, 0, -70, 180, -30, 0]).tolist())
    probe.create_timer(0.02, lambda: state_pub.publish(state))
    operator = Operator(probe, rate=20.0)
    operator.angular, operator.active = (0.1, 0.0, 0.0), True

    def velocities(msg) -> np.ndarray:
        return np.array(msg.points[0].velocities)

    assert ros.spin_until(
        lambda: (
            len(references.messages) >= 2
            and np.abs(velocities(references.messages[-1])).max() > 1e-3
        ),
        timeout=10.0,
    )
    forward = velocities(references.messages[-1])
    ros.spin_for(0.1)  # somewhere inside a period
    operator.angular = (-0.1, 0.0, 0.0)
    assert ros.spin_until(
        lambda: np.dot(velocities(references.messages[-1]), forward) < 0.0, timeout=5.0
    )
    ros.spin_for(1.2)  # two more periods

    def stamp(msg) -> float:
        return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec

    stamps = [stamp(m) for m in references.messages]
    first_reverse = next(
        k for k, m in enumerate(references.messages) if np.dot(velocities(m), forward) < 0.0
    )
    early = stamps[first_reverse] - stamps[first_reverse - 1]
    assert early < 0.45, f"the reversed command waited for the tick ({early:.3f} s)"
    later = np.diff(stamps[first_reverse:])
    assert later == pytest.approx(0.5, abs=0.05), "the period restarts at the early tick"


def test_linear_part_is_reported_as_unachieved(ros, stack):
    probe, streams = stack.probe, stack.streams
    publisher = probe.create_publisher(TwistStamped, "cmd_twist", COMMAND_QOS)
    msg = TwistStamped()
    msg.header.frame_id = "camera"
    msg.twist.linear.x, msg.twist.angular.z = 0.25, 0.05

    def fresh_ok():
        publisher.publish(msg)
        return _latest_state(streams) == "OK"

    assert ros.spin_until(fresh_ok, timeout=10.0)
    values = _state(streams["status"].messages[-1])
    assert [float(x) for x in values["unachieved_linear"].split()] == [0.25, 0.0, 0.0]


def test_runtime_parameter_changes_are_validated(ros):
    controller = _node(ros, ControllerNode)
    results = controller.set_parameters(
        [
            Parameter("method", value="magic"),
            Parameter("epsilon", value=-1.0),
            Parameter("method", value="sc"),
            Parameter("wrist_gain", value=10.0),
        ]
    )
    assert not results[0].successful
    assert "must be one of" in results[0].reason
    assert not results[1].successful
    assert results[2].successful
    assert results[3].successful
    assert controller.controller.settings.method == "sc"
    assert controller.controller.settings.gains.wrist_gain == 10.0


def test_shutdown_publishes_zero_velocity(ros, stack):
    controller, probe, streams = stack.controller, stack.probe, stack.streams
    operator = Operator(probe)
    operator.angular, operator.active = (0.0, 0.1, 0.0), True
    assert ros.spin_until(
        lambda: (
            streams["references"].messages
            and np.abs(streams["references"].messages[-1].points[0].velocities).max() > 0.01
        )
    )
    ros.detach(controller)
    count = len(streams["references"].messages)
    controller.destroy_node()
    assert ros.spin_until(lambda: len(streams["references"].messages) > count, timeout=2.0)
    assert np.all(np.array(streams["references"].messages[-1].points[0].velocities) == 0.0)


def test_config_yaml_mirrors_the_declared_defaults():
    content = yaml.safe_load((REPO / "config" / "controller.yaml").read_text())
    values = content["/**"]["ros__parameters"]
    assert values == {spec.name: spec.default for spec in PARAMETERS}


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"method": "magic"}, "'method' must be one of"),
        ({"rate": 5000.0}, "'rate' out of range"),
        ({"wrist_gain": -1.0}, "'wrist_gain' out of range"),
    ],
)
def test_bad_parameters_fail_with_a_clear_error(ros, overrides, message):
    with pytest.raises(ConfigError, match=message):
        ControllerNode(
            context=ros.context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )


def _camera_rotation(controller) -> np.ndarray:
    robot = controller.robot
    q = robot.configuration(
        controller._theta, controller._base_position, controller._base_orientation
    )
    pin.framesForwardKinematics(robot.model, robot.data, q)
    return robot.data.oMf[robot.camera_frame_id].rotation.copy()


def _odom_rotation(msg: Odometry) -> np.ndarray:
    o = msg.pose.pose.orientation
    return pin.Quaternion(o.w, o.x, o.y, o.z).toRotationMatrix()


def test_velocity_output_interface_drives_the_simulator(ros):
    """ros2_control shape: Float64MultiArray of joint velocities in the order of `joints`.

    Both ends use a reversed order. Were either end to ignore it, the simulator would drive the
    joints with a permuted theta_dot, which is not in the reaction null space: the base would turn.
    """
    order = [f"joint_{i}" for i in range(7, 0, -1)]
    _node(ros, SimulatorNode, command_interface="velocity", joints=order)
    _node(ros, ControllerNode, output_interface="velocity", joints=order)
    probe = ros.probe()
    velocities = Recorder(probe, Float64MultiArray, "joint_velocities")
    joints = Recorder(probe, JointState, "joint_states")
    odom = Recorder(probe, Odometry, "base_odom")
    operator = Operator(probe)
    operator.angular, operator.active = (0.0, 0.0, 0.1), True
    assert ros.spin_until(
        lambda: velocities.messages and np.abs(velocities.messages[-1].data).max() > 0.01
    )
    ros.spin_for(1.0)
    assert len(velocities.messages[-1].data) == 7
    moved = np.ptp([m.position for m in joints.messages], axis=0).max()
    assert moved > 1e-2
    messages = odom.messages
    deviation = max(
        attitude_deviation(_odom_rotation(messages[0]), _odom_rotation(m)) for m in messages
    )
    print(f"base attitude deviation, reversed joint order: {math.degrees(deviation):.2e} deg")
    assert math.degrees(deviation) < 1e-3


def test_velocity_output_joint_order_must_match_the_model(ros):
    with pytest.raises(ConfigError, match=r"'joints'.*missing joints \['joint_7'\]"):
        _node(ros, ControllerNode, output_interface="velocity", joints=JOINTS[:6])


def test_ctrl_c_publishes_zero_velocity(ros):
    """The installed-style executable, interrupted like a terminal user would."""
    probe = ros.probe()
    references = Recorder(probe, JointTrajectory, "joint_references")
    state_pub = probe.create_publisher(JointState, "joint_states", 10)
    names = [f"joint_{i}" for i in range(1, 8)]
    probe.create_timer(0.05, lambda: state_pub.publish(JointState(name=names, position=[0.4] * 7)))
    operator = Operator(probe)
    operator.angular, operator.active = (0.1, 0.0, 0.0), True
    process = subprocess.Popen(
        [sys.executable, "-m", "rns_ros.nodes.controller"],
        env=os.environ.copy(),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
    )
    try:
        assert ros.spin_until(
            lambda: (
                references.messages
                and np.abs(references.messages[-1].points[0].velocities).max() > 0.01
            ),
            timeout=20.0,
        )
        operator.active = False
        process.send_signal(signal.SIGINT)
        count = len(references.messages)
        assert ros.spin_until(lambda: process.poll() is not None, timeout=10.0)
        ros.spin_for(0.3)
        assert process.returncode == 0
        after = references.messages[count:]
        assert after, f"no message after Ctrl-C; output:\n{process.stdout.read().decode()}"
        assert np.all(np.array(after[-1].points[0].velocities) == 0.0)
    finally:
        if process.poll() is None:
            process.kill()
        process.wait(timeout=5)
