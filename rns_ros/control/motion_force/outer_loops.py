"""The outer loops of the motion/force controllers: motion (6.33) and force (6.34)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.validation import as_vector


def parse_gain(value, name: str, unit: str, *, allow_zero: bool = False) -> float:
    """``value`` as a finite gain > 0 (>= 0 with ``allow_zero``), or ConfigError naming it."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number {unit}, got {value!r}") from None
    if not np.isfinite(number) or number < 0.0 or (number == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ConfigError(f"{name} must be a finite number {bound} {unit}, got {value!r}")
    return number


@dataclass(frozen=True)
class MotionGains:
    """Gains of the motion loop (6.33).

    Attributes:
        k_p: position gain [1/s^2] (thesis: 100). k_d: velocity gain [1/s] (thesis: 10).
    """

    k_p: float = 100.0
    k_d: float = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "k_p", parse_gain(self.k_p, "k_p", "[1/s^2]"))
        object.__setattr__(self, "k_d", parse_gain(self.k_d, "k_d", "[1/s]"))


@dataclass(frozen=True)
class ForceGains:
    """Gain of the force loop (6.34): k_f [-] (thesis: 5; 0 = pure feed-forward)."""

    k_f: float = 5.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "k_f", parse_gain(self.k_f, "k_f", "[-]", allow_zero=True))


def motion_loop(gains: MotionGains, nu_dot_des, nu_des, nu, pose_error) -> np.ndarray:
    """Task acceleration reference of eq. (6.33) (the print shows v on the left; it is an
    acceleration): nu_dot_ref = nu_dot_des + k_d (nu_des - nu) + k_p (x_des - x).

    Args:
        gains: :class:`MotionGains`.
        nu_dot_des [m/s^2 | rad/s^2], nu_des [m/s | rad/s], nu: desired acceleration and velocity,
            measured velocity, all in task coordinates, shape (m,).
        pose_error: x_des - x in task coordinates [m | rad], shape (m,)
            (:meth:`TaskSpace.pose_error`).

    Returns:
        nu_dot_ref, shape (m,). The controllers keep only its motion-direction part S nu_dot_ref.
    """
    nu_dot_des = np.asarray(nu_dot_des, dtype=float)
    size = nu_dot_des.shape[0] if nu_dot_des.ndim == 1 else -1
    if size < 1:
        raise InputError(f"nu_dot_des must be a vector, got shape {nu_dot_des.shape}")
    nu_dot_des = as_vector(nu_dot_des, size, "nu_dot_des")
    nu_des = as_vector(nu_des, size, "nu_des")
    nu = as_vector(nu, size, "nu")
    pose_error = as_vector(pose_error, size, "pose_error")
    return nu_dot_des + gains.k_d * (nu_des - nu) + gains.k_p * pose_error


def force_loop(gains: ForceGains, f_des, f) -> np.ndarray:
    """Force reference of eq. (6.34): f_ref = f_des + k_f (f_des - f) [N], shape (k,).

    f_des and the measured f are forces the EE exerts on the environment along the contact
    normal(s) [A-4.1], shape (k,).
    """
    f_des = np.atleast_1d(np.asarray(f_des, dtype=float))
    f_des = as_vector(f_des, f_des.shape[0], "f_des")
    f = as_vector(np.atleast_1d(np.asarray(f, dtype=float)), f_des.shape[0], "f")
    return f_des + gains.k_f * (f_des - f)


__all__ = ["ForceGains", "MotionGains", "force_loop", "motion_loop", "parse_gain"]
