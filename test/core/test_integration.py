"""Helpers of rns_ros.core.integration against the momentum relations."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from rns_testing import SATELLITE_OBSERVATION_DEG

from rns_ros.core import FreeFloatingState
from rns_ros.core.integration import attitude_deviation, free_floating_velocity
from rns_ros.core.momentum import base_twist_from_momentum


def test_free_floating_velocity_matches_the_momentum_solve(robot):
    state = FreeFloatingState.compute(
        robot, robot.configuration(np.deg2rad(SATELLITE_OBSERVATION_DEG))
    )
    theta_dot = np.linspace(-0.3, 0.3, 7)
    v = free_floating_velocity(state, theta_dot)
    expected = base_twist_from_momentum(state, theta_dot)
    assert np.allclose(state.base_rotation @ v[:3], expected[:3])
    assert np.allclose(state.base_rotation @ v[3:6], expected[3:])
    assert np.array_equal(v[6:], theta_dot)


def test_free_floating_velocity_agrees_with_pinocchio_centroidal_momentum(robot):
    q = robot.configuration(np.deg2rad(SATELLITE_OBSERVATION_DEG), [1.0, 0.0, -2.0])
    state = FreeFloatingState.compute(robot, q)
    momentum_world = np.array([0.5, -1.0, 0.2, 3.0, -2.0, 1.0])  # about the world origin
    v = free_floating_velocity(state, np.full(7, 0.2), momentum_world)
    centroidal = pin.computeCentroidalMomentum(robot.model, robot.data, q, v)
    com = state.center_of_mass
    assert np.allclose(centroidal.linear, momentum_world[:3], atol=1e-9)
    # l_G = l_O - c x p
    expected = momentum_world[3:] - np.cross(com, momentum_world[:3])
    assert np.allclose(centroidal.angular, expected, atol=1e-9)


def test_attitude_deviation_is_the_rotation_angle():
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    rotation = pin.exp3(0.7 * axis)
    assert attitude_deviation(np.eye(3), rotation) == pytest.approx(0.7)
    assert attitude_deviation(rotation, rotation) == pytest.approx(0.0, abs=1e-12)
