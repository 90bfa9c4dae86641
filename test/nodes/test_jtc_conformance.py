"""Every joint command rns_controller and rns_ptp can publish is one a stock ros2_control
controller with its Jazzy defaults executes (docs/ros2_control.md), and the stream ends at rest.

:func:`jtc_rejection` applies joint_trajectory_controller's acceptance rules
(``JointTrajectoryController::validate_trajectory_msg``, ros2_controllers Jazzy) to a message,
with the controller's parameters at their defaults: allow_partial_joints_goal false,
allow_nonzero_velocity_at_trajectory_end false, allow_integration_in_goal_trajectories false,
no effort command interface. :func:`jtc_sample` is its interpolation between points
(``Trajectory::sample``): linear where a point has no velocities, cubic with them.
"""

from __future__ import annotations

import math
import time
from types import SimpleNamespace

import numpy as np
import pytest
from builtin_interfaces.msg import Duration, Time
from geometry_msgs.msg import Twist, TwistStamped
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from rns_ros.control.ptp_sampling import sample_times
from rns_ros.core import ConfigError
from rns_ros.nodes.controller import ControllerNode
from rns_ros.nodes.ptp import PtpNode
from rns_ros.nodes.robot_io import (
    TRAJECTORY_DELIVERY_MARGIN,
    TRAJECTORY_HORIZON_PERIODS,
    JointCommand,
)
from rns_ros.nodes.simulator_parameters import SATELLITE_OBSERVATION_RAD

JOINTS = [f"joint_{i}" for i in range(1, 8)]
START = np.array(SATELLITE_OBSERVATION_RAD)
PERIOD = 0.01  # both nodes' default output period [s]
#: JTC compares |v| of the last point with std::numeric_limits<float>::epsilon().
FLOAT_EPSILON = float(np.finfo(np.float32).eps)
#: A receipt lag [s] a loaded machine shows (163 ms the largest measured at 100 Hz), within
#: TRAJECTORY_DELIVERY_MARGIN.
LATE_DELIVERY = 0.2


# --- the rules ----------------------------------------------------------------------------------
def _seconds(value: Time | Duration) -> float:
    return value.sec + 1e-9 * value.nanosec


def jtc_rejection(msg: JointTrajectory, controller_joints, now: float) -> str | None:
    """Why a Jazzy joint_trajectory_controller with default parameters, whose ``joints`` are
    ``controller_joints``, refuses ``msg`` received at ``now`` [s] on its clock; None when it
    takes it. Non-finite values (which JTC would take and play) are refused here as well."""
    names, points = list(msg.joint_names), list(msg.points)
    if len(names) != len(controller_joints):  # allow_partial_joints_goal: false
        return "Joints on incoming trajectory don't match the controller joints."
    if not names:
        return "Empty joint names on incoming trajectory."
    if not points:
        return "Empty trajectory received."
    start = _seconds(msg.header.stamp)
    if start != 0.0 and start + _seconds(points[-1].time_from_start) < now:
        return "Received trajectory with non-zero start time that ends in the past"
    for name in names:
        if name not in controller_joints:
            return f"Incoming joint {name} doesn't match the controller's joints."
    for name, velocity in zip(names, points[-1].velocities, strict=False):
        if abs(velocity) > FLOAT_EPSILON:  # allow_nonzero_velocity_at_trajectory_end: false
            return f"Velocity of last trajectory point of joint {name} is not zero"
    previous = None
    for i, point in enumerate(points):
        t = _seconds(point.time_from_start)
        if previous is not None and t <= previous:
            return f"Time between points {i - 1} and {i} is not strictly increasing"
        previous = t
        for field, allow_empty in (
            ("positions", False),
            ("velocities", True),
            ("accelerations", True),
        ):
            values = getattr(point, field)
            if not (allow_empty and len(values) == 0) and len(values) != len(names):
                return f"Mismatch between joint_names size and {field} at point #{i}"
            if not np.isfinite(np.asarray(values, dtype=float)).all():
                return f"non-finite {field} at point #{i}"
        if len(point.effort):
            return "Trajectories with effort fields are only supported for effort interfaces"
    return None


