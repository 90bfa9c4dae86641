"""Recorded closed-loop runs of the shipped scenarios: cached per process, and the trace obeys
its own definitions (period midpoints, error norms, a reactionless base at rest)."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from rns_ros.analysis.closed_loop import run_scenario
from rns_ros.analysis.reproduce import scenario_runs

SCENARIO = "satellite_observation"


@pytest.fixture(scope="module")
def run():
    return scenario_runs.recorded_run(SCENARIO, "dls", True)


def test_runs_are_cached_per_arguments(run):
    assert scenario_runs.recorded_run(SCENARIO, "dls", True) is run
    assert scenario_runs.default_robot() is scenario_runs.default_robot()


def test_loop_settings_are_run_scenarios_defaults_coarser_when_quick():
    full, quick = scenario_runs.loop_settings(False), scenario_runs.loop_settings(True)
    defaults = {
        name: getattr(p.default, "value", p.default)
        for name, p in inspect.signature(run_scenario).parameters.items()
        if name in full
    }
    assert full == defaults
    assert quick == {
        **full,
        "rate": scenario_runs.QUICK_RATE,
        "simulation_step": scenario_runs.QUICK_STEP,
    }


def test_trace_rows_follow_their_definitions(run):
    trace = run.trace
    assert len(trace.t_mid) == run.result.steps
    period = 1.0 / scenario_runs.QUICK_RATE
    np.testing.assert_allclose(trace.t_end - trace.t_mid, 0.5 * period, rtol=1e-9)
    error = np.linalg.norm(trace.omega_achieved - trace.omega_ref, axis=1)
    np.testing.assert_allclose(trace.omega_error, error, rtol=0, atol=1e-15)
    assert trace.theta_dot.shape == (len(trace.t_mid), scenario_runs.default_robot().n)
    # reactionless: the base stays where it was; the trace and the summary agree on it
    assert trace.base_deviation_deg.max() < 1e-3
    assert trace.base_deviation_deg.max() == pytest.approx(run.result.max_base_deviation_deg)
    # DLS has no SC factor: its speed scale is the joint-limit scale alone, within (0, 1]
    np.testing.assert_array_equal(trace.speed_scale, trace.limit_scale)
    assert np.all((trace.limit_scale > 0.0) & (trace.limit_scale <= 1.0))


def test_run_settings_name_the_scenario_methods_and_loop(run):
    settings = scenario_runs.run_settings(SCENARIO, [run], True)
    assert settings["scenario"] == f"config/scenarios/{SCENARIO}.yaml"
    assert settings["methods"] == {
        "dls": {
            "method": "dls",
            "joint_limits": run.settings["joint_limits"],
            **run.settings["gains"],
        }
    }
    assert settings["controller_rate_hz"] == scenario_runs.QUICK_RATE
    assert settings["quick"] is True
    values = scenario_runs.run_values([run])
    assert set(values["max_base_deviation_deg"]) == {"dls"}
    assert values["min_joint_limit_scale"] == {"dls": float(run.trace.limit_scale.min())}


@pytest.mark.slow
def test_thesis_robot_never_scales_where_the_urdf_limits_do():
    """The reproductions' model has no joint limits (the thesis scales nothing down); the
    labelled URDF series scales the algorithmic-singularity run down."""
    free = scenario_runs.recorded_run("algorithmic_singularity", "pinv", True)
    limited = scenario_runs.recorded_run("algorithmic_singularity", "pinv", True, urdf_limits=True)
    np.testing.assert_array_equal(free.trace.limit_scale, 1.0)
    assert limited.trace.limit_scale.min() < 0.5
    assert limited.label == "pinv_urdf_limits"
    assert np.abs(limited.trace.theta_dot).max() <= (
        scenario_runs.default_robot().velocity_limits.max() + 1e-9
    )
    assert np.abs(free.trace.theta_dot).max() > scenario_runs.default_robot().velocity_limits.max()
    assert np.all(np.isinf(scenario_runs.thesis_robot().velocity_limits))
