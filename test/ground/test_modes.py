"""rns_ros.ground.modes: move and wait, predictive rate teleop and a supervisory goal
on one turn through a delayed link. With an exact model the delay only shifts what each mode
does: the predictive operator acts on the arm D ahead, so its task takes 2 D longer than without
a link, and so does the goal's (D up, D for the telemetry down); move and wait pays a round trip
per burst."""

from __future__ import annotations

import math

import pytest

from rns_ros.ground.modes import MODES, GroundTask, compare, run_mode


@pytest.fixture(scope="module")
def results(robot):
    q0 = robot.configuration(robot.initial_theta)
    task = dict(angle=math.radians(10.0), timeout=60.0)
    return {
        delay: {r.mode: r for r in compare(robot, GroundTask(delay=delay, **task), q0)}
        for delay in (0.0, 1.0)
    }


def test_every_mode_ends_on_the_goal_and_the_base_stays(results):
    tolerance = math.degrees(GroundTask().tolerance)
    for by_mode in results.values():
        assert set(by_mode) == set(MODES)
        for r in by_mode.values():
            assert r.final_camera_error_deg <= tolerance, r
            assert r.max_base_deviation_deg < 1e-4, r
            assert math.isfinite(r.task_time), r


def test_the_delay_costs_one_round_trip_per_look(results):
    period = GroundTask().operator_period
    near, far = results[0.0], results[1.0]
    for mode in ("predictive_rate", "supervisory_goal"):
        assert far[mode].task_time - near[mode].task_time == pytest.approx(2.0, abs=period)
    assert near["supervisory_goal"].commands == far["supervisory_goal"].commands == 1
    bursts = far["move_and_wait"].bursts
    assert bursts == near["move_and_wait"].bursts
    assert bursts >= 2  # the ramps of the command gate leave something for a second look
    delta = far["move_and_wait"].task_time - near["move_and_wait"].task_time
    assert delta == pytest.approx(2.0 * bursts, abs=period)


def test_an_unknown_mode_is_refused(robot):
    with pytest.raises(ValueError, match="mode must be one of"):
        run_mode(robot, "telepathy", GroundTask(), robot.configuration(robot.initial_theta))