def array_rejection(msg: Float64MultiArray, controller_joints) -> str | None:
    """Why a forward_command_controller (JointGroupVelocityController /
    JointGroupPositionController) of ``controller_joints`` ignores ``msg``; non-finite refused."""
    if len(msg.data) != len(controller_joints):
        return "command size does not match number of interfaces"
    if not np.isfinite(np.asarray(msg.data, dtype=float)).all():
        return "non-finite command"
    return None


def jtc_sample(msg: JointTrajectory, after: float) -> tuple[np.ndarray, np.ndarray]:
    """(positions, velocities) JTC commands ``after`` [s] past the stamp, between the points
    around it (JTC's Trajectory::sample and interpolate_between_points); the last point held
    at rest after the end."""
    times = [_seconds(p.time_from_start) for p in msg.points]
    for a, b in zip(msg.points, msg.points[1:], strict=False):
        ta, tb = _seconds(a.time_from_start), _seconds(b.time_from_start)
        if ta <= after < tb:
            h, u = tb - ta, after - ta
            pa, pb = np.array(a.positions), np.array(b.positions)
            if len(a.velocities) and len(b.velocities):
                va, vb = np.array(a.velocities), np.array(b.velocities)
                c2 = (-3 * pa + 3 * pb - 2 * va * h - vb * h) / h**2
                c3 = (2 * pa - 2 * pb + va * h + vb * h) / h**3
                return pa + va * u + c2 * u**2 + c3 * u**3, va + 2 * c2 * u + 3 * c3 * u**2
            return pa + (pb - pa) * u / h, (pb - pa) / h
    assert after >= times[-1] or after < times[0]
    last = msg.points[-1] if after >= times[-1] else msg.points[0]
    return np.array(last.positions), np.zeros(len(last.positions))


def check_stream(messages, controller_joints, period: float, latency: float) -> None:
    """Every streamed JointTrajectory: JTC takes it ``latency`` [s] after its stamp, and
    ``LATE_DELIVERY`` after it too; point 0 is the held command and JTC plays it at exactly that
    velocity until the next message is due; the arm is at rest from point 1 (two periods) on,
    and the trajectory ends at rest TRAJECTORY_DELIVERY_MARGIN after its stamp."""
    assert messages
    for msg in messages:
        stamp = _seconds(msg.header.stamp)
        for delay in (latency, LATE_DELIVERY):
            assert jtc_rejection(msg, controller_joints, stamp + delay) is None
        assert len(msg.points) == 3
        first, stop, last = msg.points
        assert _seconds(first.time_from_start) == 0.0
        horizon = _seconds(stop.time_from_start)
        assert horizon == pytest.approx(TRAJECTORY_HORIZON_PERIODS * period, abs=1e-9)
        end = _seconds(last.time_from_start)
        assert end == pytest.approx(TRAJECTORY_DELIVERY_MARGIN, abs=1e-9)
        for after in (0.0, 0.5 * period, period):
            positions, velocities = jtc_sample(msg, after)
            np.testing.assert_allclose(velocities, first.velocities, atol=1e-9)
            expected = np.array(first.positions) + after * np.array(first.velocities)
            np.testing.assert_allclose(positions, expected, atol=1e-9)
        for after in (horizon, horizon + period, LATE_DELIVERY, end, end + period):
            positions, velocities = jtc_sample(msg, after)
            np.testing.assert_array_equal(positions, stop.positions)
            assert not np.any(velocities)


# --- the checker refuses what JTC refuses -------------------------------------------------------
def _good(stamp: float = 100.0) -> JointTrajectory:
    command = JointCommand("trajectory", JOINTS, JOINTS, PERIOD)
    sec = math.floor(stamp)
    return command.message(
        Time(sec=sec, nanosec=round((stamp - sec) * 1e9)), START, np.full(7, 0.1)
    )


