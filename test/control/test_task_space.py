"""Task coordinates and selection matrices, (6.10)-(6.12) (rns_ros.control.motion_force)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from motion_force_cases import (
    PLANAR,
    PLANAR_TASK,
    WALL_TASK,
    state_case,
)

from rns_ros.control.motion_force.task_space import FULL_ROWS, PLANAR_ROWS, TaskSpace, contact_frame
from rns_ros.core import ConfigError, InputError


def test_task_space_selection_matrices():
    assert np.allclose(PLANAR_TASK.force_selection, np.diag([1.0, 0.0]))
    assert np.allclose(PLANAR_TASK.selection, np.diag([0.0, 1.0]))  # S = t t^T, t = +y
    assert np.allclose(WALL_TASK.selection, np.diag([1, 1, 0, 1, 1, 1]))
    frame = contact_frame([1.0, 1.0, 0.0])
    assert np.allclose(frame.T @ frame, np.eye(3))
    assert np.isclose(np.linalg.det(frame), 1.0)
    assert np.allclose(frame[:, 2], np.array([1, 1, 0]) / np.sqrt(2))
    assert abs(frame[2, 0]) < 1e-12  # planar default tangent stays in x-y
    free = TaskSpace.free(PLANAR_ROWS)
    assert free.k == 0
    assert np.allclose(free.selection, np.eye(2))


def test_pose_error_orientation_rows():
    state, *_ = state_case("lwr")
    rotation = pin.exp3(np.array([0.0, 0.0, 0.1])) @ state.ee_rotation
    error = WALL_TASK.pose_error(state, state.ee_position + np.array([0.01, 0, 0]), rotation)
    assert np.allclose(error, [0.01, 0, 0, 0, 0, 0.1])
    with pytest.raises(InputError, match="rotation"):
        WALL_TASK.pose_error(state, state.ee_position)


@pytest.mark.parametrize(
    ("build", "error", "match"),
    [
        (lambda: TaskSpace.free((0, 0)), ConfigError, r"distinct indices in 0\.\.5"),
        (lambda: TaskSpace.free((0, 6)), ConfigError, r"0\.\.5.*6"),
        (lambda: TaskSpace.from_contact(PLANAR_ROWS, [0, 1, 1]), ConfigError, r"\['z'\]"),
        (lambda: contact_frame([0.0, 0.0, 0.0]), InputError, "non-zero"),
        (lambda: TaskSpace.free(FULL_ROWS).check(PLANAR), ConfigError, "6 task rows exceed"),
    ],
)
def test_bad_parameters_raise_typed_errors(build, error, match):
    with pytest.raises(error, match=match):
        build()
