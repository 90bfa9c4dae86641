"""Inspection energy (thesis §5.2.1-5.2.2): physics of the per-period energy, the wheel torque
(5.14), the running costs (5.12-5.13) and the seeded condition generator."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.analysis import energy_inspection as ei
from rns_ros.control.scenario import load_scenario
from rns_ros.core import load_model
from rns_ros.core.energy import WHEEL_INERTIA, energy_metric
from rns_ros.core.state import FreeFloatingState
from rns_ros.resources import default_model_config, scenario_path

#: Coarse closed loop (50 Hz, one 20 ms RK4 step per period): a 20 s run in well under a second.
RATE, STEP = 50.0, 0.02


@pytest.fixture(scope="module")
def robot():
    return load_model(default_model_config())


@pytest.fixture(scope="module")
def comparison(robot):
    """Condition 1 (Fig. 4.3(a)): reactionless DLS and conventional runs, costed."""
    scenario = load_scenario(scenario_path("satellite_observation"))
    condition = ei.fixed_condition(robot, scenario, "condition 1")
    return ei.compare(robot, condition, rate=RATE, simulation_step=STEP)


def test_reactionless_run_has_negligible_wheel_energy(comparison):
    series = comparison.reactionless.series
    assert series.arm_energy.max() > 1e-3  # it does move
    assert series.wheel_energy.max() < 1e-6 * series.arm_energy.max()
    moving = series.arm_energy > 1e-3 * series.arm_energy.max()
    assert np.all(series.wheel_energy[moving] < 1e-6 * series.arm_energy[moving])


def test_conventional_wheel_energy_is_the_spin_energy_of_eq_5_2(robot, comparison):
    """1/2 theta_dot^T Lambda_r theta_dot = 1/2 I_r |phi_dot|^2, phi_dot = -M~_wm theta_dot / I_r,
    recomputed here from the sampled joint angles and rates."""
    series = comparison.conventional.series
    assert series.wheel_energy.max() > 10.0 * series.arm_energy.max()
    for k in np.linspace(5, len(series.t) - 5, 7).astype(int):
        state = FreeFloatingState.compute(robot, robot.configuration(series.theta[k]))
        phi_dot = -state.coupling_angular_momentum_matrix @ series.theta_dot[k] / WHEEL_INERTIA
        spin = 0.5 * WHEEL_INERTIA * float(phi_dot @ phi_dot)
        assert series.wheel_energy[k] == pytest.approx(spin, rel=1e-9, abs=1e-15)
        np.testing.assert_allclose(series.wheel_rate[k], phi_dot, rtol=1e-9, atol=1e-12)


def test_energies_are_sampled_at_the_middle_of_each_period(comparison):
    series = comparison.conventional.series
    np.testing.assert_allclose(series.t[0], 0.5 / RATE)
    np.testing.assert_allclose(np.diff(series.t), 1.0 / RATE)
    # kinematic mode: the joints move at the held rate, so consecutive midpoints are T theta_dot
    # apart in the middle of the two periods (mean of the two held rates)
    step = np.diff(series.theta, axis=0)
    mean_rate = 0.5 * (series.theta_dot[1:] + series.theta_dot[:-1])
    np.testing.assert_allclose(step, mean_rate / RATE, atol=1e-12)


def test_energy_does_not_depend_on_the_base_pose(robot, comparison):
    """The documented bookkeeping choice: the base is put at identity; Lambda is invariant."""
    series = comparison.conventional.series
    k = int(np.argmax(series.total_energy))
    theta, rate = series.theta[k], series.theta_dot[k]
    held = energy_metric(FreeFloatingState.compute(robot, robot.configuration(theta)))
    quaternion = np.array([0.3, -0.5, 0.2, 0.8])
    turned = FreeFloatingState.compute(
        robot, robot.configuration(theta, (1.0, -2.0, 0.5), quaternion)
    )
    np.testing.assert_allclose(energy_metric(turned).energy(rate), held.energy(rate), rtol=1e-9)


def test_wheel_torque_is_the_finite_difference_of_the_coupling_momentum(comparison):
    series = comparison.conventional.series
    torque = series.wheel_torque()
    h = series.coupling_momentum
    assert torque.torque.shape == (len(series.t) - 1, 3)
    np.testing.assert_allclose(torque.torque, -np.diff(h, axis=0) * RATE, rtol=1e-12)
    # integrating the torque gives back the momentum the wheels took up
    absorbed = np.cumsum(torque.torque * torque.dt[:, None], axis=0)
    np.testing.assert_allclose(absorbed, -(h[1:] - h[0]), atol=1e-9)
    assert torque.peak() > ei.ETS_VII_WHEEL_TORQUE_LIMIT
    assert 0.0 < torque.time_above() <= series.t[-1] - series.t[0] + 1e-9
    assert torque.time_above(per_wheel=True) <= torque.time_above() + 1e-12
    assert torque.peak_component() <= torque.peak() + 1e-12


def test_wheel_torque_of_a_smooth_momentum_is_its_negative_derivative():
    t = np.linspace(0.0, 2.0, 2001)
    h = np.stack((np.sin(t), t**2, np.zeros_like(t)), axis=1)
    torque = ei.wheel_torque(t, h)
    exact = -np.stack((np.cos(torque.t), 2.0 * torque.t, np.zeros_like(torque.t)), axis=1)
    np.testing.assert_allclose(torque.torque, exact, atol=1e-6)  # central in time: O(dt^2)
    with pytest.raises(ValueError, match="increase strictly"):
        ei.wheel_torque(t[::-1], h)


def test_costs_of_a_constant_energy_and_their_parts():
    t = np.linspace(1.0, 21.0, 101)
    costs = ei.running_costs(t, np.full_like(t, 0.75))
    assert costs.c_max == pytest.approx(0.75)
    assert costs.c_sum == pytest.approx(0.75 * 20.0)


def test_total_cost_adds_the_arm_and_wheel_parts(comparison):
    series = comparison.conventional.series
    total, arm, wheels = series.costs(), series.costs("arm"), series.costs("wheels")
    assert total.c_sum == pytest.approx(arm.c_sum + wheels.c_sum, rel=1e-12)
    assert max(arm.c_max, wheels.c_max) <= total.c_max <= arm.c_max + wheels.c_max
    ratio = comparison.ratio
    reactionless = comparison.reactionless.series.costs()
    assert ratio["c_max"] == pytest.approx(total.c_max / reactionless.c_max)
    assert ratio["c_sum"] > 10.0
    assert ratio["c_max"] > 10.0


def test_condition_generator_is_seeded_and_respects_limits_and_threshold(robot):
    first = ei.random_conditions(robot, 3, seed=11)
    again = ei.random_conditions(robot, 3, seed=11)
    other = ei.random_conditions(robot, 3, seed=12)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a.scenario.initial_theta, b.scenario.initial_theta)
        np.testing.assert_array_equal(a.scenario.axis, b.scenario.axis)
    assert not np.allclose(first[0].scenario.initial_theta, other[0].scenario.initial_theta)
    assert [c.label for c in first] == ["condition 2", "condition 3", "condition 4"]
    strict = ei.random_conditions(robot, 3, seed=11, sigma_threshold=0.6)
    assert sum(c.draws for c in strict) > 3  # some candidates were rejected
    for condition, threshold in [(c, 0.1) for c in first] + [(c, 0.6) for c in strict]:
        scenario = condition.scenario
        assert np.all(scenario.initial_theta >= robot.lower_limits)
        assert np.all(scenario.initial_theta <= robot.upper_limits)
        state = FreeFloatingState.compute(robot, robot.configuration(scenario.initial_theta))
        sigma = np.linalg.svd(state.restricted_jacobian, compute_uv=False)[-1]
        assert sigma >= threshold
        assert condition.sigma_min == pytest.approx(sigma)
        assert np.linalg.norm(scenario.axis) == pytest.approx(1.0)
        assert scenario.angle == pytest.approx(np.pi)
        assert scenario.duration == 20.0
        assert scenario.peak_angular_speed() == pytest.approx(np.pi * 15.0 / 8.0 / 20.0)
    with pytest.raises(RuntimeError):
        ei.random_conditions(robot, 1, seed=11, sigma_threshold=10.0, max_draws=20)


def test_geometric_mean():
    assert ei.geometric_mean([10.0, 1000.0]) == pytest.approx(100.0)