def _broken(change) -> JointTrajectory:
    msg = _good()
    change(msg)
    return msg


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        (lambda m: setattr(m, "joint_names", JOINTS[:6]), "don't match the controller joints"),
        (lambda m: m.joint_names.__setitem__(0, "elbow"), "Incoming joint elbow"),
        (lambda m: setattr(m, "points", []), "Empty trajectory"),
        (lambda m: setattr(m.points[-1], "velocities", [0.1] * 7), "last trajectory point"),
        (lambda m: setattr(m, "points", m.points[:1]), "last trajectory point"),
        (lambda m: setattr(m.points[1], "time_from_start", Duration()), "strictly increasing"),
        (lambda m: setattr(m.points[0], "positions", [0.0] * 6), "positions at point #0"),
        (lambda m: setattr(m.points[0], "velocities", [0.0] * 8), "velocities at point #0"),
        (lambda m: setattr(m.points[0], "positions", []), "positions at point #0"),
        (lambda m: setattr(m.points[1], "effort", [0.0] * 7), "effort"),
        (lambda m: m.points[0].positions.__setitem__(2, math.nan), "non-finite positions"),
    ],
)
def test_the_checker_refuses_each_broken_rule(change, reason):
    assert jtc_rejection(_good(), JOINTS, 100.0) is None
    assert reason in jtc_rejection(_broken(change), JOINTS, 100.0)


def test_a_stamped_trajectory_is_refused_once_it_ends_in_the_past_and_stamp_zero_never():
    end = TRAJECTORY_DELIVERY_MARGIN
    assert jtc_rejection(_good(100.0), JOINTS, 100.0 + end) is None
    assert "ends in the past" in jtc_rejection(_good(100.0), JOINTS, 100.0 + end + 1e-6)
    assert jtc_rejection(_good(0.0), JOINTS, 1e9) is None


def test_a_trajectory_delivered_late_is_taken_and_played_as_a_hold_at_rest():
    """Received LATE_DELIVERY (0.2 s) after its stamp, past its point 1: JTC takes it and holds
    point 1's positions (theta + 2T theta_dot) at zero velocity until its end; received more
    than TRAJECTORY_DELIVERY_MARGIN after its stamp, it is refused."""
    velocity = np.full(7, 0.1)
    msg = _good(100.0)
    assert jtc_rejection(msg, JOINTS, 100.0 + LATE_DELIVERY) is None
    stop = START + TRAJECTORY_HORIZON_PERIODS * PERIOD * velocity
    for after in (LATE_DELIVERY, LATE_DELIVERY + PERIOD, TRAJECTORY_DELIVERY_MARGIN, 1.0):
        positions, velocities = jtc_sample(msg, after)
        np.testing.assert_allclose(positions, stop, atol=1e-12)
        assert not np.any(velocities)
    too_late = 100.0 + TRAJECTORY_DELIVERY_MARGIN + 1e-3
    assert "ends in the past" in jtc_rejection(msg, JOINTS, too_late)


def test_the_stream_check_fails_on_a_one_point_trajectory_with_velocities():
    """The old shape (one point, time_from_start 0, the held velocity) is refused by JTC."""
    msg = _good()
    msg.points = msg.points[:1]
    with pytest.raises(AssertionError):
        check_stream([msg], JOINTS, PERIOD, PERIOD)


def test_the_array_checker_refuses_a_wrong_size_and_non_finite_values():
    assert array_rejection(Float64MultiArray(data=[0.0] * 7), JOINTS) is None
    assert "size" in array_rejection(Float64MultiArray(data=[0.0] * 6), JOINTS)
    assert "non-finite" in array_rejection(Float64MultiArray(data=[math.inf] + [0.0] * 6), JOINTS)


# --- every message the nodes publish ------------------------------------------------------------
def _node(ros, cls, **overrides):
    overrides.setdefault("state_timeout", 0.5)  # one shared GIL in tests: no spurious trips
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(cls(context=ros.context, parameter_overrides=parameters))


class Broadcaster:
    """A joint_state_broadcaster stand-in: JointState of fixed angles at 100 Hz until stopped
    (the controller_manager died)."""

    def __init__(self, probe, positions=START):
        self.active = True
        publisher = probe.create_publisher(JointState, "joint_states", 10)

        def tick():
            if self.active:
                msg = JointState(name=JOINTS, position=list(positions))
                msg.header.stamp = probe.get_clock().now().to_msg()
                publisher.publish(msg)

        probe.create_timer(0.01, tick)


