"""rns_simulator over real DDS (loopback, private Context): streams, commands, safety, rate."""

from __future__ import annotations

import itertools
import math
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from geometry_msgs.msg import Vector3Stamped, WrenchStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import Log
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from rclpy.time import Time
from rns_testing import Recorder
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from rns_ros.core import ConfigError, FreeFloatingModel, FreeFloatingState
from rns_ros.core.commands import VELOCITY_LIMIT_TOLERANCE
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.momentum import base_twist_from_momentum
from rns_ros.nodes.lockstep import LOCKSTEP_PATIENCE
from rns_ros.nodes.robot_io import streamed_trajectory
from rns_ros.nodes.runner import stop_worker
from rns_ros.nodes.sim_clock import stamp_from_seconds
from rns_ros.nodes.simulator import SimulatorNode
from rns_ros.nodes.simulator_commands import MAX_CATCH_UP, MAX_GRID_AGE
from rns_ros.nodes.simulator_parameters import SATELLITE_OBSERVATION_RAD

REPO = Path(__file__).resolve().parents[2]
JOINTS = [f"joint_{i}" for i in range(1, 8)]
COMMAND_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
MOMENTUM = [0.2, -0.1, 0.05, 1.0, -0.5, 0.3]


def _simulator(ros, **overrides) -> SimulatorNode:
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(SimulatorNode(context=ros.context, parameter_overrides=parameters))


def _lockstep_simulator(ros, period: float, **overrides) -> SimulatorNode:
    """As fast as possible on /clock, in lockstep with a controller of ``period`` [s]."""
    return _simulator(
        ros, real_time_factor=0.0, publish_clock=True, lockstep_period=period, **overrides
    )


def _trajectory(velocities, names=JOINTS, positions=()):
    return JointTrajectory(
        joint_names=list(names),
        points=[JointTrajectoryPoint(positions=list(positions), velocities=list(velocities))],
    )


def test_streams_agree_with_the_core_while_the_arm_moves(ros):
    node = _simulator(ros, real_time_factor=0.0, publish_clock=True, initial_momentum=MOMENTUM)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states")
    odom = Recorder(probe, Odometry, "base_odom")
    momentum = Recorder(probe, WrenchStamped, "momentum")
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)
    velocities = [0.2, -0.3, 0.25, 0.4, -0.5, 0.6, 0.7]

    def moving_pairs() -> int:
        """States recorded on both topics while the command acts (at RTF 0 the in-process
        recorder takes only some of them)."""
        odom_stamps = odom.by_stamp()
        return sum(
            stamp in odom_stamps and np.allclose(msg.velocity, velocities)
            for stamp, msg in joints.by_stamp().items()
        )

    def keep_commanding():
        command.publish(_trajectory(velocities))
        return len(joints.messages) > 60 and moving_pairs() > 10

    assert ros.spin_until(keep_commanding, timeout=20.0)
    first, last = joints.messages[0], joints.messages[-1]
    assert np.abs(np.subtract(last.position, first.position)).max() > 0.05  # the arm moved
    assert np.allclose(last.velocity, velocities)  # kinematic mode: exactly the command
    assert len(last.effort) == 0  # efforts only in dynamic mode

    # Momentum is conserved and equals the initial parameter.
    for msg in momentum.messages:
        measured = [msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z]
        measured += [msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z]
        assert np.allclose(measured, MOMENTUM, atol=1e-9)
        assert msg.header.frame_id == "world"

    # The published base twist is the one momentum conservation gives at the published pose.
    odom_by_stamp = odom.by_stamp()
    checked = 0
    robot = node.robot
    for stamp, state_msg in joints.by_stamp().items():
        if stamp not in odom_by_stamp or not np.allclose(state_msg.velocity, velocities):
            continue
        pose = odom_by_stamp[stamp].pose.pose
        q = robot.configuration(
            state_msg.position,
            [pose.position.x, pose.position.y, pose.position.z],
            [pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w],
        )
        state = FreeFloatingState.compute(robot, q)
        com = state.center_of_mass
        # momentum about the base origin = h_G shifted from the CoM to the base
        about_base = np.array(MOMENTUM, dtype=float)
        about_base[3:] += np.cross(com - state.base_position, about_base[:3])
        expected = base_twist_from_momentum(state, state_msg.velocity, about_base)
        twist = odom_by_stamp[stamp].twist.twist
        rotation = state.base_rotation
        published_linear = rotation @ [twist.linear.x, twist.linear.y, twist.linear.z]
        published_angular = rotation @ [twist.angular.x, twist.angular.y, twist.angular.z]
        assert np.allclose(published_linear, expected[:3], atol=1e-9)
        assert np.allclose(published_angular, expected[3:], atol=1e-9)
        checked += 1
    assert checked > 10
    assert odom.messages[-1].child_frame_id == "base_link"


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_serialized_state_messages_equal_the_messages_they_replace(ros, mode):
    """The pre-serialized state topics (rns_ros.nodes.cdr) carry exactly what the message path
    (kept for a layout the templates cannot capture) publishes, efforts included."""
    node = _simulator(ros, mode=mode, publish_clock=True, energy_rate=0.0)
    # only this test publishes: the simulation thread is stopped before the publishers are patched
    stop_worker(node._thread, node._stop, node._command_arrived)
    assert not node._thread.is_alive()
    sent = []
    publisher_of = node._publisher
    for publisher in (
        publisher_of.joint_pub,
        publisher_of.odom_pub,
        publisher_of.momentum_pub,
        publisher_of.clock_pub,
    ):
        publisher.publish = lambda msg, publisher=publisher: sent.append((publisher, msg))
    with node._lock:
        node.simulator.set_reference(velocities=np.linspace(-0.3, 0.4, 7))
        node.simulator.step()
        state = node.simulator.snapshot()
        momentum = node.simulator.centroidal_momentum()
    node._publisher.publish(state, momentum, clock=True)
    serialized = list(sent)
    assert all(isinstance(msg, bytes) for _, msg in serialized)
    sent.clear()
    node._publisher.templates = None
    node._publisher.publish(state, momentum, clock=True)
    assert [publisher for publisher, _ in sent] == [publisher for publisher, _ in serialized]
    for (publisher, data), (_, msg) in zip(serialized, sent, strict=True):
        assert deserialize_message(data, publisher.msg_type) == msg
    joints = sent[0][1]
    assert len(joints.effort) == (7 if mode == "dynamic" else 0)
    assert np.allclose(joints.velocity, state.v[6:])


def _rosout_errors(probe, level=Log.ERROR):
    errors = []
    qos = QoSProfile(depth=100)
    probe.create_subscription(
        Log, "/rosout", lambda m: errors.append(m.msg) if m.level >= level else None, qos
    )
    return errors


