"""rns_ptp over real DDS (loopback, private Context) driving rns_simulator (kinematic)."""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter
from rns_testing import Recorder, SimClock, status_values
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from rns_ros.analysis.ptp_runs import run_plan
from rns_ros.control.command_bounds import CommandBounds
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.control.ptp_sampling import PlanSamples, sample_plan
from rns_ros.core import ConfigError
from rns_ros.core.integration import attitude_deviation
from rns_ros.nodes.ptp import PtpNode, PtpState
from rns_ros.nodes.ptp_planning import whole_plan_problem
from rns_ros.nodes.simulator import SimulatorNode
from rns_ros.nodes.simulator_parameters import SATELLITE_OBSERVATION_RAD

REPO = Path(__file__).resolve().parents[2]
JOINTS = [f"joint_{i}" for i in range(1, 8)]
START = np.array(SATELLITE_OBSERVATION_RAD)
#: A goal a few degrees from the simulator's default initial configuration [rad].
SMALL_STEP = np.deg2rad([3.0, -3.0, 2.0, 4.0, -3.0, 2.0, 3.0])


#: rns_ptp's state watchdog in tests that are not about it: every node of a test shares one
#: process and its GIL, and CI saw joint states 0.10-0.16 s late (the default is 0.1 s).
TEST_STATE_TIMEOUT = 0.5


def _node(ros, cls, **overrides):
    if cls is PtpNode:
        overrides.setdefault("state_timeout", TEST_STATE_TIMEOUT)
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(cls(context=ros.context, parameter_overrides=parameters))


def _stack(ros, simulator=None, **ptp_overrides):
    """rns_ptp driving rns_simulator on the wall clock."""
    _node(ros, SimulatorNode, **(simulator or {}))
    ptp = _node(ros, PtpNode, **ptp_overrides)
    probe = ros.probe()
    return SimpleNamespace(
        ptp=ptp,
        probe=probe,
        goal=probe.create_publisher(JointState, "ptp_goal", 10),
        references=Recorder(probe, JointTrajectory, "joint_references"),
        status=Recorder(probe, DiagnosticArray, "rns_ptp/status"),
        joints=Recorder(probe, JointState, "joint_states"),
        odom=Recorder(probe, Odometry, "base_odom"),
        run_until=ros.spin_until,
    )


#: rns_simulator in lockstep on simulated time, as fast as the machine runs it: it publishes
#: /clock and pauses one period past each command it is given.
LOCKSTEP = {"publish_clock": True, "real_time_factor": 0.0, "lockstep_period": 0.01}
#: rns_ptp's playback period at its default rate, and the lockstep period [s].
PERIOD = 0.01


#: rns_ptp's states in which each tick commands the joints.
PLAYING = ("MOVING", "CANCELLING")


class _Lockstep:
    """rns_ptp (use_sim_time) driving rns_simulator (LOCKSTEP) with the test in between:
    rns_simulator takes its commands on lockstep/<topic>, and the test answers each tick of
    rns_ptp, in order, with the command rns_ptp sent for it or, while rns_ptp commands nothing
    (idle, planning), with zero velocity (what its last command, a stop, held). Each answer lets
    the simulation run one period, to the /clock of rns_ptp's next tick.

    So rns_ptp ticks at every period and each of its commands acts for exactly one period,
    however late a loaded machine runs either node. (On its own a lockstep rns_simulator runs in
    real time until its first command, and an rns_ptp that lags behind it starts its plan on
    ticks several periods apart.)

    Attributes as :func:`_stack`'s; ``commands`` records rns_ptp's output (``references`` too on
    the trajectory interface); :meth:`run_until` steps the loop. With ``relay_states`` the test
    relays rns_simulator's joint_states too, and drops them while ``gap`` is True.
    """

    def __init__(self, ros, simulator=None, relay_states=False, **ptp_overrides) -> None:
        simulator = {**LOCKSTEP, **(simulator or {})}
        self.velocity = simulator.get("command_interface") == "velocity"
        topic, msg_type = (
            ("joint_velocities", Float64MultiArray)
            if self.velocity
            else ("joint_references", JointTrajectory)
        )
        remappings = {topic: f"lockstep/{topic}"}
        if relay_states:
            remappings["joint_states"] = "lockstep/joint_states"
        self.simulator = ros.add(SimulatorNode, simulator, remappings=remappings)
        # a simulation paused for a late rns_ptp is not a dead one: /clock watch hang-sized
        ptp_overrides.setdefault("clock_timeout", 30.0)
        self.ptp = _node(ros, PtpNode, use_sim_time=True, **ptp_overrides)
        self.ros = ros
        self.probe = probe = ros.probe()
        self.gap = False
        if relay_states:
            states = probe.create_publisher(JointState, "joint_states", 10)

            def relay(msg: JointState) -> None:
                if not self.gap:
                    states.publish(msg)

            probe.create_subscription(JointState, "lockstep/joint_states", relay, 10)
        self.goal = probe.create_publisher(JointState, "ptp_goal", 10)
        self.commands = Recorder(probe, msg_type, topic)
        self.references = self.commands
        self.status = Recorder(probe, DiagnosticArray, "rns_ptp/status")
        self.joints = Recorder(probe, JointState, "joint_states")
        self.odom = Recorder(probe, Odometry, "base_odom")
        self._relay = probe.create_publisher(msg_type, f"lockstep/{topic}", 10)
        assert ros.spin_until(lambda: self._relay.get_subscription_count() > 0, timeout=10.0)
        self._ticks = 0  # rns_ptp ticks (status messages) answered or passed over
        self._forwarded = 0  # rns_ptp commands forwarded
        self._answered = -math.inf  # stamp of the tick answered last [s]
        self._pacer = self.simulator._pacer
        self._receipt = self._pacer.last_command  # before the last answer (wall time) [s]
        # the simulation runs free until its first command, and takes an answer that reaches it
        # a period or more after its tick a period late (then rns_ptp ticks ahead of the
        # answers): answer until one is taken within its period (from then on each is)
        while True:
            self.step()
            self._taken()
            if 0.0 <= self._pacer.command_sim_time - self._answered < PERIOD - 1e-6:
                break

    def _taken(self) -> None:
        """Wait (up to 30 s, a hang guard) until rns_simulator has taken the last answer: its
        receipt time changes, its lockstep period counts from where it took it."""
        if self._answered > -math.inf:
            taken = self.ros.spin_until(lambda: self._pacer.last_command != self._receipt, 30.0)
            assert taken

    def _commands_at(self, tick: int) -> bool:
        """rns_ptp sent a command for the ``tick``-th tick: it plays, or it played at the tick
        before (the stop: at the end, at a cancel's end, for a new goal)."""
        status = self.status.messages
        return _tick_state(status[tick]) in PLAYING or (
            tick > 0 and _tick_state(status[tick - 1]) in PLAYING
        )

    def step(self) -> None:
        """Answer rns_ptp's next tick (each wait up to 30 s: a hang guard)."""
        status, commands = self.status.messages, self.commands.messages
        self._taken()
        # rns_ptp's tick at the /clock the simulation stands at (the state grid, at or before
        # the pause); before the first answer it runs free, and any tick will do
        clock = -math.inf
        if self._answered > -math.inf:
            clock = math.floor(self.simulator.simulator.time / PERIOD + 1e-6) * PERIOD

        def ticked() -> bool:
            return len(status) > self._ticks and _seconds(status[-1].header.stamp) > clock - 1e-6

        assert self.ros.spin_until(ticked, timeout=30.0), f"no rns_ptp tick at {clock:.2f} s"
        # ticks that command nothing need no answer of their own: the newest answers for them
        while len(status) > self._ticks + 1 and not self._commands_at(self._ticks):
            self._ticks += 1
        if self._commands_at(self._ticks):
            assert self.ros.spin_until(lambda: len(commands) > self._forwarded, timeout=30.0)
            command = commands[self._forwarded]
            self._forwarded += 1
        elif self.velocity:
            command = Float64MultiArray(data=[0.0] * len(JOINTS))
        else:
            zero = JointTrajectoryPoint(velocities=[0.0] * len(JOINTS))
            command = JointTrajectory(joint_names=JOINTS, points=[zero])
            command.header.stamp = status[self._ticks].header.stamp
        self._answered = _seconds(status[self._ticks].header.stamp)
        self._ticks += 1
        self._receipt = self._pacer.last_command
        self._relay.publish(command)

    def run_until(self, condition, timeout: float = 30.0) -> bool:
        """Step until ``condition()`` holds or ``timeout`` [s] of wall time passes."""
        deadline = time.monotonic() + timeout
        while not condition() and time.monotonic() < deadline:
            self.step()
        return bool(condition())


