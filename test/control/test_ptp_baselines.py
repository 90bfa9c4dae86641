"""Point-to-point baselines (rns_ros.control.ptp_baselines): JS-C, IJ-C, TJ-C."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.control.ptp import PtpMethod, PtpSettings
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.core.state import FreeFloatingState

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


@pytest.mark.parametrize("method", ["inverse_jacobian", "transposed_jacobian"])
def test_jacobian_baselines_bring_the_camera_to_its_target(robot, method):
    """IJ-C and TJ-C drive the positioning joints only (the wrist stays on its JS-C line, here
    held) and end with the camera at the target within the tolerance."""
    start_camera = FreeFloatingState.compute(robot, robot.configuration(START)).camera.position
    target = start_camera + np.array([0.02, -0.01, 0.01])
    settings = PtpSettings(
        duration=2.0, integration_step=0.05, camera_target=tuple(target), target_tolerance=0.002
    )
    goal = START.copy()
    plan = plan_ptp(robot, START, goal, method, settings)
    assert plan.method is PtpMethod(method)
    assert plan.details["final_error"] < 0.002
    np.testing.assert_allclose(plan.details["camera_target"], target)
    np.testing.assert_allclose(plan.goal[4:], START[4:], atol=1e-12)
    assert np.abs(plan.goal[:4] - START[:4]).max() > 1e-3
