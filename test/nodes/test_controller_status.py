"""rns_controller's status: levels of the states, key values of a tick, the joint-limit text."""

from __future__ import annotations

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus

from rns_ros.control.controller import ControllerSettings, ReactionlessController, TwistFrame
from rns_ros.control.teleop import ControllerState, GateOutput
from rns_ros.core import FreeFloatingState, load_model
from rns_ros.nodes.controller_status import (
    STATE_LEVELS,
    JointLimitStop,
    joint_limit_text,
    step_values,
)
from rns_ros.resources import default_model_config

ROBOT = load_model(default_model_config())
THETA = np.deg2rad([-90.0, -30.0, 0.0, -70.0, 180.0, -30.0, 0.0])


def test_faults_are_errors_and_normal_operation_is_ok():
    for state in (ControllerState.STALE_STATE, ControllerState.CONFLICTING_STATE):
        assert STATE_LEVELS[state] == DiagnosticStatus.ERROR
    for state in (ControllerState.OK, ControllerState.IDLE, ControllerState.RAMPING):
        assert STATE_LEVELS[state] == DiagnosticStatus.OK
    assert ControllerState.SINGULAR_REGION not in STATE_LEVELS  # reported as a warning


def _step(gate: GateOutput):
    state = FreeFloatingState.compute(ROBOT, ROBOT.configuration(THETA))
    controller = ReactionlessController(ROBOT, ControllerSettings())
    return controller.step(state, gate.angular)


def test_a_stopped_output_reports_no_unachieved_twist_and_no_coupling():
    zero = np.zeros(3)
    moving = GateOutput(
        np.array([0.1, 0, 0]), zero, TwistFrame.WORLD, ControllerState.OK, False, ""
    )
    values = step_values("dls", _step(moving), moving)
    assert values["sigma_min"] > 0.0
    assert np.abs(values["coupling_momentum"]).max() < 1e-9  # reactionless
    stopped = GateOutput(zero, zero, TwistFrame.WORLD, ControllerState.IDLE, True, "")
    values = step_values("dls", _step(stopped), stopped)
    assert not values["unachieved_angular"].any()
    assert not values["coupling_momentum"].any()


def test_the_joint_limit_text_names_the_joint_nearest_its_limit():
    theta = THETA.copy()
    theta[6] = ROBOT.upper_limits[6] - 1e-4
    text = joint_limit_text(ROBOT, theta)
    assert text.startswith(f"JOINT_LIMIT: {ROBOT.joint_names[6]} at ")
    assert "0.0001 rad from its limit" in text


def test_a_joint_limit_stop_goes_on_through_a_short_hold_free_of_the_limit():
    """A late tick's output, held for a fraction of the period, may not reach the limit: the
    stop goes on (no second warning); a period free of it ends the stop."""
    period = 0.01
    stop = JointLimitStop(period)
    assert stop.update(False, period) == (False, False)
    assert stop.update(True, period) == (True, True)  # the stop begins: warned once
    assert stop.update(True, 0.0045) == (True, False)
    assert stop.update(False, 0.0005) == (True, False)  # a late tick's short hold
    assert stop.update(False, 0.0045) == (True, False)  # 5 ms free in all
    assert stop.update(True, period) == (True, False)  # the same stop
    assert stop.update(False, 0.006) == (True, False)
    assert stop.update(False, 0.006) == (False, False)  # 12 ms free: over
    assert stop.update(True, period) == (True, True)  # a new stop


def test_a_joint_limit_stop_ends_with_another_state():
    period = 0.01
    stop = JointLimitStop(period)
    assert stop.update(True, period) == (True, True)
    stop.end()  # the command ended, a fault
    assert stop.update(True, period) == (True, True)
    assert stop.update(False, period) == (False, False)  # a full period free at once