def _seconds(stamp) -> float:
    return stamp.sec + 1e-9 * stamp.nanosec


def _first_stamp(stack, state: str) -> float:
    """The stamp [s] of the first status in ``state``: the tick that reached it."""
    return next(
        _seconds(m.header.stamp)
        for m in stack.status.messages
        if status_values(m)["state"] == state
    )


def _played(stack, duration: float) -> bool:
    """rns_ptp's commands span ``duration`` [s] of simulated time (trajectory interface)."""
    references = stack.references.messages
    return bool(references) and (
        _seconds(references[-1].header.stamp) - _seconds(references[0].header.stamp) >= duration
    )


def _state_after(stack, stamp: float) -> np.ndarray:
    """The joint angles [rad] of the first joint state stamped one PERIOD after ``stamp`` [s]
    (lockstep): the command of the tick at ``stamp`` has acted for its whole period."""

    def arrived() -> bool:
        joints = stack.joints.messages
        return bool(joints) and _seconds(joints[-1].header.stamp) >= stamp + PERIOD - 1e-6

    assert stack.run_until(arrived)
    return np.array(stack.joints.messages[-1].position)


def _tick_state(msg: DiagnosticArray) -> str:
    return status_values(msg)["state"]


def _state(stack) -> str | None:
    return _tick_state(stack.status.messages[-1]) if stack.status.messages else None


def _ready(ros, stack):
    run_until = getattr(stack, "run_until", ros.spin_until)  # a _Lockstep steps its loop
    assert run_until(lambda: _state(stack) == "IDLE", timeout=10.0)


def _send(stack, names, positions):
    stack.goal.publish(JointState(name=list(names), position=[float(x) for x in positions]))


def _odom_rotation(msg: Odometry) -> np.ndarray:
    o = msg.pose.pose.orientation
    return pin.Quaternion(o.w, o.x, o.y, o.z).toRotationMatrix()


def test_joint_space_goal_is_reached_and_the_base_turns_as_in_the_core_run(ros):
    """In lockstep on simulated time: each command over DDS acts for one period, as in the core
    run, so the base turns as there on however loaded a machine."""
    stack = _Lockstep(ros, method="joint_space", duration=2.0)
    _ready(ros, stack)
    goal = START + SMALL_STEP
    _send(stack, reversed(JOINTS), goal[::-1])  # matched by name, not by order
    assert stack.run_until(lambda: _state(stack) == "MOVING")
    moving = status_values(stack.status.messages[-1])
    assert moving["method"] == "joint_space"
    assert moving["phase"] == "JS-C"
    assert stack.run_until(lambda: _state(stack) == "DONE")
    final = _state_after(stack, _first_stamp(stack, "DONE"))
    error = np.degrees(np.abs(final - goal)).max()
    print(f"final joint error {error:.2e} deg")
    assert error < 0.1
    # stopped: one zero-velocity message at the end, nothing after it
    assert np.all(np.array(stack.references.messages[-1].points[0].velocities) == 0.0)
    seen = [status_values(m)["state"] for m in stack.status.messages]
    assert seen[-1] == "DONE"
    odom = stack.odom.messages
    dds = max(attitude_deviation(_odom_rotation(odom[0]), _odom_rotation(m)) for m in odom)
    plan = plan_ptp(stack.ptp.robot, START, goal, "joint_space", stack.ptp.settings)
    core = run_plan(stack.ptp.robot, plan, rate=100.0).max_base_deviation
    print(f"base deviation over DDS {math.degrees(dds):.4e} deg, core {math.degrees(core):.4e}")
    assert core > 0.0
    assert dds == pytest.approx(core, rel=0.2)


def test_a_partial_goal_keeps_the_other_joints(ros):
    stack = _Lockstep(ros, method="joint_space", duration=1.0)  # open loop: in lockstep
    _ready(ros, stack)
    _send(stack, ["joint_4"], [START[3] + math.radians(3.0)])
    assert stack.run_until(lambda: _state(stack) == "DONE")
    final = _state_after(stack, _first_stamp(stack, "DONE"))
    expected = START.copy()
    expected[3] += math.radians(3.0)
    error = np.degrees(np.abs(final - expected)).max()
    print(f"partial goal: final joint error {error:.2e} deg")
    assert error < 0.1


