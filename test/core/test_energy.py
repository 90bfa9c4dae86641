"""Chapter-5 energy quantities against Pinocchio's kinetic energy and their definitions."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.core.conventions import pinocchio_velocity
from rns_ros.core.energy import (
    EnergyCost,
    EnergyMetric,
    c_ratio,
    energy_metric,
    kinetic_energy,
    tilde_manipulator_inertia,
)
from rns_ros.core.planar import planar_2dof_model
from rns_ros.core.state import FreeFloatingState

ANGLES = st.lists(st.floats(-math.pi, math.pi), min_size=7, max_size=7)


def _state(robot, theta) -> FreeFloatingState:
    return FreeFloatingState.compute(robot, robot.configuration(theta, [0.2, -0.1, 0.3]))


@settings(max_examples=20, deadline=None)
@given(theta=ANGLES, seed=st.integers(0, 2**16))
def test_tilde_manipulator_inertia_is_the_energy_with_zero_linear_momentum(robot, theta, seed):
    """Base not turning, translating so that p = 0: Pinocchio's kinetic energy of the whole
    system equals 1/2 theta_dot^T M~_m theta_dot."""
    state = _state(robot, theta)
    theta_dot = np.random.default_rng(seed).normal(size=robot.n)
    m_v, m_vm = state.inertia_base[:3, :3], state.coupling_inertia[:3]
    base_twist = np.concatenate((-np.linalg.solve(m_v, m_vm @ theta_dot), np.zeros(3)))
    v = pinocchio_velocity(state.base_rotation, base_twist, theta_dot)
    data = robot.model.createData()
    pin.crba(robot.model, data, state.q)
    upper = np.triu(data.M)  # crba fills the upper triangle only
    energy = 0.5 * v @ (upper + np.triu(upper, 1).T) @ v
    expected = 0.5 * theta_dot @ tilde_manipulator_inertia(state) @ theta_dot
    assert energy == pytest.approx(expected, rel=1e-10)
    pin.computeCentroidalMomentum(robot.model, data, state.q, v)
    assert np.linalg.norm(data.hg.linear) < 1e-9 * np.linalg.norm(theta_dot) * robot.total_mass


@settings(max_examples=20, deadline=None)
@given(theta=ANGLES, seed=st.integers(0, 2**16))
def test_wheel_metric_is_the_energy_of_wheels_absorbing_the_coupling_momentum(robot, theta, seed):
    """phi_dot = -M~_omega_m theta_dot / I_r (eq. 5.2) costs 1/2 I_r |phi_dot|^2 = the Lambda_r
    term, and a reactionless motion costs no wheel energy."""
    state = _state(robot, theta)
    metric = energy_metric(state, wheel_inertia=0.11)
    theta_dot = np.random.default_rng(seed).normal(size=robot.n)
    phi_dot = -state.coupling_angular_momentum_matrix @ theta_dot / 0.11
    arm, wheels = metric.energy(theta_dot)
    assert wheels == pytest.approx(0.5 * 0.11 * phi_dot @ phi_dot, rel=1e-12)
    assert arm == pytest.approx(0.5 * theta_dot @ tilde_manipulator_inertia(state) @ theta_dot)
    reactionless = state.reaction_null_space_projector @ theta_dot
    # zero up to the rank tolerance of P_RNS (1e-6 of sigma_max, squared in an energy)
    assert metric.energy(reactionless)[1] < 1e-10 * wheels
    assert np.allclose(metric.total, metric.total.T, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(theta=ANGLES)
def test_c_ratio_is_at_least_one_for_the_positioning_subchain(robot, theta):
    state = _state(robot, theta)
    joints = robot.subchains.positioning
    metric = energy_metric(state, 0.11, joints)
    coupling = state.coupling_angular_momentum_matrix[:, joints]
    assert c_ratio(metric, coupling) >= 1.0 - 1e-9


def test_c_ratio_is_one_where_the_coupling_vanishes():
    """No coupling: Lambda = Lambda_m and every motion is reactionless."""
    manipulator = np.array([[3.0, 1.0], [1.0, 2.0]])
    metric = EnergyMetric(manipulator, np.zeros((2, 2)))
    assert c_ratio(metric, np.zeros((3, 2))) == pytest.approx(1.0, abs=1e-15)


def test_planar_mean_c_ratio_is_the_thesis_value():
    """Section 5.2 planar arm (r = 0.945 m, I_r = 0.11 kg m^2, wheel mass on the base), a 30x30
    periodic grid: mean ~1.002 (thesis), C_ratio >= 1 everywhere."""
    robot = planar_2dof_model(0.945, 0.0, base_mass=1010.0, link_inertia=8.3)
    grid = -math.pi + 2 * math.pi * np.arange(30) / 30
    values = []
    for a in grid:
        for b in grid:
            state = FreeFloatingState.compute(robot, robot.configuration([a, b]))
            coupling = state.coupling_angular_momentum_matrix
            values.append(c_ratio(energy_metric(state, 0.11), coupling))
    values = np.array(values)
    assert values.min() >= 1.0 - 1e-9
    assert values.mean() == pytest.approx(1.002, abs=0.003)


def test_energy_cost_is_the_peak_and_the_trapezoidal_integral():
    cost = EnergyCost()
    for k in range(11):
        cost.add(0.1 * k, 2.0 * (0.1 * k))  # T = 2 t on [0, 1]
    assert cost.c_max == pytest.approx(2.0)
    assert cost.c_sum == pytest.approx(1.0)
    with pytest.raises(ValueError, match="finite"):
        cost.add(1.1, math.nan)
    with pytest.raises(ValueError, match="back"):
        cost.add(0.5, 1.0)


@settings(max_examples=20, deadline=None)
@given(theta=ANGLES, seed=st.integers(0, 2**16))
def test_kinetic_energy_terms_add_up_to_pinocchios(robot, theta, seed):
    """Eq. (5.1): base + arm + coupling = Pinocchio's kinetic energy for any base twist; the
    wheel term is the energy of rotors spinning at phi_dot relative to the turning base."""
    state = _state(robot, theta)
    rng = np.random.default_rng(seed)
    twist, theta_dot, speeds = rng.normal(size=6), rng.normal(size=robot.n), rng.normal(size=3)
    v = pinocchio_velocity(state.base_rotation, twist, theta_dot)
    data = robot.model.createData()
    expected = pin.computeKineticEnergy(robot.model, data, state.q, v)
    terms = kinetic_energy(state, twist, theta_dot)
    assert terms.total == pytest.approx(expected, rel=1e-10)
    assert terms.wheels == 0.0
    with_wheels = kinetic_energy(state, twist, theta_dot, speeds, 0.11)
    omega = state.base_rotation.T @ twist[3:]  # base axes, the wheels' axes
    spin = 0.5 * 0.11 * ((omega + speeds) @ (omega + speeds) - omega @ omega)
    assert with_wheels.wheels == pytest.approx(spin, rel=1e-10)
    assert with_wheels.total == pytest.approx(expected + spin, rel=1e-10)
