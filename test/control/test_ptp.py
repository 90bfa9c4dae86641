"""Point-to-point planner (rns_ros.control.ptp)."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.control.ptp import PtpMethod, plan_ptp
from rns_ros.core.errors import InputError

START = np.deg2rad([-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0])
GOAL = np.deg2rad([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])


def test_joint_space_line(robot):
    plan = plan_ptp(robot, START, GOAL, PtpMethod.JOINT_SPACE)
    assert plan.duration == pytest.approx(30.0)
    np.testing.assert_allclose(plan.sample(0.0).theta, START)
    np.testing.assert_allclose(plan.sample(plan.duration).theta, GOAL)
    middle = plan.sample(15.0)
    np.testing.assert_allclose(middle.theta_dot, 1.875 / 30.0 * (GOAL - START), atol=1e-12)
    assert plan.sample(1e6).phase == "done"
    assert not plan.sample(1e6).theta_dot.any()


def test_bad_goal_names_the_joint(robot):
    goal = GOAL.copy()
    goal[2] = np.nan
    with pytest.raises(InputError, match="theta_goal"):
        plan_ptp(robot, START, goal, "joint_space")
    goal = GOAL.copy()
    goal[1] = 50.0
    with pytest.raises(InputError, match="joint 2"):
        plan_ptp(robot, START, goal, "joint_space")
