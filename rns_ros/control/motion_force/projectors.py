"""Rank-aware solves and the null-space projectors P_J (7.2) and P_hat_RNS (7.3)."""

from __future__ import annotations

import numpy as np

#: Relative rank threshold of the projectors and of the J W^T solve [-].
DEFAULT_RCOND = 1e-10


def svd_solve(matrix: np.ndarray, rhs: np.ndarray, rcond: float):
    """x with matrix x = rhs (square solve; minimum-norm least squares when rank-deficient),
    plus (sigma_min, sigma_max)."""
    sigma = np.linalg.svd(matrix, compute_uv=False)
    if sigma[-1] > rcond * sigma[0]:
        return np.linalg.solve(matrix, rhs), sigma[-1], sigma[0]
    return np.linalg.lstsq(matrix, rhs, rcond=rcond)[0], sigma[-1], sigma[0]


def kernel_projector(matrix, rcond: float = DEFAULT_RCOND) -> np.ndarray:
    """Orthogonal projector onto ker(A): E - A^+ A from the SVD, (n, n).

    With A = W it is P_hat_RNS of (7.3)/(7.14); with A = J it is P_J of (7.2).
    Singular values <= rcond * sigma_max [-] count as zero.
    """
    matrix = np.asarray(matrix, dtype=float)
    _, sigma, vt = np.linalg.svd(matrix, full_matrices=True)
    rank = int((sigma > rcond * max(sigma[0], 1e-300)).sum())
    row_space = vt[:rank]
    return np.eye(matrix.shape[1]) - row_space.T @ row_space


__all__ = ["DEFAULT_RCOND", "kernel_projector", "svd_solve"]
