"""Figures of a recorded motion/force run (thesis Part II over DDS), from plain arrays (ROS-free).

The demo (``rns_demo --scenario wall_contact``) records the force controller's ``~/errors`` stream
(layout ``ERROR_LABELS`` of docs/part2_ros.md: one sample per control step) and the simulator's
``joint_states``; :func:`contact_run_figures` turns them into a :class:`ContactRunFigures` record,
the quantities chapter 6 compares (Figs. 6.3-6.4, 6.7-6.8): the motion and force tracking errors
and the joint speeds.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from rns_ros.control.contact_topics import ERROR_LABELS
from rns_ros.core.errors import InputError

#: Columns of the force controller's ``~/errors`` samples used here.
REQUIRED_COLUMNS = tuple(
    label
    for label in ERROR_LABELS
    if label not in ("force_measured", "force_reference", "joint_speed", "force_active")
)


@dataclass(frozen=True)
class ContactRunFigures:
    """Figures of one motion/force run (units in the names).

    Attributes:
        max_position_error_m: largest in-plane position error |e - (e . n) n|, e = p_des - p
            (the controller's reference), n the contact normal of the sample [m].
        max_orientation_error_rad: largest |log(R_des R^T)| [rad] (0 without orientation task).
        max_force_error_n: largest |f_des - f| over the whole run [N].
        held_force_error_n: largest |f_des - f| once the desired force has reached its final
            value (the band the force is held in) [N]; the whole run if it never settles.
        peak_joint_speed: largest |theta_dot_i| over joints and time [rad/s] ([A-4.5]).
        final_joint_speed: largest |theta_dot_i| over the last ``tail`` seconds of the
            joint states [rad/s] (the residual motion after the task ended).
        duration_s: span of the error samples [s]; samples: error samples used.
    """

    max_position_error_m: float
    max_orientation_error_rad: float
    max_force_error_n: float
    held_force_error_n: float
    peak_joint_speed: float
    final_joint_speed: float
    duration_s: float
    samples: int


def contact_run_figures(
    errors: Mapping[str, np.ndarray],
    joint_times: np.ndarray,
    joint_velocities: np.ndarray,
    *,
    tail: float = 0.2,
) -> ContactRunFigures:
    """Figures of one run.

    Args:
        errors: column name -> (k,) array, the ``~/errors`` samples in time order (at least the
            :data:`REQUIRED_COLUMNS`).
        joint_times: (s,) [s] stamps of the joint states; joint_velocities: (s, n) [rad/s].
        tail: window at the end for ``final_joint_speed`` [s] (> 0).

    Raises:
        InputError: a column is missing, arrays disagree in length, fewer than two samples, or a
            value is non-finite.
    """
    missing = [name for name in REQUIRED_COLUMNS if name not in errors]
    if missing:
        raise InputError(f"error samples lack the columns {missing}")
    columns = {name: np.asarray(errors[name], dtype=float) for name in REQUIRED_COLUMNS}
    k = columns["time"].shape[0]
    if k < 2 or any(column.shape != (k,) for column in columns.values()):
        raise InputError(f"need >= 2 error samples of equal length, got {k}")
    joint_times = np.asarray(joint_times, dtype=float)
    joint_velocities = np.asarray(joint_velocities, dtype=float)
    if joint_velocities.ndim != 2 or joint_velocities.shape[0] != joint_times.shape[0]:
        raise InputError(
            f"joint velocities {joint_velocities.shape} do not match {joint_times.shape[0]} stamps"
        )
    if joint_times.shape[0] < 2:
        raise InputError("need >= 2 joint states")
    arrays = (*columns.values(), joint_times, joint_velocities)
    if not all(np.isfinite(array).all() for array in arrays):
        raise InputError("recorded samples contain non-finite values")
    if not tail > 0.0:
        raise InputError(f"tail must be > 0 s, got {tail!r}")
    error = np.column_stack([columns[f"position_error_{axis}"] for axis in "xyz"])
    normal = np.column_stack([columns[f"normal_{axis}"] for axis in "xyz"])
    in_plane = error - np.sum(error * normal, axis=1, keepdims=True) * normal
    force_error = np.abs(columns["force_error"])
    desired = columns["force_desired"]
    # the band: from the first sample of the final plateau of the desired force
    moving = np.flatnonzero(~np.isclose(desired, desired[-1], rtol=0.0, atol=1e-9))
    first = moving[-1] + 1 if moving.size else 0
    speeds = np.abs(joint_velocities).max(axis=1)
    final = speeds[joint_times >= joint_times[-1] - tail]
    return ContactRunFigures(
        max_position_error_m=float(np.linalg.norm(in_plane, axis=1).max()),
        max_orientation_error_rad=float(np.abs(columns["orientation_error"]).max()),
        max_force_error_n=float(force_error.max()),
        held_force_error_n=float(force_error[first:].max()),
        peak_joint_speed=float(speeds.max()),
        final_joint_speed=float(final.max()),
        duration_s=float(columns["time"][-1] - columns["time"][0]),
        samples=k,
    )


__all__ = ["REQUIRED_COLUMNS", "ContactRunFigures", "contact_run_figures"]
