"""joint_states carrying joints beyond the model's (a gripper's fingers beside the arm's, as
joint_state_broadcaster publishes them) over real DDS (loopback, private Context): the nodes use
the model's joints by name, ignore the others and report them once."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from rcl_interfaces.msg import Log
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rns_testing import Recorder, status_values
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from rns_ros.core.commands import match_joint_state
from rns_ros.nodes.cdr import JointStateReader
from rns_ros.nodes.controller import ControllerNode
from rns_ros.nodes.ptp import PtpNode

REPO = Path(__file__).resolve().parents[2]
#: The test arm with a two-finger hand: 7 controlled revolute joints, the fingers held.
GRIPPER_ARM = REPO / "test" / "data" / "arms" / "gripper7" / "model.yaml"
FINGERS = ["g7_finger_joint1", "g7_finger_joint2"]
#: The line each node logs once for the fingers.
IGNORING = "joint_states: ignoring joints not in the model: g7_finger_joint1, g7_finger_joint2"
COMMAND_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
#: State watchdogs of the nodes here: every node shares one process and its GIL [s].
TEST_STATE_TIMEOUT = 0.5
#: Publishing period [s] of the test's joint_states.
STATE_PERIOD = 0.01


def _node(ros, cls, **overrides):
    overrides.setdefault("model_config", str(GRIPPER_ARM))
    overrides.setdefault("state_timeout", TEST_STATE_TIMEOUT)
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(cls(context=ros.context, parameter_overrides=parameters))


def _rosout(probe, node_name: str) -> list[str]:
    lines: list[str] = []

    def note(msg: Log) -> None:
        if msg.name == node_name:
            lines.append(msg.msg)

    probe.create_subscription(Log, "/rosout", note, QoSProfile(depth=100))
    return lines


class Broadcaster:
    """joint_state_broadcaster of the arm with its hand: the arm's joints in reverse order with
    the fingers between them (no velocity interface on the fingers: NaN), every STATE_PERIOD
    from a timer on the probe node. ``theta`` [rad] (n,) is in the model's joint order."""

    def __init__(self, probe, joint_names, theta) -> None:
        arm = list(reversed(joint_names))
        self.names = [*arm[:3], FINGERS[0], *arm[3:], FINGERS[1]]
        self.joint_names = list(joint_names)
        self.theta = np.array(theta, dtype=float)
        self._publisher = probe.create_publisher(JointState, "joint_states", 10)
        probe.create_timer(STATE_PERIOD, self._publish)

    def message(self) -> JointState:
        value = dict(zip(self.joint_names, self.theta.tolist(), strict=True))
        value.update(dict.fromkeys(FINGERS, 0.02))
        positions = [value[name] for name in self.names]
        velocities = [math.nan if name in FINGERS else 0.0 for name in self.names]
        return JointState(name=self.names, position=positions, velocity=velocities)

    def _publish(self) -> None:
        self._publisher.publish(self.message())


def test_the_serialized_reader_keeps_every_name_of_a_longer_message(ros):
    """rns_controller reads joint_states from the bytes: a message with more names than the
    model has joints is read whole, and the model's joints are then taken by name."""
    from rclpy.serialization import serialize_message

    joints = [f"g7_joint{k}" for k in range(1, 8)]
    broadcaster = Broadcaster(ros.probe(), joints, np.linspace(-0.3, 0.3, 7))
    fields = JointStateReader()(serialize_message(broadcaster.message()))
    assert list(fields.names) == broadcaster.names
    assert fields.position.shape == fields.velocity.shape == (9,)
    state, extras = match_joint_state(
        fields.names, joints, positions=fields.position, velocities=fields.velocity
    )
    np.testing.assert_array_equal(state.positions, broadcaster.theta)
    assert extras == tuple(FINGERS)


def test_the_controller_serves_on_joint_states_with_finger_joints(ros):
    """rns_controller of the gripper arm, fed joint_states with the arm's joints reversed and
    the two fingers among them: it serves (status OK, joint_references in the model's order
    from the measured angles) and logs the ignored fingers once."""
    controller = _node(ros, ControllerNode, twist_stamped=False, default_twist_frame="world")
    probe = ros.probe()
    logs = _rosout(probe, controller.get_name())
    references = Recorder(probe, JointTrajectory, "joint_references")
    status = Recorder(probe, DiagnosticArray, "rns_controller/status")
    robot = controller.robot
    Broadcaster(probe, robot.joint_names, robot.initial_theta)
    twist = probe.create_publisher(Twist, "cmd_twist", COMMAND_QOS)

    def serving() -> bool:
        command = Twist()
        command.angular.z = 0.05
        twist.publish(command)
        return (
            bool(status.messages)
            and status_values(status.messages[-1])["state"] == "OK"
            and len(references.messages) > 3
        )

    assert ros.spin_until(serving, timeout=20.0), [
        status_values(m)["state"] for m in status.messages[-3:]
    ]
    point = references.messages[-1].points[0]
    assert list(references.messages[-1].joint_names) == list(robot.joint_names)
    np.testing.assert_allclose(point.positions, robot.initial_theta, atol=0.05)
    assert ros.spin_until(lambda: IGNORING in logs, timeout=5.0), logs
    ros.spin_for(0.2)
    assert sum("ignoring joints not in the model" in line for line in logs) == 1


def test_ptp_reaches_a_goal_on_joint_states_with_finger_joints(ros):
    """rns_ptp of the gripper arm driving a robot that takes each reference's positions at once
    (the test's) and reports them as joint_state_broadcaster would, fingers among the arm's
    joints: the goal is reached (DONE: the measured angles at the goal)."""
    ptp = _node(ros, PtpNode, method="joint_space", duration=0.5)
    probe = ros.probe()
    logs = _rosout(probe, ptp.get_name())
    status = Recorder(probe, DiagnosticArray, "rns_ptp/status")
    robot = ptp.robot
    arm = Broadcaster(probe, robot.joint_names, robot.initial_theta)

    def follow(msg: JointTrajectory) -> None:
        # positions of this arm's joints only (another test's nodes may share the domain)
        if (
            msg.points
            and sorted(msg.joint_names) == sorted(robot.joint_names)
            and len(msg.points[0].positions) == robot.n
        ):
            named = dict(zip(msg.joint_names, msg.points[0].positions, strict=True))
            arm.theta = np.array([named[joint] for joint in robot.joint_names])

    probe.create_subscription(JointTrajectory, "joint_references", follow, 10)

    def state() -> str | None:
        return status_values(status.messages[-1])["state"] if status.messages else None

    assert ros.spin_until(lambda: state() == "IDLE", timeout=20.0), state()
    goal = robot.initial_theta + np.deg2rad([3.0, -3.0, 2.0, 4.0, -3.0, 2.0, 3.0])
    goal_pub = probe.create_publisher(JointState, "ptp_goal", 10)
    goal_pub.publish(JointState(name=list(robot.joint_names), position=goal.tolist()))
    assert ros.spin_until(lambda: state() == "DONE", timeout=20.0), state()
    np.testing.assert_allclose(arm.theta, goal, atol=1e-6)
    assert IGNORING in logs
