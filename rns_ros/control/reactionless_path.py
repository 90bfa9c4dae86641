"""Reactionless elbow paths by arc length (thesis eqs. 4.3, 4.17-4.18; A-2.2).

The positioning joints move along d theta_P / d sigma = n(theta), n the unit vector spanning
ker M~_P_omega_m (the 3 x p block of M~_omega_m for the positioning joints; wrist held), kept
sign-continuous. Unlike eq. (4.17)'s theta_dot_4 / n_4 this has no singularity where n_4 = 0:
the path passes turning points of theta_4 smoothly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ModelError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import as_vector, positive


def positioning_null_vector(
    robot: FreeFloatingModel, theta: np.ndarray, data: pin.Data | None = None
) -> np.ndarray:
    """Unit n spanning ker M~_P_omega_m (eq. 4.3), shape (p,), sign arbitrary: the last right
    singular vector of the positioning columns of M~_omega_m (3 x p), on ``data`` (default
    ``robot.data``)."""
    if robot.subchains is None:
        raise ModelError(f"{robot.name}: reactionless paths need positioning/wrist subchains")
    q = robot.configuration(theta)
    centroidal = pin.computeCentroidalMap(robot.model, robot.data if data is None else data, q)
    block = centroidal[3:, 6:][:, robot.subchains.positioning]
    return np.linalg.svd(block)[2][-1]


class NullVector:
    """n(theta) of :func:`positioning_null_vector` on a private ``pin.Data``, sign-continuous."""

    def __init__(self, robot: FreeFloatingModel) -> None:
        if robot.subchains is None:
            raise ModelError(f"{robot.name}: reactionless paths need positioning/wrist subchains")
        self.robot = robot
        self.data = robot.model.createData()
        self.positioning = robot.subchains.positioning

    def __call__(self, theta: np.ndarray, reference: np.ndarray | None = None) -> np.ndarray:
        """Unit n, shape (p,), signed so that n . reference >= 0 (sign continuity)."""
        n = positioning_null_vector(self.robot, theta, self.data)
        if reference is not None and n @ reference < 0.0:
            n = -n
        return n


@dataclass(frozen=True)
class ReactionlessPath:
    """A reactionless elbow path by arc length (eqs. 4.3, 4.17-4.18; A-2.2).

    Attributes:
        arc: arc length of the nodes [rad], shape (m,), from 0 (the start).
        theta: configurations at the nodes [rad], shape (m, n) (wrist constant).
        tangent: unit d theta / d sigma at the nodes (zero on the wrist), shape (m, n).
        reached: theta_4 reached the target.
        turning_points: theta_4 where n_4 changed sign along the followed path [rad].
        min_n4: smallest |n_4| on the path [-].
        turn_kinks: |change of the unit tangent| over the step of each turning point [-]: ~step
            at a smooth turning point; O(1) where the path grazes a rank drop of M~_P_omega_m
            (sigma_3 -> 0) and n(theta) swings within one step.
    """

    arc: np.ndarray
    theta: np.ndarray
    tangent: np.ndarray
    reached: bool
    turning_points: tuple[float, ...]
    min_n4: float
    turn_kinks: tuple[float, ...] = ()

    @property
    def length(self) -> float:
        """Total arc length L [rad]."""
        return float(self.arc[-1])

    @property
    def end(self) -> np.ndarray:
        """Last configuration [rad], shape (n,)."""
        return self.theta[-1]

    def at(self, sigma: float) -> tuple[np.ndarray, np.ndarray]:
        """theta(sigma) by cubic Hermite interpolation of the nodes, and the interpolated tangent.

        Returns:
            (theta [rad] (n,), unit-ish tangent d theta / d sigma (n,)).
        """
        sigma = min(max(sigma, 0.0), self.length)
        k = int(np.clip(np.searchsorted(self.arc, sigma, side="right") - 1, 0, self.arc.size - 2))
        h = self.arc[k + 1] - self.arc[k]
        if h <= 0.0:
            return self.theta[k].copy(), self.tangent[k].copy()
        u = (sigma - self.arc[k]) / h
        p0, p1, m0, m1 = self.theta[k], self.theta[k + 1], self.tangent[k], self.tangent[k + 1]
        h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
        h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
        theta = h00 * p0 + h10 * h * m0 + h01 * p1 + h11 * h * m1
        d00, d10 = (6 * u**2 - 6 * u) / h, 3 * u**2 - 4 * u + 1
        d01, d11 = (-6 * u**2 + 6 * u) / h, 3 * u**2 - 2 * u
        tangent = d00 * p0 + d10 * m0 + d01 * p1 + d11 * m1
        return theta, tangent


def reactionless_path(
    robot: FreeFloatingModel,
    theta0,
    theta4_target: float,
    *,
    step: float = 0.01,
    max_arc: float = 12.0,
    stop_at_turning_point: bool = True,
) -> ReactionlessPath:
    """Follow the reactionless elbow family from ``theta0`` towards theta_4 = ``theta4_target``.

    d theta_P / d sigma = n(theta) (unit, sign-continuous), integrated with RK4 in arc length
    sigma [rad] (``step``); the wrist is held. The direction starts with n_4 towards the target.
    Stops where theta_4 crosses the target (the last node is interpolated onto it), after
    ``max_arc`` [rad], or, with ``stop_at_turning_point``, at the first point where n_4 changes
    sign (theta_4 turns back away from the target; the node is interpolated to n_4 = 0).

    Raises:
        InputError: ``theta0`` is not a finite vector of the model's size.
    """
    theta = as_vector(theta0, robot.n, "theta0").copy()
    step = positive(step, "path step", "[rad]")
    null = NullVector(robot)
    p = null.positioning
    elbow = int(np.flatnonzero(p == p[-1])[0])  # index of the elbow (last positioning joint)
    sense = 1.0 if theta4_target >= theta[p[-1]] else -1.0
    n = null(theta)
    if n[elbow] * sense < 0.0:
        n = -n

    def tangent(vector: np.ndarray) -> np.ndarray:
        full = np.zeros(robot.n)
        full[p] = vector
        return full

    arcs, thetas, tangents = [0.0], [theta.copy()], [tangent(n)]
    turning, kinks, min_n4, reached, arc = [], [], abs(float(n[elbow])), False, 0.0
    while arc < max_arc - 1e-12:
        h = min(step, max_arc - arc)
        new, n_new = _rk4_step(null, theta, n, h, p)
        min_n4 = min(min_n4, abs(float(n_new[elbow])))
        elbow_before, elbow_after = theta[p[-1]], new[p[-1]]
        if (elbow_after - theta4_target) * sense >= 0.0:
            fraction = (theta4_target - elbow_before) / (elbow_after - elbow_before)
            new, n_new, h, reached = _refine(null, theta, n, h, fraction, p)
            arcs.append(arc + h)
            thetas.append(new)
            tangents.append(tangent(n_new))
            break
        if n_new[elbow] * n[elbow] < 0.0:
            fraction = n[elbow] / (n[elbow] - n_new[elbow])
            turn, n_turn, h_turn, _ = _refine(null, theta, n, h, fraction, p)
            turning.append(float(turn[p[-1]]))
            kinks.append(float(np.linalg.norm(n_new - n)))
            if stop_at_turning_point and n[elbow] * sense > 0.0:
                arcs.append(arc + h_turn)
                thetas.append(turn)
                tangents.append(tangent(n_turn))
                break
        arc += h
        theta, n = new, n_new
        arcs.append(arc)
        thetas.append(theta.copy())
        tangents.append(tangent(n))
    return ReactionlessPath(
        arc=np.array(arcs),
        theta=np.array(thetas),
        tangent=np.array(tangents),
        reached=reached,
        turning_points=tuple(turning),
        min_n4=min_n4,
        turn_kinks=tuple(kinks),
    )


def _rk4_step(null: NullVector, theta, n, h, p) -> tuple[np.ndarray, np.ndarray]:
    """One RK4 step of arc length ``h`` [rad] along d theta_P / d sigma = n(theta) from
    (theta, n): (theta [rad] (n_joints,), unit n at it, sign-continuous)."""
    k1 = n
    x = theta.copy()
    x[p] += 0.5 * h * k1
    k2 = null(x, k1)
    x = theta.copy()
    x[p] += 0.5 * h * k2
    k3 = null(x, k2)
    x = theta.copy()
    x[p] += h * k3
    k4 = null(x, k3)
    new = theta.copy()
    new[p] += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return new, null(new, k4)


def _refine(null: NullVector, theta, n, h, fraction, p):
    """One RK4 step of length ``fraction * h`` from (theta, n): (theta, n, length, True)."""
    h = float(np.clip(fraction, 0.0, 1.0)) * h
    new, n_new = _rk4_step(null, theta, n, h, p)
    return new, n_new, h, True
