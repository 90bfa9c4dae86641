"""Kinematic free-floating integration (RK4, Munthe-Kaas form) conserves what physics conserves."""

from __future__ import annotations

import numpy as np
import pytest
from rns_testing import SATELLITE_OBSERVATION_DEG

from rns_ros.core import FreeFloatingState
from rns_ros.core.integration import attitude_deviation, free_floating_velocity, rk4_step
from rns_ros.core.momentum import (
    base_twist_from_momentum,
    reactionless_joint_velocity,
    shift_momentum,
    spatial_momentum,
)

THETA_0 = np.deg2rad(SATELLITE_OBSERVATION_DEG)
DIRECTION = np.array([0.3, -0.2, 0.25, 0.4, -0.5, 0.6, 0.7])  # rad/s, a generic joint motion


def generic(t, state):
    return DIRECTION * np.sin(0.8 * t)


def reactionless(t, state):
    return reactionless_joint_velocity(state, generic(t, state))


def _run(robot, joint_velocity, duration, dt, momentum_world=None):
    q = robot.configuration(THETA_0, [0.5, -0.2, 0.1], [0.1, -0.2, 0.05, 0.97])
    states = [FreeFloatingState.compute(robot, q)]
    for k in range(round(duration / dt)):
        q = rk4_step(robot, q, k * dt, dt, joint_velocity, momentum_world)
        states.append(FreeFloatingState.compute(robot, q))
    return states


def _world_momentum(state, theta_dot, momentum_world=None):
    v = free_floating_velocity(state, theta_dot, momentum_world)
    base_twist = np.concatenate((state.base_rotation @ v[:3], state.base_rotation @ v[3:6]))
    about_base = spatial_momentum(state, base_twist, theta_dot)
    return shift_momentum(about_base, state.base_position, np.zeros(3))


def test_reactionless_motion_keeps_the_base_attitude(robot):
    states = _run(robot, reactionless, duration=4.0, dt=0.02)
    deviation = max(attitude_deviation(states[0].base_rotation, s.base_rotation) for s in states)
    assert deviation < 1e-10  # rad
    assert np.linalg.norm(states[-1].theta - states[0].theta) > 0.1  # the arm did move


def test_generic_motion_turns_the_base(robot):
    states = _run(robot, generic, duration=4.0, dt=0.02)
    assert attitude_deviation(states[0].base_rotation, states[-1].base_rotation) > 1e-3


def test_momentum_and_center_of_mass_are_conserved(robot):
    momentum = np.array([0.5, -1.0, 0.2, 3.0, -2.0, 1.0])  # [kg m/s, kg m^2/s] about world origin
    states = _run(robot, generic, duration=3.0, dt=0.01, momentum_world=momentum)
    for t, state in zip((0.0, 3.0), (states[0], states[-1]), strict=True):
        measured = _world_momentum(state, generic(t, state), momentum)
        assert np.allclose(measured, momentum, atol=1e-9)
    # with zero momentum the system CoM stays where it is
    still = _run(robot, generic, duration=3.0, dt=0.01)
    drift = np.linalg.norm(still[-1].center_of_mass - still[0].center_of_mass)
    assert drift < 1e-9
    # CoM drift with momentum: linear p / m_C
    moved = states[-1].center_of_mass - states[0].center_of_mass
    assert np.allclose(moved, momentum[:3] / robot.total_mass * 3.0, atol=1e-9)


def test_rk4_converges_at_fourth_order(robot):
    def final_attitude(dt):
        return _run(robot, generic, duration=1.6, dt=dt)[-1].base_rotation

    reference = final_attitude(0.0125)
    errors = [attitude_deviation(reference, final_attitude(dt)) for dt in (0.2, 0.1)]
    assert errors[0] / errors[1] == pytest.approx(16.0, rel=0.25)


def test_base_twist_zero_momentum_consistent(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    theta_dot = generic(1.0, state)
    v = free_floating_velocity(state, theta_dot)
    expected = base_twist_from_momentum(state, theta_dot)
    assert np.allclose(state.base_rotation @ v[3:6], expected[3:])
