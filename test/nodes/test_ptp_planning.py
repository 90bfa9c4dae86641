"""The planning worker of rns_ptp (rns_ros.nodes.ptp_planning.PtpPlanning), in process: no DDS."""

from __future__ import annotations

import numpy as np

from rns_ros.control.ptp import PtpMethod, PtpSettings
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.nodes.ptp_planning import PtpPlanning

#: rns_simulator's default start and a goal tens of degrees away [rad].
START = np.deg2rad([-90.0, -30.0, 0.0, -70.0, 180.0, -30.0, 0.0])
GOAL = np.deg2rad([-65.0, -50.0, 20.0, -45.0, 160.0, -10.0, 25.0])


def test_a_replanned_ij_c_keeps_the_camera_target_of_the_plan_it_replaces(robot):
    """IJ-C drives the camera to the final camera position of a 3-phase plan from its start
    (A-2.5). Replanned half-way (the arm was off the held path), the same goal must keep that
    target: a 3-phase plan from the new start would end the base, and so the camera, elsewhere.
    The replanned motion ends its camera on the first target within target_tolerance."""
    settings = PtpSettings()
    planning = PtpPlanning(robot, PtpMethod.INVERSE_JACOBIAN, settings, lambda: 0.0, print)
    first = plan_ptp(robot, START, GOAL, PtpMethod.INVERSE_JACOBIAN, settings)
    target = np.asarray(first.details["camera_target"])
    assert planning.settings_for(None) is settings
    joint_space = plan_ptp(robot, START, GOAL, PtpMethod.JOINT_SPACE, settings)
    assert planning.settings_for(joint_space) is settings
    again = planning.settings_for(first)
    np.testing.assert_array_equal(again.camera_target, target)

    middle = first.sample(0.5 * first.duration).theta
    planning.compute(0, middle, GOAL, again)
    replanned = planning.take(np.inf)
    np.testing.assert_array_equal(replanned.details["camera_target"], target)
    fresh = plan_ptp(robot, middle, GOAL, PtpMethod.INVERSE_JACOBIAN, settings)
    assert np.linalg.norm(np.asarray(fresh.details["camera_target"]) - target) > 1e-4
    assert replanned.details["final_error"] < settings.target_tolerance
