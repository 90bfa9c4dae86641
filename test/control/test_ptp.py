"""Point-to-point planner (rns_ros.control.ptp): reactionless elbow paths by arc length, the
3-phase method, JS-C, stretching to the velocity limits and input checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.control.ptp import PtpMethod, PtpSettings
from rns_ros.control.ptp_phases import plan_deployment
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.control.reactionless_path import reactionless_path
from rns_ros.core.errors import InputError
from rns_ros.core.state import FreeFloatingState

START = np.deg2rad([-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0])
GOAL = np.deg2rad([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])
STOWED = np.array([math.pi / 2, -math.pi / 2, 0.0, -math.pi, math.pi, math.pi, 0.0])


def _relative_coupling(robot, theta, theta_dot) -> float:
    state = FreeFloatingState.compute(robot, robot.configuration(theta))
    speed = float(np.linalg.norm(theta_dot))
    return float(np.linalg.norm(state.coupling_angular_momentum_matrix @ theta_dot)) / speed


def test_joint_space_line(robot):
    plan = plan_ptp(robot, START, GOAL, PtpMethod.JOINT_SPACE)
    assert plan.duration == pytest.approx(30.0)
    np.testing.assert_allclose(plan.sample(0.0).theta, START)
    np.testing.assert_allclose(plan.sample(plan.duration).theta, GOAL)
    middle = plan.sample(15.0)
    np.testing.assert_allclose(middle.theta_dot, 1.875 / 30.0 * (GOAL - START), atol=1e-12)
    assert plan.sample(1e6).phase == "done"
    assert not plan.sample(1e6).theta_dot.any()


def test_path_is_reactionless_through_a_turning_point(robot):
    """From the partial-deployment goal [90 50 0 -300 0 20 0] deg the default arm's elbow path
    turns back smoothly at theta_4 ~ -197.3 deg (n_4 passes 0): followed by arc length it passes
    the turning point with a continuous unit tangent (no 1/n_4) and stays reactionless. (The
    Phase III start's turn at -145.4 deg is a near rank drop of M~_P where n swings; see
    test_three_phase_reaches_goal_reactionlessly.)"""
    start = np.deg2rad([90.0, 50.0, 0.0, -300.0, 0.0, 20.0, 0.0])
    path = reactionless_path(robot, start, -math.pi, max_arc=3.6, stop_at_turning_point=False)
    assert path.turning_points, "expected a turning point of theta_4 on this path"
    assert path.turn_kinks[0] < 0.05
    turn = np.argmax(path.theta[:, 3])
    assert 5 < turn < path.arc.size - 5  # passed, not stopped at
    assert path.theta[-1, 3] < path.theta[turn, 3] - 0.01  # theta_4 went back down
    np.testing.assert_allclose(np.linalg.norm(path.tangent[:, :4], axis=1), 1.0, atol=1e-12)
    assert np.abs(np.diff(path.tangent, axis=0)).max() < 0.1  # sign-continuous, no blow-up
    for k in range(turn - 5, turn + 6):
        assert _relative_coupling(robot, path.theta[k], path.tangent[k]) < 1e-12
    np.testing.assert_allclose(path.theta[:, 4:], np.tile(start[4:], (path.arc.size, 1)))


def test_three_phase_reaches_goal_reactionlessly(robot):
    plan = plan_ptp(robot, START, GOAL, "three_phase")
    assert [p.name for p in plan.phases] == ["I", "II", "III"]
    assert [p.reactionless for p in plan.phases] == [True, False, True]
    assert plan.phases[0].fold_reached == pytest.approx(-math.pi, abs=1e-4)
    # the default arm's Phase III fold turns back before -pi (docs/arm_identification.md)
    assert math.degrees(plan.phases[2].fold_reached) == pytest.approx(-145.4, abs=0.5)
    assert any("turning point" in note and "III" in note for note in plan.notes)
    assert np.abs(np.rad2deg(plan.sample(plan.duration).theta - GOAL)).max() < 0.1
    np.testing.assert_allclose(plan.sample(0.0).theta, START, atol=1e-12)
    for t in np.linspace(0.0, plan.duration, 241):
        reference = plan.sample(t)
        assert np.all(np.abs(reference.theta_dot) <= robot.velocity_limits + 1e-9)
        if plan.is_reactionless(t) and np.linalg.norm(reference.theta_dot) > 1e-9:
            assert _relative_coupling(robot, reference.theta, reference.theta_dot) < 1e-12
    for phase in plan.phases[:-1]:  # continuous at the boundaries
        before, after = plan.sample(phase.end - 1e-9), plan.sample(phase.end + 1e-9)
        np.testing.assert_allclose(before.theta, after.theta, atol=1e-6)


def test_stretch_instead_of_clip(robot):
    """5 s Phases I/III would need > 0.5 rad/s on joints 1-4: the phase is made longer, the
    direction (reactionless) is kept, and a note says so."""
    plan = plan_ptp(robot, START, GOAL, "three_phase")
    assert plan.phases[0].end > 5.0
    assert any("phase I stretched from 5" in note for note in plan.notes)
    peak = max(
        float(np.max(np.abs(plan.sample(t).theta_dot[:4]) / robot.velocity_limits[:4]))
        for t in np.linspace(0.0, plan.phases[0].end, 401)
    )
    assert 0.8 < peak <= 1.0 + 1e-9
    fast = plan_ptp(robot, START, GOAL, "joint_space", PtpSettings(duration=0.5))
    assert fast.duration > 0.5
    assert any("stretched" in note for note in fast.notes)
    peak = max(
        float(np.max(np.abs(fast.sample(t).theta_dot) / robot.velocity_limits))
        for t in np.linspace(0.0, fast.duration, 401)
    )
    assert peak == pytest.approx(1.0, abs=1e-3)


def test_deployment_is_reactionless(robot):
    plan = plan_deployment(robot, STOWED)
    assert plan.method is PtpMethod.DEPLOY
    assert plan.phases[0].fold_reached == pytest.approx(-math.pi + 0.183 * 30.0, abs=1e-4)
    for t in np.linspace(0.1, plan.duration - 0.1, 31):
        reference = plan.sample(t)
        assert _relative_coupling(robot, reference.theta, reference.theta_dot) < 1e-12


def test_command_feedback_is_reactionless(robot):
    plan = plan_ptp(robot, START, GOAL, "three_phase")
    theta = plan.sample(2.0).theta + np.array([0.01, -0.01, 0.02, 0.0, 0.0, 0.0, 0.0])
    command = plan.command(2.0, theta)
    assert _relative_coupling(robot, theta, command) < 1e-12


def test_bad_goal_names_the_joint(robot):
    goal = GOAL.copy()
    goal[2] = np.nan
    with pytest.raises(InputError, match="theta_goal"):
        plan_ptp(robot, START, goal, "joint_space")
    goal = GOAL.copy()
    goal[1] = 50.0
    with pytest.raises(InputError, match=r"joint 2 \(joint_2\)"):
        plan_ptp(robot, START, goal, "three_phase")
    with pytest.raises(InputError, match="shape"):
        plan_ptp(robot, START, GOAL[:6], "inverse_jacobian")
