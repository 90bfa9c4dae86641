"""rns_controller on a /clock that cannot be trusted (use_sim_time, lockstep side by side, the
position interface): a second publisher far ahead, a clock that runs backwards. Every joint
command stays within the URDF limits and near the measured angles, the fault is reported once,
naming the publishers of /clock, and the controller resumes from the measured angles once the
clock runs forward from one publisher again. Also: use_sim_time cannot be switched on a running
controller, and its hold output is bounded when the reference stands far from the arm."""

from __future__ import annotations

import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rns_testing import (
    SATELLITE_OBSERVATION_DEG,
    Recorder,
    assert_one_clock_fault_logged,
    status_values,
)
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import SetBool
from trajectory_msgs.msg import JointTrajectory

from rns_ros.nodes.controller import ControllerNode
from rns_ros.nodes.sim_clock import stamp_from_seconds

JOINTS = [f"joint_{i}" for i in range(1, 8)]
PERIOD = 0.01  # [s] the controller's default rate
#: How far a command may stand from the measured angles here [rad]: max_reference_error (0.25)
#: and rounding.
NEAR = 0.3
#: Wall time [s] the plant waits for the output a /clock may cause, and the longest any
#: condition is waited for (a loaded machine; nothing is asserted about either).
OUTPUT_WAIT = 1.0
PATIENCE = 20.0


def _controller(ros, **parameters) -> ControllerNode:
    overrides = [Parameter(name, value=value) for name, value in parameters.items()]
    return ros.add(ControllerNode(context=ros.context, parameter_overrides=overrides))


class _PositionPlant:
    """A controller on simulated time with output_lead one period and output_interface
    position, and by hand what a lockstep plant gives it: each period a joint state (at the
    newest commanded positions: a position controller), the base pose, an operator sample and
    then /clock."""

    def __init__(self, ros) -> None:
        self.ros = ros
        self.controller = _controller(
            ros,
            use_sim_time=True,
            output_lead=PERIOD,
            output_interface="position",
            state_timeout=0.5,
            clock_timeout=30.0,  # /clock stands still while the test waits for outputs
            wrist_gain=0.0,
        )
        probe = ros.probe()
        self.positions = Recorder(probe, Float64MultiArray, "joint_positions", qos=1000)
        self.status = Recorder(probe, DiagnosticArray, "rns_controller/status", qos=1000)
        self._states = probe.create_publisher(JointState, "joint_states", 10)
        self._odom = probe.create_publisher(Odometry, "base_odom", 10)
        self.clock = probe.create_publisher(Clock, "/clock", 10)
        self._twists = probe.create_publisher(
            TwistStamped,
            "cmd_twist",
            QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT),
        )
        self.angles = np.deg2rad(SATELLITE_OBSERVATION_DEG)
        #: (measured angles [rad] (7,), the command received while they were measured)
        self.commands: list[tuple[np.ndarray, np.ndarray]] = []
        probe.create_subscription(Float64MultiArray, "joint_positions", self._on_command, 1000)
        ros.spin_until(lambda: self.controller.count_publishers("/clock") > 0, timeout=PATIENCE)

    def _on_command(self, msg: Float64MultiArray) -> None:
        self.commands.append((self.angles.copy(), np.array(msg.data)))

    def step(self, t: float, omega_x: float = 0.2) -> None:
        """The plant at ``t`` [s]: it moved to the newest command; state, pose, an operator
        sample about world x [rad/s], then /clock at ``t``; waits (briefly) for the output."""
        if self.commands:
            self.angles = self.commands[-1][1].copy()
        joints = JointState(name=JOINTS, position=self.angles.tolist(), velocity=[0.0] * 7)
        joints.header.stamp = stamp_from_seconds(t)
        self._states.publish(joints)
        pose = Odometry()
        pose.header.stamp, pose.pose.pose.orientation.w = stamp_from_seconds(t), 1.0
        self._odom.publish(pose)
        twist = TwistStamped()
        twist.header.stamp, twist.header.frame_id = stamp_from_seconds(t), "world"
        twist.twist.angular.x = omega_x
        self._twists.publish(twist)
        self.ros.spin_for(0.02)
        count = len(self.commands)
        self.clock.publish(Clock(clock=stamp_from_seconds(t)))
        self.ros.spin_until(lambda: len(self.commands) > count, timeout=OUTPUT_WAIT)

    def run(self, start: float, condition, steps: int | None = None) -> float:
        """Steps from ``start`` [s] on, one period apart, until ``condition()`` (at most
        ``steps`` of them, and PATIENCE of wall time); returns the time of the last step."""
        deadline = time.monotonic() + PATIENCE
        k, t = 0, start
        while (steps is None or k < steps) and time.monotonic() < deadline:
            t = round(start + k * PERIOD, 9)
            self.step(t)
            if condition():
                return t
            k += 1
        raise AssertionError(f"not met after {k} steps, up to {t} s")

    def state(self) -> str | None:
        return status_values(self.status.messages[-1])["state"] if self.status.messages else None

    def message(self) -> str:
        return self.status.messages[-1].status[0].message

    def assert_commands_bounded(self, robot) -> None:
        """Every command so far: within the URDF limits and NEAR of the angles measured then."""
        assert self.commands
        for measured, command in self.commands:
            assert np.all(np.isfinite(command))
            assert np.all(command >= robot.lower_limits)
            assert np.all(command <= robot.upper_limits)
            worst = np.abs(command - measured).max()
            assert worst <= NEAR, f"command {worst:.4g} rad from the measured angles"


