"""rns_controller's ~/pause and camera orientation goal over DDS (loopback, private Context), in
closed loop with rns_simulator: the physics decides whether the camera got there and whether the
base stayed put."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rns_testing import Recorder, status_values
from std_srvs.srv import SetBool
from trajectory_msgs.msg import JointTrajectory

from rns_ros.core.integration import attitude_deviation
from rns_ros.nodes.controller import ControllerNode
from rns_ros.nodes.controller_requests import REACHED_QOS
from rns_ros.nodes.simulator import SimulatorNode

#: Base attitude deviation allowed [deg]: the DLS level of the other closed-loop tests.
BASE_DEVIATION_DEG = 1e-3
GOAL_TOLERANCE = 1e-3  # [rad], the controller's default
COMMAND_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
#: state_timeout of these tests [s]: every node shares one process (see test_controller_node).
TEST_STATE_TIMEOUT = 0.5
#: Time for the simulated joint servos to reach a held reference [s].
SETTLE = 0.3


def _stack(ros):
    simulator = ros.add(SimulatorNode(context=ros.context))
    overrides = [Parameter("state_timeout", value=TEST_STATE_TIMEOUT)]
    controller = ros.add(ControllerNode(context=ros.context, parameter_overrides=overrides))
    probe = ros.probe()
    return SimpleNamespace(
        simulator=simulator,
        controller=controller,
        probe=probe,
        references=Recorder(probe, JointTrajectory, "joint_references"),
        status=Recorder(probe, DiagnosticArray, "rns_controller/status"),
        odom=Recorder(probe, Odometry, "base_odom"),
        reached=Recorder(probe, PoseStamped, "rns_controller/camera_goal_reached", REACHED_QOS),
        goal=probe.create_publisher(PoseStamped, "rns_controller/camera_goal", 1),
    )


@pytest.fixture
def stack(ros):
    return _stack(ros)


def _state(stack) -> str | None:
    messages = stack.status.messages
    return status_values(messages[-1])["state"] if messages else None


def _camera(simulator) -> np.ndarray:
    """The simulated camera's attitude (world <- camera) now."""
    with simulator._lock:
        state = simulator.simulator.snapshot()
    robot = simulator.robot
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, state.q)
    return data.oMf[robot.camera_frame_id].rotation.copy()


def _odom_rotation(msg: Odometry) -> np.ndarray:
    o = msg.pose.pose.orientation
    return pin.Quaternion(o.w, o.x, o.y, o.z).toRotationMatrix()


def _base_deviation_deg(odom: list[Odometry]) -> float:
    first = _odom_rotation(odom[0])
    return math.degrees(max(attitude_deviation(first, _odom_rotation(m)) for m in odom))


def _goal_msg(rotation: np.ndarray, frame_id: str = "world") -> PoseStamped:
    q = pin.Quaternion(rotation)
    msg = PoseStamped()
    msg.header.frame_id = frame_id
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = q.x, q.y, q.z, q.w
    return msg


def _send_goal(ros, stack, msg: PoseStamped) -> None:
    assert ros.spin_until(lambda: stack.goal.get_subscription_count() > 0, timeout=10.0)
    stack.goal.publish(msg)


def _pause(ros, stack, data: bool) -> SetBool.Response:
    client = stack.probe.create_client(SetBool, "rns_controller/pause")
    assert client.wait_for_service(timeout_sec=5.0)
    future = client.call_async(SetBool.Request(data=data))
    assert ros.spin_until(future.done, timeout=5.0)
    return future.result()


def _speeds(references) -> np.ndarray:
    return np.array([np.abs(m.points[0].velocities).max() for m in references])


def test_pause_holds_the_arm_at_zero_velocity_and_resumes_with_a_ramp(ros, stack):
    """An operator streams 0.1 rad/s about world x. ~/pause true: status PAUSED (level OK), every
    output is exactly zero velocity and the simulated camera stands still although the operator
    keeps commanding; false: the command ramps up from rest and the camera turns again."""
    twist = TwistStamped()
    twist.header.frame_id = "world"
    twist.twist.angular.x = 0.1
    operator = stack.probe.create_publisher(TwistStamped, "cmd_twist", COMMAND_QOS)
    stack.probe.create_timer(0.02, lambda: operator.publish(twist))
    assert ros.spin_until(lambda: _state(stack) == "OK", timeout=10.0)

    response = _pause(ros, stack, True)
    assert response.success
    assert response.message == "paused: zero velocity"
    assert ros.spin_until(lambda: _state(stack) == "PAUSED", timeout=5.0)
    status = stack.status.messages[-1].status[0]
    assert status.level == status.OK  # a hold is not a fault
    count = len(stack.references.messages)
    stopped = _camera(stack.simulator)
    ros.spin_for(SETTLE)  # the joint servos catch up with the held reference
    before = _camera(stack.simulator)
    ros.spin_for(0.6)
    paused = stack.references.messages[count:]
    settled = np.linalg.norm(pin.log3(before @ stopped.T))
    turned = np.linalg.norm(pin.log3(_camera(stack.simulator) @ before.T))
    print(f"camera turned {settled:.2e} rad settling, then {turned:.2e} rad in 0.6 s of pause")
    assert len(paused) > 20
    assert np.all(_speeds(paused) == 0.0)
    assert settled < 1e-3
    assert turned < 1e-6  # moving, it would have turned ~0.06 rad
    assert {status_values(m)["state"] for m in stack.status.messages[-20:]} == {"PAUSED"}
    assert _pause(ros, stack, True).message == "already paused"

    assert _pause(ros, stack, False).message == "resumed"
    count = len(stack.references.messages)
    assert ros.spin_until(lambda: _state(stack) == "OK", timeout=5.0)
    resumed = [status_values(m)["state"] for m in stack.status.messages[-100:]]
    assert "RAMPING" in resumed  # from rest, not a step
    speeds = _speeds(stack.references.messages[count:])
    assert speeds[0] < 0.5 * speeds.max()
    before = _camera(stack.simulator)
    ros.spin_for(0.5)
    assert np.linalg.norm(pin.log3(_camera(stack.simulator) @ before.T)) > 0.02
    assert _base_deviation_deg(stack.odom.messages) < BASE_DEVIATION_DEG


