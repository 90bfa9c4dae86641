"""A planned motion (rns_ros.control.ptp): stretching to the velocity limits, position feedback."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.control.ptp import PtpSettings
from rns_ros.control.ptp_planner import plan_ptp

START = np.deg2rad([-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0])
GOAL = np.deg2rad([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])


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


def test_command_feedback_is_reactionless(robot, relative_coupling):
    plan = plan_ptp(robot, START, GOAL, "three_phase")
    theta = plan.sample(2.0).theta + np.array([0.01, -0.01, 0.02, 0.0, 0.0, 0.0, 0.0])
    command = plan.command(2.0, theta)
    assert relative_coupling(theta, command) < 1e-12