def _operator(probe, angular=(0.0, 0.0, 0.1)):
    publisher = probe.create_publisher(
        TwistStamped, "cmd_twist", QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
    )

    def tick():
        msg = TwistStamped(twist=Twist())
        msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = angular
        msg.header.frame_id = "world"
        msg.header.stamp = probe.get_clock().now().to_msg()
        publisher.publish(msg)

    probe.create_timer(0.02, tick)


def _record(probe, msg_type, topic):
    """Messages of ``topic`` with their receipt times [s] (probe clock)."""
    received = []
    probe.create_subscription(
        msg_type,
        topic,
        lambda msg: received.append((msg, probe.get_clock().now().nanoseconds * 1e-9)),
        50,
    )
    return received


def _stop_and_destroy(ros, node, received):
    """Destroy ``node``; its last message arrives."""
    ros.detach(node)
    count = len(received)
    node.destroy_node()
    assert ros.spin_until(lambda: len(received) > count, timeout=5.0)
    ros.spin_for(0.2)


def test_every_controller_trajectory_is_taken_by_a_default_jtc(ros):
    """Moving, stopped by a lost joint_states stream (STALE_STATE) and at shutdown: each message
    passes JTC's rules one period after its stamp; the receipt latency seen here is printed."""
    probe = ros.probe()
    received = _record(probe, JointTrajectory, "joint_references")
    broadcaster = Broadcaster(probe)
    _node(ros, ControllerNode)
    _operator(probe)
    assert ros.spin_until(
        lambda: received and np.abs(received[-1][0].points[0].velocities).max() > 0.01
    )
    broadcaster.active = False  # the controller_manager died: joint_states stop
    assert ros.spin_until(
        lambda: (
            not np.any(received[-1][0].points[0].velocities)
            and len(received) > 5
            and all(not np.any(m.points[0].velocities) for m, _ in received[-3:])
        ),
        timeout=5.0,
    )
    broadcaster.active = True
    ros.spin_for(0.3)
    controller = ros.nodes[-1]
    _stop_and_destroy(ros, controller, received)
    messages = [msg for msg, _ in received]
    check_stream(messages, JOINTS, PERIOD, latency=PERIOD)
    assert not np.any(messages[-1].points[0].velocities)
    latency = np.array([t - _seconds(m.header.stamp) for m, t in received])
    print(
        f"{len(messages)} trajectories; receipt - stamp: median {np.median(latency) * 1e3:.2f} "
        f"ms, max {latency.max() * 1e3:.2f} ms (JTC refuses beyond "
        f"{TRAJECTORY_DELIVERY_MARGIN * 1e3:.0f} ms)"
    )


@pytest.mark.parametrize("interface", ["velocity", "position"])
def test_array_interfaces_stop_on_state_loss_and_at_shutdown(ros, interface):
    """A forward controller repeats its last command: the stream must end on rest. joint_states
    stop (the controller_manager died): the output turns to rest within state_timeout; at
    shutdown the last message is rest too. Velocity: zeros; position: the reference, unmoved.
    Arrays in the order of ``joints`` (reversed here)."""
    order = JOINTS[::-1]
    probe = ros.probe()
    topic = JointCommand(interface, JOINTS, order, PERIOD).topic
    received = _record(probe, Float64MultiArray, topic)
    broadcaster = Broadcaster(probe)
    controller = _node(ros, ControllerNode, output_interface=interface, joints=order)
    _operator(probe, angular=(0.0, 0.1, 0.0))

    def step(msg) -> np.ndarray:
        data = np.array(msg.data)[::-1]  # model order
        return data if interface == "velocity" else (data - START) / PERIOD

    assert ros.spin_until(
        lambda: received and np.abs(step(received[-1][0])).max() > 0.01, timeout=10.0
    )
    if interface == "position":
        # the command is where the reference is one period on: theta + T theta_dot
        reference = np.array(controller.controller.reference_positions)
        assert np.abs(np.array(received[-1][0].data)[::-1] - reference).max() < 0.2
    broadcaster.active = False
    lost = time.monotonic()

    def at_rest() -> bool:
        if interface == "velocity":
            return not np.any(received[-1][0].data)
        return len(received) > 2 and received[-1][0].data == received[-2][0].data

    assert ros.spin_until(at_rest, timeout=5.0)
    print(f"{interface}: joint_states lost -> rest after {time.monotonic() - lost:.3f} s")
    count = len(received)
    ros.spin_for(0.2)
    rest = received[-1][0].data
    assert all(msg.data == rest for msg, _ in received[count:])
    broadcaster.active = True
    assert ros.spin_until(lambda: np.abs(step(received[-1][0])).max() > 0.01, timeout=10.0)
    _stop_and_destroy(ros, controller, received)
    for msg, _ in received:
        assert array_rejection(msg, order) is None
    # shutdown: zero velocity, or the measured angles as the position to hold
    last = np.array(received[-1][0].data)[::-1]
    np.testing.assert_array_equal(last, np.zeros(7) if interface == "velocity" else START)


