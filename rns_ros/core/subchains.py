"""Positioning / wrist subchain decomposition of reactionless motion (thesis section 4.1.2).

With theta = [theta_P; theta_W] (joint names from the model spec) the reactionless constraint reads
M~_P theta_dot_P + M~_W theta_dot_W = 0 (eq. 4.1). Every reactionless motion is then
theta_dot = [B; E] theta_dot_W + b [n; 0] (eq. 4.4): the predominant wrist motion (4.2) plus the
elbow motion along n(theta), the kernel of M~_P (4.3).

The split needs M~_P of full row rank. It loses rank where positioning joints line up, e.g. at the
straight arm theta = 0 where joints 1 and 3 are coaxial: there ker(M~_P) is two-dimensional and
nearby B(theta) can grow without bound; ``positioning_singular_values`` shows it coming.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rns_ros.core.errors import ModelError
from rns_ros.core.inverses import kernel_basis, pseudoinverse
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import as_vector


class SubchainDecomposition(NamedTuple):
    """Reactionless motion split by subchain, for p positioning and w wrist joints.

    Attributes:
        wrist_map: B = -M~_P^+ M~_W of eq. (4.2), shape (p, w) [-].
        elbow_null_vectors: orthonormal basis of ker(M~_P), shape (p, k); k = 1 for the default
            arm (p = 4, rank 3), its column is n(theta) of eq. (4.3), signed so that its
            last-positioning-joint (elbow) entry is >= 0.
        positioning_singular_values: singular values of M~_P, descending, shape (min(3, p),)
            [kg m^2]; the split is ill-conditioned when the smallest is near zero.
        positioning: indices of P in theta, shape (p,).
        wrist: indices of W in theta, shape (w,).
    """

    wrist_map: np.ndarray
    elbow_null_vectors: np.ndarray
    positioning_singular_values: np.ndarray
    positioning: np.ndarray
    wrist: np.ndarray

    def predominant_wrist_motion(self, wrist_velocity) -> np.ndarray:
        """theta_dot = [B theta_dot_W; theta_dot_W] of eq. (4.2) in theta order [rad/s], (n,)."""
        wrist_velocity = as_vector(wrist_velocity, self.wrist.size, "wrist_velocity")
        theta_dot = np.zeros(self.positioning.size + self.wrist.size)
        theta_dot[self.wrist] = wrist_velocity
        theta_dot[self.positioning] = self.wrist_map @ wrist_velocity
        return theta_dot

    def elbow_motion(self, speed: float) -> np.ndarray:
        """theta_dot = b [n; 0] of eq. (4.3) in theta order [rad/s], shape (n,).

        Uses the first kernel vector when ker(M~_P) has more than one dimension.
        """
        theta_dot = np.zeros(self.positioning.size + self.wrist.size)
        theta_dot[self.positioning] = float(speed) * self.elbow_null_vectors[:, 0]
        return theta_dot


def subchain_decomposition(
    robot: FreeFloatingModel, state: FreeFloatingState, rank_tolerance: float = 1e-9
) -> SubchainDecomposition:
    """Compute B(theta) and n(theta) of eq. (4.2)-(4.3) at ``state``.

    Raises:
        ModelError: the model spec names no subchains, or ker(M~_P) is empty.
    """
    if robot.subchains is None:
        raise ModelError(
            f"{robot.name}: no subchains configured; set positioning_joints and wrist_joints"
        )
    positioning, wrist = robot.subchains.positioning, robot.subchains.wrist
    coupling = state.coupling_angular_momentum_matrix
    coupling_p, coupling_w = coupling[:, positioning], coupling[:, wrist]
    wrist_map = -pseudoinverse(coupling_p) @ coupling_w
    kernel, sigma, rank = kernel_basis(coupling_p, rank_tolerance)
    if kernel.shape[1] == 0:
        raise ModelError(
            f"{robot.name}: the positioning subchain has no reactionless motion of its own "
            f"({positioning.size} joints, coupling rank {rank})"
        )
    elbow = kernel[-1]
    signs = np.where(elbow < 0.0, -1.0, 1.0)
    return SubchainDecomposition(
        wrist_map=wrist_map,
        elbow_null_vectors=kernel * signs,
        positioning_singular_values=sigma,
        positioning=positioning,
        wrist=wrist,
    )
