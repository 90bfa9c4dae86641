"""Pinocchio (base-frame twist) <-> thesis (world-frame twist) conversions, in one place."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from rns_testing import configurations, unit_quaternions, vectors

from rns_ros.core import FreeFloatingState, InputError
from rns_ros.core.conventions import (
    base_twist_to_base,
    base_twist_to_world,
    pinocchio_velocity,
    rotation_from_quaternion,
    thesis_inertia_blocks,
)

SETTINGS = settings(max_examples=40, deadline=None)


@SETTINGS
@given(unit_quaternions(), vectors(6, 2.0))
def test_twist_round_trip(quaternion, twist):
    rotation = pin.Quaternion(*quaternion[[3, 0, 1, 2]]).toRotationMatrix()
    assert np.allclose(base_twist_to_base(rotation, base_twist_to_world(rotation, twist)), twist)


@SETTINGS
@given(configurations(), vectors(13, 1.0))
def test_kinetic_energy_is_the_same_in_both_conventions(robot, config, v):
    position, quaternion, theta = config
    q = robot.configuration(theta, position, quaternion)
    inertia_pin = pin.crba(robot.model, robot.data, q)
    rotation = pin.Quaternion(*quaternion[[3, 0, 1, 2]]).toRotationMatrix()
    m_b, m_bm, m_m = thesis_inertia_blocks(inertia_pin, rotation)
    base_twist = base_twist_to_world(rotation, v[:6])
    thesis = np.concatenate((base_twist, v[6:]))
    inertia_thesis = np.block([[m_b, m_bm], [m_bm.T, m_m]])
    assert np.isclose(v @ inertia_pin @ v, thesis @ inertia_thesis @ thesis, rtol=1e-12)
    assert np.allclose(pinocchio_velocity(rotation, base_twist, v[6:]), v)


def test_world_frame_base_twist_moves_the_base_as_stated(robot):
    """Integrating v built from a world-frame V_b moves r_b by v_b dt in world axes."""
    q = robot.configuration(np.zeros(7), [1.0, 2.0, 3.0], [0.3, -0.1, 0.4, 0.86])
    state = FreeFloatingState.compute(robot, q)
    base_twist = np.array([0.2, -0.1, 0.3, 0.0, 0.0, 0.0])
    v = pinocchio_velocity(state.base_rotation, base_twist, np.zeros(7))
    moved = pin.integrate(robot.model, q, 0.5 * v)
    assert np.allclose(moved[:3] - q[:3], 0.5 * base_twist[:3])


def test_rotation_from_quaternion_normalizes_and_rejects_zero():
    rotation = rotation_from_quaternion([0.0, 0.0, 2.0 * math.sin(0.25), 2.0 * math.cos(0.25)])
    expected = pin.AngleAxis(0.5, np.array([0.0, 0.0, 1.0])).toRotationMatrix()
    assert rotation == pytest.approx(expected, abs=1e-12)
    with pytest.raises(InputError, match="non-zero"):
        rotation_from_quaternion([0.0, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="finite"):
        rotation_from_quaternion([0.0, 0.0, math.nan, 1.0])