def test_three_phase_goal_is_reached_under_sim_time(ros):
    """The thesis 3-phase motion to a goal a few degrees away: reactionless fold of theta_4 to
    -180 deg, joint-space phase II, reactionless unfold (~33 s: the folds are stretched to the
    velocity limits). Played on simulated time in lockstep, as fast as the machine runs it."""
    stack = _Lockstep(ros, method="three_phase", phase_durations=[2.0, 4.0, 2.0])
    goal = START + SMALL_STEP
    try:
        plan = plan_ptp(stack.ptp.robot, START, goal, "three_phase", stack.ptp.settings)
    except NotImplementedError as exc:
        pytest.skip(f"planner: {exc}")
    _ready(ros, stack)
    _send(stack, JOINTS, goal)
    assert stack.run_until(lambda: _state(stack) == "MOVING")
    phases = set()

    def done():
        if stack.status.messages:
            phases.add(status_values(stack.status.messages[-1]).get("phase"))
        return _state(stack) == "DONE"

    started = time.monotonic()
    # a hang guard: the 3300 lockstep periods take 11-55 s of wall time here, quiet to loaded
    assert stack.run_until(done, timeout=240.0), _state(stack)
    wall = time.monotonic() - started
    assert {"I", "II", "III"} <= phases
    final = _state_after(stack, _first_stamp(stack, "DONE"))
    values = status_values(stack.status.messages[-1])
    assert "I: -180 deg" in values["fold_reached"]
    error = np.degrees(np.abs(final - goal)).max()
    odom = stack.odom.messages
    dds = max(attitude_deviation(_odom_rotation(odom[0]), _odom_rotation(m)) for m in odom)
    print(f"three_phase {plan.duration:.1f} s in {wall:.1f} s: joint error {error:.2e} deg")
    print(f"base deviation {math.degrees(dds):.2e} deg (phase II is not reactionless)")
    assert error < 0.1


@pytest.mark.parametrize(
    ("names", "positions", "message"),
    [
        (JOINTS, [math.nan, *START[1:]], "must be finite"),
        (["joint_9"], [0.0], "unknown joints ['joint_9']"),
        (["joint_2"], [10.0], "outside its limits"),
        (["joint_1", "joint_2"], [0.0], "2 names"),
    ],
)
def test_bad_goals_are_rejected_and_nothing_moves(ros, names, positions, message):
    stack = _stack(ros, method="joint_space", duration=1.0)
    _ready(ros, stack)
    count = len(stack.joints.messages)
    _send(stack, names, positions)
    assert ros.spin_until(lambda: _state(stack) == "INVALID_GOAL", timeout=10.0)
    ros.spin_for(0.3)
    status = stack.status.messages[-1].status[0]
    assert status.level == status.ERROR
    assert message in status.message
    assert stack.references.messages == []
    positions = np.array([m.position for m in stack.joints.messages[count:]])
    assert np.ptp(positions, axis=0).max() < 1e-12


def test_cancel_decelerates_to_rest_without_a_velocity_jump(ros):
    """Lockstep on simulated time: the playback rate ramps down by cancel_deceleration * PERIOD
    per simulated period, which is what the steps between commands are compared with."""
    deceleration = 2.0
    stack = _Lockstep(ros, method="joint_space", duration=3.0, cancel_deceleration=deceleration)
    _ready(ros, stack)
    _send(stack, JOINTS, START + 4.0 * SMALL_STEP)
    references = stack.references.messages
    assert stack.run_until(lambda: _played(stack, 1.2))  # mid-quintic: fastest
    client = stack.probe.create_client(Trigger, "rns_ptp/cancel")
    assert client.wait_for_service(timeout_sec=10.0)
    before = len(references)
    future = client.call_async(Trigger.Request())
    assert stack.run_until(future.done)
    assert future.result().success
    assert stack.run_until(lambda: _state(stack) == "IDLE")
    seen = [status_values(m)["state"] for m in stack.status.messages]
    assert "CANCELLING" in seen
    velocities = np.array([m.points[0].velocities for m in references])
    stamps = np.array([_seconds(m.header.stamp) for m in references])
    assert np.all(velocities[-1] == 0.0)
    speed = np.abs(velocities[before - 1]).max()
    assert speed > 0.01
    periods = np.diff(stamps[before - 5 :]) / PERIOD
    assert np.all(periods > 0.5)  # one command per tick
    steps = np.abs(np.diff(velocities[before - 5 :], axis=0)).max(axis=1) / periods
    # the rate falls by 2/s * 10 ms = 2 % of the speed per period (plus the plan's own change):
    # no jump
    print(
        f"speed at cancel {speed:.3f} rad/s, largest step {steps.max():.2e} rad/s per "
        f"simulated period ({periods.min():.3g}-{periods.max():.3g} periods apart)"
    )
    assert steps.max() < 0.1 * speed
    # at rest 1 / cancel_deceleration after the first decelerating tick (simulated time)
    stopping = stamps[-1] - _first_stamp(stack, "CANCELLING")
    print(f"at rest {stopping:.3f} s after the cancel (1 / cancel_deceleration)")
    assert abs(stopping - 1.0 / deceleration) <= 2 * PERIOD


def test_stale_state_stops_the_arm_and_abandons_the_plan(ros):
    """The simulator dies mid-plan (wall clock): once the state is state_timeout old the arm is
    commanded to rest and the plan held, and once it is state_loss_timeout old the plan is
    abandoned; a fresh state does not resume it. (The ages on given times are the sim-time
    tests'; state_timeout 0.5 s here.)"""
    simulator = _node(ros, SimulatorNode)
    ptp = _node(
        ros,
        PtpNode,
        method="joint_space",
        duration=3.0,
        state_timeout=0.5,
        state_loss_timeout=1.5,
    )
    probe = ros.probe()
    goal = probe.create_publisher(JointState, "ptp_goal", 10)
    references = Recorder(probe, JointTrajectory, "joint_references")
    status = Recorder(probe, DiagnosticArray, "rns_ptp/status")
    stack = SimpleNamespace(status=status, goal=goal)
    _ready(ros, stack)
    _send(stack, JOINTS, START + 4.0 * SMALL_STEP)
    assert ros.spin_until(lambda: _state(stack) == "MOVING", timeout=10.0)
    ros.spin_for(0.5)
    ros.detach(simulator)
    simulator.destroy_node()
    assert ros.spin_until(lambda: _state(stack) == "STALE_STATE", timeout=10.0)
    assert "HOLDING" in {_tick_state(m) for m in status.messages}
    ros.spin_for(0.3)
    assert np.all(np.array(references.messages[-1].points[0].velocities) == 0.0)
    entry = status.messages[-1].status[0]
    assert entry.level == entry.ERROR
    assert "joint_states" in entry.message
    assert "state_loss_timeout 1.5 s" in entry.message
    assert ptp.plan is None
    # a fresh state: IDLE, the old plan does not resume (no moving reference from here on)
    _node(ros, SimulatorNode)
    count = len(references.messages)
    assert ros.spin_until(lambda: _state(stack) == "IDLE", timeout=10.0)
    ros.spin_for(0.3)
    after = [m.points[0].velocities for m in references.messages[count:]]
    assert all(np.all(np.array(v) == 0.0) for v in after)


