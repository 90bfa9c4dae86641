r"""Chapter-5 maps of the motion-equivalence ratio C_ratio (eq. 5.5) over joint space, batched.

C_ratio = (n^T Lambda_m n) / sigma_min(Lambda) >= 1 with Lambda = Lambda_m + M~_omega_m^T
M~_omega_m / I_r (5.3), n the unit kernel vector of M~_omega_m: the same numbers as
:func:`rns_ros.core.energy.c_ratio`, on whole grids. The planar 2-DoF maps of Figs. 5.1-5.2 are
here; the spatial subchain of Fig. 5.3: :mod:`rns_ros.analysis.chain_energy_maps`. Method, rank
rule and wheels (A-3.1): docs/chapter5.md, "How the maps are computed".
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from rns_ros.analysis.planar_field import PlanarArm
from rns_ros.core.energy import WHEEL_INERTIA, EnergyMetric, c_ratio
from rns_ros.core.errors import ConfigError

#: Mass of one reaction wheel [kg] (thesis section 5.2); added at the base CoM (A-3.1).
WHEEL_MASS = 10.0
#: Planar model of section 5.2: r [m], base mass incl. one wheel [kg], link inertia [kg m^2].
PLANAR_ATTACH_DISTANCE = 0.945
PLANAR_BASE_MASS = 1000.0 + WHEEL_MASS
PLANAR_LINK_INERTIA = 8.3
#: |cofactor vector| <= this * |M~_omega_m|_F^(k-1): recompute the point with the reference.
CANDIDATE_RANK_LOSS = 1e-6
#: Relative singular-value threshold of the kernel in the reference (as core.energy.c_ratio).
RANK_TOLERANCE = 1e-9


def periodic_grid(count: int, start: float = -math.pi, span: float = 2.0 * math.pi) -> np.ndarray:
    """start + span k / count, k = 0..count-1 [rad], shape (count,) (choice A-3.2: the end point
    start + span is the same angle as start and is left out)."""
    if count < 1:
        raise ConfigError(f"a grid needs at least one point, got {count}")
    return start + span * np.arange(count) / count


# --- the ratio from M~_m and M~_omega_m, batched ------------------------------------------------
def _kernel_vectors(coupling: np.ndarray) -> np.ndarray:
    """Cofactor vector of each (k-1, k) matrix (generalized cross product), shape (..., k).

    It spans the kernel when the rank is k - 1 and its norm is the product of the singular values.
    """
    rows, k = coupling.shape[-2:]
    if rows != k - 1:
        raise ConfigError(f"M~_omega_m must be (k - 1, k) for a 1-D kernel, got {(rows, k)}")
    if k == 2:
        return np.stack([-coupling[..., 0, 1], coupling[..., 0, 0]], -1)
    if k == 4:
        g = coupling
        # 2x2 minors of rows 1, 2 for column pairs (a, b)
        minor = {
            (a, b): g[..., 1, a] * g[..., 2, b] - g[..., 1, b] * g[..., 2, a]
            for a in range(4)
            for b in range(a + 1, 4)
        }
        out = np.empty((*coupling.shape[:-2], 4))
        for j in range(4):
            a, b, c = (col for col in range(4) if col != j)
            det = (
                g[..., 0, a] * minor[b, c] - g[..., 0, b] * minor[a, c] + g[..., 0, c] * minor[a, b]
            )
            out[..., j] = det if j % 2 == 0 else -det
        return out
    out = np.empty((*coupling.shape[:-2], k))
    for j in range(k):
        out[..., j] = (-1) ** j * np.linalg.det(np.delete(coupling, j, axis=-1))
    return out


def _cholesky_solve(chol: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with L L^T x = rhs for lower-triangular L (N, k, k) and rhs (N, k)."""
    k = rhs.shape[-1]
    y = np.empty_like(rhs)
    for i in range(k):
        partial = np.einsum("nj,nj->n", chol[:, i, :i], y[:, :i])
        y[:, i] = (rhs[:, i] - partial) / chol[:, i, i]
    x = np.empty_like(rhs)
    for i in range(k - 1, -1, -1):
        partial = np.einsum("nj,nj->n", chol[:, i + 1 :, i], x[:, i + 1 :])
        x[:, i] = (y[:, i] - partial) / chol[:, i, i]
    return x