@pytest.mark.parametrize(
    ("message", "reason"),
    [
        (_trajectory([0.1, 0.1, 0.1, math.nan, 0.1, 0.1, 0.1]), "velocities must be finite"),
        (_trajectory([0.1] * 7, names=[*JOINTS[:6], "elbow"]), "unknown joints ['elbow']"),
        (_trajectory([0.1] * 6, names=JOINTS[:6]), "missing joints ['joint_7']"),
        (_trajectory([0.1] * 6 + [9.0]), "exceeds its limit"),
    ],
)
def test_bad_references_are_rejected_and_nothing_moves(ros, message, reason):
    # real time: a free-running simulation thread in this process would starve the executor
    # that records the states and logs the rejections (one GIL)
    _simulator(ros, real_time_factor=1.0)
    probe = ros.probe()
    errors = _rosout_errors(probe)
    joints = Recorder(probe, JointState, "joint_states")
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)

    def keep_sending():
        command.publish(message)
        return any(reason in error for error in errors) and len(joints.messages) > 20

    assert ros.spin_until(keep_sending, timeout=20.0), errors
    positions = np.array([m.position for m in joints.messages])
    assert np.abs(positions - positions[0]).max() == 0.0


def test_velocity_interface_and_command_timeout(ros):
    """Velocities on joint_velocities drive the joints; once the newest command is
    command_timeout (0.2 s) old the joints stop, and stay still. In lockstep a command's age is
    simulated time, so here (a lockstep_period far longer than the timeout: the simulation runs
    on in real time past the last command) the stop falls on the state stamps exactly, at the
    last command's receipt + 0.2 s, however slow the machine. (Off lockstep the age is wall
    time, on an injected clock in test_lockstep.py.)"""
    node = _simulator(
        ros,
        command_interface="velocity",
        command_timeout=0.2,
        publish_clock=True,
        lockstep_period=1.0,
    )
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states", qos=1000)
    command = probe.create_publisher(Float64MultiArray, "joint_velocities", COMMAND_QOS)
    velocities = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0, -0.2]
    assert ros.spin_until(lambda: len(joints.messages) > 5)
    for _ in range(12):
        command.publish(Float64MultiArray(data=velocities))
        ros.spin_for(0.05)
    assert np.allclose(joints.messages[-1].velocity, velocities)
    assert ros.spin_until(lambda: not np.any(joints.messages[-1].velocity), timeout=10.0)
    expiry = node._pacer.command_sim_time + 0.2  # the last command's receipt + command_timeout
    resting = joints.messages[-1].position
    ros.spin_for(0.3)
    assert np.allclose(joints.messages[-1].position, resting)
    moving = [_seconds(m.header.stamp) for m in joints.messages if np.any(m.velocity)]
    still = [
        _seconds(m.header.stamp)
        for m in joints.messages
        if not np.any(m.velocity) and _seconds(m.header.stamp) > moving[0]
    ]
    print(
        f"last moving state {max(moving) - expiry:+.4f} s, first still {min(still) - expiry:+.4f} s"
    )
    dt, period = node.simulator.dt, 0.01  # step, publish period
    assert max(moving) <= expiry + dt + 1e-9  # driven up to the expiry, not beyond
    assert expiry - 1e-9 <= min(still) <= expiry + period + dt + 1e-9  # at the next state


def test_lockstep_pauses_one_period_past_each_command(ros):
    """As fast as possible (real_time_factor 0) but in lockstep with a 100 Hz controller: the
    simulated time never runs more than lockstep_period past the newest command (before the
    first one, past the start), and the next command releases it. Free-running, 0.1 s of wall
    time would be seconds of simulation."""
    period = 0.01
    node = _lockstep_simulator(ros, period, command_interface="velocity")
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states")
    command = probe.create_publisher(Float64MultiArray, "joint_velocities", COMMAND_QOS)
    assert ros.spin_until(lambda: len(joints.messages) > 0)
    ros.spin_for(0.1)
    # no command yet: a period in, one more per START_PATIENCE, not seconds of simulation
    assert node._pacer.awaiting_first
    assert node.simulator.time == pytest.approx(node._pacer.command_sim_time + period)
    assert node.simulator.time < 100 * period  # free-running: seconds in 0.1 s
    for _ in range(3):
        before = node._pacer.last_command  # wall time of the last receipt
        command.publish(Float64MultiArray(data=[0.1] * 7))
        assert ros.spin_until(lambda b=before: node._pacer.last_command != b, timeout=2.0)
        received_at = node._pacer.command_sim_time
        ros.spin_for(0.1)
        assert node.simulator.time == pytest.approx(received_at + period)
    # a controller that stops answering pauses the simulation, the arm does not run on
    ros.spin_for(0.3)
    assert node.simulator.time == pytest.approx(received_at + period)
    assert np.allclose(joints.messages[-1].velocity, 0.1)


def _seconds(stamp) -> float:
    return stamp.sec + 1e-9 * stamp.nanosec


def test_lockstep_clock_comes_with_the_states_and_pauses_follow_the_command_stamps(ros):
    """A controller ticking on /clock stamps each command with the state it sampled. In
    lockstep the next pause is one period past that stamp, whatever the command's latency (the
    first one arrives while the simulation still runs in real time), so from then on exactly
    one state per period is published, at the controller's ticks. /clock comes with the
    states only (not every 1 ms step): a sim-time timer elsewhere fires at those instants."""
    period = 0.01
    node = _lockstep_simulator(ros, period)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states", qos=1000)
    clock = Recorder(probe, Clock, "/clock", qos=1000)
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)
    assert ros.spin_until(lambda: len(joints.messages) >= 1)
    answered = 0
    first_command_at = None
    while answered < 30:
        count = len(joints.messages)
        state = joints.messages[-1]
        msg = _trajectory([0.05] * 7)
        msg.header.stamp = state.header.stamp  # the instant this "controller" sampled
        command.publish(msg)
        first_command_at = first_command_at or _seconds(state.header.stamp)
        answered += 1
        assert ros.spin_until(lambda c=count: len(joints.messages) > c, timeout=10.0)
    ros.spin_for(0.1)
    stamps = [_seconds(m.header.stamp) for m in joints.messages]
    locked = [t for t in stamps if t > first_command_at + 1.5 * period]
    assert len(locked) >= 20
    assert np.allclose(np.diff(locked), period, atol=1e-9)  # one state per period, no extra
    # on the grid of the stamps the "controller" sent, not shifted by the first one's latency
    periods = (np.array(locked) - first_command_at) / period
    assert np.allclose(periods, np.round(periods), atol=1e-6)
    assert node.simulator.time == pytest.approx(locked[-1])  # paused there
    ticks = [_seconds(m.clock) for m in clock.messages]
    assert ticks == sorted(ticks)
    assert len(ticks) >= len(locked)
    assert set(np.round(ticks, 9)) <= set(np.round(stamps, 9))  # /clock only with a state