def _ptp(ros, **overrides):
    probe = ros.probe()
    received = _record(probe, JointTrajectory, "joint_references")
    Broadcaster(probe)
    overrides = {"method": "joint_space", "duration": 1.0, **overrides}
    ptp = _node(ros, PtpNode, **overrides)
    goal = probe.create_publisher(JointState, "ptp_goal", 10)
    cancel = probe.create_client(Trigger, "rns_ptp/cancel")
    ros.spin_for(0.3)
    return SimpleNamespace(ptp=ptp, received=received, goal=goal, cancel=cancel)


def test_every_ptp_tick_trajectory_is_taken_by_a_default_jtc(ros):
    stack = _ptp(ros)
    stack.goal.publish(JointState(name=JOINTS, position=list(START + 0.05)))
    received = stack.received
    assert ros.spin_until(lambda: stack.ptp._mode.value == "SETTLING", timeout=20.0)
    _stop_and_destroy(ros, stack.ptp, received)
    messages = [msg for msg, _ in received]
    assert len(messages) > 50
    check_stream(messages, JOINTS, PERIOD, latency=PERIOD)
    assert not np.any(messages[-1].points[0].velocities)


def test_a_whole_ptp_plan_is_one_trajectory_a_default_jtc_takes_and_cancel_replaces_it(ros):
    """plan_output whole: one message with the plan's samples (the sampling grid of
    rns_ros.control.ptp_sampling), from the start, at rest at its end; ~/cancel then streams
    per-period trajectories (the first replaces the plan in JTC), all taken by JTC."""
    stack = _ptp(ros, plan_output="whole", plan_sample_period=0.1, duration=3.0)
    goal = START + 0.3
    stack.goal.publish(JointState(name=JOINTS, position=list(goal)))
    received = stack.received
    assert ros.spin_until(lambda: received, timeout=20.0)
    whole = received[0][0]
    plan = stack.ptp.plan
    stamp = _seconds(whole.header.stamp)
    assert jtc_rejection(whole, JOINTS, stamp + plan.duration) is None
    times = [_seconds(p.time_from_start) for p in whole.points]
    np.testing.assert_allclose(times, sample_times(plan, 0.1), atol=1e-9)
    np.testing.assert_allclose(whole.points[0].positions, START, atol=1e-9)
    np.testing.assert_allclose(whole.points[-1].positions, goal, atol=1e-9)
    assert not np.any(whole.points[-1].velocities)
    # JTC's cubic through the samples follows the plan between them
    for t in np.linspace(0.05, plan.duration - 0.05, 23):
        positions, _ = jtc_sample(whole, t)
        np.testing.assert_allclose(positions, plan.sample(t).theta, atol=1e-5)
    ros.spin_for(0.5)
    assert len(received) == 1  # nothing else while the plan plays
    future = stack.cancel.call_async(Trigger.Request())
    assert ros.spin_until(future.done, timeout=5.0)
    assert future.result().success
    assert ros.spin_until(lambda: stack.ptp._mode.value == "IDLE", timeout=10.0)
    _stop_and_destroy(ros, stack.ptp, received)
    streamed = [msg for msg, _ in received[1:]]
    assert len(streamed) > 10
    check_stream(streamed, JOINTS, PERIOD, latency=PERIOD)
    assert not np.any(streamed[-1].points[0].velocities)


def test_a_whole_plan_needs_the_trajectory_interface(ros):
    with pytest.raises(ConfigError, match=r"plan_output 'whole'.*output_interface 'trajectory'"):
        _node(ros, PtpNode, plan_output="whole", output_interface="velocity")
