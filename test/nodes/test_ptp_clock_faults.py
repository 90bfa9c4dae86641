"""rns_ptp on a /clock that cannot be trusted (use_sim_time, the position interface, a lockstep
plant played by the test): a second publisher far ahead, a clock that runs backwards, a step
below max_clock_jump but of many periods. Every joint command stays within the URDF limits and
near the measured angles; a clock fault holds the plan (CLOCK_FAULT, one error line naming the
publishers of /clock) and the same plan resumes on its path and reaches the goal once the clock
runs forward from one publisher again. Also: use_sim_time cannot be switched on a running
rns_ptp."""

from __future__ import annotations

import time

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rns_testing import (
    Recorder,
    assert_commands_bounded,
    assert_one_clock_fault_logged,
    status_values,
)
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rns_ros.nodes.ptp import PtpNode
from rns_ros.nodes.sim_clock import stamp_from_seconds
from rns_ros.nodes.simulator_parameters import SATELLITE_OBSERVATION_RAD

JOINTS = [f"joint_{i}" for i in range(1, 8)]
START = np.array(SATELLITE_OBSERVATION_RAD)
#: The goal: joint_4 0.6 rad from START, farther than any command may be from the arm [rad].
GOAL_STEP = 0.6
PERIOD = 0.01  # [s] rns_ptp's default rate
#: How far a command may stand from the measured angles here [rad]: max_reference_error (0.25)
#: and rounding.
NEAR = 0.3
#: Wall time [s] a step waits for the tick (and command) a /clock causes, and the longest any
#: condition is waited for (a loaded machine; nothing is asserted about either).
OUTPUT_WAIT = 1.0
PATIENCE = 30.0
#: rns_ptp's playing states: each tick commands the joints, and the tick after one commands
#: the stop.
PLAYING = ("MOVING", "CANCELLING")


class _PositionPlant:
    """rns_ptp (use_sim_time, output_interface position, joint_space) and by hand what a
    lockstep position-controlled plant gives it: each period a joint state at the newest
    commanded positions and the base pose, then /clock; each step waits for rns_ptp's tick at
    that clock and for the command it sends."""

    def __init__(self, ros) -> None:
        self.ros = ros
        overrides = {
            "use_sim_time": True,
            "output_interface": "position",
            "method": "joint_space",
            "duration": 2.0,
            "state_timeout": 0.5,
            "clock_timeout": 30.0,  # /clock stands still while the test waits for outputs
        }
        self.ptp = ros.add(
            PtpNode(
                context=ros.context,
                parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
            )
        )
        probe = ros.probe()
        self.status = Recorder(probe, DiagnosticArray, "rns_ptp/status", qos=1000)
        self._states = probe.create_publisher(JointState, "joint_states", 10)
        self._odom = probe.create_publisher(Odometry, "base_odom", 10)
        self.clock = probe.create_publisher(Clock, "/clock", 10)
        self.goal = probe.create_publisher(JointState, "ptp_goal", 10)
        self.angles = START.copy()
        #: (measured angles [rad] (7,), the command received while they were measured)
        self.commands: list[tuple[np.ndarray, np.ndarray]] = []
        probe.create_subscription(Float64MultiArray, "joint_positions", self._on_command, 1000)
        assert ros.spin_until(lambda: self.clock.get_subscription_count() > 0, timeout=PATIENCE)

    def _on_command(self, msg: Float64MultiArray) -> None:
        self.commands.append((self.angles.copy(), np.array(msg.data)))

    def step(self, t: float) -> None:
        """The plant at ``t`` [s]: it moved to the newest command; state and pose stamped
        ``t``, then /clock at ``t``; waits (briefly) for rns_ptp's tick there and its
        command."""
        if self.commands:
            self.angles = self.commands[-1][1].copy()
        joints = JointState(name=JOINTS, position=self.angles.tolist())
        joints.header.stamp = stamp_from_seconds(t)
        self._states.publish(joints)
        pose = Odometry()
        pose.header.stamp, pose.pose.pose.orientation.w = stamp_from_seconds(t), 1.0
        self._odom.publish(pose)
        self.ros.spin_for(0.02)
        ticks, count = len(self.status.messages), len(self.commands)
        self.clock.publish(Clock(clock=stamp_from_seconds(t)))

        def ticked() -> bool:
            return any(
                abs(_seconds(m.header.stamp) - t) < 1e-6 for m in self.status.messages[ticks:]
            )

        if not self.ros.spin_until(ticked, timeout=OUTPUT_WAIT):
            return  # no tick at t (the clock went back: the next one is a period on)
        states = [_state(m) for m in self.status.messages[max(ticks - 1, 0) :]]
        if any(state in PLAYING for state in states):
            self.ros.spin_until(lambda: len(self.commands) > count, timeout=OUTPUT_WAIT)

    def run(self, start: float, condition, steps: int | None = None) -> float:
        """Steps from ``start`` [s] on, one period apart, until ``condition()`` (or ``steps``
        of them when given; at most PATIENCE of wall time); returns the time of the last step."""
        deadline = time.monotonic() + PATIENCE
        k, t = 0, start
        while time.monotonic() < deadline:
            t = round(start + k * PERIOD, 9)
            self.step(t)
            k += 1
            if (steps is None and condition()) or k == steps:
                return t
        raise AssertionError(f"not met after {k} steps, up to {t} s")

    def state(self) -> str | None:
        return _state(self.status.messages[-1]) if self.status.messages else None

    def states(self) -> list[str]:
        return [_state(m) for m in self.status.messages]

    def message(self) -> str:
        return self.status.messages[-1].status[0].message

    def start_motion(self, start: float) -> float:
        """IDLE from ``start`` [s], then the goal (joint_4 GOAL_STEP on), played for 0.3 s;
        returns the time of the last step."""
        t = self.run(start, lambda: self.state() == "IDLE")
        self.goal.publish(JointState(name=["joint_4"], position=[START[3] + GOAL_STEP]))
        t = self.run(round(t + PERIOD, 9), lambda: self.state() == "MOVING")
        return self.run(round(t + PERIOD, 9), None, steps=30)

    def assert_goal_reached(self, plan) -> None:
        """DONE, on the plan the motion started with (resumed, never replanned), the arm at
        its goal."""
        assert self.ptp.plan is plan
        assert np.abs(self.angles - plan.goal).max() <= 0.01
        assert plan.goal[3] == START[3] + GOAL_STEP


