"""Rigid surfaces of Part II and the projection onto them: derivatives, normals, projection."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rns_ros.core import ConfigError, InputError
from rns_ros.core.contact_geometry import (
    ArcConstraint,
    PlaneConstraint,
    ee_point_jacobian,
    project_onto_constraint,
)
from rns_ros.core.fixed_base import load_fixed_base_model

CONFIG = Path(__file__).resolve().parents[2] / "config"
PLANAR_START = np.radians([106.4, -45.7, -56.2])  # thesis_rest, about 1 mm off the arc
CENTER, RADIUS = np.array([1.91, 1.91, 0.0]), 0.707


@pytest.mark.parametrize(
    "constraint",
    [
        ArcConstraint([0.3, -0.2, 0.1], 0.5, axis=[0.2, 1.0, 0.4]),
        PlaneConstraint([0.1, 0.2, 0.3], [1.0, -2.0, 0.5]),
    ],
    ids=["arc", "plane"],
)
def test_constraint_gradient_and_curvature_are_the_derivatives(constraint):
    rng = np.random.default_rng(1)
    h = 1e-5
    for _ in range(5):
        p, v = rng.normal(size=3), rng.normal(size=3)
        gradient = constraint.gradient(p)
        assert np.linalg.norm(gradient) == pytest.approx(1.0)
        numeric = [
            (constraint.phi(p + h * e) - constraint.phi(p - h * e)) / (2 * h) for e in np.eye(3)
        ]
        np.testing.assert_allclose(gradient, numeric, atol=1e-8)
        second = (
            constraint.phi(p + h * v) - 2 * constraint.phi(p) + constraint.phi(p - h * v)
        ) / h**2
        assert constraint.curvature(p, v) == pytest.approx(second, abs=1e-4)
        phi, normal, kappa = constraint.evaluate(p, v)
        assert (phi, kappa) == pytest.approx((constraint.phi(p), constraint.curvature(p, v)))
        np.testing.assert_allclose(normal, gradient)


def test_arc_normal_points_into_the_cylinder():
    arc = ArcConstraint(CENTER, RADIUS)
    outside = CENTER + np.array([RADIUS, 0.0, 0.3])
    assert arc.phi(outside) == pytest.approx(0.0)
    np.testing.assert_allclose(arc.gradient(outside), [-1.0, 0.0, 0.0])
    assert arc.phi(CENTER + np.array([0.5 * RADIUS, 0.0, 0.0])) > 0.0  # inside: penetration
    # moving along the circle at 2 m/s needs 4 / R m/s^2 toward the centre
    assert arc.curvature(outside, [0.0, 2.0, 5.0]) == pytest.approx(-4.0 / RADIUS)


def test_projection_lands_on_the_surface_with_no_normal_velocity():
    """phi(q) = 0 to the tolerance and J_c v = 0 (6.19) after projecting an off-surface start."""
    robot = load_fixed_base_model(CONFIG / "planar_3dof.yaml")
    arc = ArcConstraint(CENTER, RADIUS)
    data = robot.model.createData()
    p, _ = ee_point_jacobian(robot, data, PLANAR_START)
    assert abs(arc.phi(p)) > 1e-4  # the rounded thesis start is off the arc
    q, v = project_onto_constraint(robot, arc, PLANAR_START, [0.3, -0.2, 0.5], tolerance=1e-14)
    p, J_v = ee_point_jacobian(robot, data, q)
    assert abs(arc.phi(p)) <= 1e-14
    assert arc.gradient(p) @ J_v @ v == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(q, PLANAR_START, atol=1e-3)  # a small correction, not a jump
    with pytest.raises(ConfigError, match="could not project"):
        project_onto_constraint(robot, ArcConstraint(CENTER, 10.0), PLANAR_START)


def test_bad_surfaces_fail_with_typed_errors():
    with pytest.raises(ConfigError, match="arc center must be 3 finite"):
        ArcConstraint([1.0, math.nan, 0.0], 1.0)
    for radius in (0.0, -1.0, math.inf, "big"):
        with pytest.raises(ConfigError, match="arc radius must be a finite number > 0"):
            ArcConstraint(CENTER, radius)
    with pytest.raises(ConfigError, match="arc axis must be a non-zero direction"):
        ArcConstraint(CENTER, 1.0, axis=[0.0, 0.0, 0.0])
    with pytest.raises(ConfigError, match="plane normal must be a non-zero"):
        PlaneConstraint([0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(ConfigError, match="plane point must be 3 finite numbers"):
        PlaneConstraint([0.0, 0.0], [0.0, 0.0, 1.0])
    with pytest.raises(InputError, match="on the arc axis"):
        ArcConstraint(CENTER, 1.0).gradient(CENTER + np.array([0.0, 0.0, 1.0]))
