"""Layouts of the Part II telemetry topics ``contact`` and ``~/errors``.

Each sample is a std_msgs/Float64MultiArray whose layout label is the space-separated tuple;
units and meaning of every column: docs/part2_ros.md.
"""

from __future__ import annotations

#: One ``contact`` sample of the contact simulator, one per state.
CONTACT_LABELS = (
    "time",
    "contact_state",
    "normal_force",
    "gap",
    "gap_rate",
    "point_x",
    "point_y",
    "point_z",
    "normal_x",
    "normal_y",
    "normal_z",
    "saturated_joints",
)
#: One ``~/errors`` sample of the force controller, one per control step.
ERROR_LABELS = (
    "time",
    "position_error_x",
    "position_error_y",
    "position_error_z",
    "orientation_error",
    "force_desired",
    "force_measured",
    "force_error",
    "force_reference",
    "joint_speed",
    "normal_x",
    "normal_y",
    "normal_z",
    "force_active",
)

__all__ = ["CONTACT_LABELS", "ERROR_LABELS"]