def test_lockstep_a_command_stamped_ahead_waits_for_its_stamp(ros):
    """A controller that stamps each output one period after the state it sampled (output_lead)
    lets the simulation run on meanwhile: the output acts from its stamp, not on receipt, and
    the next pause is one period past that stamp. Kinematic mode: over each period the joints
    move at the rate of the newest command stamped at or before its start."""
    period = 0.01
    node = _lockstep_simulator(ros, period)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states", qos=1000)
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)
    assert ros.spin_until(lambda: len(joints.messages) >= 1)
    sent = {}  # stamp [ns] -> commanded rate [rad/s]
    for k in range(30):
        count = len(joints.messages)
        sampled = joints.messages[-1].header.stamp
        acts = sampled.sec * 1_000_000_000 + sampled.nanosec + round(period * 1e9)
        rate = 0.01 * (k + 1)  # a new rate every period: acting early would show
        msg = _trajectory([rate] * 7)
        msg.header.stamp = stamp_from_seconds(acts * 1e-9)
        command.publish(msg)
        sent[acts] = rate
        assert ros.spin_until(lambda c=count: len(joints.messages) > c, timeout=10.0)
    ros.spin_for(0.1)
    assert node.simulator.time == pytest.approx(max(sent) * 1e-9 + period)  # paused there
    first = min(sent)
    states = [m for m in joints.messages if _nanoseconds(m.header.stamp) >= first]
    assert len(states) >= 25
    checked = 0
    for before, after in itertools.pairwise(states):
        start, end = _nanoseconds(before.header.stamp), _nanoseconds(after.header.stamp)
        assert end - start == round(period * 1e9)  # one state per period
        applied = sent[max(stamp for stamp in sent if stamp <= start)]
        moved = (np.array(after.position) - np.array(before.position)) / period
        np.testing.assert_allclose(moved, applied, atol=1e-9)
        np.testing.assert_allclose(after.velocity, applied, atol=1e-12)  # the rate up to it
        checked += 1
    assert checked >= 25


def test_lockstep_a_late_command_counts_its_period_on_its_stamp_grid(ros):
    """The first command can reach a simulation still running in real time a few periods
    after its stamp (seen: 11 ms). Its period then counts from the last point of its stamp's
    grid before now, so the pauses fall where a controller ticking on /clock ticks; counted
    from the receipt, every later pause stayed 1 ms off that grid and each command was late."""
    period = 0.01
    node = _lockstep_simulator(ros, period)
    node._stop.set()  # the simulated time stays where this test puts it
    node._command_arrived.set()
    node._thread.join(timeout=2.0)
    node.simulator.time = 0.091
    with node._lock:
        assert node._commands.command_anchor(0.08) == pytest.approx(0.09)  # late: on its grid
        assert node._commands.command_anchor(0.05) == pytest.approx(0.09)
        assert node._commands.command_anchor(0.085) == pytest.approx(0.085)  # within the period
        assert node._commands.command_anchor(0.095) == pytest.approx(0.095)  # waits ahead
        assert node._commands.command_anchor(0.091 - 2 * MAX_GRID_AGE) == pytest.approx(0.091)
        assert node._commands.command_anchor(None) == pytest.approx(0.091)  # unstamped: receipt


def _nanoseconds(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def test_lockstep_patience_takes_one_step_with_a_state_and_a_clock(ros):
    """A controller that stops answering pauses the simulation; after LOCKSTEP_PATIENCE (wall
    time) one step is taken and published with its /clock, so a controller whose sim-time
    timer waits for a later time gets it."""
    period = 0.01
    node = _lockstep_simulator(ros, period, command_interface="velocity", command_timeout=60.0)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states", qos=1000)
    clock = Recorder(probe, Clock, "/clock", qos=1000)
    command = probe.create_publisher(Float64MultiArray, "joint_velocities", COMMAND_QOS)
    assert ros.spin_until(lambda: len(joints.messages) >= 1)
    before = node._pacer.last_command
    command.publish(Float64MultiArray(data=[0.1] * 7))
    assert ros.spin_until(lambda: node._pacer.last_command != before, timeout=2.0)
    pause = node._pacer.command_sim_time + period
    assert ros.spin_until(lambda: node.simulator.time == pytest.approx(pause), timeout=2.0)
    ros.spin_for(LOCKSTEP_PATIENCE - 0.5)
    assert node.simulator.time == pytest.approx(pause)  # still waiting
    dt = node.simulator.dt
    assert ros.spin_until(lambda: node.simulator.time > pause + 0.5 * dt, timeout=2.0)
    ros.spin_for(0.1)
    assert node.simulator.time == pytest.approx(pause + dt)  # one step, then paused again
    assert _seconds(joints.messages[-1].header.stamp) == pytest.approx(pause + dt)
    assert _seconds(clock.messages[-1].clock) == pytest.approx(pause + dt)


class _Wall:
    """A monotonic wall clock [s] the test moves on by ``offset`` [s]."""

    def __init__(self) -> None:
        self.offset = 0.0

    def __call__(self) -> float:
        return time.monotonic() + self.offset


def test_lockstep_a_command_stale_in_wall_time_stops_the_joints_and_wheels(ros):
    """Controllers gone in lockstep: the pause lasts LOCKSTEP_PATIENCE of wall time (the
    injected clock jumps past it) and the step then forced finds the joint command and the
    wheel torque one period old in simulated time but older than command_timeout in wall
    time: the joints stop and the wheel motors go off from that step on, logged once with both
    ages; the simulation then runs in real time."""
    period = 0.01
    wall = _Wall()
    overrides = {
        "real_time_factor": 0.0,
        "publish_clock": True,
        "lockstep_period": period,
        "command_interface": "velocity",
        "reaction_wheels": True,
        "command_timeout": 0.5,
    }
    node = ros.add(
        SimulatorNode(
            context=ros.context,
            parameter_overrides=[Parameter(name, value=value) for name, value in overrides.items()],
            wall_clock=wall,
        )
    )
    probe = ros.probe()
    warnings = _rosout_errors(probe, level=Log.WARN)
    joints = Recorder(probe, JointState, "joint_states", qos=1000)
    wheels = Recorder(probe, JointState, "wheel_states", qos=1000)
    command = probe.create_publisher(Float64MultiArray, "joint_velocities", COMMAND_QOS)
    torque = probe.create_publisher(Vector3Stamped, "wheel_torque", COMMAND_QOS)
    assert ros.spin_until(lambda: len(joints.messages) >= 1)
    wheel_torque = Vector3Stamped()
    wheel_torque.vector.z = 0.05
    torque.publish(wheel_torque)
    assert ros.spin_until(lambda: node._commands._last_wheel_command is not None, timeout=2.0)
    command.publish(Float64MultiArray(data=[0.1] * 7))
    assert ros.spin_until(lambda: node._pacer.last_command is not None, timeout=2.0)
    pause = node._pacer.command_sim_time + period
    assert ros.spin_until(lambda: node.simulator.time == pytest.approx(pause), timeout=2.0)
    assert ros.spin_until(
        lambda: _seconds(joints.messages[-1].header.stamp) == pytest.approx(pause), timeout=2.0
    )
    assert np.allclose(joints.messages[-1].velocity, 0.1)  # in force up to the pause
    assert ros.spin_until(lambda: wheels.messages and wheels.messages[-1].effort[2] == 0.05)

    wall.offset += LOCKSTEP_PATIENCE + 1.0  # the controllers have not answered for 6 s
    dt = node.simulator.dt

    def after_pause(recorder):
        return [m for m in recorder.messages if _seconds(m.header.stamp) > pause + 0.5 * dt]

    assert ros.spin_until(lambda: after_pause(joints) and after_pause(wheels), timeout=10.0)
    assert node.simulator.time - pause < 1.0  # simulated time barely moved
    assert not np.any(after_pause(joints)[0].velocity)
    assert after_pause(wheels)[0].effort[2] == 0.0
    assert ros.spin_until(lambda: sum("stopping the joints" in w for w in warnings) == 1)
    stop = next(w for w in warnings if "stopping the joints" in w)
    assert "s old in simulated time" in stop
    assert "s in wall time" in stop
    assert any("wheel motors off" in w for w in warnings)


def test_velocity_interface_takes_the_order_of_the_joints_parameter(ros):
    """The ros2_control forward_command_controller convention: data[i] is for joints[i]."""
    order = ["joint_3", "joint_1", "joint_2", "joint_7", "joint_6", "joint_5", "joint_4"]
    _simulator(ros, command_interface="velocity", joints=order)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states")
    command = probe.create_publisher(Float64MultiArray, "joint_velocities", COMMAND_QOS)
    by_name = {name: 0.01 * (k + 1) for k, name in enumerate(JOINTS)}

    def keep_commanding():
        command.publish(Float64MultiArray(data=[by_name[name] for name in order]))
        return joints.messages and np.any(joints.messages[-1].velocity)

    assert ros.spin_until(keep_commanding)
    last = joints.messages[-1]
    assert dict(zip(last.name, last.velocity, strict=True)) == pytest.approx(by_name)


def test_robot_description_is_latched_for_late_subscribers(ros):
    from rclpy.qos import DurabilityPolicy
    from std_msgs.msg import String

    node = _simulator(ros)
    ros.spin_for(0.5)  # published long before anyone listens
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    description = Recorder(ros.probe(), String, "robot_description", qos=latched)
    assert ros.spin_until(lambda: description.messages, timeout=10.0)
    (message,) = description.messages
    urdf = (REPO / "config" / "urdf" / "rns_7dof_arm.urdf").read_text()
    assert message.data == urdf
    # and it is the model the simulator integrates: the same joints in the same order
    rebuilt = FreeFloatingModel.from_urdf_string(message.data, node.robot.spec)
    assert rebuilt.joint_names == node.robot.joint_names


def test_reset_service_restores_the_initial_state(ros):
    _simulator(ros, real_time_factor=0.0, command_timeout=0.1)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states")
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)
    client = probe.create_client(Trigger, "/rns_simulator/reset")
    assert ros.spin_until(lambda: len(joints.messages) > 2)
    initial = np.array(joints.messages[0].position)

    def moved():
        command.publish(_trajectory([0.3] * 7))
        return np.abs(np.array(joints.messages[-1].position) - initial).max() > 0.1

    assert ros.spin_until(moved, timeout=20.0)
    # stop commanding and let the timeout stop the arm, so no late command races the reset
    assert ros.spin_until(lambda: not np.any(joints.messages[-1].velocity), timeout=5.0)
    assert client.wait_for_service(timeout_sec=5.0)
    future = client.call_async(Trigger.Request())
    assert ros.spin_until(future.done, timeout=5.0)
    assert future.result().success
    # messages published before the reset may still be queued: wait for the reset state
    assert ros.spin_until(
        lambda: np.allclose(joints.messages[-1].position, initial, atol=1e-9), timeout=5.0
    )


