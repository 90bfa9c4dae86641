"""rns_predictor over real DDS, on a /clock the test publishes: the predicted arm stands for
now + execution_delay, moves only once a twist's execution time has come, turns the camera at
the commanded rate, and compares and re-anchors on the telemetry it is given."""

from __future__ import annotations

import math
import time

import numpy as np
import pinocchio as pin
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rns_testing import Recorder, SimClock, status_values
from sensor_msgs.msg import JointState

from rns_ros.core import FreeFloatingState
from rns_ros.core.integration import attitude_deviation
from rns_ros.nodes.predictor import PredictorNode
from rns_ros.nodes.sim_clock import stamp_from_seconds

START = 10.0  # [s] the first clock reading and telemetry stamp
DELAY = 1.0  # [s] execution_delay
RATE = 0.1  # [rad/s] about world z


def _seconds(stamp) -> float:
    return stamp.sec + 1e-9 * stamp.nanosec


class _Ground:
    """The predictor in /ground with a hand-made clock, telemetry and operator."""

    def __init__(self, ros, **parameters) -> None:
        overrides = [
            Parameter("use_sim_time", value=True),
            Parameter("execution_delay", value=DELAY),
        ]
        overrides += [Parameter(name, value=value) for name, value in parameters.items()]
        self.node = ros.add(
            PredictorNode(
                context=ros.context,
                parameter_overrides=overrides,
                cli_args=["--ros-args", "-r", "__ns:=/ground"],
            )
        )
        self.ros, self.robot = ros, self.node.robot
        probe = ros.probe()
        self.clock = SimClock(probe, START)
        self.joints = probe.create_publisher(JointState, "/ground/joint_states", 10)
        self.odom = probe.create_publisher(Odometry, "/ground/base_odom", 10)
        self.twists = probe.create_publisher(TwistStamped, "/ground/cmd_twist", 10)
        self.predicted = Recorder(probe, JointState, "/ground/predicted/joint_states", qos=1000)
        self.status = Recorder(probe, DiagnosticArray, "/ground/rns_predictor/status", qos=100)
        self.theta = self.robot.initial_theta.copy()

    def telemetry(self, t: float, theta: np.ndarray) -> None:
        stamp = stamp_from_seconds(t)
        joints = JointState(name=list(self.robot.joint_names), position=theta.tolist())
        joints.header.stamp = stamp
        odom = Odometry()
        odom.header.stamp, odom.pose.pose.orientation.w = stamp, 1.0
        self.joints.publish(joints)
        self.odom.publish(odom)

    def twist(self, t: float, rate: float) -> None:
        msg = TwistStamped()
        msg.header.stamp, msg.header.frame_id = stamp_from_seconds(t), "world"
        msg.twist.angular.z = rate
        self.twists.publish(msg)

    def step_to(self, t: float, rate: float) -> None:
        """Advance the clock to ``t`` [s] in 10 ms steps, the operator streaming ``rate``
        [rad/s] stamped at each; wait for each step's prediction (as far as the twists go)."""
        while self.clock.seconds < t - 1e-9:
            self.twist(self.clock.seconds, rate)
            want = self.clock.seconds + DELAY
            self.clock.advance(0.01)
            self.ros.spin_until(lambda w=want: self.newest() >= w - 1e-6, 10.0)

    def newest(self) -> float:
        if not self.predicted.messages:
            return -math.inf
        return _seconds(self.predicted.messages[-1].header.stamp)

    def camera(self, msg: JointState) -> np.ndarray:
        q = self.robot.configuration(np.array(msg.position))
        return FreeFloatingState.compute(self.robot, q).camera.rotation


def test_the_predicted_arm_moves_at_the_execution_time_at_the_commanded_rate(ros):
    ground = _Ground(ros, wrist_gain=0.0)
    ground.clock.advance(0.0)
    ground.telemetry(START, ground.theta)  # the first telemetry starts the prediction
    ground.ros.spin_until(lambda: ground.node.arm is not None, 10.0)
    ground.step_to(START + 0.5, RATE)
    ground.step_to(START + 2.01, 0.0)  # a half-second pulse
    by_stamp = {round(_seconds(m.header.stamp), 6): m for m in ground.predicted.messages}
    rest = ground.camera(by_stamp[round(START + DELAY, 6)])
    before = ground.camera(JointState(position=ground.theta.tolist()))  # the telemetry
    later = ground.camera(by_stamp[round(START + 2.0 + DELAY, 6)])
    # the prediction starts at START + DELAY, where nothing has acted yet; the pulse turns the
    # camera by RATE * 0.5 s, less the ramp from rest (1 rad/s^2: RATE^2 / 2 = 0.005 rad)
    assert attitude_deviation(before, rest) < 1e-12
    turned = attitude_deviation(rest, later)
    assert turned == pytest.approx(RATE * 0.5 - RATE**2 / 2, abs=2e-3)