def test_status_before_the_first_joint_state(ros):
    node = _node(ros, PtpNode)
    probe = ros.probe()
    status = Recorder(probe, DiagnosticArray, "rns_ptp/status")
    diagnostics = Recorder(probe, DiagnosticArray, "/diagnostics")
    assert ros.spin_until(lambda: diagnostics.messages, timeout=10.0)  # 1 Hz, wall clock
    values = status_values(status.messages[-1])
    assert values["state"] == "WAITING_FOR_STATE"
    assert values["method"] == "three_phase"
    entry = diagnostics.messages[-1].status[0]
    assert entry.hardware_id == node.robot.name
    assert entry.level == entry.WARN


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"method": "magic"}, "'method' must be one of"),
        ({"rate": 5000.0}, "'rate' out of range"),
        ({"output_interface": "velocity", "joints": JOINTS[:6]}, "'joints'"),
        (
            {"state_timeout": 1.0, "state_loss_timeout": 0.5},
            r"state_loss_timeout 0.5 s must be >= state_timeout 1.0 s",
        ),
    ],
)
def test_bad_parameters_fail_with_a_clear_error(ros, overrides, message):
    with pytest.raises(ConfigError, match=message):
        PtpNode(
            context=ros.context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )


def test_deploy_goal_runs_the_reactionless_deployment(ros):
    """name: ["deploy"] (positions ignored): the full deployment from the measured configuration;
    a reactionless fold, so the base stays (nearly) still over DDS (open loop: in lockstep)."""
    stack = _Lockstep(ros, deploy_duration=2.0)
    _ready(ros, stack)
    stack.goal.publish(JointState(name=["deploy"]))
    assert stack.run_until(lambda: _state(stack) == "MOVING")
    assert status_values(stack.status.messages[-1])["phase"] == "deploy"
    assert stack.run_until(lambda: _state(stack) == "DONE")
    final = _state_after(stack, _first_stamp(stack, "DONE"))
    plan = stack.ptp.plan
    assert str(plan.method) == "deploy"
    error = np.degrees(np.abs(final - plan.goal)).max()
    assert error < 0.1
    assert np.degrees(abs(final[3] - START[3])) > 5.0  # theta_4 moved
    odom = stack.odom.messages
    dds = max(attitude_deviation(_odom_rotation(odom[0]), _odom_rotation(m)) for m in odom)
    values = status_values(stack.status.messages[-1])
    print(
        f"deploy: base deviation {math.degrees(dds):.2e} deg, joint error {error:.2e} deg, "
        f"fold {values['fold_reached']}"
    )
    assert math.degrees(dds) < 0.01
    assert values["fold_reached"].startswith("deploy: ")


def test_a_gap_in_joint_states_holds_the_deployment_and_it_resumes_on_its_path(ros):
    """Lockstep on simulated time; the test relays rns_simulator's joint_states and drops them
    for 0.4 s mid-plan (longer than state_timeout, shorter than state_loss_timeout): rns_ptp
    stops the arm with one zero-velocity command and holds the plan; when joint states come
    again it resumes the same plan where it stood, from rest. The deployment stays reactionless
    across the pause and ends at its goal."""
    stack = _Lockstep(ros, relay_states=True, deploy_duration=2.0, state_timeout=0.1)
    _ready(ros, stack)
    stack.goal.publish(JointState(name=["deploy"]))
    assert stack.run_until(lambda: _played(stack, 0.8))  # mid-plan: fast
    plan = stack.ptp.plan
    references = stack.references.messages
    stack.gap = True
    assert stack.run_until(lambda: _state(stack) == "HOLDING")
    held_at = _first_stamp(stack, "HOLDING")
    hold = len(references) - 1
    assert _seconds(references[hold].header.stamp) == pytest.approx(held_at)
    assert not np.any(references[hold].points[0].velocities)
    speed = np.abs(references[hold - 1].points[0].velocities).max()
    assert speed > 0.05
    entry = stack.status.messages[-1].status[0]
    assert entry.level == entry.WARN
    assert "holding the plan at s = " in entry.message
    assert stack.run_until(lambda: _seconds(stack.status.messages[-1].header.stamp) > held_at + 0.3)
    assert _state(stack) == "HOLDING"
    assert len(references) == hold + 1  # nothing but the stop during the gap
    assert stack.ptp.plan is plan
    stack.gap = False
    assert stack.run_until(lambda: _state(stack) == "MOVING")
    assert stack.ptp.plan is plan  # not replanned: the same path
    resumed = references[hold + 1]
    np.testing.assert_array_equal(resumed.points[0].positions, references[hold].points[0].positions)
    # from rest: the playback rate rises at resume_acceleration (mid-period rate 0.01)
    assert 0.0 < np.abs(resumed.points[0].velocities).max() < 0.05 * speed
    assert stack.run_until(lambda: _state(stack) == "DONE")
    final = _state_after(stack, _first_stamp(stack, "DONE"))
    error = np.abs(final - plan.goal).max()
    states = [_tick_state(m) for m in stack.status.messages]
    played = [state for k, state in enumerate(states) if k == 0 or state != states[k - 1]]
    assert played[-5:] == ["MOVING", "HOLDING", "MOVING", "SETTLING", "DONE"]
    odom = stack.odom.messages
    dds = max(attitude_deviation(_odom_rotation(odom[0]), _odom_rotation(m)) for m in odom)
    print(
        f"deploy held {_first_stamp(stack, 'DONE') - held_at:.2f} s before its end: joint "
        f"error {error:.2e} rad, base deviation {math.degrees(dds):.2e} deg"
    )
    assert error < stack.ptp.get_parameter("goal_tolerance").value
    assert math.degrees(dds) < 0.01