def test_dynamic_mode_tracks_references_and_publishes_efforts(ros):
    _simulator(ros, mode="dynamic", real_time_factor=0.0, initial_momentum=MOMENTUM)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states")
    momentum = Recorder(probe, WrenchStamped, "momentum")
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)

    def moving():
        command.publish(_trajectory([0.2] * 7))
        # the 200 N m effort limits (H*_22 ~ 360 kg m^2) allow ~0.5 rad/s^2: the servo, built
        # for 50 rad/s, settles in ~2.7 s of simulated time
        return len(joints.messages) > 350

    # a correctness test, not a speed test: the in-process throughput at real_time_factor 0 is
    # GIL-bound and varies 2x between runs (6-13 s here quiet, more on a loaded CI machine)
    assert ros.spin_until(moving, timeout=60.0)
    last = joints.messages[-1]
    assert len(last.effort) == 7
    assert np.allclose(last.velocity, 0.2, atol=1e-2)
    torque = momentum.messages[-1].wrench.torque
    assert np.allclose([torque.x, torque.y, torque.z], MOMENTUM[3:], atol=1e-8)


@pytest.mark.parametrize("rate", [100.0, 500.0])
def test_states_are_published_at_the_publish_rate_of_simulated_time(ros, rate):
    """publish_rate counts simulated time: consecutive states are 1/rate of simulated time apart
    on their stamps (/clock time here), whatever the machine's speed; a state the recorder
    missed leaves a gap of a whole number of periods. (That the simulated time keeps pace with
    the wall clock at real_time_factor 1 is LockstepPacer's, on an injected clock, in
    test_lockstep.py; the arrival rate on the wall clock is a figure:
    scripts/benchmark.py --only publish.)"""
    _simulator(ros, publish_rate=rate, publish_clock=True)
    joints = Recorder(ros.probe(), JointState, "joint_states", qos=1000)
    assert ros.spin_until(lambda: len(joints.messages) > 50, timeout=20.0)
    gaps = np.diff([_nanoseconds(m.header.stamp) for m in joints.messages]) / (1e9 / rate)
    print(f"{len(gaps)} gaps of {gaps.min():.6f} to {gaps.max():.6f} periods")
    assert np.all(gaps >= 1.0 - 1e-6)
    assert np.allclose(gaps, np.round(gaps), atol=1e-6)  # whole periods of simulated time
    assert np.min(gaps) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"mode": "teleport"}, "'mode' must be one of"),
        ({"step_size": 0.5}, "'step_size' out of range"),
        ({"initial_joint_positions": [0.1, 0.2]}, "needs 7 values"),
        ({"initial_momentum": [0.0, 1.0]}, "'initial_momentum' must have length in [6]"),
        ({"publish_rate": 100}, "wrong type"),
        ({"command_interface": "velocity", "joints": ["joint_1", "elbow"]}, "unknown joints"),
    ],
)
def test_bad_parameters_fail_with_a_clear_error(ros, overrides, message):
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        SimulatorNode(
            context=ros.context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )


def _sim_seconds(msg) -> float:
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec


def _after_reset(messages):
    """The messages from the first whose simulated stamp went back (the reset) on; [] if none."""
    for k in range(1, len(messages)):
        if _sim_seconds(messages[k]) < _sim_seconds(messages[k - 1]):
            return messages[k:]
    return []


