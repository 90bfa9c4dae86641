"""Small dense solves and SVDs without numpy's per-call wrapper overhead (hot paths).

``np.linalg.solve`` spends most of its ~7 us on a 6x6 system in Python-level checks. The gufunc
behind it, ``numpy.linalg._umath_linalg.solve1``, does the same LAPACK solve in ~2 us. It is a
private numpy API (numpy is pinned exactly in requirements.txt), so it is looked up once with a
fallback to the public function, and a test checks both agree. Use it only where the matrix is
known to be well conditioned (it does not raise LinAlgError on a singular matrix). The SVD
gufuncs (``svd_s``, ``svd_f``), the many-right-hand-side solve (``solve``), the inverse (``inv``)
and the symmetric eigenvalues (``eigvalsh_lo``) are used the same way: same LAPACK routines as
``np.linalg``, about half the call time on the 3 x 3 to 6 x 7 matrices of the controller.
"""

from __future__ import annotations

import numpy as np

try:  # pragma: no branch - depends on the numpy build
    from numpy.linalg import _umath_linalg

    _SOLVE1 = getattr(_umath_linalg, "solve1", None)
    _SOLVE = getattr(_umath_linalg, "solve", None)
    _SVD_THIN = getattr(_umath_linalg, "svd_s", None)
    _SVD_FULL = getattr(_umath_linalg, "svd_f", None)
    _EIGVALSH = getattr(_umath_linalg, "eigvalsh_lo", None)
    _INV = getattr(_umath_linalg, "inv", None)
except ImportError:  # pragma: no cover
    _SOLVE1 = _SOLVE = _SVD_THIN = _SVD_FULL = _EIGVALSH = _INV = None


def solve_small(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with matrix @ x = rhs for a square, well-conditioned ``matrix`` (k, k) and rhs (k,)."""
    if _SOLVE1 is None:
        return np.linalg.solve(matrix, rhs)
    return _SOLVE1(matrix, rhs)


def solve_small_many(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """X with matrix @ X = rhs for a square, well-conditioned ``matrix`` (k, k), rhs (k, m)."""
    if _SOLVE is None:
        return np.linalg.solve(matrix, rhs)
    return _SOLVE(matrix, rhs)


def inverse_small(matrix: np.ndarray) -> np.ndarray:
    """matrix^-1 of a square, well-conditioned ``matrix`` (k, k), for when blocks of the inverse
    are needed (the Schur complement of the controller's midpoint law)."""
    if _INV is None:
        return np.linalg.inv(matrix)
    return _INV(matrix)


def symmetric_eigenvalues(matrix: np.ndarray) -> np.ndarray:
    """Eigenvalues of a finite symmetric matrix (k, k), ascending, shape (k,) (LAPACK syevd on
    the lower triangle, like ``np.linalg.eigvalsh``)."""
    if _EIGVALSH is None:
        return np.linalg.eigvalsh(matrix)
    return _EIGVALSH(matrix)


def svd_small(matrix: np.ndarray, full: bool = False):
    """(U, sigma, V^T) of a finite matrix (m, n), m <= n: U (m, m), sigma (m,) descending,
    V^T (m, n) thin or (n, n) with ``full``. Raises LinAlgError if LAPACK does not converge."""
    gufunc = _SVD_FULL if full else _SVD_THIN
    if gufunc is not None:
        u, sigma, vt = gufunc(matrix)
        if sigma[-1] >= 0.0:  # False for the NaNs of a LAPACK failure
            return u, sigma, vt
    return np.linalg.svd(matrix, full_matrices=full)  # raises LinAlgError on failure


def gram_determinant(matrix: np.ndarray) -> float:
    """det(A A^T) of a (3, n) matrix by the closed-form 3 x 3 determinant (no LAPACK call)."""
    (a, b, c), (_, e, f), (_, _, i) = (matrix @ matrix.T).tolist()
    # symmetric Gram matrix [[a b c] [b e f] [c f i]]
    return a * (e * i - f * f) - b * (b * i - f * c) + c * (b * f - e * c)


def has_fast_solve() -> bool:
    """True when the private gufunc is in use (reported by the benchmark)."""
    return _SOLVE1 is not None
