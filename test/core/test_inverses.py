"""Pseudoinverse, DLS with numerical filtering (4.10-4.12) and the SC inverse (4.13-4.14)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.core import (
    ConfigError,
    InputError,
    damped_least_squares_inverse,
    pseudoinverse,
    singularity_consistent_inverse,
)
from rns_ros.core.inverses import THESIS_EPSILON, THESIS_LAMBDA2_MAX, dls_damping

SETTINGS = settings(max_examples=60, deadline=None)


def _orthonormal(rng: np.random.Generator, size: int) -> np.ndarray:
    q, r = np.linalg.qr(rng.standard_normal((size, size)))
    return q * np.sign(np.diag(r))


def jacobian_with(sigma, seed: int = 0) -> np.ndarray:
    """A 3 x 7 matrix with prescribed singular values and random singular vectors."""
    rng = np.random.default_rng(seed)
    u, v = _orthonormal(rng, 3), _orthonormal(rng, 7)
    return u @ np.diag(sigma) @ v[:3]


near_singular = st.tuples(
    st.floats(0.5, 3.0), st.floats(0.3, 1.0), st.floats(0.0, 0.3), st.integers(0, 10_000)
).map(lambda t: jacobian_with([t[0], max(t[1], t[2]), t[2]], t[3]))
regular = st.tuples(
    st.floats(0.5, 3.0), st.floats(0.3, 1.0), st.floats(0.21, 0.29), st.integers(0, 10_000)
).map(lambda t: jacobian_with([t[0], t[1], t[2]], t[3]))


def test_pseudoinverse_satisfies_penrose_conditions():
    jacobian = jacobian_with([2.0, 1.0, 0.1])
    inverse = pseudoinverse(jacobian)
    assert np.allclose(jacobian @ inverse @ jacobian, jacobian)
    assert np.allclose(inverse @ jacobian @ inverse, inverse)
    assert np.allclose((jacobian @ inverse).T, jacobian @ inverse)
    assert np.allclose((inverse @ jacobian).T, inverse @ jacobian)
    assert np.allclose(inverse, np.linalg.pinv(jacobian))


def test_pseudoinverse_drops_exactly_singular_directions():
    jacobian = jacobian_with([2.0, 1.0, 0.0])
    assert np.isfinite(pseudoinverse(jacobian)).all()
    assert np.allclose(pseudoinverse(jacobian), np.linalg.pinv(jacobian, rcond=1e-12))


@SETTINGS
@given(regular)
def test_dls_equals_pseudoinverse_outside_the_singular_region(jacobian):
    result = damped_least_squares_inverse(jacobian)
    assert result.damping == 0.0
    assert np.allclose(result.matrix, pseudoinverse(jacobian), atol=1e-12)


@SETTINGS
@given(near_singular)
def test_dls_matches_the_closed_form_of_eq_4_10(jacobian):
    result = damped_least_squares_inverse(jacobian)
    u, sigma, _ = np.linalg.svd(jacobian)
    if sigma[1] <= THESIS_EPSILON:
        return  # two directions in the region: our documented extension, not eq. (4.10)
    damping = dls_damping(sigma[2], THESIS_EPSILON, THESIS_LAMBDA2_MAX)
    gram = jacobian @ jacobian.T + damping * np.outer(u[:, 2], u[:, 2])
    expected = np.linalg.solve(gram, jacobian).T  # J^T (J J^T + lambda^2 u3 u3^T)^-1
    assert np.allclose(result.matrix, expected, atol=1e-9)
    assert result.damping == pytest.approx(damping)


def test_dls_stays_bounded_as_sigma_min_goes_to_zero():
    norms = []
    for sigma_min in (1e-1, 1e-3, 1e-6, 1e-9, 0.0):
        result = damped_least_squares_inverse(jacobian_with([2.0, 1.0, sigma_min]))
        norms.append(np.linalg.norm(result.matrix, 2))
        assert result.damping == pytest.approx(dls_damping(sigma_min, 0.2, 2.0))
    # ||J^#|| <= max(1/sigma_2, max_s s/(s^2 + lambda^2(s))) stays O(1); pinv would grow like 1/s
    assert max(norms) < 5.0
    assert np.linalg.norm(pseudoinverse(jacobian_with([2.0, 1.0, 1e-9])), 2) > 1e8


def test_dls_damping_is_continuous_and_smooth_at_epsilon():
    eps, lam2 = 0.2, 2.0
    assert dls_damping(eps, eps, lam2) == 0.0
    assert dls_damping(eps * (1 - 1e-8), eps, lam2) == pytest.approx(0.0, abs=1e-14)
    assert dls_damping(0.0, eps, lam2) == lam2
    # zero slope at the border: (1 - s^2/eps^2)^2 ~ (2 d/eps)^2 for s = eps - d
    slopes = [dls_damping(eps - delta, eps, lam2) / delta for delta in (1e-4, 1e-5)]
    assert slopes[0] == pytest.approx(4 * lam2 * 1e-4 / eps**2, rel=1e-3)
    assert slopes[1] == pytest.approx(slopes[0] / 10, rel=1e-3)
    # the inverse is continuous across the border
    below = damped_least_squares_inverse(jacobian_with([2.0, 1.0, eps - 1e-9])).matrix
    above = damped_least_squares_inverse(jacobian_with([2.0, 1.0, eps + 1e-9])).matrix
    assert np.allclose(below, above, atol=1e-6)


@SETTINGS
@given(near_singular, st.lists(st.floats(-1, 1), min_size=3, max_size=3).map(np.array))
def test_dls_error_is_confined_to_the_damped_direction(jacobian, command):
    result = damped_least_squares_inverse(jacobian)
    achieved = jacobian @ result.matrix @ command
    u, sigma, _ = np.linalg.svd(jacobian)
    if sigma[1] <= THESIS_EPSILON:
        return
    error = command - achieved
    # components along u1, u2 are exact; the u3 component is scaled by s^2 / (s^2 + lambda^2)
    assert np.allclose(u[:, :2].T @ error, 0.0, atol=1e-9)
    gain = sigma[2] ** 2 / (sigma[2] ** 2 + result.damping)
    assert u[:, 2] @ achieved == pytest.approx(gain * (u[:, 2] @ command), abs=1e-9)


@SETTINGS
@given(near_singular)
def test_sc_inverse_keeps_direction_and_scales_speed(jacobian):
    result = singularity_consistent_inverse(jacobian, gain=1.7)
    sigma = np.linalg.svd(jacobian, compute_uv=False)
    assert result.speed_scale == pytest.approx(1.7 * np.prod(sigma), abs=1e-12)
    # J J^SC = b prod(sigma) E: every commanded direction is reproduced, only the speed scales.
    assert np.allclose(jacobian @ result.matrix, result.speed_scale * np.eye(3), atol=1e-9)


def test_sc_inverse_through_a_singularity():
    command = np.array([0.0, -0.2, 0.0])
    speeds, joint_rates = [], []
    for sigma_min in (0.2, 0.05, 1e-3, 1e-6, 0.0):
        jacobian = jacobian_with([2.0, 1.0, sigma_min], seed=3)
        result = singularity_consistent_inverse(jacobian, gain=1.7)
        achieved = jacobian @ result.matrix @ command
        if sigma_min > 0.0:
            cosine = achieved @ command / (np.linalg.norm(achieved) * np.linalg.norm(command))
            assert cosine == pytest.approx(1.0, abs=1e-9)
        speeds.append(np.linalg.norm(achieved))
        joint_rates.append(np.linalg.norm(result.matrix @ command))
    assert speeds == sorted(speeds, reverse=True)  # the speed drops towards the singularity
    assert speeds[-1] == pytest.approx(0.0, abs=1e-12)
    assert max(joint_rates) < 1.7 * 2.0 * 1.0 * 0.2 + 1e-9  # bounded by b sigma1 sigma2 |w|


def test_sc_is_not_svd_filtering():
    """SC scales all directions alike; DLS only the damped one: their images differ near sigma=0."""
    jacobian = jacobian_with([2.0, 1.0, 0.05], seed=5)
    command = np.array([0.3, -0.2, 0.5])
    sc = jacobian @ singularity_consistent_inverse(jacobian).matrix @ command
    dls = jacobian @ damped_least_squares_inverse(jacobian).matrix @ command
    assert np.allclose(np.cross(sc, command), 0.0, atol=1e-12)  # parallel to the command
    assert np.linalg.norm(np.cross(dls, command)) > 1e-3  # DLS bends the direction


def test_inverses_reject_bad_input():
    with pytest.raises(InputError, match="finite"):
        pseudoinverse([[np.nan, 0.0, 1.0]])
    with pytest.raises(InputError, match="2-D"):
        damped_least_squares_inverse(np.ones(3))
    with pytest.raises(ConfigError, match="epsilon must be a finite number > 0"):
        damped_least_squares_inverse(np.eye(3), epsilon=0.0)
    with pytest.raises(ConfigError, match="lambda2_max"):
        damped_least_squares_inverse(np.eye(3), lambda2_max=-1.0)
    with pytest.raises(ConfigError, match="gain"):
        singularity_consistent_inverse(np.eye(3), gain=float("nan"))