@pytest.mark.parametrize(
    ("offset", "reason"),
    [
        # the input (it diverged to NaN within 16 ms)
        (100.0, "position 98.43 rad on joint_1 is outside its limits [-6.283, 6.283] rad"),
        # a 1 rad step inside the position limits (it ran the joints at 18.5 rad/s)
        (1.0, "on joint_1 is 1 rad from its current angle -1.571 rad; allowed [-1.821, -1.321]"),
    ],
    ids=["100-rad", "1-rad-step"],
)
def test_implausible_position_references_are_rejected_in_dynamic_mode(ros, offset, reason):
    _simulator(ros, mode="dynamic", real_time_factor=0.0)
    probe = ros.probe()
    errors = _rosout_errors(probe)
    joints = Recorder(probe, JointState, "joint_states")
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)
    message = _trajectory([], positions=np.add(SATELLITE_OBSERVATION_RAD, offset))

    def keep_sending():
        command.publish(message)
        return any(reason in error for error in errors) and len(joints.messages) > 20

    assert ros.spin_until(keep_sending, timeout=20.0), errors
    positions = np.array([m.position for m in joints.messages])
    assert np.isfinite(positions).all()
    assert np.abs(positions - SATELLITE_OBSERVATION_RAD).max() < 1e-12  # no motion at all


def test_dynamic_reset_with_a_stale_controller_keeps_the_arm_still(ros):
    """Issue 11, defect 3: a controller still streaming the pre-reset angles must not jerk the
    arm back. The reset state is held for reset_hold, then the stale references are rejected
    (too far); the joints stay within their velocity limits and the base does not turn."""
    # real time: a stale controller's references lag the state by milliseconds, not seconds
    node = _simulator(ros, mode="dynamic", publish_clock=True)
    probe = ros.probe()
    errors = _rosout_errors(probe, level=Log.WARN)
    joints = Recorder(probe, JointState, "joint_states")
    odom = Recorder(probe, Odometry, "base_odom")
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)
    client = probe.create_client(Trigger, "/rns_simulator/reset")
    initial = np.array(SATELLITE_OBSERVATION_RAD)

    def moved():
        command.publish(_trajectory([0.4] * 7))
        return joints.messages and np.abs(joints.messages[-1].position - initial).min() > 0.4

    assert ros.spin_until(moved, timeout=20.0)
    stale = _trajectory([0.0] * 7, positions=joints.messages[-1].position)
    for _ in range(10):  # the arm settles on the stale controller's reference
        command.publish(stale)
        ros.spin_for(0.01)
    assert client.wait_for_service(timeout_sec=5.0)
    future = client.call_async(Trigger.Request())

    def streaming_stale_after_reset():
        command.publish(stale)
        return (
            future.done()
            and _after_reset(joints.messages)
            and (
                _sim_seconds(joints.messages[-1]) > 1.0  # simulated seconds after the reset
            )
        )

    assert ros.spin_until(streaming_stale_after_reset, timeout=30.0)
    assert future.result().success
    after = _after_reset(joints.messages)
    speeds = np.abs([m.velocity for m in after]) / node.robot.velocity_limits
    print(f"peak joint speed after the reset: {speeds.max():.3g} x the URDF limit")
    assert speeds.max() <= 1.0 + VELOCITY_LIMIT_TOLERANCE
    assert np.allclose([m.position for m in after], initial, atol=1e-9)  # at rest, reset state
    for msg in _after_reset(odom.messages):
        o = msg.pose.pose.orientation
        rotation = pin.Quaternion(o.w, o.x, o.y, o.z).toRotationMatrix()
        assert attitude_deviation(np.eye(3), rotation) < 1e-12  # rad
    assert any("ignoring joint commands for reset_hold = 0.2 s" in e for e in errors), errors
    assert any("from its current angle" in e for e in errors), errors


def test_a_diverged_step_stops_the_simulation_until_reset(ros):
    """A step that turns non-finite (forced here: NaN accelerations once) is reported once; the
    node then publishes the last finite state at rest, never a NaN, until ~/reset."""
    node = _simulator(ros, mode="dynamic", real_time_factor=0.0, publish_clock=True)
    probe = ros.probe()
    errors = _rosout_errors(probe)
    joints = Recorder(probe, JointState, "joint_states")
    client = probe.create_client(Trigger, "/rns_simulator/reset")
    assert ros.spin_until(lambda: len(joints.messages) > 5)
    simulator = node.simulator
    healthy = simulator._acceleration
    poisoned = []

    def nan_once(q, v, tau, fraction=0.0):
        if poisoned:
            return healthy(q, v, tau, fraction)
        poisoned.append(True)
        return np.full(v.shape, np.nan)

    simulator._acceleration = nan_once
    assert ros.spin_until(lambda: node._run_state.fault, timeout=5.0)
    simulator._acceleration = healthy
    fault_time = simulator.time  # the last finite state's

    def held_states():
        # states published before the fault may still arrive after it (at real_time_factor 0
        # the simulation ran flat out): the held ones are those stamped at the fault
        return [m for m in joints.messages if _sim_seconds(m) >= fault_time - 1e-9]

    assert ros.spin_until(lambda: len(held_states()) > 15, timeout=5.0)
    held = held_states()
    assert np.isfinite([m.position for m in joints.messages]).all()
    assert np.isfinite([m.velocity for m in joints.messages]).all()
    assert np.array_equal([m.position for m in held], [held[0].position] * len(held))
    assert not np.any([m.velocity for m in held])
    assert len({_sim_seconds(m) for m in held}) == 1  # simulated time stopped
    diverged = [e for e in errors if "diverged" in e]
    assert len(diverged) == 1, errors
    assert "non-finite" in diverged[0]  # q and v, or v alone: depends on the RK4 stage hit

    assert client.wait_for_service(timeout_sec=5.0)
    future = client.call_async(Trigger.Request())
    assert ros.spin_until(future.done, timeout=5.0)

    def running_again():
        after = _after_reset(joints.messages)
        return after and _sim_seconds(after[-1]) > 0.2

    assert ros.spin_until(running_again, timeout=10.0)
    assert not node._run_state.fault
    assert np.allclose(joints.messages[-1].position, SATELLITE_OBSERVATION_RAD, atol=1e-9)


def test_a_reference_that_starts_at_the_reset_state_ends_the_reset_hold(ros):
    """A controller that saw the reset and resynchronized sends references starting at the
    reset angles: those end the hold at once. Waiting out reset_hold instead would let its
    integrated reference run ahead of the still arm, and the servo's catch-up is not
    reactionless (base 1.7e-4 deg after a reset in the controller's end-to-end test, against
    3e-5 deg with this rule)."""
    _simulator(ros, mode="kinematic", publish_clock=True, reset_hold=5.0)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states")
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)
    client = probe.create_client(Trigger, "/rns_simulator/reset")
    initial = np.array(SATELLITE_OBSERVATION_RAD)
    assert ros.spin_until(lambda: len(joints.messages) > 3)
    assert client.wait_for_service(timeout_sec=5.0)
    future = client.call_async(Trigger.Request())
    assert ros.spin_until(lambda: future.done() and _after_reset(joints.messages), timeout=5.0)
    velocities = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1]
    far = _trajectory(velocities, positions=initial + 0.05)  # a stale reference: ignored
    for _ in range(20):
        command.publish(far)
        ros.spin_for(0.01)
    assert np.allclose(joints.messages[-1].position, initial, atol=1e-12)
    resynced = _trajectory(velocities, positions=initial)

    def moving():
        command.publish(resynced)
        return joints.messages[-1].position[6] > initial[6] + 0.005

    assert ros.spin_until(moving, timeout=2.0)  # long before reset_hold = 5 s
    assert _sim_seconds(joints.messages[-1]) < 1.0


