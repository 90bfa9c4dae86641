"""Read-only arrays for the immutable run records of the analyses."""

from __future__ import annotations

import numpy as np


def read_only(array) -> np.ndarray:
    """A read-only float copy of ``array`` (the records own their arrays)."""
    array = np.array(array, dtype=float)
    array.setflags(write=False)
    return array


__all__ = ["read_only"]
