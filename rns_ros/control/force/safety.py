"""The force controller's safety monitor: latched wrench limit and contact supervision."""

from __future__ import annotations

import numpy as np

from rns_ros.control.force.commands import WrenchSample
from rns_ros.control.force.status import ForceControlState


class SafetyMonitor:
    """Latched wrench limit and contact supervision (cleared by :meth:`reset`).

    * WRENCH_LIMIT: measured |force| > ``max_force`` [N] or |torque| > ``max_torque`` [N m].
    * CONTACT_LOST / NO_CONTACT: while the force task is active and f_des >= 2 ``threshold``,
      the measured normal force stayed below ``threshold`` [N] for ``loss_time`` [s] or more
      (by state stamps); CONTACT_LOST when it had been >= threshold since the last reset.
    """

    def __init__(
        self, max_force: float, max_torque: float, threshold: float, loss_time: float
    ) -> None:
        self.max_force, self.max_torque = max_force, max_torque
        self.threshold, self.loss_time = threshold, loss_time
        self.reset()

    def reset(self) -> None:
        self.fault: tuple[ForceControlState, str] | None = None
        self.ever_in_contact = False
        self._below_since: int | None = None

    def contact(self, f: float) -> str:
        """in_contact | lost | none for the measured normal force f [N]."""
        if f >= self.threshold:
            return "in_contact"
        return "lost" if self.ever_in_contact else "none"

    def update(
        self, stamp: int, force_active: bool, f_des: float, f: float, wrench: WrenchSample | None
    ) -> tuple[ForceControlState, str] | None:
        """Check one step (stamp [ns], f_des and the measured normal f [N]); returns the latched
        fault, if any."""
        if self.fault is not None:
            return self.fault
        if wrench is not None:
            force, torque = np.linalg.norm(wrench.force), np.linalg.norm(wrench.torque)
            if force > self.max_force or torque > self.max_torque:
                self.fault = (
                    ForceControlState.WRENCH_LIMIT,
                    f"measured |force| {force:.4g} N / |torque| {torque:.4g} N m over the limits "
                    f"{self.max_force:g} N / {self.max_torque:g} N m",
                )
                return self.fault
        if f >= self.threshold:
            self.ever_in_contact = True
        if force_active and f_des >= 2.0 * self.threshold and f < self.threshold:
            if self._below_since is None:
                self._below_since = stamp
            elapsed = (stamp - self._below_since) * 1e-9
            if elapsed >= self.loss_time:
                lost = self.ever_in_contact
                self.fault = (
                    ForceControlState.CONTACT_LOST if lost else ForceControlState.NO_CONTACT,
                    f"{'contact lost' if lost else 'no contact made'}: measured force "
                    f"{f:.3g} N < contact_threshold {self.threshold:g} N for {elapsed:.3f} s "
                    f"while {f_des:.3g} N was desired",
                )
        else:
            self._below_since = None
        return self.fault


__all__ = ["SafetyMonitor"]
