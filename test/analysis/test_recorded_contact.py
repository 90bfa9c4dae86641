"""Figures of a recorded motion/force run: the in-plane projection, the force band, the tail."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.analysis.recorded_contact import REQUIRED_COLUMNS, contact_run_figures
from rns_ros.core.errors import InputError


def _errors(k: int = 101, normal=(0.0, 0.0, 1.0)) -> dict[str, np.ndarray]:
    t = np.linspace(0.0, 1.0, k)
    errors = {name: np.zeros(k) for name in REQUIRED_COLUMNS}
    errors["time"] = t
    for axis, value in zip("xyz", normal, strict=True):
        errors[f"normal_{axis}"] = np.full(k, value)
    return errors


def _joints(k: int = 11, n: int = 7):
    return np.linspace(0.0, 1.0, k), np.zeros((k, n))


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3).filter(
        lambda v: np.linalg.norm(v) > 0.1
    ),
    st.lists(st.floats(-0.01, 0.01), min_size=3, max_size=3),
    st.floats(-0.05, 0.05),
)
def test_the_normal_component_of_the_position_error_does_not_count(normal, tangential, along):
    """e = tangential part + any amount along n: the figure is the tangential part's norm."""
    n = np.array(normal) / np.linalg.norm(normal)
    e_t = np.array(tangential) - (np.array(tangential) @ n) * n
    errors = _errors(normal=n)
    (
        errors["position_error_x"][50],
        errors["position_error_y"][50],
        errors["position_error_z"][50],
    ) = e_t + along * n
    figures = contact_run_figures(errors, *_joints())
    assert figures.max_position_error_m == pytest.approx(np.linalg.norm(e_t), abs=1e-12)


def test_the_force_band_starts_where_the_desired_force_settles():
    errors = _errors()
    ramp = np.minimum(errors["time"] / 0.5, 1.0) * 10.0  # reaches 10 N at t = 0.5 s (index 50)
    errors["force_desired"] = ramp
    errors["force_error"][10] = 3.0  # during the ramp
    errors["force_error"][80] = -0.2  # on the plateau
    figures = contact_run_figures(errors, *_joints())
    assert figures.max_force_error_n == 3.0
    assert figures.held_force_error_n == pytest.approx(0.2)


def test_joint_speeds_peak_and_tail():
    t, v = _joints(k=101)
    v[30, 2] = -1.5  # the peak, early
    v[-5, 4] = 0.01  # inside the last 0.2 s
    v[-30, 1] = 0.5  # before the tail window
    figures = contact_run_figures(_errors(), t, v, tail=0.2)
    assert figures.peak_joint_speed == 1.5
    assert figures.final_joint_speed == pytest.approx(0.01)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda e, t, v: e.pop("force_error"), "lack the columns"),
        (lambda e, t, v: e.__setitem__("force_error", np.zeros(3)), "equal length"),
        (lambda e, t, v: e["force_error"].__setitem__(4, np.nan), "non-finite"),
    ],
)
def test_bad_records_are_rejected_by_name(change, match):
    errors = _errors()
    t, v = _joints()
    change(errors, t, v)
    with pytest.raises(InputError, match=match):
        contact_run_figures(errors, t, v)


def test_mismatched_joint_arrays_are_rejected():
    t, v = _joints()
    with pytest.raises(InputError, match="do not match"):
        contact_run_figures(_errors(), t[:-1], v)
