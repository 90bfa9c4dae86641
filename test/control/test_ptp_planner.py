"""plan_ptp (rns_ros.control.ptp_planner): one planner per method, input checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.control.ptp import PtpMethod
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.core.errors import ConfigError, InputError

START = np.deg2rad([-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0])
GOAL = np.deg2rad([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])
STOWED = np.array([math.pi / 2, -math.pi / 2, 0.0, -math.pi, math.pi, math.pi, 0.0])


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


def test_deploy_needs_no_goal_and_unknown_methods_are_rejected(robot):
    plan = plan_ptp(robot, STOWED, None, "deploy")
    assert plan.method is PtpMethod.DEPLOY
    with pytest.raises(ConfigError, match="ptp method"):
        plan_ptp(robot, START, GOAL, "teleport")
