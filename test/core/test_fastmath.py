"""The private-gufunc fast paths agree with numpy's public functions and with identities."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.core.fastmath import (
    gram_determinant,
    solve_small,
    solve_small_many,
    svd_small,
    symmetric_eigenvalues,
)

matrices = st.lists(st.floats(-3.0, 3.0), min_size=21, max_size=21).map(
    lambda values: np.array(values).reshape(3, 7)
)


def test_fast_small_solve_matches_numpy():
    rng = np.random.default_rng(1)
    matrix = rng.standard_normal((6, 6)) + 6 * np.eye(6)
    rhs = rng.standard_normal(6)
    assert np.allclose(solve_small(matrix, rhs), np.linalg.solve(matrix, rhs), atol=1e-14)


@settings(max_examples=50, deadline=None)
@given(matrices)
def test_svd_reconstructs_and_matches_numpy(matrix):
    u, sigma, vt = svd_small(matrix)
    assert vt.shape == (3, 7)
    assert np.allclose((u * sigma) @ vt, matrix, atol=1e-12)
    assert np.allclose(vt @ vt.T, np.eye(3), atol=1e-12)
    assert np.allclose(sigma, np.linalg.svd(matrix, compute_uv=False), atol=1e-12)
    _, _, full = svd_small(matrix, full=True)
    assert full.shape == (7, 7)
    assert np.allclose(full @ full.T, np.eye(7), atol=1e-12)


@settings(max_examples=50, deadline=None)
@given(matrices)
def test_gram_determinant_is_the_product_of_squared_singular_values(matrix):
    expected = np.prod(np.linalg.svd(matrix, compute_uv=False) ** 2)
    assert gram_determinant(matrix) == pytest.approx(expected, rel=1e-9, abs=1e-9)


@settings(max_examples=50, deadline=None)
@given(matrices)
def test_many_rhs_solve_and_symmetric_eigenvalues_match_numpy(matrix):
    gram = matrix @ matrix.T + 1e-3 * np.eye(3)  # the Gram matrices of the controller
    solution = solve_small_many(gram, matrix)
    assert np.allclose(gram @ solution, matrix, atol=1e-9 * max(1.0, np.abs(matrix).max()))
    eigenvalues = symmetric_eigenvalues(gram)
    expected = np.linalg.svd(matrix, compute_uv=False)[::-1] ** 2 + 1e-3
    assert np.allclose(eigenvalues, expected, rtol=1e-10, atol=1e-12)
