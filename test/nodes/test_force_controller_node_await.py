"""rns_force_controller with ``await_commands`` over DDS without a simulator or an operator: the
test publishes /clock, the wrist wrench, joint_states and the operator's stamped cmd_twist and
force_setpoint itself, so it decides what has arrived when a state comes
(docs/nodes/rns_force_controller.md, "The operator in the lockstep"). Simulated time is the
test's; nothing here asserts a rate."""

from __future__ import annotations

import time

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rns_testing import SimClock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rns_ros.control.contact_topics import ERROR_LABELS
from rns_ros.nodes.force_controller import ForceControllerNode
from rns_ros.nodes.sim_clock import stamp_from_seconds

JOINTS = [f"joint_{i}" for i in range(1, 8)]
START = np.radians([20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0])
ZERO7 = np.zeros(7)
PUSH = np.array([0.0, 0.0, 3.0])  # the wrench the EE exerts, EE axes [N]
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)

#: How long the test waits for a step a message may cause [s] (a loaded machine is slow), and
#: for one it must not cause.
OUTPUT_WAIT, NO_OUTPUT_WAIT = 2.0, 0.3
#: The operator's best-effort commands (as rns_operator publishes them).
COMMAND_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
TIME, FORCE_DESIRED = ERROR_LABELS.index("time"), ERROR_LABELS.index("force_desired")


class _Plant:
    """rns_force_controller (use_sim_time, await_commands) and what a lockstep simulator and an
    operator publish to it, by hand: each :meth:`state` is the next state ``step`` [s] of
    simulated time later (wrench, joint_states, then /clock, as rns_simulator publishes them)."""

    def __init__(self, ros, step: float, **parameters) -> None:
        self.node = ros.add(
            ForceControllerNode,
            {
                "use_sim_time": True,
                "await_commands": True,
                "state_timeout": 1.0,
                # this plant's /clock stands still while the test waits for outputs
                "clock_timeout": 30.0,
                **parameters,
            },
        )
        self.ros, self.step = ros, step
        self.errors = ros.record(Float64MultiArray, "rns_force_controller/errors")
        self.status = ros.record(DiagnosticArray, "rns_force_controller/status")
        probe = ros.probe()
        self.clock = SimClock(probe, start=100.0)
        self._states = probe.create_publisher(JointState, "joint_states", RELIABLE)
        self._wrench = probe.create_publisher(WrenchStamped, "wrist_wrench", RELIABLE)
        self._twist = probe.create_publisher(TwistStamped, "cmd_twist", COMMAND_QOS)
        self._setpoint = probe.create_publisher(WrenchStamped, "force_setpoint", COMMAND_QOS)
        publishers = (self._states, self._wrench, self._twist, self._setpoint)
        assert ros.spin_until(lambda: all(p.get_subscription_count() for p in publishers), 10.0)

    @property
    def next_time(self) -> float:
        """The stamp of the next state [s]."""
        return round(self.clock.seconds + self.step, 9)

    def state(self, waits: bool = False) -> float:
        """The next state; waits (up to OUTPUT_WAIT) for its step unless it ``waits`` for
        commands. Returns its stamp [s]."""
        t = self.next_time
        stamp = stamp_from_seconds(t)
        wrench = WrenchStamped()
        wrench.header.stamp, wrench.header.frame_id = stamp, "ee"
        wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z = PUSH
        self._wrench.publish(wrench)
        self.ros.spin_for(0.01)  # the wrench first (two topics: no order guaranteed)
        msg = JointState(
            name=JOINTS, position=START.tolist(), velocity=ZERO7.tolist(), effort=ZERO7.tolist()
        )
        msg.header.stamp = stamp
        self._states.publish(msg)
        self.clock.advance(self.step)
        self._await_step(not waits)
        return t

    def twist(self, t: float, vx: float, releases: bool = False) -> None:
        """The operator's twist stamped ``t`` [s]: ``vx`` [m/s] along world x; ``releases``:
        a waiting step is expected to run (waited for up to OUTPUT_WAIT)."""
        msg = TwistStamped()
        msg.header.stamp, msg.header.frame_id = stamp_from_seconds(t), "world"
        msg.twist.linear.x = vx
        self._twist.publish(msg)
        self._await_step(releases)

    def setpoint(self, t: float, force: float, releases: bool = False) -> None:
        """The operator's force setpoint stamped ``t`` [s]: ``force`` [N] along the EE z axis
        (the default contact normal); ``releases`` as for :meth:`twist`."""
        msg = WrenchStamped()
        msg.header.stamp, msg.header.frame_id = stamp_from_seconds(t), "ee"
        msg.wrench.force.z = force
        self._setpoint.publish(msg)
        self._await_step(releases)

    def _await_step(self, expected: bool) -> None:
        """Spin until the next step when one is ``expected``, else briefly (for the callbacks)."""
        count = len(self.errors)
        if expected:
            self.ros.spin_until(lambda: len(self.errors) > count, timeout=OUTPUT_WAIT)
        else:
            self.ros.spin_for(0.02)

    def steps(self) -> list[float]:
        """The stamps of the states stepped so far [s] (after NO_OUTPUT_WAIT for late ones)."""
        self.ros.spin_for(NO_OUTPUT_WAIT)
        return [round(m.data[TIME], 9) for m in self.errors.messages]

    def force_desired(self) -> float:
        """f_des of the newest step [N]."""
        return self.errors.latest().data[FORCE_DESIRED]

    def detail(self) -> str:
        """The newest status message ('' before the first)."""
        latest = self.status.latest()
        return "" if latest is None else latest.status[0].message


