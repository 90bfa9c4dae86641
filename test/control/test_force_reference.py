"""The operator's motion reference (rns_ros.control.force.reference): feed-forward and limits."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.control.force.commands import TwistCommand
from rns_ros.control.force.reference import (
    TwistTrack,
    held_twist,
    limit_norm,
    rate_limit,
    remove_constrained,
)
from rns_ros.control.force.settings import CommandFrame, ForceControlSettings

ZERO = np.zeros(3)


def _twist(linear, stamp_ns, frame=CommandFrame.WORLD):
    return TwistCommand(np.asarray(linear, float), ZERO, frame, stamp_ns, 0.0)


def test_feed_forward_is_the_twist_difference_over_the_stamps():
    first = TwistTrack.following(None, _twist([0.1, 0.0, 0.0], 1_000_000))
    second = TwistTrack.following(first, _twist([0.1, 0.02, 0.0], 3_000_000))
    assert np.allclose(second.linear_acceleration, [0.0, 10.0, 0.0])  # 0.02 m/s over 2 ms
    assert second.period == pytest.approx(2e-3)
    other_frame = TwistTrack.following(first, _twist([0.1, 0.02, 0.0], 3_000_000, CommandFrame.EE))
    assert other_frame.period == 0.0
    assert not other_frame.linear_acceleration.any()


def test_held_twist_extrapolates_at_most_two_periods():
    settings = ForceControlSettings()
    first = TwistTrack.following(None, _twist([0.0, 0.0, 0.0], 1_000_000))
    track = TwistTrack.following(first, _twist([0.0, 0.002, 0.0], 2_000_000))  # 2 m/s^2
    v, a = held_twist(track, settings, np.eye(3), 3_000_000)
    assert v[1] == pytest.approx(0.002 + 2.0 * 1e-3)
    assert a[1] == pytest.approx(2.0)
    v, a = held_twist(track, settings, np.eye(3), 10_000_000)
    assert v[1] == pytest.approx(0.002 + 2.0 * 2e-3)
    assert not a.any()


def test_limits_keep_the_direction():
    scaled, norm = limit_norm(np.array([3.0, 4.0, 0.0]), 1.0)
    assert norm == pytest.approx(5.0)
    assert np.allclose(scaled, [0.6, 0.8, 0.0])
    same, none = limit_norm(np.array([0.3, 0.4, 0.0]), 1.0)
    assert none is None
    assert np.allclose(same, [0.3, 0.4, 0.0])
    v, a = rate_limit(np.zeros(3), np.array([1.0, 0.0, 0.0]), np.zeros(3), 1e-3, 5.0)
    assert np.allclose(v, [5e-3, 0.0, 0.0])
    assert np.allclose(a, [5.0, 0.0, 0.0])
    v, a = rate_limit(np.zeros(3), np.array([1e-3, 0.0, 0.0]), np.ones(3), 1e-3, 5.0)
    assert np.allclose(v, [1e-3, 0.0, 0.0])
    assert np.allclose(a, np.ones(3))


def test_normal_and_non_task_components_are_removed():
    v = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    a = np.ones(6)
    removed = remove_constrained(v, a, (0, 1, 2, 5), np.array([0.0, 0.0, 1.0]))
    assert np.allclose(v, [0.1, 0.2, 0.0, 0.0, 0.0, 0.6])
    assert np.allclose(a, [1.0, 1.0, 0.0, 0.0, 0.0, 1.0])
    assert np.allclose(removed, [0.0, 0.0, 0.3, 0.4, 0.5, 0.0])