def _energy(msg: Float64MultiArray) -> dict[str, float]:
    labels = msg.layout.dim[0].label.split()
    return dict(zip(labels, msg.data, strict=True))


def test_energy_topic_follows_the_moving_arm(ros):
    """The energy terms add up, and equal Pinocchio's kinetic energy of the published state; the
    running C_sum grows by the trapezoid of lambda_arm + lambda_wheels over sim time."""
    node = _simulator(ros, real_time_factor=0.0, publish_clock=True)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states")
    odom = Recorder(probe, Odometry, "base_odom")
    energy = Recorder(probe, Float64MultiArray, "energy")
    command = probe.create_publisher(JointTrajectory, "joint_references", COMMAND_QOS)
    velocities = [0.2, -0.3, 0.25, 0.4, -0.5, 0.6, 0.7]

    def matched() -> int:
        """Energy samples whose moving joint state and base pose were both recorded (at real
        time factor 0 a busy recorder may miss some of the states: wait for enough)."""
        moving = {
            (m.header.stamp.sec, m.header.stamp.nanosec)
            for m in joints.messages
            if np.abs(m.velocity).max(initial=0.0) > 0.0
        } & set(odom.by_stamp())
        return sum(
            divmod(round(_energy(m)["time"] * 1e9), 1_000_000_000) in moving
            for m in energy.messages
        )

    def keep_commanding():
        command.publish(_trajectory(velocities))
        return len(energy.messages) > 40 and matched() > 20

    assert ros.spin_until(keep_commanding, timeout=30.0), (len(energy.messages), matched())
    robot = node.robot
    odom_by_stamp = odom.by_stamp()
    samples = [_energy(m) for m in energy.messages]
    checked = 0
    by_stamp = {divmod(round(s["time"] * 1e9), 1_000_000_000): s for s in samples}
    for state_msg in joints.messages:
        key = (state_msg.header.stamp.sec, state_msg.header.stamp.nanosec)
        sample = by_stamp.get(key)
        if sample is None or key not in odom_by_stamp or np.abs(state_msg.velocity).max() == 0:
            continue
        base = odom_by_stamp[key]
        p, o = base.pose.pose.position, base.pose.pose.orientation
        t = base.twist.twist
        q = robot.configuration(state_msg.position, [p.x, p.y, p.z], [o.x, o.y, o.z, o.w])
        v = np.array([t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z])
        v = np.concatenate((v, state_msg.velocity))
        expected = pin.computeKineticEnergy(robot.model, robot.model.createData(), q, v)
        assert sample["total"] == pytest.approx(expected, rel=1e-9)
        parts = sample["base"] + sample["arm"] + sample["coupling"] + sample["wheels"]
        assert parts == pytest.approx(sample["total"], rel=1e-12)
        assert sample["wheels"] == 0.0
        checked += 1
    assert checked > 10
    # Between two consecutive samples (none missed by the recorder, which a busy one may do),
    # C_sum grows by exactly the trapezoid of the Lambda cost, and C_max, the running peak, is
    # max(previous peak, cost). C_max never falls and never lies below the current cost.
    cost = [s["lambda_arm"] + s["lambda_wheels"] for s in samples]
    times = [s["time"] for s in samples]
    period = min(b - a for a, b in itertools.pairwise(times))
    consecutive = 0
    for (before, cost_before), (after, cost_after) in itertools.pairwise(
        zip(samples, cost, strict=True)
    ):
        assert before["c_max"] >= cost_before
        assert after["c_max"] >= before["c_max"]
        if after["time"] - before["time"] < 1.5 * period:
            assert after["c_max"] == max(before["c_max"], cost_after)
            trapezoid = 0.5 * (cost_before + cost_after) * (after["time"] - before["time"])
            gained = after["c_sum"] - before["c_sum"]
            assert gained == pytest.approx(trapezoid, rel=1e-9, abs=1e-12)
            consecutive += 1
    assert consecutive > 10
    assert samples[-1]["c_max"] >= max(cost)


def test_reaction_wheels_turn_the_base_and_stop_on_a_stale_command(ros):
    """0.1 N m on the z wheel: it spins up at tau / I_r relative to the (nearly still) base and
    the base turns the other way; total momentum stays zero. A torque above the limit is applied
    at the limit; with no new command for command_timeout the motors go off."""
    _simulator(
        ros, reaction_wheels=True, command_timeout=0.3, real_time_factor=0.0, publish_clock=True
    )
    probe = ros.probe()
    wheels = Recorder(probe, JointState, "wheel_states")
    momentum = Recorder(probe, WrenchStamped, "momentum")
    odom = Recorder(probe, Odometry, "base_odom")
    energy = Recorder(probe, Float64MultiArray, "energy")
    torque = probe.create_publisher(Vector3Stamped, "wheel_torque", COMMAND_QOS)

    def command(z: float):
        msg = Vector3Stamped()
        msg.vector.z = z
        torque.publish(msg)

    def spinning():
        command(0.5)  # above the 0.1 N m limit
        return bool(wheels.messages) and wheels.messages[-1].velocity[2] > 0.5

    assert ros.spin_until(spinning, timeout=20.0)
    last = wheels.messages[-1]
    assert list(last.name) == ["wheel_x", "wheel_y", "wheel_z"]
    assert last.effort[2] == pytest.approx(0.1)  # clipped to the limit
    assert odom.messages[-1].twist.twist.angular.z < 0.0
    for msg in momentum.messages:
        t = msg.wrench.torque
        assert abs(t.z) < 1e-9
    assert _energy(energy.messages[-1])["wheels"] > 0.0
    # stale: stop commanding; after command_timeout the applied torque is zero
    speed = wheels.messages[-1].velocity[2]
    assert ros.spin_until(lambda: wheels.messages[-1].effort[2] == 0.0, timeout=10.0)
    ros.spin_for(0.3)
    assert wheels.messages[-1].velocity[2] == pytest.approx(
        wheels.messages[-5].velocity[2], rel=1e-6
    )  # coasting: constant spin
    assert wheels.messages[-1].velocity[2] >= speed


def test_wheel_torque_in_a_foreign_frame_is_rejected(ros):
    _simulator(ros, reaction_wheels=True)
    probe = ros.probe()
    logs = Recorder(probe, Log, "/rosout")
    wheels = Recorder(probe, JointState, "wheel_states")
    torque = probe.create_publisher(Vector3Stamped, "wheel_torque", COMMAND_QOS)
    msg = Vector3Stamped()
    msg.header.frame_id = "camera"
    msg.vector.x = 0.05

    def rejected():
        torque.publish(msg)
        return any("rejected wheel torque" in m.msg for m in logs.messages)

    assert ros.spin_until(rejected, timeout=10.0)
    assert "frame_id 'camera'" in next(m.msg for m in logs.messages if "wheel" in m.msg)
    assert all(m.effort[0] == 0.0 for m in wheels.messages)