def _rayleigh(vector, tilde_inertia, coupling, wheel_inertia) -> np.ndarray:
    """v^T Lambda v / v^T v [kg m^2], (N,), evaluated as v^T M~_m v + |M~_omega_m v|^2 / I_r: two
    non-negative terms and no assembled Lambda, so its relative accuracy stays near machine
    epsilon."""
    moved = np.einsum("nij,nj->ni", coupling, vector)
    quadratic = np.einsum("ni,nij,nj->n", vector, tilde_inertia, vector)
    wheels = np.einsum("ni,ni->n", moved, moved) / wheel_inertia
    return (quadratic + wheels) / np.einsum("ni,ni->n", vector, vector)


def smallest_eigenvalue(
    tilde_inertia: np.ndarray,
    coupling: np.ndarray,
    wheel_inertia: float,
    start: np.ndarray,
    *,
    shift: float = 1e-4,
    steps: int = 2,
) -> np.ndarray:
    """sigma_min(Lambda) of eq. (5.4) [kg m^2], shape (N,), to near machine precision.

    LAPACK's eigenvalue of the assembled Lambda = M~_m + M~_omega_m^T M~_omega_m / I_r is only
    accurate to ~eps cond(Lambda) relative (cond up to ~1e7 on the 4-DoF arm: errors ~1e-9). So
    that estimate is used as the shift of inverse iteration, (Lambda - (1 - shift) sigma E)^-1,
    started from the reactionless direction ``start`` (N, k): each step shrinks the other
    eigen-directions by < ``shift``, and the Rayleigh quotient of :func:`_rayleigh` (no
    cancellation, error quadratic in the direction's) gives the eigenvalue. Points where that
    fails (factorization or a quotient above the estimate) keep the LAPACK value.

    Args:
        tilde_inertia: M~_m, (N, k, k); coupling: M~_omega_m, (N, k - 1, k) [kg m^2].
        wheel_inertia: I_r [kg m^2].
    """
    lam = tilde_inertia + np.einsum("nai,naj->nij", coupling, coupling) / wheel_inertia
    estimate = np.linalg.eigvalsh(lam)[:, 0]
    shifted = lam.copy()
    diagonal = np.einsum("nii->ni", shifted)  # a writable view of the diagonals
    diagonal -= ((1.0 - shift) * estimate)[:, None]
    try:
        chol = np.linalg.cholesky(shifted)
    except np.linalg.LinAlgError:  # pragma: no cover - needs cond(Lambda) ~ shift / eps
        return estimate
    vector = np.array(start, dtype=float)
    for _ in range(steps):
        vector = _cholesky_solve(chol, vector)
        vector /= np.linalg.norm(vector, axis=-1, keepdims=True)
    value = _rayleigh(vector, tilde_inertia, coupling, wheel_inertia)
    return np.where(value <= estimate * (1.0 + 1e-6), value, estimate)


def c_ratio_batch(
    tilde_inertia: np.ndarray, coupling: np.ndarray, wheel_inertia: float = WHEEL_INERTIA
) -> np.ndarray:
    """C_ratio of eq. (5.5) for a batch of points [-], >= 1.

    T_RNS = n^T M~_m n / n^T n with n the cofactor (kernel) vector of M~_omega_m, and
    T_min = :func:`smallest_eigenvalue` (both per unit joint speed, the 1/2 cancels).

    Args:
        tilde_inertia: Lambda_m = M~_m [kg m^2], shape (..., k, k), symmetric positive definite.
        coupling: M~_omega_m [kg m^2], shape (..., k - 1, k): its nonzero rows (the planar arm's
            z row, shape (..., 1, 2); the spatial subchain's three rows, (..., 3, 4)).
        wheel_inertia: I_r [kg m^2].

    Returns:
        C_ratio, shape (...). Equal to :func:`rns_ros.core.energy.c_ratio`, which is used for the
        points where M~_omega_m may have lost rank (same rank rule).
    """
    coupling = np.asarray(coupling, dtype=float)
    shape, (rows, k) = coupling.shape[:-2], coupling.shape[-2:]
    tilde_inertia = np.broadcast_to(np.asarray(tilde_inertia, dtype=float), (*shape, k, k))
    tilde_inertia = tilde_inertia.reshape(-1, k, k)
    coupling = coupling.reshape(-1, rows, k)
    kernel = _kernel_vectors(coupling)
    norm = np.linalg.norm(kernel, axis=-1)
    scale = np.sqrt(np.einsum("nij,nij->n", coupling, coupling))
    suspect = ~(norm > CANDIDATE_RANK_LOSS * scale ** (k - 1))  # also catches NaN
    kernel[suspect] = 1.0  # any start vector; these points are redone below
    unit = kernel / np.linalg.norm(kernel, axis=-1, keepdims=True)
    t_rns = np.einsum("ni,nij,nj->n", unit, tilde_inertia, unit)
    t_min = smallest_eigenvalue(tilde_inertia, coupling, wheel_inertia, unit)
    ratio = t_rns / t_min
    for index in np.flatnonzero(suspect):
        g = coupling[index]
        metric = EnergyMetric(tilde_inertia[index], g.T @ g / wheel_inertia)
        ratio[index] = c_ratio(metric, g, RANK_TOLERANCE)
    return ratio.reshape(shape)