def test_a_step_waits_until_the_commands_in_force_on_both_streams_are_known(ros):
    """A state stamped t is stepped once a cmd_twist and a force_setpoint stamped at or after t
    came (the commands in force at t are then known), with the newest of each stamped at or
    before t; a stream that has sent nothing yet is not waited for. Without the wait the step
    at t2 would run on whatever setpoint had arrived when its state did."""
    plant = _Plant(ros, step=0.001, command_timeout=10.0)
    t0 = plant.state()  # no operator yet: nothing to wait for
    assert plant.steps() == [t0]
    t1 = plant.next_time
    plant.twist(t1, 0.0)  # the operator's zeros before its profile: twists only
    plant.state()
    assert plant.steps() == [t0, t1]  # no force setpoint yet: not waited for
    assert plant.force_desired() == 0.0
    t2 = plant.next_time
    plant.twist(t2, 0.0)
    plant.setpoint(t2, 2.0)  # the force task starts at t2 (published ahead of it)
    assert plant.steps() == [t0, t1]
    plant.state()  # both commands in force at t2 are known: stepped at once
    assert plant.steps() == [t0, t1, t2]
    assert plant.force_desired() == pytest.approx(2.0)
    t3 = plant.state(waits=True)  # what is in force at t3 is not known yet: the step waits
    assert plant.steps() == [t0, t1, t2]
    plant.twist(t3 + 0.001, 0.01)  # the twist stream is known up to t3 + 1 ms, the force not
    assert plant.steps() == [t0, t1, t2]
    # published ahead: the 2 N are still in force at t3
    plant.setpoint(t3 + 0.001, 4.0, releases=True)
    assert plant.steps() == [t0, t1, t2, t3]
    assert plant.force_desired() == pytest.approx(2.0)
    t4 = plant.state()  # the commands of t3 + 1 ms are in force: stepped at once
    assert plant.steps() == [t0, t1, t2, t3, t4]
    assert plant.force_desired() == pytest.approx(4.0)


def test_a_silent_operator_is_waited_for_command_timeout_at_most_and_the_motion_stops(ros):
    """The operator stops mid-motion: the step waits command_timeout of wall time (longer than
    clock_timeout: the wait holds /clock still, and it is not a dead simulator), then runs
    with the newest commands; the next steps do not wait, and the twist, aged in simulated
    time past command_timeout, stops the motion (the pose is held)."""
    plant = _Plant(ros, step=0.1, command_timeout=1.6, clock_timeout=0.8)
    plant.state()
    for _ in range(3):
        t = plant.next_time
        plant.twist(t, 0.01)
        plant.setpoint(t, 2.0)
        plant.state()
    stepped = len(plant.steps())
    assert stepped == 4
    start = time.monotonic()
    t = plant.state(waits=True)  # the operator went silent: this step waits
    assert plant.ros.spin_until(lambda: len(plant.errors) > stepped, timeout=10.0)
    waited = time.monotonic() - start
    # never before command_timeout; how much later depends on the machine (the give-up itself
    # on given instants: test/control/test_ticks.py)
    print(f"the step waited {waited:.3f} s (command_timeout 1.6 s)")
    assert waited >= 1.6 - 0.05
    assert plant.steps()[-1] == t
    assert "STALE_STATE" not in plant.detail()
    for _ in range(20):  # 2 s of simulated time: the twist goes stale at 1.6 s
        t = plant.state()
        assert plant.steps()[-1] == t  # stepped without waiting
        if "cmd_twist stale" in plant.detail():
            break
    assert plant.ros.spin_until(lambda: "cmd_twist stale" in plant.detail(), timeout=5.0)
    assert "holding the pose" in plant.detail()


def test_await_commands_refuses_the_wall_clock(ros):
    """await_commands waits for commands stamped ahead of simulated time: turning
    use_sim_time off under it is refused, with the reason (at start-up: one line, exit code 2,
    test_force_controller_node.py)."""
    plant = _Plant(ros, step=0.001)
    result = plant.node.set_parameters([Parameter("use_sim_time", value=False)])[0]
    assert not result.successful
    assert "await_commands needs use_sim_time: true" in result.reason
    assert plant.node.get_parameter("use_sim_time").value is True