def test_a_camera_goal_is_predicted_from_its_stamp_plus_the_delay(ros):
    """A 5 deg goal stamped START: the predicted camera stands still until START + D, then the
    goal law turns it onto the goal (within goal_tolerance), as the spacecraft will once the
    goal arrives; the operator streams zeros meanwhile, which do not cancel it."""
    ground = _Ground(ros, wrist_gain=0.0)
    goals = ground.ros.probe().create_publisher(
        PoseStamped, "/ground/rns_controller/camera_goal", 10
    )
    ground.clock.advance(0.0)
    ground.telemetry(START, ground.theta)
    ground.ros.spin_until(lambda: ground.node.arm is not None, 10.0)
    before = ground.camera(JointState(position=ground.theta.tolist()))
    goal = pin.exp3(np.array([0.0, 0.0, math.radians(5.0)])) @ before
    x, y, z, w = pin.Quaternion(goal).coeffs()
    msg = PoseStamped()
    msg.header.stamp, msg.header.frame_id = stamp_from_seconds(START), "world"
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = float(x), float(y), float(z), float(w)
    goals.publish(msg)
    assert ground.ros.spin_until(lambda: ground.node.goals == 1, 10.0)
    ground.step_to(START + 4.0, 0.0)
    by_stamp = {round(_seconds(m.header.stamp), 6): m for m in ground.predicted.messages}
    still = ground.camera(by_stamp[round(START + DELAY, 6)])
    assert attitude_deviation(before, still) < 1e-12
    end = ground.camera(by_stamp[round(START + 4.0 + DELAY - 0.01, 6)])
    assert attitude_deviation(goal, end) <= 1e-3  # goal_tolerance [rad]


def test_telemetry_that_disagrees_is_reported_and_re_anchors(ros):
    ground = _Ground(ros, wrist_gain=0.0, status_period=0.05)
    ground.clock.advance(0.0)
    ground.telemetry(START, ground.theta)
    ground.ros.spin_until(lambda: ground.node.arm is not None, 10.0)
    ground.step_to(START + DELAY + 0.5, RATE)
    # the spacecraft "did not move": telemetry at rest for a stamp the prediction moved through
    ground.telemetry(START + DELAY + 0.5, ground.theta)
    ground.ros.spin_until(lambda: ground.node.arm.resyncs > 0, 10.0)
    ground.step_to(START + DELAY + 0.6, RATE)
    ground.ros.spin_until(
        lambda: ground.status.messages and "resynced" in status_values(ground.status.messages[-1])
    )
    values = status_values(ground.status.messages[-1])
    assert int(values["resynced"]) == 1
    # the camera had turned about RATE * 0.5 s in the prediction: that much off, in degrees
    assert float(values["max_prediction_error_camera_deg"]) == pytest.approx(
        math.degrees(RATE * 0.5 - RATE**2 / 2), abs=0.2
    )


def test_after_a_stall_of_its_own_the_predictor_takes_the_waiting_twists_before_judging_silence(
    ros,
):
    """The operator's twists stop coming for longer than command_timeout on both clocks, but
    only because this process stalled (its ticks 1 s apart on the steady clock): the twists of
    meanwhile still wait in the queue, so the prediction goes no further than the newest twist's
    stamp + D until the process has run command_timeout without one (predicted on to now + D
    with a stale command, a 1 s SIGSTOP of rns_predictor made a 1 deg prediction error)."""
    ground = _Ground(ros)
    node = ground.node
    timeout = node._settings.gate.command_timeout
    ground.telemetry(START, ground.theta)
    ground.step_to(START + 0.5, RATE)
    ground.ros.spin_until(lambda: node.arm is not None and node.twists > 0, 10.0)
    newest = node.newest_command
    ground.clock.advance(2.0)  # the rest of the run went on meanwhile
    ground.ros.spin_until(lambda: node.now_s() >= newest + 2.0 - 1e-9, 10.0)
    node._command_received = node._last_tick = time.monotonic() - 2 * timeout  # stalled
    node._on_tick()
    assert node._horizon() == pytest.approx(newest + DELAY)
    node._awake_since -= 2 * timeout  # ran command_timeout since, no twist came: silent
    assert node._horizon() == pytest.approx(node.now_s() + DELAY)