def test_commands_stamped_ahead_each_act_from_their_own_stamp(ros):
    """Lockstep side by side at a real-time factor > 0 with one step per control period: the
    controller's next output (stamped one period later) can arrive while the simulation still
    sits before the stamp of the previous one. Both wait for their stamps, and each is the joint
    rate of the step that starts at its stamp (a single waiting slot lost the first: the arm
    never got the commanded motion)."""
    period = 0.01
    node = _simulator(
        ros,
        real_time_factor=1.0,
        publish_clock=True,
        lockstep_period=period,
        step_size=period,
    )
    stop_worker(node._thread, node._stop, node._command_arrived)
    assert not node._thread.is_alive()
    first, second = np.full(7, 0.1), np.full(7, -0.2)
    start = node.simulator.time
    node._commands._accept(None, first, None, stamp=start + period)
    node.advance()  # to the first stamp; the second command comes before the next step
    assert node.simulator.time == pytest.approx(start + period)
    assert np.array_equal(node.simulator.reference.velocities, np.zeros(7))
    node._commands._accept(None, second, None, stamp=start + 2 * period)
    node.advance()
    assert np.array_equal(node.simulator.reference.velocities, first)
    node.advance()
    assert np.array_equal(node.simulator.reference.velocities, second)


def test_tf_carries_the_link_tree_as_robot_state_publisher_would(ros):
    """/tf_static (transient local: a late subscriber gets it) holds the fixed joints, /tf the
    world -> base pose of base_odom and every moving joint; composed, they put the camera where
    the core's forward kinematics does."""
    from tf2_msgs.msg import TFMessage

    from rns_ros.nodes.tf_publishing import STATIC_QOS

    node = _simulator(ros, real_time_factor=0.0, publish_clock=True, initial_momentum=MOMENTUM)
    probe = ros.probe()
    odom = Recorder(probe, Odometry, "base_odom")
    joints = Recorder(probe, JointState, "joint_states")
    tf = Recorder(probe, TFMessage, "/tf")
    static = Recorder(probe, TFMessage, "/tf_static", STATIC_QOS)
    ros.spin_until(lambda: static.messages and len(tf.messages) > 5 and odom.messages, 10.0)
    robot = node.robot
    (fixed,) = static.messages
    message = tf.messages[-1]
    stamp = (message.transforms[0].header.stamp.sec, message.transforms[0].header.stamp.nanosec)
    ros.spin_until(lambda: stamp in odom.by_stamp() and stamp in joints.by_stamp(), 5.0)
    pose = odom.by_stamp()[stamp].pose.pose
    world_base = message.transforms[0]
    assert (world_base.header.frame_id, world_base.child_frame_id) == ("world", robot.base_link)
    t, r = world_base.transform.translation, world_base.transform.rotation
    position, orientation = pose.position, pose.orientation
    expected = [position.x, position.y, position.z]
    expected += [orientation.x, orientation.y, orientation.z, orientation.w]
    np.testing.assert_allclose([t.x, t.y, t.z, r.x, r.y, r.z, r.w], expected)
    assert len(message.transforms) == 1 + robot.n  # world -> base, one per moving joint
    placed = {}
    for transform in [*fixed.transforms, *message.transforms]:
        tr, rot = transform.transform.translation, transform.transform.rotation
        placed[transform.child_frame_id] = (
            transform.header.frame_id,
            pin.XYZQUATToSE3(np.array([tr.x, tr.y, tr.z, rot.x, rot.y, rot.z, rot.w])),
        )

    def world_pose(frame: str) -> pin.SE3:
        parent, relative = placed[frame]
        return relative if parent == "world" else world_pose(parent) * relative

    state = joints.by_stamp()[stamp]
    q = robot.configuration(state.position, expected[:3], expected[3:])
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    camera = robot.model.frames[robot.camera_frame_id].name
    np.testing.assert_allclose(
        world_pose(camera).homogeneous, data.oMf[robot.camera_frame_id].homogeneous, atol=1e-9
    )


def test_publish_tf_false_leaves_tf_to_a_robot_state_publisher(ros):
    from tf2_msgs.msg import TFMessage

    _simulator(ros, real_time_factor=0.0, publish_clock=True, publish_tf=False)
    probe = ros.probe()
    joints = Recorder(probe, JointState, "joint_states")
    tf = Recorder(probe, TFMessage, "/tf")
    ros.spin_until(lambda: len(joints.messages) > 20, 10.0)
    assert len(joints.messages) > 20
    assert tf.messages == []


# --- a streamed trajectory ends at rest, as joint_trajectory_controller plays it --------------

#: Control period T [s] of the streamed trajectories below: point 1 (at rest) at 2T.
PERIOD = 0.01
#: Joint rates [rad/s] of point 0 (within the 0.5 rad/s URDF limits).
RATES = 0.05 * np.array([1.0, -2.0, 1.5, 3.0, -2.5, 2.0, 1.0])


def _stepped_simulator(ros, lockstep_period: float = 1.0, **overrides) -> SimulatorNode:
    """A simulator on /clock whose steps the test takes (``node.advance()``), so every time is
    simulated. ``lockstep_period`` 1 s (longer than the motions here) makes a command's age
    simulated time too (the test's own steps ignore the pauses); off lockstep the age is wall
    time, on a clock that stands still here."""
    overrides = {"publish_clock": True, "lockstep_period": lockstep_period, **overrides}
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    node = ros.add(
        SimulatorNode(context=ros.context, parameter_overrides=parameters, wall_clock=lambda: 0.0)
    )
    stop_worker(node._thread, node._stop, node._command_arrived)
    assert not node._thread.is_alive()
    return node


def _send_streamed(node, stamp: float, rates=RATES):
    """rns_controller's JointTrajectory of one period, stamped ``stamp`` [s] (simulated), from
    the current angles, through the simulator's raw-bytes subscription callback."""
    msg = streamed_trajectory(
        stamp_from_seconds(stamp), JOINTS, node.simulator.q[7:].copy(), rates, 2 * PERIOD
    )
    node._commands._on_trajectory(serialize_message(msg))


def _angles(node, steps: int) -> np.ndarray:
    """Joint angles [rad] (steps + 1, n): now and after each of ``steps`` steps."""
    angles = [node.simulator.q[7:].copy()]
    for _ in range(steps):
        assert node.advance() is not None
        angles.append(node.simulator.q[7:].copy())
    return np.array(angles)


#: A step that turns a joint by less [rad] leaves it still (the rounding of simulated times).
STILL = 1e-12


def _last_moving_step(angles: np.ndarray) -> int:
    """The number of steps after which the joints stood still (to the end of ``angles``)."""
    moved = np.abs(np.diff(angles, axis=0)).max(axis=1) > STILL
    return int(np.flatnonzero(moved)[-1]) + 1 if moved.any() else 0