def _whole_samples(robot, settings) -> PlanSamples:
    """A joint_space plan from START by SMALL_STEP, sampled as plan_output whole sends it."""
    plan = plan_ptp(robot, START, START + SMALL_STEP, "joint_space", settings)
    return sample_plan(plan, 0.25)


def _with_sample(samples: PlanSamples, k: int, joint: int, theta: float) -> PlanSamples:
    """``samples`` with joint ``joint`` of sample ``k`` at ``theta`` [rad]."""
    changed = samples.theta.copy()
    changed[k, joint] = theta
    return PlanSamples(t=samples.t, theta=changed, theta_dot=samples.theta_dot)


def test_a_whole_plan_is_checked_against_the_urdf_limits_and_the_measured_angles(ros):
    """Every sample within the URDF position and velocity limits, and the first within
    max_reference_error of the measured angles; the reason names the joint and the value."""
    node = _node(ros, PtpNode, plan_output="whole")
    robot, names = node.robot, node.robot.joint_names
    bounds = CommandBounds.of(robot, 0.25)
    samples = _whole_samples(robot, node.settings)
    assert whole_plan_problem(samples, bounds, START, names) is None
    outside = _with_sample(samples, 2, 1, robot.upper_limits[1] + 0.1)
    problem = whole_plan_problem(outside, bounds, START, names)
    assert "joint_2 at" in problem
    assert "outside its URDF limits" in problem
    fast = PlanSamples(samples.t, samples.theta, samples.theta_dot.copy())
    fast.theta_dot[1, 3] = 2.0 * robot.velocity_limits[3]
    assert "beyond its URDF velocity limit" in whole_plan_problem(fast, bounds, START, names)
    away = START + np.array([0.0, 0.0, 0.0, 0.4, 0.0, 0.0, 0.0])
    problem = whole_plan_problem(samples, bounds, away, names)
    assert "first point puts joint_4" in problem
    assert "max_reference_error 0.25 rad" in problem
    nan = _with_sample(samples, 1, 0, math.nan)
    assert "non-finite" in whole_plan_problem(nan, bounds, START, names)


def test_a_whole_plan_with_a_sample_outside_the_limits_is_refused_and_not_sent(ros):
    """rns_ptp with plan_output whole refuses to send a plan one of whose samples lies outside
    the URDF limits (a joint_trajectory_controller would play it to there): INVALID_GOAL, the
    arm commanded to rest where it stands, no multi-point trajectory published."""
    node = _node(ros, PtpNode, plan_output="whole")
    references = Recorder(ros.probe(), JointTrajectory, "joint_references")
    node._theta = START.copy()
    samples = _whole_samples(node.robot, node.settings)
    bad = _with_sample(samples, 3, 4, node.robot.lower_limits[4] - 0.05)
    assert node._publish_plan(bad) is False
    assert node._mode is PtpState.INVALID_GOAL
    assert "joint_5" in node._detail
    assert "outside its URDF limits" in node._detail
    assert ros.spin_until(lambda: references.messages, timeout=10.0)
    ros.spin_for(0.2)
    for msg in references.messages:  # the stop: one streamed trajectory where the arm stands
        assert len(msg.points) == 3
        np.testing.assert_array_equal(msg.points[0].positions, START)
        assert not np.any(msg.points[0].velocities)


def test_velocity_interface_and_a_planned_closed_loop_method(ros):
    """output_interface velocity (joints reversed at both ends) with inverse_jacobian, which is
    integrated offline while the node reports PLANNING; the arm ends at the plan's goal (open
    loop: in lockstep on simulated time, each command anchored where it is received)."""
    order = list(reversed(JOINTS))
    stack = _Lockstep(
        ros,
        simulator={"command_interface": "velocity", "joints": order},
        method="inverse_jacobian",
        duration=2.0,
        output_interface="velocity",
        joints=order,
    )
    _ready(ros, stack)
    _send(stack, JOINTS, START + SMALL_STEP)
    assert stack.run_until(lambda: _state(stack) == "DONE")
    final = _state_after(stack, _first_stamp(stack, "DONE"))
    seen = {status_values(m)["state"] for m in stack.status.messages}
    assert {"PLANNING", "MOVING", "DONE"} <= seen
    assert np.all(np.array(stack.commands.messages[-1].data) == 0.0)
    error = np.degrees(np.abs(final - stack.ptp.plan.goal)).max()
    print(f"inverse_jacobian over the velocity interface: error {error:.2e} deg")
    assert error < 0.1


def test_a_new_goal_replaces_the_current_plan(ros):
    """A goal in the middle of a fast motion (~0.5 rad/s): the arm stops, the goal is planned
    from where it came to rest (a joint state sampled after the stop), and is reached (open
    loop: in lockstep)."""
    stack = _Lockstep(ros, method="joint_space", duration=1.0)
    _ready(ros, stack)
    _send(stack, JOINTS, START + 4.0 * SMALL_STEP)
    assert stack.run_until(lambda: _played(stack, 0.5))  # half-way: fastest
    assert np.abs(stack.references.messages[-1].points[0].velocities).max() > 0.3
    second = START - SMALL_STEP
    _send(
        stack,
        ["joint_1", "joint_2", "joint_3", "joint_5", "joint_6", "joint_7"],
        np.delete(second, 3),
    )
    assert stack.run_until(lambda: _state(stack) == "DONE")
    final = _state_after(stack, _first_stamp(stack, "DONE"))
    goal = stack.ptp.plan.goal
    assert np.allclose(np.delete(goal, 3), np.delete(second, 3))
    # joint_4 was not named: it keeps the angle where the arm came to rest
    print(f"replaced goal: final error {np.degrees(np.abs(final - goal)).max():.2e} deg")
    assert np.degrees(np.abs(final - goal)).max() < 0.1
    assert np.degrees(abs(final[3] - START[3])) > 1.0
    # the first motion was cut short: no DONE before the second goal's
    states = [status_values(m)["state"] for m in stack.status.messages]
    assert states.count("DONE") == len(states) - states.index("DONE")


