"""Thesis scenarios in closed loop (controller core + simulator core, no DDS), section 4.2-4.3.

Figures for the record are printed by ``scripts/scenarios.py``; here the physics is asserted.
"""

from __future__ import annotations

import functools

import pytest

from rns_ros.analysis.closed_loop import run_scenario
from rns_ros.control.camera_law import ControlGains

INSPECTION = ("satellite_observation", "own_device_inspection")


@pytest.fixture(scope="module")
def run(robot, scenario):
    """run(name, **options) -> ClosedLoopResult, cached for the module (each run takes seconds)."""

    @functools.cache
    def cached(name, **options):
        return run_scenario(robot, scenario(name), **options)

    return lambda name, **options: cached(name, **options)


@pytest.mark.parametrize("name", INSPECTION)
def test_reactionless_dls_keeps_the_base_and_reaches_the_target(run, name):
    result = run(name)  # 100 Hz, midpoint hold, kinematic mode
    assert result.max_base_deviation_deg < 1e-5
    assert result.final_orientation_error_deg < 1.0
    assert result.max_coupling_momentum < 1e-9  # kg m^2/s, predicted each cycle
    assert result.momentum_drift < 1e-9
    assert result.max_wrist_drift < 1.0  # m: bounded (k_g = 0 in satellite_observation)


@pytest.mark.parametrize("name", INSPECTION)
def test_naive_hold_turns_the_base_first_order_in_the_period(run, name):
    naive = run(name, hold_correction="naive")
    midpoint = run(name)
    assert naive.max_base_deviation_deg > 30 * midpoint.max_base_deviation_deg
    assert naive.max_base_deviation_deg > 1e-5


@pytest.mark.parametrize("name", INSPECTION)
def test_conventional_baseline_disturbs_the_base_by_orders_of_magnitude(run, name):
    conventional = run(name, method="conventional")
    assert conventional.max_base_deviation_deg > 0.05  # deg, above the ETS-VII allowance
    assert conventional.max_base_deviation_deg > 1e3 * run(name).max_base_deviation_deg
    assert conventional.max_coupling_momentum > 0.1


@pytest.mark.parametrize("name", INSPECTION)
def test_sc_keeps_the_rotation_axis_and_trades_speed(run, name):
    result = run(name, method="sc")
    assert result.max_axis_error_deg < 1.0
    assert result.max_base_deviation_deg < 1e-5
    # natural motion: the speed follows b * prod(sigma) instead of the command
    assert result.max_speed_scale > 1.05 or result.min_speed_scale < 0.95


def test_wrist_stabilization_bounds_the_wrist_drift(run):
    """satellite_observation runs with the thesis k_g = 100: the wrist stays within 0.1 m, seven
    times less than without the wrist term. (On own_device_inspection the identified geometry
    drifts 0.22 m with the term and 0.25 m without: docs/reproduction.md, fig4.5.)"""
    held = run("satellite_observation")
    free = run("satellite_observation", gains=ControlGains(wrist_gain=0.0))
    assert held.max_wrist_drift < 0.1
    assert free.max_wrist_drift > 5 * held.max_wrist_drift


def test_algorithmic_singularity_dls_bounded_with_error_sc_keeps_direction(run):
    """Thesis Figs. 4.6-4.8 on our model: pinv passes a near-algorithmic singularity, DLS
    damps it (tracking error), SC keeps the axis (speed error)."""
    pinv = run("algorithmic_singularity", method="pinv")
    # algorithmic: J-bar nearly loses rank while J_omega_e and M~_omega_m stay regular
    assert pinv.min_algorithmic_determinant < 0.05
    assert pinv.min_kinematic_determinant > 1.0
    assert pinv.min_coupling_determinant > 1e9
    dls = run("algorithmic_singularity")
    assert dls.max_damping > 0.1
    assert dls.max_joint_speed <= pinv.max_joint_speed + 1e-9
    assert dls.max_axis_error_deg > 1.0 > pinv.max_axis_error_deg
    sc = run("algorithmic_singularity", method="sc")
    assert sc.max_axis_error_deg < 1.0
    assert sc.min_speed_scale < 0.5
    for result in (pinv, dls, sc):
        assert result.max_base_deviation_deg < 1e-5


def test_dynamic_mode_servo_error_costs_little_reactionlessness(run):
    kinematic = run("own_device_inspection")
    dynamic = run("own_device_inspection", mode="dynamic")
    assert 0.0 < dynamic.max_servo_error < 1e-3  # rad, computed-torque servo at 50 rad/s
    assert dynamic.max_base_deviation_deg < 1e-4
    assert dynamic.final_orientation_error_deg < 0.01
    assert dynamic.max_base_deviation_deg > kinematic.max_base_deviation_deg


@pytest.mark.parametrize("method", ["dls", "conventional"])
def test_one_rk4_step_per_held_period_gives_the_millisecond_figures(run, method):
    """Kinematic mode holds the joint rate over the control period, so the joints move exactly
    and only the base is integrated: its rate follows the arm smoothly (momentum conservation,
    eq. 2.33), and one RK4 step over the 10 ms period reproduces the 1 ms figures (the lockstep
    demo's default). The conventional controller turns the base by 0.56 deg, so a poor base integral
    would show there; measured: both agree to nine digits."""
    fine = run("satellite_observation", method=method)
    coarse = run("satellite_observation", method=method, simulation_step=0.01)
    assert coarse.steps == fine.steps
    assert coarse.max_base_deviation_deg == pytest.approx(fine.max_base_deviation_deg, rel=1e-6)
    assert coarse.final_orientation_error_deg == pytest.approx(
        fine.final_orientation_error_deg, rel=1e-6, abs=1e-9
    )
    assert coarse.momentum_drift < 1e-12
