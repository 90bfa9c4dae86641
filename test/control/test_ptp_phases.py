"""Reactionless planners (rns_ros.control.ptp_phases): 3-phase and deployment."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.control.ptp import PtpMethod
from rns_ros.control.ptp_phases import plan_deployment
from rns_ros.control.ptp_planner import plan_ptp

START = np.deg2rad([-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0])
GOAL = np.deg2rad([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])
STOWED = np.array([math.pi / 2, -math.pi / 2, 0.0, -math.pi, math.pi, math.pi, 0.0])


def test_three_phase_reaches_goal_reactionlessly(robot, relative_coupling):
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
            assert relative_coupling(reference.theta, reference.theta_dot) < 1e-12
    for phase in plan.phases[:-1]:  # continuous at the boundaries
        before, after = plan.sample(phase.end - 1e-9), plan.sample(phase.end + 1e-9)
        np.testing.assert_allclose(before.theta, after.theta, atol=1e-6)


def test_deployment_is_reactionless(robot, relative_coupling):
    plan = plan_deployment(robot, STOWED)
    assert plan.method is PtpMethod.DEPLOY
    assert plan.phases[0].fold_reached == pytest.approx(-math.pi + 0.183 * 30.0, abs=1e-4)
    for t in np.linspace(0.1, plan.duration - 0.1, 31):
        reference = plan.sample(t)
        assert relative_coupling(reference.theta, reference.theta_dot) < 1e-12