def test_two_joint_state_sources_stop_the_arm_and_a_second_commander_is_reported(ros):
    """The graph is read once a second (wall clock): the plan (10 s) is long enough to be
    moving when a loaded machine gets to it, and the state watchdog (5 s) rides out the build
    of the second simulator in this process, which holds the GIL long enough on a loaded
    machine to age the first one's states past 0.5 s."""
    stack = _stack(
        ros, method="joint_space", duration=10.0, state_timeout=5.0, state_loss_timeout=10.0
    )
    _ready(ros, stack)
    commander = ros.probe("other_commander")
    other = commander.create_publisher(JointTrajectory, "joint_references", 1)
    assert ros.spin_until(
        lambda: "other_commander" in stack.status.messages[-1].status[0].message, timeout=10.0
    )
    entry = stack.status.messages[-1].status[0]
    assert entry.level == entry.WARN
    assert "run only one of rns_controller / rns_ptp" in entry.message
    commander.destroy_publisher(other)
    _send(stack, JOINTS, START + 4.0 * SMALL_STEP)
    assert ros.spin_until(lambda: _state(stack) == "MOVING", timeout=10.0)
    _node(ros, SimulatorNode)  # a second robot on the same joint_states
    assert ros.spin_until(lambda: _state(stack) == "CONFLICTING_STATE", timeout=10.0)
    states = [status_values(m)["state"] for m in stack.status.messages]
    assert states[states.index("CONFLICTING_STATE") - 1] == "MOVING"  # stopped mid-motion
    ros.spin_for(0.2)
    assert np.all(np.array(stack.references.messages[-1].points[0].velocities) == 0.0)
    assert "2 publishers on /joint_states" in stack.status.messages[-1].status[0].message
    assert stack.ptp.plan is None


def test_shutdown_publishes_zero_velocity(ros):
    stack = _stack(ros, method="joint_space", duration=3.0)
    _ready(ros, stack)
    _send(stack, JOINTS, START + 4.0 * SMALL_STEP)
    references = stack.references.messages

    def moving() -> bool:
        return bool(references) and np.abs(references[-1].points[0].velocities).max() > 0.01

    assert ros.spin_until(moving, timeout=10.0)
    ros.detach(stack.ptp)
    count = len(references)
    stack.ptp.destroy_node()
    assert ros.spin_until(lambda: len(references) > count, timeout=10.0)
    ros.spin_for(0.2)
    assert np.all(np.array(stack.references.messages[-1].points[0].velocities) == 0.0)


def test_dynamic_simulator_follows_the_positions_of_the_plan(ros):
    """Dynamic mode: the simulator's joint servo tracks positions + velocities (the trajectory
    contract); the goal is reached and a second cancel finds nothing to cancel."""
    _node(ros, SimulatorNode, mode="dynamic")
    ptp = _node(ros, PtpNode, method="joint_space", duration=2.0)
    probe = ros.probe()
    stack = SimpleNamespace(
        probe=probe,
        goal=probe.create_publisher(JointState, "ptp_goal", 10),
        status=Recorder(probe, DiagnosticArray, "rns_ptp/status"),
        joints=Recorder(probe, JointState, "joint_states"),
    )
    _ready(ros, stack)
    goal = START + SMALL_STEP
    _send(stack, JOINTS, goal)
    assert ros.spin_until(lambda: _state(stack) == "DONE", timeout=30.0)
    ros.spin_for(0.3)
    final = np.array(stack.joints.messages[-1].position)
    error = np.degrees(np.abs(final - goal)).max()
    print(f"dynamic mode: final joint error {error:.2e} deg")
    assert error < 0.1
    assert np.allclose(ptp.plan.goal, goal)
    client = probe.create_client(Trigger, "rns_ptp/cancel")
    assert client.wait_for_service(timeout_sec=10.0)
    future = client.call_async(Trigger.Request())
    assert ros.spin_until(future.done, timeout=10.0)
    assert not future.result().success
    assert "nothing to cancel (DONE)" in future.result().message


# --- simulated time: the test publishes /clock and joint_states itself -------------------------

#: Simulated time per step of the test's /clock [s].
STEP = 0.01


def _sim_time_stack(ros, **ptp_overrides):
    """rns_ptp under use_sim_time (joint_space, 5 s plans) on a /clock and joint_states that the
    test publishes (no simulator: the arm stands at ``stack.arm``, START unless a test moves
    it)."""
    ptp_overrides.setdefault("method", "joint_space")
    ptp_overrides.setdefault("duration", 5.0)
    ptp = _node(ros, PtpNode, use_sim_time=True, **ptp_overrides)
    probe = ros.probe()
    states = probe.create_publisher(JointState, "joint_states", 10)
    clock = SimClock(probe)

    def step(state: bool = True) -> None:
        """One STEP of simulated time, with a joint state at its stamp unless ``state`` is
        False, then the callbacks of 10 ms of wall time."""
        stamp = clock.advance(STEP)
        if state:
            msg = JointState(name=JOINTS, position=stack.arm.tolist())
            msg.header.stamp = stamp
            states.publish(msg)
        ros.spin_for(0.01)

    def step_until(condition, timeout: float = 10.0, state: bool = True) -> bool:
        """Step until ``condition()`` holds or ``timeout`` [s] of wall time passes."""
        deadline = time.monotonic() + timeout
        while not condition() and time.monotonic() < deadline:
            step(state)
        return bool(condition())

    stack = SimpleNamespace(
        ptp=ptp,
        probe=probe,
        goal=probe.create_publisher(JointState, "ptp_goal", 10),
        references=Recorder(probe, JointTrajectory, "joint_references"),
        status=Recorder(probe, DiagnosticArray, "rns_ptp/status"),
        step=step,
        step_until=step_until,
        arm=START.copy(),
    )
    assert step_until(lambda: _state(stack) == "IDLE")
    _send(stack, JOINTS, START + 4.0 * SMALL_STEP)
    assert step_until(lambda: _state(stack) == "MOVING")
    for _ in range(20):
        step()
    return stack


def _velocities(stack) -> np.ndarray:
    return np.array(stack.references.messages[-1].points[0].velocities)


def _states_seen(stack) -> set[str]:
    return {status_values(m)["state"] for m in stack.status.messages}


def test_sim_time_a_wall_clock_pause_of_the_simulation_does_not_stop_the_arm(ros):
    """Under use_sim_time the state's age is simulated time: /clock and joint_states paused for
    1 s of wall time (4 state_timeouts, below clock_timeout) age nothing, the plan goes on."""
    stack = _sim_time_stack(ros, state_timeout=0.25, clock_timeout=10.0)
    ros.spin_for(1.0)  # the simulation pauses: no /clock, no joint_states
    for _ in range(20):
        stack.step()
    assert _state(stack) == "MOVING"
    assert not {"STALE_STATE", "HOLDING"} & _states_seen(stack)
    assert np.abs(_velocities(stack)).max() > 0.0
    assert stack.ptp.plan is not None


