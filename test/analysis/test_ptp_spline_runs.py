"""The base attitude a joint_trajectory_controller's interpolation between plan samples costs
(rns_ros.analysis.ptp_spline_runs), against the bound docs/ros2_control.md states."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.analysis.ptp_spline_runs import spline_cost
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.nodes.ptp_parameters import SPECS

START = np.deg2rad([-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0])
GOAL = np.deg2rad([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])
#: docs/ros2_control.md: a whole three_phase plan sampled at plan_sample_period's default keeps
#: the base within this of the exact plan's base attitude [deg].
WHOLE_PLAN_BASE_BOUND_DEG = 1e-4


@pytest.fixture(scope="module")
def plan(robot):
    return plan_ptp(robot, START, GOAL, "three_phase")


def test_the_default_sampling_keeps_the_base_within_the_documented_bound(robot, plan):
    spacing = SPECS["plan_sample_period"].default
    cost = spline_cost(robot, plan, spacing, dt=0.01)
    print(
        f"three_phase {plan.duration:.1f} s, {cost.samples} samples every <= {spacing} s: base "
        f"{cost.base_gap_deg:.2e} deg from the exact plan (which turns it "
        f"{math.degrees(cost.plan_deviation):.3f} deg in phase II), joints {cost.joint_gap:.1e} rad"
    )
    assert cost.base_gap_deg < WHOLE_PLAN_BASE_BOUND_DEG
    assert cost.spline_deviation == pytest.approx(cost.plan_deviation, abs=1e-5)


def test_coarse_sampling_costs_more_than_the_bound(robot, plan):
    """The measure sees the interpolation: eight times coarser samples leave the bound far
    behind (the gap grows about as h^3)."""
    fine = spline_cost(robot, plan, 0.25, dt=0.01)
    coarse = spline_cost(robot, plan, 2.0, dt=0.01)
    assert coarse.base_gap_deg > 10 * WHOLE_PLAN_BASE_BOUND_DEG
    assert coarse.base_gap > 100 * fine.base_gap
