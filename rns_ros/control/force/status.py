"""What one force controller step reports: its state and its result record."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rns_ros.core.validation import Choice


class ForceControlState(Choice):
    """What the controller is doing (status level in brackets)."""

    WAITING_FOR_STATE = "WAITING_FOR_STATE"  # [WARN] no joint_states yet
    OK = "OK"  # [OK] following a fresh twist
    HOLDING = "HOLDING"  # [OK] no fresh twist: decelerating to rest / holding the pose
    SPEED_LIMITED = "SPEED_LIMITED"  # [WARN] twist scaled to max_linear/angular_speed
    FORCE_SETPOINT_STALE = "FORCE_SETPOINT_STALE"  # [WARN] setpoint older than force_timeout
    WRENCH_STALE = "WRENCH_STALE"  # [WARN] force task on, no fresh wrist wrench: push paused
    TORQUE_LIMITED = "TORQUE_LIMITED"  # [WARN] torque clipped to the URDF effort limits
    INVALID_COMMAND = "INVALID_COMMAND"  # [ERROR] the newest twist/setpoint was rejected
    WRENCH_LIMIT = "WRENCH_LIMIT"  # [ERROR, latched] measured wrench over the limit
    CONTACT_LOST = "CONTACT_LOST"  # [ERROR, latched] contact made, then lost
    NO_CONTACT = "NO_CONTACT"  # [ERROR, latched] the force task never made contact
    STALE_STATE = "STALE_STATE"  # [ERROR] no joint_states for state_timeout: zero torque
    NON_FINITE = "NON_FINITE"  # [ERROR] a non-finite torque: nothing published
    CONTROL_ERROR = "CONTROL_ERROR"  # [ERROR] the law failed (e.g. OS-C singular): nothing


#: Latched safety stops (cleared by :meth:`ForceTeleopController.reset`).
SAFETY_STOPS = (
    ForceControlState.WRENCH_LIMIT,
    ForceControlState.CONTACT_LOST,
    ForceControlState.NO_CONTACT,
)


#: Which state to report when several apply (highest first; safety stops come before these).
PRIORITY = (
    ForceControlState.INVALID_COMMAND,
    ForceControlState.TORQUE_LIMITED,
    ForceControlState.WRENCH_STALE,
    ForceControlState.FORCE_SETPOINT_STALE,
    ForceControlState.SPEED_LIMITED,
    ForceControlState.HOLDING,
)


@dataclass(frozen=True)
class ForceStep:
    """One control step's result.

    Attributes:
        torque: joint torques [N m] (n,) in model order, clipped to the effort limits, finite;
            None: publish nothing new (non-finite or failed step).
        state, detail: status (detail = reasons and reports, '; '-joined).
        time: the state's stamp [s]. position_error: p_des - p, world [m] (3,).
        orientation_error: |log(R_des R^T)| [rad] (0 when the orientation is not a task).
        force_desired, force_measured, force_reference [N]: f_des, the measured f along n, f_ref.
        joint_speed: max |theta_dot_i| [rad/s]. normal: n (3,). force_active: the force task runs.
        contact: in_contact | lost | none. saturated: joint names clipped to their effort limit.
        ignored: size of the twist removed along constrained / non-task directions [m/s, rad/s].
    """

    torque: np.ndarray | None
    state: ForceControlState
    detail: str
    time: float
    position_error: np.ndarray
    orientation_error: float
    force_desired: float
    force_measured: float
    force_reference: float
    joint_speed: float
    normal: np.ndarray
    force_active: bool
    contact: str
    saturated: tuple[str, ...] = ()
    ignored: float = 0.0

    @property
    def force_error(self) -> float:
        """f_des - f [N]."""
        return self.force_desired - self.force_measured

    def error_sample(self) -> np.ndarray:
        """The ``~/errors`` sample (14,) in the layout ``contact_topics.ERROR_LABELS``."""
        return np.array(
            [
                self.time,
                *self.position_error,
                self.orientation_error,
                self.force_desired,
                self.force_measured,
                self.force_error,
                self.force_reference,
                self.joint_speed,
                *self.normal,
                float(self.force_active),
            ]
        )


__all__ = ["PRIORITY", "SAFETY_STOPS", "ForceControlState", "ForceStep"]
