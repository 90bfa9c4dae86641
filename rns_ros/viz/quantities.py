"""What the rerun logger plots, computed from plain arrays (no rclpy, no rerun).

The node converts messages to numpy arrays; these functions turn them into the plotted quantities,
so every number in a recording can be tested without DDS or a viewer.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import as_vector


def roll_pitch_yaw(rotation: np.ndarray) -> np.ndarray:
    """(roll, pitch, yaw) [rad] with rotation = Rz(yaw) Ry(pitch) Rx(roll), shape (3,).

    pitch is in [-pi/2, pi/2]; roll and yaw in [-pi, pi].
    """
    return np.asarray(pin.rpy.matrixToRpy(np.asarray(rotation, dtype=float)), dtype=float)


class AttitudeDeviation:
    """Base attitude relative to the first rotation it is given (the thesis' Δφ).

    ``deviation(R)`` returns (roll, pitch, yaw, total) [deg] of R_0^T R, total being the rotation
    angle |log(R_0^T R)|; the first call sets R_0 and returns zeros.
    """

    def __init__(self) -> None:
        self.reference: np.ndarray | None = None

    def __call__(self, rotation: np.ndarray) -> np.ndarray:
        if self.reference is None:
            self.reference = np.array(rotation, dtype=float)
        relative = self.reference.T @ rotation
        total = float(np.linalg.norm(pin.log3(relative)))
        return np.degrees(np.append(roll_pitch_yaw(relative), total))


def achieved_angular_velocity(
    state: FreeFloatingState, theta_dot, base_angular_velocity_base=None
) -> np.ndarray:
    """Camera angular velocity in world axes [rad/s], shape (3,).

    omega_e = R_b omega_b^B + J_omega_e(q) theta_dot: the base's own rotation (``base_odom``
    twist, base axes, hence R_b) plus the joints' contribution through the camera Jacobian at the
    measured configuration. Exact at the sample, unlike a finite difference of camera rotations,
    and free of stamp jitter.

    Args:
        state: state at the measured joint angles and base pose.
        theta_dot: joint velocities [rad/s], shape (n,).
        base_angular_velocity_base: base angular velocity in base axes [rad/s], shape (3,);
            None counts as zero (no odometry yet).
    """
    theta_dot = as_vector(theta_dot, state.n, "theta_dot")
    omega = state.camera.jacobian[3:] @ theta_dot
    if base_angular_velocity_base is not None:
        base_omega = as_vector(base_angular_velocity_base, 3, "base angular velocity")
        omega = omega + state.base_rotation @ base_omega
    return omega


@dataclass(frozen=True)
class ControllerStatus:
    """The numbers of one ``rns_controller/status`` entry; None where a key is missing or bad.

    Attributes:
        state: controller state name (``OK``, ``SINGULAR_REGION``, ...).
        sigma_min: sigma_min of J-bar [-].
        det_kinematic, det_algorithmic: Gram determinants [-]; det_coupling [(kg m^2)^6].
        damping: DLS lambda^2 [-].
        speed_scale: uniform speed scale of the output [-].
        coupling_momentum: predicted base disturbance M~_omega_m theta_dot [kg m^2/s], (3,).
    """

    state: str | None = None
    sigma_min: float | None = None
    det_kinematic: float | None = None
    det_coupling: float | None = None
    det_algorithmic: float | None = None
    damping: float | None = None
    speed_scale: float | None = None
    coupling_momentum: np.ndarray | None = None

    @classmethod
    def parse(cls, values: Mapping[str, str]) -> ControllerStatus:
        """From the status key/values (numbers as text, vectors space-separated)."""
        scalars = {
            key: _number(values.get(key))
            for key in (
                "sigma_min",
                "det_kinematic",
                "det_coupling",
                "det_algorithmic",
                "damping",
                "speed_scale",
            )
        }
        vector = _vector(values.get("coupling_momentum"), 3)
        return cls(state=values.get("state") or None, coupling_momentum=vector, **scalars)


@dataclass(frozen=True)
class PtpStatus:
    """The numbers of one ``rns_ptp/status`` entry; None where a key is missing or bad.

    Attributes:
        state: node state name (``IDLE``, ``MOVING``, ``DONE``, ...).
        phase: phase name (``I``, ``II``, ``III``, ``JS-C``, ..., ``done``).
        progress: fraction of the plan played [-] in [0, 1].
        coupling_momentum: predicted |M~_omega_m theta_dot| [kg m^2/s].
    """

    state: str | None = None
    phase: str | None = None
    progress: float | None = None
    coupling_momentum: float | None = None

    @classmethod
    def parse(cls, values: Mapping[str, str]) -> PtpStatus:
        """From the status key/values (numbers as text)."""
        return cls(
            state=values.get("state") or None,
            phase=values.get("phase") or None,
            progress=_number(values.get("progress")),
            coupling_momentum=_number(values.get("coupling_momentum")),
        )


def _number(text: str | None) -> float | None:
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def _vector(text: str | None, size: int) -> np.ndarray | None:
    if text is None:
        return None
    try:
        vector = np.array([float(part) for part in text.split()])
    except ValueError:
        return None
    if vector.shape != (size,) or not np.all(np.isfinite(vector)):
        return None
    return vector


class RateLimiter:
    """Keeps a stream at or below ``max_rate`` [Hz] by stamp time; 0 keeps everything.

    A sample is kept when it is at least 1/max_rate after the last kept one, or earlier than it
    (time jumped back, e.g. a simulator reset).
    """

    def __init__(self, max_rate: float) -> None:
        self.min_period_ns = 0 if max_rate <= 0.0 else round(1e9 / max_rate)
        self._last: int | None = None

    def accept(self, stamp_ns: int) -> bool:
        last = self._last
        if last is not None and 0 <= stamp_ns - last < self.min_period_ns:
            return False
        self._last = stamp_ns
        return True


class Trail:
    """The last ``length`` positions, one every ``period`` [s] of stamp time; length 0 = off."""

    def __init__(self, length: int, period: float) -> None:
        self.length = length
        self.points: deque[np.ndarray] = deque(maxlen=max(length, 1))
        self._limiter = RateLimiter(0.0 if period <= 0.0 else 1.0 / period)

    def add(self, stamp_ns: int, position: np.ndarray) -> bool:
        """Append ``position`` [m] if its turn has come; True when the trail changed."""
        if self.length == 0 or not self._limiter.accept(stamp_ns):
            return False
        self.points.append(np.array(position, dtype=np.float32))
        return True

    def strip(self) -> np.ndarray:
        """The trail as one line strip, shape (k, 3), oldest point first."""
        return np.array(self.points, dtype=np.float32).reshape(-1, 3)
