"""The chapter-5 C_ratio maps (eq. 5.5): the batched ratio, the planar maps and their identities."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.analysis import energy_maps as em
from rns_ros.analysis.planar_field import fixed_points
from rns_ros.core.energy import c_ratio
from rns_ros.core.planar import planar_2dof_model

EPS = np.finfo(float).eps


def test_c_ratio_is_one_where_the_coupling_vanishes():
    """M~_omega_m = 0: every motion is reactionless and Lambda = Lambda_m, so C_ratio = 1."""
    rng = np.random.default_rng(5)
    for k in (2, 4):
        a = rng.normal(size=(7, k, k))
        tilde = a @ np.swapaxes(a, 1, 2) + np.eye(k)
        coupling = np.zeros((7, k - 1, k))
        coupling[3] = rng.normal(size=(k - 1, k))  # one regular point among them
        ratio = em.c_ratio_batch(tilde, coupling)
        assert np.all(np.delete(ratio, 3) == 1.0)
        assert ratio[3] >= 1.0


def test_near_a_planar_fixed_point_the_wheels_do_nothing_but_the_ratio_stays_bounded():
    """At the fixed points of Fig. 3.2(b) M~_omega_m ~ 0 (not exactly): Lambda ~ Lambda_m, and
    C_ratio takes the direction-dependent value n^T M~_m n / sigma_min(M~_m) in
    [1, cond(M~_m)] (the 'large errors at specific points' of Fig. 5.1)."""
    arm = em.planar_arm()
    points = fixed_points(arm)
    assert points, "r = 0.945 m lies above r*: the planar arm has fixed points"
    for point in points:
        assert np.linalg.norm(arm.coupling_inertia(point.theta)) < 1e-6
        tilde = arm.manipulator_inertia(point.theta)
        low, high = np.linalg.eigvalsh(tilde)
        n = arm.reactionless_field(point.theta)
        ratio = em.planar_c_ratio(arm, point.theta)
        assert ratio == pytest.approx(n @ tilde @ n / low, rel=1e-9)
        assert 1.0 <= ratio <= high / low


def test_rank_two_coupling_uses_the_plane_of_reactionless_motions():
    """Two dependent rows leave a 2-D kernel: C_ratio = sigma_min(N^T M~_m N) / sigma_min(Lambda)
    as in core.energy.c_ratio."""
    rng = np.random.default_rng(8)
    a = rng.normal(size=(4, 4))
    tilde = a @ a.T + np.eye(4)
    coupling = rng.normal(size=(3, 4))
    coupling[2] = 0.3 * coupling[0] - 2.0 * coupling[1]
    from rns_ros.core.energy import EnergyMetric

    expected = c_ratio(EnergyMetric(tilde, coupling.T @ coupling / 0.11), coupling)
    assert em.c_ratio_batch(tilde, coupling) == pytest.approx(expected, rel=1e-12)


def test_planar_map_matches_pinocchio_and_has_the_thesis_mean(reference_c_ratio):
    """Fig. 5.1: the section-5.2 arm (r = 0.945 m, 1010 kg base, I_i = 8.3 kg m^2)."""
    model = planar_2dof_model(0.945, 0.0, base_mass=1010.0, link_inertia=8.3)
    grid, ratio = em.planar_c_ratio_map(count=100)
    assert ratio.shape == (100, 100)
    assert grid[0] == -math.pi
    assert grid[-1] < math.pi
    for i, j in [(0, 0), (10, 73), (55, 20), (99, 42)]:
        reference, _, _ = reference_c_ratio(model, [grid[j], grid[i]])
        assert ratio[i, j] == pytest.approx(reference, rel=1e-9)
    assert ratio.min() >= 1.0 - 1e-12
    assert ratio.mean() == pytest.approx(1.0015, abs=1e-4)  # thesis: 1.002
    assert np.median(ratio) < 1.0001


@pytest.mark.parametrize("scale_inertia", [False, True])
def test_parameter_variation_scales_masses_com_distances_and_optionally_inertias(
    reference_c_ratio, scale_inertia
):
    """alpha, beta of eqs. (5.6)-(5.7) against a Pinocchio model edited the same way: alpha
    scales the masses (and the inertias only with ``scale_inertia``), beta the CoM distances."""
    alpha, beta = 0.7, 1.3
    arm = em.planar_arm(alpha, beta, scale_inertia=scale_inertia)
    base = planar_2dof_model(0.945, 0.0, base_mass=1010.0, link_inertia=8.3)
    model = pin.Model(base.model)
    for j in (2, 3):
        body = model.inertias[j]
        rotational = body.inertia.copy() * (alpha if scale_inertia else 1.0)
        model.inertias[j] = pin.Inertia(alpha * body.mass, beta * body.lever, rotational)
    edited = type(base)(model, base.spec, name="planar_scaled")
    for theta in ([0.3, -1.2], [2.5, 0.4], [-3.0, 2.9]):
        reference, _, _ = reference_c_ratio(edited, theta)
        assert em.planar_c_ratio(arm, theta) == pytest.approx(reference, rel=1e-9)
    means = em.parameter_variation_map([0.5, 1.5], [1.0], count=40, scale_inertia=scale_inertia)
    assert means.shape == (2, 1)
    if scale_inertia:  # heavier (denser) links: closer to minimum energy (Fig. 5.2)
        assert means[1, 0] < means[0, 0]
