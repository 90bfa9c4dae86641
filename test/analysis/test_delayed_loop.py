"""The DDS loop's timing in process: an unpredicted output delay turns the base in proportion to
the delay (first order, 2 d / T of the naive hold's error); predicting when the output acts
restores the undelayed loop."""

from __future__ import annotations

from dataclasses import replace

import pytest

from rns_ros.analysis.delayed_loop import DDS_TIMING, NODE_PREDICTION, LoopTiming, run_delayed_loop
from rns_ros.control.prediction import OutputTiming
from rns_ros.control.scenario import load_scenario
from rns_ros.core import ConfigError
from rns_ros.resources import scenario_path

#: Simulated seconds per run: the fastest part of the quintic profile starts at 10 s.
DURATION = 6.0


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(scenario_path("satellite_observation"))


def _deviation(robot, scenario, timing, **kwargs):
    return run_delayed_loop(robot, scenario, timing, duration=DURATION, **kwargs)


def test_an_unpredicted_delay_turns_the_base_in_proportion(robot, scenario):
    # outputs arriving on a grid point act there: the delay is exactly output_delay
    reference = _deviation(robot, scenario, LoopTiming()).max_base_deviation_deg
    one = _deviation(robot, scenario, LoopTiming(output_delay=1e-3)).max_base_deviation_deg
    two = _deviation(robot, scenario, LoopTiming(output_delay=2e-3)).max_base_deviation_deg
    assert one > 50 * reference
    assert two / one == pytest.approx(2.0, rel=0.1)
    naive = _deviation(
        robot, scenario, LoopTiming(), hold_correction="naive"
    ).max_base_deviation_deg
    assert one / naive == pytest.approx(2 * 1e-3 / 0.01, rel=0.25)  # 2 d / T


def test_predicting_the_delay_and_the_update_grid_restores_the_undelayed_loop(robot, scenario):
    reference = _deviation(robot, scenario, LoopTiming()).max_base_deviation_deg
    timing = LoopTiming(output_delay=5e-4, tick_phase=3e-4, predicted=OutputTiming(5e-4, 1e-3))
    assert _deviation(robot, scenario, timing).max_base_deviation_deg < 2 * reference


@pytest.mark.parametrize("method", ["dls", "sc"])
def test_the_dds_timing_is_within_1e_5_deg_when_predicted(robot, scenario, method):
    """All DDS effects together (state age, delay, cut holds, jitter): > 1e-5 deg without the
    prediction of when outputs act, well below it with the node's defaults."""
    unpredicted = _deviation(robot, scenario, DDS_TIMING, method=method)
    predicted = _deviation(
        robot,
        scenario,
        replace(DDS_TIMING, predicted=NODE_PREDICTION),
        method=method,
    )
    assert unpredicted.max_base_deviation_deg > 1e-5
    assert predicted.max_base_deviation_deg < 0.1 * unpredicted.max_base_deviation_deg
    assert predicted.shortest_hold_s < 0.01  # holds were cut


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"state_period": 0.0105}, "state_period"),
        ({"state_phase": 0.02}, "state_phase"),
        ({"output_delay": -1e-3}, "output_delay"),
        ({"command_period": 0.0}, "command_period"),
    ],
)
def test_bad_timing_is_rejected_by_name(overrides, message):
    with pytest.raises(ConfigError, match=message):
        LoopTiming(**overrides)


def test_late_ticks_turn_the_base_unless_the_law_expects_their_mean_lateness(robot, scenario):
    """Timer ticks 0-8 ms late (uniform), the plant's 1 ms update grid predicted: told the
    time to the timer's next grid instant, every hold runs longer than the law assumed, always
    the same way, and the base turns by far more than on time; told that plus the mean
    lateness (TickLateness, as rns_controller), most of it is gone. On time both are the same
    loop."""
    grid_predicted = OutputTiming(plant_period=1e-3)
    late = LoopTiming(timer_latency=(0.0, 8e-3), predicted=grid_predicted)
    to_grid = _deviation(robot, scenario, late, told_hold="grid").max_base_deviation_deg
    expected = _deviation(robot, scenario, late, told_hold="expected").max_base_deviation_deg
    on_time = LoopTiming(predicted=grid_predicted)
    reference = _deviation(robot, scenario, on_time, told_hold="grid").max_base_deviation_deg
    print(f"on time {reference:.2e}, late: to the grid {to_grid:.2e}, expected {expected:.2e} deg")
    assert to_grid > 50 * reference
    assert expected < 0.35 * to_grid
    assert _deviation(
        robot, scenario, on_time, told_hold="expected"
    ).max_base_deviation_deg == pytest.approx(reference, rel=1e-9)


def test_a_told_hold_needs_an_absolute_timer_grid(robot, scenario):
    with pytest.raises(ConfigError, match="told_hold 'grid' needs a timer without immediate"):
        _deviation(robot, scenario, DDS_TIMING, told_hold="grid")
    with pytest.raises(ConfigError, match="told_hold must be one of"):
        _deviation(robot, scenario, LoopTiming(), told_hold="late")