def test_a_streamed_trajectory_ends_at_rest_and_a_one_point_one_is_held(ros):
    """Our streamed shape (point 0: theta, theta_dot; point 1 at 2T, no velocities; point 2 at
    0.25 s at rest) and no newer command: the joints move by theta_dot 2T, exactly (kinematic
    mode), and stay there, as behind joint_trajectory_controller; logged once. A one-point
    trajectory (another sender's) keeps its velocity until command_timeout."""
    node = _stepped_simulator(ros, command_timeout=0.5)
    probe = ros.probe()
    warnings = _rosout_errors(probe, level=Log.WARN)
    dt = node.simulator.dt
    _send_streamed(node, node.simulator.time)
    angles = _angles(node, 60)
    assert _last_moving_step(angles) == round(2 * PERIOD / dt)
    np.testing.assert_allclose(angles[-1] - angles[0], 2 * PERIOD * RATES, rtol=0, atol=1e-12)
    assert not np.any(node.simulator.v[6:])
    assert not np.any(node.simulator.reference.velocities)
    assert node._commands.ended_at_rest == 1
    assert ros.spin_until(lambda: any("ended at rest" in w for w in warnings), timeout=5.0)
    (line,) = [w for w in warnings if "ended at rest" in w]
    assert "joint_references ended at rest 0.020 s after its stamp" in line

    held = _trajectory(RATES, positions=node.simulator.q[7:].copy())
    held.header.stamp = stamp_from_seconds(node.simulator.time)
    node._commands._on_trajectory(serialize_message(held))
    angles = _angles(node, 700)
    moving = _last_moving_step(angles)
    print(f"one-point trajectory: moved for {moving * dt:.3f} s")
    assert moving * dt == pytest.approx(0.5, abs=1.5 * dt)  # command_timeout, simulated
    np.testing.assert_allclose(angles[-1] - angles[0], moving * dt * RATES, atol=1e-12)
    assert node._commands.ended_at_rest == 1


@pytest.mark.parametrize(
    ("offset", "still_for", "moves_after"),
    [
        (-0.005, 0, 15),  # late: caught up, the end counts from the stamp (2T - 5 ms on)
        (-0.03, 0, 1),  # later than its end (within MAX_CATCH_UP): theta_dot 2T in one step
        (0.005, 5, 25),  # stamped ahead (lockstep side by side): from its stamp, 2T on
    ],
    ids=["late", "past-its-end", "ahead"],
)
@pytest.mark.parametrize("lockstep_period", [1.0, 0.0], ids=["lockstep", "free"])
def test_a_streamed_trajectory_ends_at_rest_2T_after_its_stamp(
    ros, offset, still_for, moves_after, lockstep_period
):
    """Kinematic mode, a streamed trajectory stamped ``offset`` [s] from the simulated time and
    no newer one: late, it makes up the motion it missed and stops 2T after its stamp; past
    its end on arrival, it moves theta_dot 2T at once, as joint_trajectory_controller samples
    it at rest at point 1; stamped ahead, it waits for its stamp and stops 2T after it. The
    joints end theta_dot 2T from where they stood, exactly. In lockstep or not."""
    node = _stepped_simulator(ros, lockstep_period)
    _send_streamed(node, node.simulator.time + offset)
    angles = _angles(node, 60)
    assert _last_moving_step(angles) == moves_after
    assert _last_moving_step(angles[: still_for + 1]) == 0  # nothing before its stamp
    np.testing.assert_allclose(angles[-1] - angles[0], 2 * PERIOD * RATES, rtol=0, atol=1e-12)
    assert not np.any(node.simulator.reference.velocities)
    assert node._commands.ended_at_rest == 1


def test_a_streamed_trajectory_ends_at_rest_in_dynamic_mode(ros):
    """Dynamic mode: the servo's reference moves at theta_dot for 2T, then stands at point 1's
    positions (theta + 2T theta_dot) at zero velocity; the joints settle there."""
    node = _stepped_simulator(ros, mode="dynamic")
    dt = node.simulator.dt
    start = node.simulator.q[7:].copy()
    _send_streamed(node, node.simulator.time)
    references = []
    for _ in range(round(2 * PERIOD / dt) + 5):
        node.advance()
        references.append(node.simulator.reference)
    # the velocity ends before the step that starts at 2T
    moving = [bool(np.any(reference.velocities)) for reference in references]
    assert moving == [True] * round(2 * PERIOD / dt) + [False] * 5
    end = start + 2 * PERIOD * RATES  # point 1
    np.testing.assert_allclose(references[-1].positions, end, rtol=0, atol=1e-12)
    _angles(node, 1000)
    print(f"settled within {np.abs(node.simulator.q[7:] - end).max():.2e} rad of point 1")
    np.testing.assert_allclose(node.simulator.q[7:], end, rtol=0, atol=1e-6)
    np.testing.assert_allclose(node.simulator.v[6:], 0.0, atol=1e-6)
    assert node._commands.ended_at_rest == 1


@pytest.mark.parametrize("catch_up", [True, False])
def test_on_the_real_time_pace_a_command_stamped_ahead_waits_for_its_stamp(ros, catch_up):
    """A simulation behind its real-time pace (its process waited for a core, and sprints to
    catch up) receives a JointTrajectory stamped 20 ms after the instant its pace maps the
    simulated time to. With catch_up_late_commands the joints keep the previous command (rest)
    until the simulated time reaches the stamp, then move at the new rate: the arm follows the
    stamped timeline, as a late command caught up does, not early at a configuration the
    controller predicted it past. Stamped farther ahead than MAX_CATCH_UP (another clock), or
    without catch_up_late_commands, a command acts at the next step."""
    node = _simulator(ros, catch_up_late_commands=catch_up)
    stop_worker(node._thread, node._stop, node._command_arrived)  # steps only when told here
    intake, simulator = node._commands, node.simulator
    epoch = 1_000_000.0  # the node-clock instant the pace maps simulated time 0 to [s]
    intake._paced_time = lambda sim_time: Time(nanoseconds=round((epoch + sim_time) * 1e9))
    dt, theta_0 = simulator.dt, simulator.q[7:].copy()
    rate = np.array([0.2, -0.3, 0.25, 0.4, -0.5, 0.6, 0.7])

    def accept(ahead: float) -> None:
        intake._accept(None, rate, None, epoch + simulator.time + ahead)

    accept(0.02)
    for _ in range(round(0.03 / dt)):
        node.advance()
    moved = simulator.q[7:] - theta_0
    acted = 0.01 if catch_up else 0.03  # [s] of motion at the new rate
    np.testing.assert_allclose(moved, acted * rate, atol=1e-9)

    theta_1 = simulator.q[7:].copy()
    intake._accept(None, np.zeros(7), None, None)  # unstamped: at rest from the next step
    node.advance()
    np.testing.assert_allclose(simulator.q[7:], theta_1, atol=1e-12)
    accept(2.0 * MAX_CATCH_UP)  # another clock: acts at once
    node.advance()
    np.testing.assert_allclose(simulator.q[7:] - theta_1, dt * rate, atol=1e-12)
