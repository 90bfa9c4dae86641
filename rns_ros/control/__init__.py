"""Control laws (thesis chapter 4): the reactionless inspection law (eq. 4.5, 4.7-4.15), the
controller that holds it over a sampling period, operator-command handling for teleoperation,
the scripted inspection scenarios, and the Part II task records and scenario files. Built on
:mod:`rns_ros.core` (and :mod:`rns_ros.resources` for the shipped config files); no rclpy or rerun.
"""

from rns_ros.control.camera_law import (
    ControlGains,
    ControlOutput,
    Method,
    reactionless_camera_control,
)

__all__ = ["ControlGains", "ControlOutput", "Method", "reactionless_camera_control"]
