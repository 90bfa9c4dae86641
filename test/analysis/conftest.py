"""Shared reference of the C_ratio map tests: the Pinocchio value and an accurate one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.core.energy import WHEEL_INERTIA, c_ratio, energy_metric
from rns_ros.core.state import FreeFloatingState


def _c_ratio_reference(model, theta, joints=None):
    """(C_ratio of core.energy, cond(Lambda), an independent accurate C_ratio) at theta."""
    state = FreeFloatingState.compute(model, model.configuration(theta))
    joints = np.arange(model.n) if joints is None else joints
    metric = energy_metric(state, WHEEL_INERTIA, joints)
    coupling = state.coupling_angular_momentum_matrix[:, joints]
    eigenvalues = np.linalg.eigvalsh(metric.total)
    # sigma_min(Lambda) as the squared smallest singular value of [chol(M~_m)^T; G / sqrt(I_r)]:
    # no assembled Lambda, so accurate to ~eps sqrt(cond) instead of eps cond
    stacked = np.vstack(
        (np.linalg.cholesky(metric.manipulator).T, coupling / math.sqrt(WHEEL_INERTIA))
    )
    t_min = np.linalg.svd(stacked, compute_uv=False)[-1] ** 2
    kernel = np.linalg.svd(coupling)[2][-1]
    accurate = kernel @ metric.manipulator @ kernel / t_min
    return c_ratio(metric, coupling), eigenvalues[-1] / eigenvalues[0], accurate


@pytest.fixture(scope="session")
def reference_c_ratio():
    """(model, theta, joints=None) -> (C_ratio of core.energy, cond(Lambda), accurate C_ratio)."""
    return _c_ratio_reference
