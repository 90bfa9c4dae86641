"""Playback of a plan that holds and resumes on its path (rns_ros.control.ptp_playback), on
injected times: no ROS, no clock."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.control.ptp import PhaseInfo, PtpPlan, QuinticLine
from rns_ros.control.ptp_phases import plan_deployment
from rns_ros.control.ptp_playback import PlanPlayback, PlaybackMode, ramp
from rns_ros.control.ptp_sampling import hermite
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.state import FreeFloatingState
from rns_ros.sim.free_floating import FreeFloatingSimulator, SimulationMode

PERIOD = 0.01
STOWED = np.array([math.pi / 2, -math.pi / 2, 0.0, -math.pi, math.pi, math.pi, 0.0])


def _line(duration: float = 2.0) -> PtpPlan:
    """A two-phase joint-space plan: two quintic lines of different directions (n = 3)."""
    a, b, c = np.zeros(3), np.array([0.4, -0.2, 0.1]), np.array([0.1, 0.3, 0.5])
    half = 0.5 * duration
    return PtpPlan(
        "joint_space",
        [PhaseInfo("A", 0.0, half, False), PhaseInfo("B", half, duration, False)],
        [QuinticLine(a, b, half), QuinticLine(b, c, half)],
        [],
        goal=c,
        start=a,
    )


def _play(playback: PlanPlayback, ticks: int) -> list:
    return [playback.tick(PERIOD) for _ in range(ticks)]


def test_ramp_integrates_a_clamped_linear_rate():
    assert ramp(1.0, 0.0, 0.3) == (1.0, pytest.approx(0.3))
    assert ramp(0.0, 2.0, 0.25) == (pytest.approx(0.5), pytest.approx(0.0625))
    # reaches 1 after 0.5 s, then 1: 0.25 + 0.5
    assert ramp(0.0, 2.0, 1.0) == (1.0, pytest.approx(0.75))
    # falls to 0 after 0.5 s, then stands: 0.25
    assert ramp(1.0, -2.0, 1.0) == (0.0, pytest.approx(0.25))


def test_a_hold_stops_at_once_freezes_the_plan_clock_and_a_resume_ramps_up_on_the_path():
    plan = _line()
    playback = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    playback.tick(0.0)
    steps = _play(playback, 50)
    assert steps[-1].s == pytest.approx(0.5)
    moving = np.linalg.norm(steps[-1].theta_dot)
    assert moving > 0.1
    # stale input 0.02 s after the last tick: that command acted, then the arm stops there
    held = playback.hold(0.02)
    assert held.mode is PlaybackMode.HOLDING
    assert held.at_rest
    assert held.s == pytest.approx(0.52)
    assert not np.any(held.theta_dot)
    np.testing.assert_array_equal(held.theta, plan.sample(held.s).theta)
    # ticks while held: at rest, s frozen, however long the gap
    for step in _play(playback, 100):
        assert step.at_rest
        assert step.s == held.s
        assert not np.any(step.theta_dot)
    assert playback.path_error(held.theta + 0.003) == pytest.approx(0.003)
    playback.resume()
    first = playback.tick(0.0)  # the resume tick: nothing played since the hold
    assert first.s == held.s
    assert first.rate == 0.0
    np.testing.assert_array_equal(first.theta, held.theta)
    # the first command runs at the mid-period rate a T / 2 = 0.01
    direction = plan.sample(held.s).theta_dot
    assert np.linalg.norm(first.theta_dot) == pytest.approx(
        0.01 * np.linalg.norm(direction), rel=0.01
    )
    steps = [first, *_play(playback, 60)]
    rates = [step.rate for step in steps]
    assert rates[:51] == pytest.approx(np.minimum(2.0 * PERIOD * np.arange(51), 1.0))
    assert rates[51:] == pytest.approx([1.0] * 10)
    # the path is kept: every position played is the plan's sample at its s, and s goes on
    # from the held s by the integral of r
    for step in steps:
        np.testing.assert_array_equal(step.theta, plan.sample(step.s).theta)
    assert steps[50].s == pytest.approx(held.s + 0.25)  # half a second of a 0 -> 1 ramp
    assert np.all(np.diff([step.s for step in steps]) >= 0.0)
    # no velocity jump across the ramp: steps of at most a T |theta_dot_plan| and the change of
    # the plan's own rate
    velocities = np.array([step.theta_dot for step in steps])
    assert np.abs(np.diff(velocities, axis=0)).max() < 0.05 * moving


def test_the_played_velocity_is_the_plans_scaled_so_a_reactionless_phase_stays_so(
    robot, relative_coupling
):
    """The deployment (one reactionless phase) held mid-way and resumed: each command is
    r_mid theta_dot_plan(s_mid), in the reaction null space like the plan's (eq. 3.3)."""
    plan = plan_deployment(robot, STOWED)
    playback = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    playback.tick(0.0)
    _play(playback, round(0.4 * plan.duration / PERIOD))
    playback.hold(PERIOD)
    _play(playback, 10)
    playback.resume()
    steps = [playback.tick(0.0), *_play(playback, 80)]
    checked = 0
    for step in steps:
        speed = np.linalg.norm(step.theta_dot)
        if speed < 1e-9:
            continue
        rate_mid, to_mid = ramp(step.rate, 2.0, 0.5 * PERIOD)
        middle = plan.sample(step.s + to_mid)
        np.testing.assert_allclose(step.theta_dot, rate_mid * middle.theta_dot, atol=1e-15)
        assert relative_coupling(middle.theta, step.theta_dot) < 1e-12
        checked += 1
    assert checked == len(steps)


