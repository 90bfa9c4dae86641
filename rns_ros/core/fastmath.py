"""Small dense solves without numpy's per-call wrapper overhead (simulator hot path).

``np.linalg.solve`` spends most of its ~7 us on a 6x6 system in Python-level checks. The gufunc
behind it, ``numpy.linalg._umath_linalg.solve1``, does the same LAPACK solve in ~2 us. It is a
private numpy API (numpy is pinned exactly in requirements.txt), so it is looked up once with a
fallback to the public function, and a test checks both agree. Use it only where the matrix is
known to be well conditioned (it does not raise LinAlgError on a singular matrix).
"""

from __future__ import annotations

import numpy as np

try:  # pragma: no branch - depends on the numpy build
    from numpy.linalg import _umath_linalg

    _SOLVE1 = getattr(_umath_linalg, "solve1", None)
except ImportError:  # pragma: no cover
    _SOLVE1 = None


def solve_small(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with matrix @ x = rhs for a square, well-conditioned ``matrix`` (k, k) and rhs (k,)."""
    if _SOLVE1 is None:
        return np.linalg.solve(matrix, rhs)
    return _SOLVE1(matrix, rhs)


def has_fast_solve() -> bool:
    """True when the private gufunc is in use (reported by the benchmark)."""
    return _SOLVE1 is not None