# --- planar 2-DoF arm (Figs. 5.1, 5.2) ----------------------------------------------------------
def planar_arm(alpha: float = 1.0, beta: float = 1.0, *, scale_inertia: bool = False) -> PlanarArm:
    """The section-5.2 planar arm with the parameter variation of eqs. (5.6)-(5.7).

    alpha scales both link masses (m_i* = alpha m_i, eq. 5.6); with ``scale_inertia`` also both
    link inertias about their CoM (I_i* = alpha I_i, uniform density: thesis_rest's reading
    A-3.3, which the equation does not state). beta scales both CoM distances
    (l_ci* = beta l_i / 2, eq. 5.7); the link lengths (joint positions) stay 1 m. Base 1010 kg
    (1000 kg + one 10 kg wheel at its CoM).
    """
    inertia = PLANAR_LINK_INERTIA * (alpha if scale_inertia else 1.0)
    return PlanarArm(
        attach_distance=PLANAR_ATTACH_DISTANCE,
        base_mass=PLANAR_BASE_MASS,
        link_masses=(100.0 * alpha, 100.0 * alpha),
        link_inertias=(inertia, inertia),
        com_distances=(0.5 * beta, 0.5 * beta),
    )


def planar_c_ratio(arm: PlanarArm, theta, wheel_inertia: float = WHEEL_INERTIA) -> np.ndarray:
    """C_ratio (5.5) of the planar arm at joint angles ``theta`` [rad], shape (..., 2) -> (...)."""
    coupling = arm.coupling_inertia(theta)[..., None, :]  # (..., 1, 2), the z row
    return c_ratio_batch(arm.manipulator_inertia(theta), coupling, wheel_inertia)


def planar_c_ratio_map(
    arm: PlanarArm | None = None, count: int = 100, wheel_inertia: float = WHEEL_INERTIA
) -> tuple[np.ndarray, np.ndarray]:
    """C_ratio on the periodic count x count grid of (theta_1, theta_2) (Fig. 5.1).

    Returns:
        (grid [rad] (count,), C_ratio (count, count) indexed [theta_2, theta_1], rows theta_2).
    """
    arm = planar_arm() if arm is None else arm
    grid = periodic_grid(count)
    t1, t2 = np.meshgrid(grid, grid)
    return grid, planar_c_ratio(arm, np.stack([t1, t2], -1), wheel_inertia)


def parameter_variation_map(
    alphas: Sequence[float],
    betas: Sequence[float],
    count: int = 100,
    *,
    scale_inertia: bool = False,
) -> np.ndarray:
    """Mean C_ratio over the count^2 mesh for each (alpha, beta) of eqs. (5.6)-(5.7) (Fig. 5.2);
    ``scale_inertia`` as in :func:`planar_arm`.

    Returns:
        shape (len(alphas), len(betas)), [-].
    """
    return np.array(
        [
            [
                float(
                    planar_c_ratio_map(planar_arm(a, b, scale_inertia=scale_inertia), count)[
                        1
                    ].mean()
                )
                for b in betas
            ]
            for a in alphas
        ]
    )


@dataclass(frozen=True)
class MapSummary:
    """Statistics of a C_ratio map [-] and the time it took [s]."""

    mean: float
    median: float
    p99: float
    maximum: float
    minimum: float
    points: int
    wall_s: float

    @classmethod
    def of(cls, values: np.ndarray, wall_s: float = 0.0) -> MapSummary:
        flat = np.asarray(values).ravel()
        return cls(
            mean=float(flat.mean()),
            median=float(np.median(flat)),
            p99=float(np.percentile(flat, 99.0)),
            maximum=float(flat.max()),
            minimum=float(flat.min()),
            points=int(flat.size),
            wall_s=float(wall_s),
        )

    def timed(self, wall_s: float) -> MapSummary:
        return replace(self, wall_s=float(wall_s))
