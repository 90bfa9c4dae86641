"""The matrices the reactionless law (thesis eq. 4.5) is solved with.

On a full :class:`~rns_ros.core.state.FreeFloatingState`: the restricted Jacobian
J-bar = J_omega_e P_RNS and S = J-bar J-bar^T (:func:`restricted_jacobian`). On the partial state
:class:`~rns_ros.core.state.ArmKinematics`, without P_RNS: A = [J_omega_e; M~_omega_m / s] and
A A^T, whose inverse holds S^-1 as its upper-left block (:func:`stacked_jacobian`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from rns_ros.core.fastmath import symmetric_eigenvalues
from rns_ros.core.state import GRAM_CONDITION_LIMIT, ArmKinematics, FreeFloatingState


class RestrictedJacobian(NamedTuple):
    """J-bar = J_omega_e P_RNS of eq. (4.5) at one state and its Gram matrix.

    Attributes:
        angular: J_omega_e, the camera's angular rows [-], shape (3, n).
        projector: P_RNS [-], shape (n, n).
        matrix: J-bar [-], shape (3, n).
        gram: S = J-bar J-bar^T [-], shape (3, 3).
        sigma_min: smallest singular value of J-bar [-].
        determinant: det S, the algorithmic determinant of section 4.3.1 [-].
    """

    angular: np.ndarray
    projector: np.ndarray
    matrix: np.ndarray
    gram: np.ndarray
    sigma_min: float
    determinant: float


def restricted_jacobian(state: FreeFloatingState) -> RestrictedJacobian:
    """:class:`RestrictedJacobian` of ``state``; sigma(J-bar) from the eigenvalues of S."""
    j_omega = state.camera.jacobian[3:]
    projector = state.reaction_null_space_projector
    restricted = j_omega @ projector
    gram = restricted @ restricted.T
    eigenvalues = symmetric_eigenvalues(gram).tolist()  # sigma_i^2 of J-bar, ascending
    sigma_min = math.sqrt(max(eigenvalues[0], 0.0))
    return RestrictedJacobian(
        j_omega, projector, restricted, gram, sigma_min, math.prod(eigenvalues)
    )


class StackedJacobian(NamedTuple):
    """A = [J_omega_e; M~_omega_m / s] of an :class:`ArmKinematics` and its Gram matrix.

    The reactionless minimum-norm solutions are A^+ = A^T (A A^T)^-1: J-bar^+ omega =
    A^+ [omega; 0] and P_RNS (E - J-bar^+ J-bar) = E - A^+ A; the upper-left 3 x 3 block of
    (A A^T)^-1 is S^-1 (the Schur complement of M~ M~^T in A A^T), whose eigenvalues give
    sigma(J-bar). s only balances the rows.

    Attributes:
        matrix: A [-], shape (6, n).
        gram: A A^T [-], shape (6, 6).
        coupling_determinant: det(M~ M~^T) / s^6 [-].
        coupling_scale: s [kg m^2].
    """

    matrix: np.ndarray
    gram: np.ndarray
    coupling_determinant: float
    coupling_scale: float


def stacked_jacobian(arm: ArmKinematics, coupling_scale: float) -> StackedJacobian | None:
    """:class:`StackedJacobian` of ``arm`` with s = ``coupling_scale`` [kg m^2] (e.g. sigma_max
    of M~), or None where M~ is closer to a coupling singularity than GRAM_CONDITION_LIMIT."""
    stacked = np.concatenate((arm.camera_angular_jacobian, arm.coupling_angular_momentum_matrix))
    stacked[3:] *= 1.0 / coupling_scale
    gram = stacked @ stacked.T
    coupling_gram = gram[3:, 3:].tolist()
    coupling_determinant = determinant_3x3(coupling_gram)  # of M~ M~^T / s^6
    trace = coupling_gram[0][0] + coupling_gram[1][1] + coupling_gram[2][2]
    # lambda_min / lambda_max >= det / trace^3: enough to show M~ far from a coupling singularity
    if coupling_determinant <= GRAM_CONDITION_LIMIT**2 * trace**3:
        eigenvalues = symmetric_eigenvalues(gram[3:, 3:])
        if eigenvalues[0] <= GRAM_CONDITION_LIMIT**2 * eigenvalues[-1]:
            return None
    return StackedJacobian(stacked, gram, coupling_determinant, coupling_scale)


def determinant_3x3(matrix: list) -> float:
    """det of a symmetric 3 x 3 matrix given as nested lists (closed form)."""
    (a, b, c), (_, e, f), (_, _, i) = matrix
    return a * (e * i - f * f) - b * (b * i - f * c) + c * (b * f - e * c)