def _seconds(stamp) -> float:
    return stamp.sec + 1e-9 * stamp.nanosec


def _state(msg: DiagnosticArray) -> str:
    return status_values(msg)["state"]


def test_a_second_clock_publisher_far_ahead_holds_the_plan_naming_it_and_it_resumes(ros, capfd):
    """A stranger publishes /clock 1e6 s ahead of the lockstep plant mid-plan. Without the
    clock checks, the tick at its reading plays the plan 1e6 s on: its end, 0.6 rad from the
    arm. Here every command stays within the limits and near the measured angles, the status
    says CLOCK_FAULT naming /stranger (one error line), the node runs on, and once the stranger
    is gone the same plan resumes on its path and reaches the goal."""
    plant = _PositionPlant(ros)
    t = plant.start_motion(1.0)
    plan = plant.ptp.plan
    assert plant.state() == "MOVING"
    stranger_node = ros.probe("stranger")
    stranger = stranger_node.create_publisher(Clock, "/clock", 10)
    assert ros.spin_until(lambda: stranger.get_subscription_count() > 0, timeout=PATIENCE)
    stranger.publish(Clock(clock=stamp_from_seconds(t + 1e6)))
    ros.spin_for(0.1)
    t = plant.run(round(t + PERIOD, 9), None, steps=5)
    assert_commands_bounded(plant.commands, plant.ptp.robot, NEAR)
    t = plant.run(
        round(t + PERIOD, 9),
        lambda: plant.state() == "CLOCK_FAULT" and "/stranger" in plant.message(),
    )
    status = plant.status.messages[-1].status[0]
    assert status.level == status.ERROR
    assert "2 publishers on /clock" in status.message
    assert plant.ptp.plan is plan  # held, not abandoned
    assert_commands_bounded(plant.commands, plant.ptp.robot, NEAR)
    # the stranger leaves: the clock runs forward from one publisher again
    stranger_node.destroy_publisher(stranger)
    plant.run(round(t + PERIOD, 9), lambda: plant.state() == "DONE")
    states = plant.states()
    after = states[states.index("CLOCK_FAULT") :]
    assert "MOVING" in after
    assert "PLANNING" not in after
    plant.assert_goal_reached(plan)
    assert_commands_bounded(plant.commands, plant.ptp.robot, NEAR)
    assert_one_clock_fault_logged(capfd)