def test_the_camera_turns_to_an_orientation_goal_reactionlessly_and_reports_it(ros, stack):
    """A goal 0.3 rad from the camera's attitude about an oblique world axis: the controller
    reports GOAL_ACTIVE, publishes the goal on ~/camera_goal_reached once there, then
    GOAL_REACHED; the simulated camera is within the tolerance of the goal and the base did not
    turn beyond the DLS level."""
    assert ros.spin_until(lambda: _state(stack) == "IDLE", timeout=10.0)
    start = _camera(stack.simulator)
    axis = np.array([1.0, -1.0, 1.0]) / math.sqrt(3.0)
    target = pin.exp3(0.3 * axis) @ start
    msg = _goal_msg(target)
    _send_goal(ros, stack, msg)
    assert ros.spin_until(lambda: _state(stack) == "GOAL_ACTIVE", timeout=5.0)
    assert ros.spin_until(lambda: stack.reached.messages, timeout=30.0)
    assert ros.spin_until(lambda: _state(stack) == "GOAL_REACHED", timeout=5.0)
    ros.spin_for(0.3)
    reached = stack.reached.messages
    assert len(reached) == 1
    assert reached[0].pose.orientation == msg.pose.orientation
    error = np.linalg.norm(pin.log3(target @ _camera(stack.simulator).T))
    deviation = _base_deviation_deg(stack.odom.messages)
    print(f"camera {error:.2e} rad from the goal; base deviation {deviation:.2e} deg")
    assert error < 2 * GOAL_TOLERANCE  # reached on the measured state, then held still
    assert deviation < BASE_DEVIATION_DEG
    states = {status_values(m)["state"] for m in stack.status.messages}
    assert "GOAL_ACTIVE" in states
    limits = stack.controller.robot.velocity_limits
    velocities = np.array([m.points[0].velocities for m in stack.references.messages])
    peak = (np.abs(velocities) / limits).max()
    print(f"peak joint speed {peak:.3f} of the URDF limit")
    assert 0.0 < peak <= 1.0


@pytest.mark.parametrize(
    ("orientation", "frame_id", "text"),
    [
        ((0.0, 0.0, 0.0, 0.0), "world", "not a unit quaternion"),
        ((math.nan, 0.0, 0.0, 1.0), "world", "finite"),
        ((0.0, 0.0, 0.0, 1.0), "camera", "not the world frame"),
    ],
    ids=["zero-quaternion", "nan", "frame"],
)
def test_a_bad_goal_is_rejected_with_a_reported_error_and_nothing_moves(
    ros, stack, orientation, frame_id, text
):
    assert ros.spin_until(lambda: _state(stack) == "IDLE", timeout=10.0)
    msg = PoseStamped()
    msg.header.frame_id = frame_id
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = orientation
    _send_goal(ros, stack, msg)
    assert ros.spin_until(lambda: _state(stack) == "INVALID_COMMAND", timeout=5.0)
    status = stack.status.messages[-1].status[0]
    assert status.level == status.ERROR
    assert text in status.message
    assert "camera goal" in status.message
    ros.spin_for(0.3)
    assert np.all(_speeds(stack.references.messages) == 0.0)
    assert not stack.reached.messages


def test_a_moving_twist_takes_over_from_the_goal_and_zeros_do_not(ros, stack):
    """A goal 1 rad away is being turned to; a zero twist (a teleop at rest) leaves it active, a
    moving one cancels it: the controller follows the twist, the goal is never reported."""
    assert ros.spin_until(lambda: _state(stack) == "IDLE", timeout=10.0)
    target = pin.exp3(np.array([0.0, 0.0, 1.0])) @ _camera(stack.simulator)
    _send_goal(ros, stack, _goal_msg(target, frame_id=""))
    assert ros.spin_until(lambda: _state(stack) == "GOAL_ACTIVE", timeout=5.0)
    operator = stack.probe.create_publisher(TwistStamped, "cmd_twist", COMMAND_QOS)
    twist = TwistStamped()
    twist.header.frame_id = "world"
    for _ in range(5):
        operator.publish(twist)
        ros.spin_for(0.05)
    assert _state(stack) == "GOAL_ACTIVE"
    twist.twist.angular.y = 0.05
    timer = stack.probe.create_timer(0.02, lambda: operator.publish(twist))
    assert ros.spin_until(lambda: _state(stack) == "OK", timeout=5.0)
    ros.spin_for(0.5)
    timer.cancel()
    assert _state(stack) == "OK"
    assert not stack.reached.messages