def _moving(plant: _PositionPlant) -> bool:
    return plant.state() in ("OK", "RAMPING")


def test_a_second_clock_publisher_far_ahead_stops_the_arm_naming_it_and_it_resumes(ros, capfd):
    """A stranger publishes /clock 1e6 s ahead of the lockstep plant. Without a bound, the tick
    at the stranger's reading ends a hold of 1e6 s and commands theta_ref + 1e6 s theta_dot
    (9.3e4 rad), blaming joint_states. Here every command stays within the limits and near the
    measured angles, the status says CLOCK_FAULT naming /stranger (one error line), and once
    the stranger is gone the arm resumes from the measured angles, ramping up."""
    plant = _PositionPlant(ros)
    t = plant.run(1.0, lambda: plant.state() == "OK")
    moved = plant.commands[-1][1] - plant.commands[-1][0]
    assert np.abs(moved).max() > 1e-4  # the arm moves when the stranger comes
    stranger = ros.probe("stranger").create_publisher(Clock, "/clock", 10)
    assert ros.spin_until(lambda: stranger.get_subscription_count() > 0, timeout=PATIENCE)
    stranger.publish(Clock(clock=stamp_from_seconds(t + 1e6)))
    ros.spin_for(0.1)
    for k in range(1, 6):
        plant.step(round(t + k * PERIOD, 9))
    t = round(t + 5 * PERIOD, 9)
    plant.assert_commands_bounded(plant.controller.robot)
    t = plant.run(
        round(t + PERIOD, 9),
        lambda: plant.state() == "CLOCK_FAULT" and "/stranger" in plant.message(),
    )
    status = plant.status.messages[-1].status[0]
    assert status.level == status.ERROR
    assert "2 publishers on /clock" in status.message
    plant.assert_commands_bounded(plant.controller.robot)
    # the stranger leaves: the clock runs forward from one publisher again
    ros.probe("stranger").destroy_publisher(stranger)
    plant.run(round(t + PERIOD, 9), lambda: _moving(plant))
    states = [status_values(m)["state"] for m in plant.status.messages]
    assert "RAMPING" in states[states.index("CLOCK_FAULT") :]
    plant.assert_commands_bounded(plant.controller.robot)
    assert_one_clock_fault_logged(capfd)