def test_a_clock_that_runs_backwards_holds_the_plan_and_it_resumes_once_it_runs_forward(ros, capfd):
    """The plant's own /clock goes back from past 5 s to 1.5 s mid-plan (a reset, or a
    publisher behind): CLOCK_FAULT once ("jumped back", naming the publisher), the arm held
    with bounded commands, and the same plan resumes once the clock has run forward again."""
    plant = _PositionPlant(ros)
    t = plant.start_motion(5.0)
    plan = plant.ptp.plan
    plant.run(1.5, lambda: plant.state() == "CLOCK_FAULT", steps=1)
    assert plant.state() == "CLOCK_FAULT"
    assert f"/clock jumped back {t - 1.5:.4g} s" in plant.message()
    assert "/clock published by /rns_harness_probe" in plant.message()
    plant.run(1.51, lambda: plant.state() == "DONE")
    states = plant.states()
    after = states[states.index("CLOCK_FAULT") :]
    assert "MOVING" in after
    assert "PLANNING" not in after
    plant.assert_goal_reached(plan)
    assert_commands_bounded(plant.commands, plant.ptp.robot, NEAR)
    assert_one_clock_fault_logged(capfd)


@pytest.mark.parametrize(
    ("step", "reason"),
    [(0.3, "s between two ticks"), (0.9, "joint_states 0.9")],
)
def test_a_clock_step_of_many_periods_advances_the_plan_by_a_few_and_holds_it(ros, step, reason):
    """/clock steps ``step`` [s] mid-plan, below max_clock_jump (1 s), so no clock fault: the
    plan clock advances by at most max(5 T, 0.05 s) over it, not by ``step`` of plan, and the
    plan is held (HOLDING: ticks too far apart, or at 0.9 s a joint state older than
    state_timeout) and resumes on its path to the goal. No command moves the arm farther than
    the plan does in that bound at its top speed."""
    plant = _PositionPlant(ros)
    t = plant.start_motion(1.0)
    t = plant.run(round(t + PERIOD, 9), None, steps=70)  # near the plan's top speed
    plan = plant.ptp.plan
    count = len(plant.commands)
    t = round(t + step, 9)
    plant.run(t, lambda: plant.state() == "HOLDING", steps=1)
    assert plant.state() == "HOLDING"
    assert reason in plant.message()
    assert_commands_bounded(plant.commands, plant.ptp.robot, NEAR)
    plant.run(round(t + PERIOD, 9), lambda: plant.state() == "DONE")
    plant.assert_goal_reached(plan)
    assert "PLANNING" not in plant.states()
    speed = float(np.max(plant.ptp.robot.velocity_limits))  # the plan keeps to the limits
    commands = np.array([command for _, command in plant.commands[count - 1 :]])
    largest = np.abs(np.diff(commands, axis=0)).max()
    assert largest <= (0.05 + PERIOD) * speed, f"a command moved the arm by {largest:.4g} rad"
    assert_commands_bounded(plant.commands, plant.ptp.robot, NEAR)


def test_use_sim_time_cannot_be_switched_on_a_running_ptp(ros):
    """Switched, the node would go on with the clock it started with (its ticks, watchdogs
    and stamps): the change is refused, naming the restart that makes it; clock_timeout still
    changes at run time, within its range."""
    ptp = ros.add(PtpNode(context=ros.context))
    result = ptp.set_parameters([Parameter("use_sim_time", value=True)])[0]
    assert not result.successful
    assert "use_sim_time cannot change on a running node" in result.reason
    assert "-p use_sim_time:=true" in result.reason
    assert ptp.get_parameter("use_sim_time").value is False
    assert not ptp.get_clock().ros_time_is_active
    assert ptp.set_parameters([Parameter("use_sim_time", value=False)])[0].successful
    assert ptp.set_parameters([Parameter("clock_timeout", value=2.0)])[0].successful
    assert ptp._input_clock.timeout == 2.0
    assert not ptp.set_parameters([Parameter("clock_timeout", value=100.0)])[0].successful