def _stop_the_clock(ros, stack) -> None:
    """clock_timeout 1 s set at run time, seen by the /clock watch at its new checks while the
    clock moves; then /clock (and joint_states) stop until rns_ptp reports it."""
    result = stack.ptp.set_parameters([Parameter("clock_timeout", value=1.0)])
    assert result[0].successful
    for _ in range(50):
        stack.step()
    assert _state(stack) == "MOVING"
    assert ros.spin_until(
        lambda: "/clock stood still" in stack.status.messages[-1].status[0].message,
        timeout=15.0,
    )


def test_sim_time_a_stopped_clock_holds_the_arm_and_the_plan_resumes_with_it(ros):
    """/clock stops during a motion: no simulated time passes and the playback timer stops, yet
    after clock_timeout of wall time the arm gets zero velocity and the plan is held (HOLDING,
    WARN); when /clock and joint_states come back the same plan resumes where the arm stands
    on its path (a 20 s plan: the test's arm stands at START, the plan's start)."""
    stack = _sim_time_stack(ros, duration=20.0, state_timeout=0.5, clock_timeout=30.0)
    plan = stack.ptp.plan
    _stop_the_clock(ros, stack)
    entry = stack.status.messages[-1].status[0]
    assert status_values(stack.status.messages[-1])["state"] == "HOLDING"
    assert entry.level == entry.WARN
    assert "(clock_timeout 1.0 s wall time)" in entry.message
    assert np.all(_velocities(stack) == 0.0)
    assert stack.ptp.plan is plan
    references = stack.references.messages
    held = len(references) - 1
    assert stack.step_until(lambda: _state(stack) == "MOVING")
    assert stack.ptp.plan is plan
    np.testing.assert_allclose(references[held + 1].points[0].positions, START, atol=1e-12)
    assert "STALE_STATE" not in _states_seen(stack)


def test_sim_time_a_dead_simulator_abandons_the_plan_after_state_loss_timeout(ros):
    """/clock and joint_states stop for good: the arm is held at clock_timeout, and once no joint
    state came for state_loss_timeout of wall time the plan is abandoned (STALE_STATE); the clock
    coming back leaves the arm at rest."""
    stack = _sim_time_stack(ros, state_timeout=0.5, state_loss_timeout=2.0, clock_timeout=30.0)
    _stop_the_clock(ros, stack)
    assert ros.spin_until(lambda: _state(stack) == "STALE_STATE", timeout=15.0)
    entry = stack.status.messages[-1].status[0]
    assert entry.level == entry.ERROR
    assert "(state_loss_timeout 2.0 s)" in entry.message
    assert "HOLDING" in _states_seen(stack)
    assert np.all(_velocities(stack) == 0.0)
    assert stack.ptp.plan is None
    count = len(stack.references.messages)
    assert stack.step_until(lambda: _state(stack) == "IDLE")
    for _ in range(10):
        stack.step()
    assert len(stack.references.messages) == count


def test_sim_time_a_state_stale_for_state_loss_timeout_abandons_the_plan(ros):
    """/clock goes on without joint_states: after state_timeout of simulated time the arm gets
    zero velocity and the plan is held; after state_loss_timeout it is abandoned
    (STALE_STATE)."""
    stack = _sim_time_stack(ros, state_timeout=0.25, state_loss_timeout=1.0, clock_timeout=30.0)
    plan = stack.ptp.plan
    last_state = stack.ptp._state_received  # receipt time of the last joint state [s]
    assert stack.step_until(lambda: _state(stack) == "HOLDING", state=False)
    assert np.all(_velocities(stack) == 0.0)
    held = _first_stamp(stack, "HOLDING")
    assert 0.25 <= held - last_state <= 0.25 + 2 * STEP
    assert stack.ptp.plan is plan
    count = len(stack.references.messages)
    assert stack.step_until(lambda: _state(stack) == "STALE_STATE", state=False)
    lost = _first_stamp(stack, "STALE_STATE")
    assert 1.0 <= lost - last_state <= 1.0 + 2 * STEP
    message = stack.status.messages[-1].status[0].message
    assert "joint_states" in message
    assert "state_loss_timeout 1.0 s" in message
    assert np.all(_velocities(stack) == 0.0)
    assert len(stack.references.messages) == count + 1  # the zero of the hold, then of the loss
    assert stack.ptp.plan is None


def test_sim_time_a_cancel_during_a_hold_ends_the_plan_where_the_arm_stands(ros):
    stack = _sim_time_stack(ros, state_timeout=0.25, clock_timeout=30.0)
    assert stack.step_until(lambda: _state(stack) == "HOLDING", state=False)
    client = stack.probe.create_client(Trigger, "rns_ptp/cancel")
    future = client.call_async(Trigger.Request())
    assert stack.step_until(future.done, state=False)
    assert future.result().success
    assert "held at rest on the path" in future.result().message
    count = len(stack.references.messages)
    assert stack.step_until(lambda: _state(stack) == "IDLE")
    for _ in range(10):
        stack.step()
    assert len(stack.references.messages) == count  # at rest since the hold: nothing resumes
    assert "cancelled: at rest on the path" in stack.status.messages[-1].status[0].message


def test_sim_time_an_arm_off_the_held_path_is_replanned_to_the_same_goal(ros):
    """After a gap in joint_states the test's arm stands 0.05 rad across the JS-C line from
    its start: no sample of the held plan is within resume_tolerance of it, so the goal is
    planned again from the measured angles instead of jumping to the path."""
    stack = _sim_time_stack(ros, state_timeout=0.25, clock_timeout=30.0)
    for _ in range(150):
        stack.step()
    plan = stack.ptp.plan
    assert stack.step_until(lambda: _state(stack) == "HOLDING", state=False)
    assert stack.ptp.plan is plan
    other = np.roll(SMALL_STEP, 1)
    across = other - SMALL_STEP * (other @ SMALL_STEP) / (SMALL_STEP @ SMALL_STEP)
    stack.arm = START + 0.05 * across / np.abs(across).max()
    assert stack.step_until(lambda: _state(stack) == "MOVING")
    states = [_tick_state(m) for m in stack.status.messages]
    assert "PLANNING" in states[states.index("HOLDING") :]
    replanned = stack.ptp.plan
    assert replanned is not plan
    np.testing.assert_allclose(replanned.start, stack.arm, atol=1e-12)
    np.testing.assert_allclose(replanned.goal, plan.goal, atol=1e-12)