def test_a_cancel_falls_to_rest_and_a_held_playback_cancels_where_it_stands():
    plan = _line()
    playback = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    playback.tick(0.0)
    _play(playback, 50)
    assert playback.cancel()
    steps = _play(playback, 60)
    stopped = next(k for k, step in enumerate(steps) if step.at_rest)
    assert steps[stopped].mode is PlaybackMode.CANCELLED
    assert stopped == 50  # 1 / deceleration = 0.5 s: r falls from the first cancelling tick
    assert steps[-1].s == pytest.approx(0.5 + 0.01 + 0.25)
    assert not playback.cancel()
    # held, then cancelled: it ends where the arm stands; a cancel during a hold too
    held = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    held.tick(0.0)
    _play(held, 30)
    held.hold(PERIOD)
    assert held.cancel()
    assert held.mode is PlaybackMode.CANCELLED
    assert held.tick(PERIOD).s == pytest.approx(0.31)
    with pytest.raises(InputError, match="only a held playback resumes"):
        held.resume()
    cancelling = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    cancelling.tick(0.0)
    cancelling.cancel()
    assert cancelling.hold(PERIOD).mode is PlaybackMode.CANCELLED


def test_the_plan_ends_at_rest_and_a_hold_at_its_end_is_the_end():
    plan = _line(duration=0.5)
    playback = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    playback.tick(0.0)
    steps = _play(playback, 60)
    end = next(step for step in steps if step.at_rest)
    assert end.mode is PlaybackMode.ENDED
    assert end.s == plan.duration
    np.testing.assert_allclose(end.theta, plan.goal, atol=1e-12)
    late = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    late.tick(0.0)
    assert late.hold(1.0).mode is PlaybackMode.ENDED


def test_the_rest_of_a_held_plan_as_one_trajectory_follows_the_resumed_playback():
    """plan_output whole after a hold: samples of the rest of the plan from rest, on the ramp
    the tick playback follows, every phase end and the end of the ramp included."""
    plan = _line(duration=4.0)
    playback = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    playback.tick(0.0)
    _play(playback, 100)
    held = playback.hold(0.0)
    samples = playback.resumed_samples(0.1)
    t = samples.t
    assert t[0] == 0.0
    assert np.all(np.diff(t) > 0.0)
    assert np.diff(t).max() <= 0.1 + 1e-12
    np.testing.assert_array_equal(samples.theta[0], held.theta)
    assert not np.any(samples.theta_dot[0])
    assert not np.any(samples.theta_dot[-1])
    np.testing.assert_allclose(samples.theta[-1], plan.goal, atol=1e-12)
    ramp_end = 0.5  # 1 / acceleration
    phase_end = ramp_end + (plan.phases[0].end - held.s - 0.25)
    for instant in (ramp_end, phase_end):
        assert np.min(np.abs(t - instant)) < 1e-9
    assert t[-1] == pytest.approx(ramp_end + plan.duration - held.s - 0.25)
    # the tick playback after resume() is at the same place at the same times
    playback.resume()
    played = [playback.tick(0.0), *_play(playback, 300)]
    for k in (0, 17, 50, 120, 260):
        theta, _ = hermite(samples, k * PERIOD)
        np.testing.assert_allclose(played[k].theta, theta, atol=2e-4)
    with pytest.raises(ConfigError, match="spacing"):
        playback.resumed_samples(0.0)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"period": 0.0}, "period"),
        ({"acceleration": -1.0}, "acceleration"),
        ({"deceleration": math.nan}, "deceleration"),
    ],
)
def test_bad_settings_name_the_value(arguments, message):
    settings = {"period": PERIOD, "acceleration": 2.0, "deceleration": 2.0, **arguments}
    with pytest.raises(ConfigError, match=message):
        PlanPlayback(_line(), **settings)