def test_a_clock_that_runs_backwards_stops_the_arm_and_it_resumes_once_it_runs_forward(ros, capfd):
    """The plant's own /clock goes back from past 5 s to 1.5 s (a reset, or a publisher behind): the
    controller reports CLOCK_FAULT once ("jumped back"), holds the arm with bounded commands,
    and resumes from the measured angles once the clock has run forward again."""
    plant = _PositionPlant(ros)
    t = plant.run(5.0, lambda: plant.state() == "OK")
    plant.run(1.5, lambda: plant.state() == "CLOCK_FAULT", steps=1)
    assert f"/clock jumped back {t - 1.5:.4g} s" in plant.message()
    assert "/clock published by /rns_harness_probe" in plant.message()
    plant.run(1.51, lambda: _moving(plant))
    states = [status_values(m)["state"] for m in plant.status.messages]
    assert "RAMPING" in states[states.index("CLOCK_FAULT") :]
    plant.assert_commands_bounded(plant.controller.robot)
    assert_one_clock_fault_logged(capfd)


def test_use_sim_time_cannot_be_switched_on_a_running_controller(ros):
    """Switched, the node would go on with the clock it started with (its ticks, watchdogs and
    stamps) and fall silent: the change is refused, naming the restart that makes it."""
    controller = _controller(ros)
    for value in (True, False):
        result = controller.set_parameters([Parameter("use_sim_time", value=value)])[0]
        if value:
            assert not result.successful
            assert "use_sim_time cannot change on a running node" in result.reason
            assert "-p use_sim_time:=true" in result.reason
        else:
            assert result.successful  # the value it has: no change
    assert controller.get_parameter("use_sim_time").value is False
    assert not controller.get_clock().ros_time_is_active
    # the other run-time parameters still change
    assert controller.set_parameters([Parameter("epsilon", value=0.3)])[0].successful


def test_the_hold_output_is_bounded_when_the_reference_stands_far_from_the_arm(ros):
    """Paused while the operator turns the camera, the controller holds its reference; the arm
    is then re-homed 1 rad away on joint_3 (measured). The hold output (zero velocity) stays
    within max_reference_error of the measured angles instead of commanding the old pose."""
    controller = _controller(ros, wrist_gain=0.0)
    probe = ros.probe()
    references = Recorder(probe, JointTrajectory, "joint_references", qos=1000)
    status = Recorder(probe, DiagnosticArray, "rns_controller/status", qos=1000)
    measured = {"theta": np.deg2rad(SATELLITE_OBSERVATION_DEG)}
    states = probe.create_publisher(JointState, "joint_states", 10)

    def publish_state():
        msg = JointState(name=JOINTS, position=measured["theta"].tolist())
        msg.header.stamp = probe.get_clock().now().to_msg()
        states.publish(msg)

    probe.create_timer(PERIOD, publish_state)
    twists = probe.create_publisher(
        TwistStamped, "cmd_twist", QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
    )

    def publish_twist():
        msg = TwistStamped()
        msg.header.frame_id, msg.twist.angular.x = "world", 0.2
        twists.publish(msg)

    probe.create_timer(0.02, publish_twist)

    def state() -> str | None:
        return status_values(status.messages[-1])["state"] if status.messages else None

    assert ros.spin_until(lambda: state() == "OK", timeout=PATIENCE)
    client = probe.create_client(SetBool, "rns_controller/pause")
    assert client.wait_for_service(timeout_sec=PATIENCE)
    future = client.call_async(SetBool.Request(data=True))
    assert ros.spin_until(future.done, timeout=PATIENCE)
    assert ros.spin_until(lambda: state() == "PAUSED", timeout=PATIENCE)
    rehomed = measured["theta"] + np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
    measured["theta"] = rehomed
    assert ros.spin_until(
        lambda: np.array_equal(controller._theta, rehomed), timeout=PATIENCE
    )  # the controller measures the new pose
    count = len(references.messages)
    assert ros.spin_until(lambda: len(references.messages) > count + 5, timeout=PATIENCE)
    for msg in references.messages[count + 1 :]:
        start, end = (np.array(point.positions) for point in msg.points[:2])
        assert np.all(np.array(msg.points[0].velocities) == 0.0)
        for positions in (start, end):
            assert np.abs(positions - rehomed).max() <= 0.25 + 1e-9
            assert np.all(positions >= controller.robot.lower_limits)
            assert np.all(positions <= controller.robot.upper_limits)
    assert state() == "PAUSED"
