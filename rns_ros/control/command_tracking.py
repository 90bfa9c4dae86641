"""Commanded camera attitude: the integral of the operator's rate over the command stamps.

Pure logic (no ROS), used by ``rns_controller`` once per control period. A rate command held
for one control period moves the camera only as far as the ticks that ran, the ramps from rest
and the law's scaling let it; on a loaded machine the camera then falls short of the turn the
operator commanded. This object integrates the commanded rate over the *command stamps* into
the attitude R_cmd (world <- camera) the operator asked for, and gives the small rate that
closes the gap to the measured camera attitude R_c (world axes):

    R_cmd <- exp(omega_w dt) R_cmd           world or base axes (omega_w = R_b omega_b)
    R_cmd <- R_cmd exp(omega_c dt)           camera axes (a body-fixed rate of the camera)
    dt = clip(stamp_next - stamp, 0, max_interval)        [s]

    e = log(R_cmd R_c^T)                                  [rad], (3,)
    omega_corr = k e * min(1, omega_max / (k |e|))        [rad/s], (3,)

k the tracking gain [1/s] (0: off), omega_max the largest correction [rad/s]. The newest
command counts up to the tick from its receipt (its stamp is on the sender's clock), the
committed intervals between commands from their stamps: delivery jitter and missed ticks do
not change the integral. The correction is added to the rate the command gate serves, so it
passes the same camera law (eq. 4.5, reactionless) and the same speed and joint-limit scaling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from rns_ros.control.controller import TwistFrame
from rns_ros.core.errors import ConfigError

#: An attitude error below this [rad] is rounding (log3 of a product of rotation matrices), not
#: a gap: no correction, so an operator's zero twist leaves the joints exactly at rest.
NEGLIGIBLE_ERROR = 1e-9


@dataclass(frozen=True)
class TrackingSettings:
    """Settings of :class:`CommandedAttitude`.

    Attributes:
        gain: k, feedback gain on the attitude error [1/s], >= 0 (0: off).
        max_correction: omega_max, largest correction rate [rad/s], > 0.
        max_error: an error |e| above this [rad] cannot be closed by a correction (a joint
            limit, a singular region, a blocked arm): the commanded attitude restarts at the
            measured one instead of winding up, > 0.
        max_interval: the longest time one command counts for [s], > 0 (the command timeout:
            past it the gate stops the arm).
    """

    gain: float = 1.0
    max_correction: float = 0.05
    max_error: float = 0.3
    max_interval: float = 0.5

    def __post_init__(self) -> None:
        if not (math.isfinite(self.gain) and self.gain >= 0.0):
            raise ConfigError(f"tracking_gain must be a finite number >= 0 1/s, got {self.gain!r}")
        for name, value, unit in (
            ("tracking_max_correction", self.max_correction, "rad/s"),
            ("tracking_max_error", self.max_error, "rad"),
            ("command_timeout", self.max_interval, "s"),
        ):
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"{name} must be a finite number > 0 {unit}, got {value!r}")


@dataclass(frozen=True)
class TrackingStep:
    """One period of tracking.

    Attributes:
        correction: omega_corr, world axes [rad/s], (3,).
        error: |e|, angle between the commanded and the measured camera attitude [rad].
        restarted: True when |e| exceeded ``max_error`` and R_cmd restarted at R_c.
    """

    correction: np.ndarray
    error: float
    restarted: bool = False


@dataclass(frozen=True)
class _Held:
    """The newest command: rate [rad/s] (3,) in ``frame`` axes, base rotation (3, 3) at its
    receipt (base axes), its stamp [s] on the sender's clock and receipt [s] on the input
    clock."""

    angular: np.ndarray
    frame: TwistFrame
    base_rotation: np.ndarray
    stamp: float
    received: float


class CommandedAttitude:
    """R_cmd, the camera attitude the operator's commands add up to (see the module docstring).

    Args:
        settings: :class:`TrackingSettings`.
    """

    def __init__(self, settings: TrackingSettings) -> None:
        self.settings = settings
        self._committed: np.ndarray | None = None  # R_cmd at the held command's stamp (3, 3)
        self._held: _Held | None = None
        self._stopped_at = -math.inf  # when the tracking last stopped [s] (input clock)

    @property
    def active(self) -> bool:
        """True while an attitude is tracked (after :meth:`restart`, until :meth:`stop`)."""
        return self._committed is not None

    def restart(self, camera_rotation: np.ndarray, now: float) -> None:
        """R_cmd := the measured camera attitude ``camera_rotation`` (3, 3) at ``now`` [s]
        (input clock), where the camera has stood since the tracking stopped; the held command
        counts from its receipt or the stop, whichever came later (its stamp moved on alike)."""
        self._committed = np.array(camera_rotation, dtype=float)
        held = self._held
        if held is not None:
            start = min(max(held.received, self._stopped_at), now)
            if start > held.received:
                shift = start - held.received
                self._held = replace(held, stamp=held.stamp + shift, received=start)

    def stop(self, now: float) -> None:
        """Nothing tracked from ``now`` [s] (input clock) until the next :meth:`restart` (the
        arm stopped, a goal took over); the newest command is kept."""
        self._committed = None
        self._stopped_at = now

    def take(
        self,
        angular: np.ndarray,
        frame: TwistFrame,
        stamp: float,
        received: float,
        base_rotation: np.ndarray,
    ) -> None:
        """A command: ``angular`` [rad/s] (3,) in ``frame`` axes, stamped ``stamp`` [s] (sender's
        clock), received at ``received`` [s] (input clock), with the base rotation (3, 3) at
        receipt. The held command is committed over the stamp interval first (while tracked)."""
        held = self._held
        if held is not None and self._committed is not None:
            self._committed = self._advanced(self._committed, held, stamp - held.stamp)
        self._held = _Held(
            np.array(angular, dtype=float), frame, np.array(base_rotation), stamp, received
        )

    def target(self, now: float) -> np.ndarray | None:
        """R_cmd (3, 3) at ``now`` [s] on the input clock, or None when nothing is tracked."""
        if self._committed is None:
            return None
        held = self._held
        if held is None:
            return self._committed
        return self._advanced(self._committed, held, now - held.received)

    def step(self, camera_rotation: np.ndarray, now: float) -> TrackingStep:
        """The correction for the measured camera attitude ``camera_rotation`` (3, 3) at ``now``
        [s] (input clock); zero when nothing is tracked or the gain is 0."""
        target = self.target(now)
        if target is None or self.settings.gain == 0.0:
            return TrackingStep(np.zeros(3), 0.0)
        e = pin.log3(target @ np.asarray(camera_rotation).T)
        error = float(np.linalg.norm(e))
        if error > self.settings.max_error:
            self.stop(now)
            self.restart(camera_rotation, now)
            return TrackingStep(np.zeros(3), error, restarted=True)
        if error < NEGLIGIBLE_ERROR:
            return TrackingStep(np.zeros(3), error)
        k, cap = self.settings.gain, self.settings.max_correction
        correction = k * e
        if k * error > cap:
            correction *= cap / (k * error)
        return TrackingStep(correction, error)

    def _advanced(self, rotation: np.ndarray, held: _Held, dt: float) -> np.ndarray:
        """``rotation`` turned by the held command over ``dt`` [s], clipped to
        [0, max_interval]."""
        dt = min(max(dt, 0.0), self.settings.max_interval)
        if dt == 0.0:
            return rotation
        if held.frame is TwistFrame.CAMERA:
            return rotation @ pin.exp3(held.angular * dt)
        omega = (
            held.angular if held.frame is TwistFrame.WORLD else held.base_rotation @ held.angular
        )
        return pin.exp3(omega * dt) @ rotation