def _short_plant(playback: PlanPlayback, share: float, feedback: bool, settle: float) -> list:
    """Kinematic joints that play only ``share`` of each period's command (a plant late on
    every command), with or without the position feedback; ``settle`` [s] of the settle
    command after the end. Returns (theta [rad], step) per tick."""
    theta = playback.plan.start.copy()
    played = []
    playback.tick(0.0)
    step = playback.tick(0.0, theta) if feedback else playback.tick(0.0)
    while True:
        played.append((theta.copy(), step))
        theta = theta + share * PERIOD * step.theta_dot
        if step.at_rest:
            break
        step = playback.tick(PERIOD, theta) if feedback else playback.tick(PERIOD)
    for _ in range(round(settle / PERIOD) if feedback else 0):
        step = playback.settle(theta)
        played.append((theta.copy(), step))
        theta = theta + share * PERIOD * step.theta_dot
    played.append((theta, step))
    return played


def test_a_plant_short_on_every_command_ends_on_the_goal_only_with_the_position_feedback():
    """eq. (4.18) on a joint-space plan: a plant that plays 70 % of each command ends 30 % of
    the way short open loop; with k (theta_plan(s) - theta) added and 1 s of settling it ends
    within 1e-3 rad (e^-k t of the lag left at k = 5 /s)."""
    plan = _line()
    short = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    open_loop = _short_plant(short, 0.7, feedback=False, settle=0.0)[-1][0]
    assert np.abs(open_loop - plan.goal).max() > 0.1
    fed = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    closed = _short_plant(fed, 0.7, feedback=True, settle=1.0)[-1][0]
    assert np.abs(closed - plan.goal).max() < 1e-3


def test_the_feedback_in_a_reactionless_phase_keeps_the_base_still_and_ends_on_the_goal(robot):
    """The deployment (one reactionless phase) on the kinematic free-floating simulator, with
    joints that run at 80 % of each command: open loop the arm ends a fifth of the path short;
    with the feedback along the path (the null vector taken where the arm is on the path) it
    ends at the path's end. Open loop the plan's rates act where the arm is not, and the base
    turns by degrees; closed loop the motion stays reactionless (eq. 3.3): 2e-4 deg measured
    (1e-6 deg for the plan played in full)."""
    plan = plan_deployment(robot, STOWED)

    def run(feedback: bool) -> tuple[np.ndarray, float]:
        sim = FreeFloatingSimulator(
            robot, mode=SimulationMode.KINEMATIC, dt=1e-3, initial_q=robot.configuration(STOWED)
        )
        playback = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
        start = FreeFloatingState.compute(robot, sim.q).base_rotation
        playback.tick(0.0)
        elapsed, deviation = 0.0, 0.0
        for _ in range(round((plan.duration + 1.0) / PERIOD)):
            theta = FreeFloatingState.compute(robot, sim.q).theta
            if playback.mode is PlaybackMode.ENDED:
                step = playback.settle(theta) if feedback else playback.tick(PERIOD)
            else:
                step = playback.tick(elapsed, theta if feedback else None)
            elapsed = PERIOD
            sim.set_reference(velocities=0.8 * step.theta_dot)
            for _step in range(10):
                sim.step()
            rotation = FreeFloatingState.compute(robot, sim.q).base_rotation
            deviation = max(deviation, attitude_deviation(start, rotation))
        return FreeFloatingState.compute(robot, sim.q).theta, deviation

    open_loop, turned = run(feedback=False)
    assert np.abs(open_loop - plan.goal).max() > 0.1
    assert math.degrees(turned) > 1.0
    closed, deviation = run(feedback=True)
    assert np.abs(closed - plan.goal).max() < 1e-3
    assert math.degrees(deviation) < 1e-3


