"""Control laws (thesis chapter 4): the reactionless inspection law (eq. 4.5, 4.7-4.15), the
controller that holds it over a sampling period, operator-command handling for teleoperation, and
the scripted inspection scenarios. Built on :mod:`rns_ros.core` only; no rclpy or rerun.
"""

from rns_ros.control.camera_law import (
    ControlGains,
    ControlOutput,
    Method,
    reactionless_camera_control,
)

__all__ = ["ControlGains", "ControlOutput", "Method", "reactionless_camera_control"]