def test_sim_time_a_whole_plan_is_held_and_its_rest_sent_at_the_resume(ros):
    """plan_output whole: the hold replaces the plan by one at rest where the arm stands; at the
    resume the rest of the plan goes out as one trajectory, from rest at the plan's sample
    nearest the arm (the test's arm stands at START: the plan's start) to the goal."""
    stack = _sim_time_stack(
        ros, duration=20.0, plan_output="whole", state_timeout=0.25, clock_timeout=30.0
    )
    plan = stack.ptp.plan
    references = stack.references.messages
    assert len(references) == 1
    assert stack.step_until(lambda: _state(stack) == "HOLDING", state=False)
    assert len(references) == 2
    held = references[1]
    assert not np.any(held.points[0].velocities)
    assert stack.step_until(lambda: _state(stack) == "MOVING")
    assert stack.ptp.plan is plan
    assert len(references) == 3
    rest = references[2]
    np.testing.assert_allclose(rest.points[0].positions, START, atol=1e-12)
    assert not np.any(rest.points[0].velocities)
    np.testing.assert_allclose(rest.points[-1].positions, plan.goal, atol=1e-12)
    times = [_seconds(p.time_from_start) for p in rest.points]
    assert np.diff(times).max() <= stack.ptp.get_parameter("plan_sample_period").value + 1e-6


def test_a_goal_flood_plans_one_goal_at_a_time_and_the_newest_wins(ros):
    """Goals sent faster than they are planned (each plan held up 0.2 s here) never run more
    than one planner thread; goals that come meanwhile replace each other, and the newest is
    the one planned and played."""
    stack = _stack(ros, method="joint_space", duration=0.5)
    ptp = stack.ptp
    compute = ptp.planning.compute

    def slow_plan(*args):
        time.sleep(0.2)
        compute(*args)

    ptp.planning.compute = slow_plan
    assert stack.run_until(lambda: ptp._theta is not None, timeout=10.0)
    start = ptp._theta.copy()
    planners = []
    for k in range(1, 41):
        stack.goal.publish(JointState(name=["joint_2"], position=[float(start[1]) + 0.002 * k]))
        ros.spin_for(0.01)
        planners.append(sum(t.name == "rns_ptp_plan" for t in threading.enumerate()))
    assert max(planners) == 1
    newest = start[1] + 0.002 * 40
    # the plan that plays is the newest goal's (whether the arm then tracks it on the wall
    # clock of a loaded machine is the lockstep tests' subject, not this one's)
    assert stack.run_until(
        lambda: (
            ptp.plan is not None
            and ptp._mode in (PtpState.MOVING, PtpState.DONE)
            and ptp.plan.goal[1] == pytest.approx(newest)
        ),
        timeout=30.0,
    )


def test_done_only_once_the_measured_angles_reach_the_goal(ros):
    """A plan played to its end is not success by itself: with its output going nowhere (a
    simulator that refused it), the arm never moves and rns_ptp reports GOAL_MISSED naming
    the joint and how far it is, never DONE."""
    _node(ros, SimulatorNode)
    ptp = ros.add(
        PtpNode,
        {"method": "joint_space", "duration": 0.3, "settle_timeout": 0.3},
        remappings={"joint_references": "nowhere"},
    )
    status = Recorder(ros.probe(), DiagnosticArray, "rns_ptp/status")
    goal = ros.probe().create_publisher(JointState, "ptp_goal", 10)
    assert ros.spin_until(lambda: ptp._theta is not None, timeout=10.0)
    start = ptp._theta.copy()
    goal.publish(JointState(name=["joint_2"], position=[float(start[1]) + 0.05]))
    assert ros.spin_until(lambda: ptp._mode is PtpState.GOAL_MISSED, timeout=30.0)
    assert ptp._detail.startswith("joint_2 is 0.05 rad from the goal")
    assert ros.spin_until(lambda: status_values(status.messages[-1])["state"] == "GOAL_MISSED")
    assert status.messages[-1].status[0].level == DiagnosticStatus.ERROR
    states = {status_values(m)["state"] for m in status.messages}
    assert "DONE" not in states
    assert "SETTLING" in states


def test_a_late_tick_on_the_wall_clock_advances_the_plan_by_what_the_plant_played(ros):
    """On the wall clock a tick 0.2 s late is a loaded machine, not a clock fault: no hold, and
    the plan clock advances by what one streamed trajectory plays before it ends at rest (2 T),
    so the arm stays on the path. Under use_sim_time such a gap is a clock that jumped, and a
    clock that goes back is one anywhere."""
    wall = _node(ros, PtpNode)
    assert not wall._clock_jumped(0.2)
    assert wall._clock_jumped(-0.01)
    assert wall._played == pytest.approx(2 * PERIOD)
    sim = ros.add(PtpNode, {"use_sim_time": True}, name="rns_ptp_sim")
    assert sim._clock_jumped(0.2)
    assert not sim._clock_jumped(PERIOD)


def test_sim_time_a_goal_sent_while_the_input_is_late_waits_for_a_fresh_state(ros):
    """A loaded machine delays joint_states: a goal that comes during the hold is not refused;
    it replaces the held plan and is planned from the first fresh state (PLANNING "waiting for
    a fresh state", then MOVING from the measured angles)."""
    stack = _sim_time_stack(ros, state_timeout=0.25, state_loss_timeout=5.0, clock_timeout=30.0)
    held = stack.ptp.plan
    assert stack.step_until(lambda: _state(stack) == "HOLDING", state=False)
    goal = START.copy()
    goal[0] += 0.2
    _send(stack, JOINTS, goal)
    for _ in range(5):
        stack.step(state=False)
    values = status_values(stack.status.messages[-1])
    assert values["state"] == "PLANNING"
    assert "waiting for a fresh state" in stack.status.messages[-1].status[0].message
    assert "rejected_goal" not in values
    assert stack.ptp.plan is None
    assert np.all(_velocities(stack) == 0.0)
    assert stack.step_until(lambda: _state(stack) == "MOVING")
    assert stack.ptp.plan is not held
    np.testing.assert_allclose(stack.ptp.plan.sample(0.0).theta, START, atol=1e-9)
    np.testing.assert_allclose(
        stack.ptp.plan.sample(stack.ptp.plan.duration).theta, goal, atol=1e-6
    )