def test_the_feedback_is_scaled_as_a_whole_within_the_velocity_limits():
    """A plan that runs at its joints' speed limits leaves the feedback no room: a command
    over a limit is scaled down as a whole, so it keeps its direction (the path's), never
    clipped per joint; the lag is made up once the plan slows, and the arm still ends there."""
    plan = _line()
    peak = np.max([np.abs(plan.sample(t).theta_dot) for t in np.linspace(0, 2, 201)], axis=0)
    limits = 1.02 * peak
    free = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    bounded = PlanPlayback(plan, PERIOD, 2.0, 2.0, velocity_limits=limits)
    played = _short_plant(bounded, 0.7, feedback=True, settle=1.5)
    for _, step in played:
        assert np.all(np.abs(step.theta_dot) <= limits * (1 + 1e-12))
    unbounded = _short_plant(free, 0.7, feedback=True, settle=1.5)
    assert any(np.any(np.abs(step.theta_dot) > limits) for _, step in unbounded)
    assert np.abs(played[-1][0] - plan.goal).max() < 1e-3
    with pytest.raises(ConfigError, match="velocity_limits must be 3 values > 0 rad/s"):
        PlanPlayback(plan, PERIOD, 2.0, 2.0, velocity_limits=[1.0, 0.0, 1.0])


def test_a_late_joint_state_is_compared_with_the_plan_when_it_was_measured():
    """Angles exactly on the plan 0.1 s before the tick, 0.1 s old: no feedback; read as new,
    they would be a lag of 0.1 s of motion and add k times it."""
    plan = _line()
    playback = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    playback.tick(0.0)
    _play(playback, 40)
    then = plan.sample(playback.s).theta
    _play(playback, 9)
    plain = playback.tick(PERIOD)
    fed = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    fed.tick(0.0)
    _play(fed, 49)
    on_time = fed.tick(PERIOD, then, age=0.1)
    np.testing.assert_allclose(on_time.theta_dot, plain.theta_dot, atol=1e-12)
    replay = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    replay.tick(0.0)
    _play(replay, 49)
    as_new = replay.tick(PERIOD, then, age=0.0)
    lag = plan.sample(as_new.s).theta - then
    np.testing.assert_allclose(as_new.theta_dot - plain.theta_dot, plan.elbow_gain * lag)


def test_a_held_plan_is_located_where_the_arm_stands_on_its_path():
    """An arm held 0.3 s of plan behind s (a plant that fell behind): s moves back to where
    the arm is, within the search grid; an arm off the path reports its distance; a playing
    plan is not moved."""
    plan = _line()
    playback = PlanPlayback(plan, PERIOD, acceleration=2.0, deceleration=2.0)
    playback.tick(0.0)
    _play(playback, 80)
    with pytest.raises(InputError, match="only a held playback is located, not one PLAYING"):
        playback.locate(plan.angles(0.5))
    playback.hold(0.0)
    assert playback.locate(plan.angles(0.5)) < 1e-9
    assert playback.s == pytest.approx(0.5)
    off = plan.angles(0.5) + np.array([0.0, 0.0, 0.02])
    assert 0.01 < playback.locate(off) <= 0.02 + 1e-12


def test_bad_elapsed_and_theta_are_refused():
    playback = PlanPlayback(_line(), PERIOD, acceleration=2.0, deceleration=2.0)
    with pytest.raises(InputError, match=r"elapsed must be a finite number >= 0 s, got -0.1"):
        playback.tick(-0.1)
    with pytest.raises(InputError, match=r"shape \(3,\)"):
        playback.path_error(np.zeros(7))
    with pytest.raises(InputError, match=r"age must be a finite number >= 0 s, got -0.5"):
        playback.tick(0.0, np.zeros(3), age=-0.5)
    with pytest.raises(InputError, match=r"only an ended playback settles, not one PLAYING"):
        playback.settle(np.zeros(3))
