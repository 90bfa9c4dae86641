"""Generalized inverses for the restricted Jacobian (thesis section 4.3).

Three separate inverses, all through the SVD J = sum_i sigma_i u_i v_i^T (eq. 4.9):

* :func:`pseudoinverse` - Moore-Penrose, eq. (4.9); unbounded as sigma_min -> 0.
* :func:`damped_least_squares_inverse` - DLS with numerical filtering, eq. (4.10)-(4.12): damping
  only on the directions inside the singular region; bounded; errors in direction and speed.
* :func:`singularity_consistent_inverse` - the Singularity-Consistent inverse, eq. (4.13)-(4.14):
  J J^SC = b prod(sigma) E, so the achieved velocity keeps the commanded direction exactly and only
  the speed is scaled. It is *not* an SVD filter: it rescales every direction by the same factor.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rns_ros.core.errors import InputError
from rns_ros.core.fastmath import svd_small
from rns_ros.core.validation import as_matrix, positive

#: Thesis values, section 4.3.2: singular region epsilon [-], maximum damping lambda_max^2 [-],
#: SC gain b [-].
THESIS_EPSILON = 0.2
THESIS_LAMBDA2_MAX = 2.0
THESIS_SC_GAIN = 1.7
#: Smallest positive normal float: floor for relative thresholds when sigma_max is 0.
TINY = float(np.finfo(float).tiny)


class DampedInverse(NamedTuple):
    """Result of :func:`damped_least_squares_inverse` for J of shape (m, n).

    Attributes:
        matrix: J^# of eq. (4.11), shape (n, m).
        singular_values: sigma_1 >= ... >= sigma_m of J, shape (m,).
        damping: lambda^2 of eq. (4.12) applied to the smallest singular value [-].
    """

    matrix: np.ndarray
    singular_values: np.ndarray
    damping: float


class SingularityConsistentInverse(NamedTuple):
    """Result of :func:`singularity_consistent_inverse` for J of shape (m, n).

    Attributes:
        matrix: J^SC = b sum_i mu_i v_i u_i^T of eq. (4.13), shape (n, m).
        singular_values: sigma_1 >= ... >= sigma_m of J, shape (m,).
        speed_scale: b prod_i sigma_i = b sqrt(det(J J^T)): J J^SC = speed_scale E [-].
    """

    matrix: np.ndarray
    singular_values: np.ndarray
    speed_scale: float


class WideSvd(NamedTuple):
    """Thin SVD J = U diag(sigma) V^T of a wide J (m, n), m <= n.

    Attributes:
        u: left singular vectors, shape (m, m).
        sigma: singular values, descending, shape (m,).
        vt: right singular vectors V^T, shape (m, n).
    """

    u: np.ndarray
    sigma: np.ndarray
    vt: np.ndarray


def wide_svd(jacobian) -> WideSvd:
    """Thin SVD of a finite wide matrix (m, n), m <= n (one LAPACK call)."""
    jacobian = as_matrix(jacobian, "jacobian")
    if jacobian.shape[0] > jacobian.shape[1]:
        raise InputError(f"expected a wide matrix (m <= n), got shape {jacobian.shape}")
    return WideSvd(*svd_small(jacobian))


def kernel_basis(
    matrix, rank_tolerance: float, *, checked: bool = False
) -> tuple[np.ndarray, np.ndarray, int]:
    """Orthonormal basis of ker(A) from the SVD, with a relative rank decision.

    Args:
        matrix: A, shape (m, n).
        rank_tolerance: singular values <= rank_tolerance * sigma_max count as zero [-].
        checked: the caller guarantees a finite 2-D float array (skips the edge check).

    Returns:
        (basis (n, n - rank), singular values (min(m, n),) descending, rank).
    """
    if not checked:
        matrix = as_matrix(matrix, "matrix")
    if matrix.shape[0] <= matrix.shape[1]:
        _, sigma, vt = svd_small(matrix, full=True)
    else:
        _, sigma, vt = np.linalg.svd(matrix, full_matrices=True)
    rank = int((sigma > rank_tolerance * max(sigma[0], TINY)).sum())
    return vt[rank:].T, sigma, rank


def pseudoinverse(jacobian, rcond: float = 1e-12) -> np.ndarray:
    """Moore-Penrose pseudoinverse J^+ = sum_i (1/sigma_i) v_i u_i^T, eq. (4.9).

    Args:
        jacobian: J, shape (m, n).
        rcond: singular values below rcond * sigma_max are treated as zero [-].

    Returns:
        J^+, shape (n, m).
    """
    jacobian = as_matrix(jacobian, "jacobian")
    if jacobian.shape[0] > jacobian.shape[1]:
        return np.linalg.pinv(jacobian, rcond=rcond)
    return pseudoinverse_from_svd(wide_svd(jacobian), rcond)


def pseudoinverse_from_svd(svd: WideSvd, rcond: float = 1e-12) -> np.ndarray:
    """J^+ of eq. (4.9) from a precomputed :class:`WideSvd`, shape (n, m)."""
    u, sigma, vt = svd
    keep = sigma > rcond * max(sigma[0], TINY)
    inverse_sigma = np.where(keep, 1.0 / np.where(keep, sigma, 1.0), 0.0)
    return (vt.T * inverse_sigma) @ u.T


def dls_damping(sigma, epsilon: float, lambda2_max: float):
    """Damping lambda^2 of eq. (4.12) for a singular value sigma (float), or for each of an
    array of them (array of the same shape).

    lambda^2 = 0 for sigma > epsilon, else (1 - 2 sigma^2/eps^2 + sigma^4/eps^4) lambda2_max,
    i.e. (1 - (sigma/eps)^2)^2 lambda2_max: continuous with zero slope at sigma = epsilon.
    """
    damping = np.where(sigma > epsilon, 0.0, (1.0 - (sigma / epsilon) ** 2) ** 2 * lambda2_max)
    return float(damping) if np.ndim(damping) == 0 else damping


def damped_least_squares_inverse(
    jacobian,
    epsilon: float = THESIS_EPSILON,
    lambda2_max: float = THESIS_LAMBDA2_MAX,
) -> DampedInverse:
    """DLS inverse with numerical filtering, eq. (4.10)-(4.12).

    J^# = sum_{i<m} (1/sigma_i) v_i u_i^T + sigma_m / (sigma_m^2 + lambda^2) v_m u_m^T, damping
    only the minimum singular value. Where more than one singular value lies inside the singular
    region (not covered by the thesis), each is filtered the same way, so J^# stays bounded for
    any rank loss; with one value inside the region this is exactly eq. (4.11).

    Args:
        jacobian: J, shape (m, n), m <= n.
        epsilon: size of the singular region in sigma [-] (thesis 0.2).
        lambda2_max: maximum damping lambda_max^2 [-] (thesis 2).
    """
    epsilon = positive(epsilon, "epsilon")
    lambda2_max = positive(lambda2_max, "lambda2_max")
    return dls_from_svd(wide_svd(jacobian), epsilon, lambda2_max)


def dls_from_svd(svd: WideSvd, epsilon: float, lambda2_max: float) -> DampedInverse:
    """:func:`damped_least_squares_inverse` from a precomputed SVD (no argument checks)."""
    u, sigma, vt = svd
    damping = dls_damping(sigma, epsilon, lambda2_max)
    denominator = sigma**2 + damping
    # denominator is 0 only when sigma = 0 and lambda2_max = 0 (excluded by the checks)
    gains = sigma / np.where(denominator > 0.0, denominator, 1.0)
    return DampedInverse(
        matrix=(vt.T * gains) @ u.T, singular_values=sigma, damping=float(damping[-1])
    )


def singularity_consistent_inverse(
    jacobian, gain: float = THESIS_SC_GAIN
) -> SingularityConsistentInverse:
    """Singularity-Consistent inverse, eq. (4.13)-(4.14).

    J^SC = b sum_i mu_i v_i u_i^T with mu_i = prod_{j != i} sigma_j. Since J v_i = sigma_i u_i,
    J J^SC = b (prod_j sigma_j) E: the commanded direction is kept exactly, the speed is scaled by
    b sqrt(det(J J^T)). Near sigma_m -> 0 the term of v_m dominates instead of blowing up.

    Args:
        jacobian: J, shape (m, n), m <= n.
        gain: b of eq. (4.13) [-] (thesis 1.7).
    """
    gain = positive(gain, "gain")
    return sc_from_svd(wide_svd(jacobian), gain)


def sc_from_svd(svd: WideSvd, gain: float) -> SingularityConsistentInverse:
    """:func:`singularity_consistent_inverse` from a precomputed SVD (no argument checks)."""
    u, sigma, vt = svd
    # mu_i = prod_{j != i} sigma_j as prefix * suffix products (exact even when a sigma is 0)
    before = np.cumprod(np.concatenate(([1.0], sigma[:-1])))
    after = np.cumprod(np.concatenate(([1.0], sigma[:0:-1])))[::-1]
    mu = before * after
    return SingularityConsistentInverse(
        matrix=gain * (vt.T * mu) @ u.T,
        singular_values=sigma,
        speed_scale=gain * float(np.prod(sigma)),
    )
