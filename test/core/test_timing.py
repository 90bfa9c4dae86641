"""The rest-to-rest quintic of core/timing (thesis section 4.2.2)."""

from __future__ import annotations

import pytest

from rns_ros.core.errors import ConfigError
from rns_ros.core.timing import QUINTIC_PEAK_RATE, quintic, quintic_profile, quintic_shape


def test_quintic_rests_at_both_ends_and_peaks_at_the_middle():
    assert quintic_profile(0.0, 2.0) == (0.0, 0.0, 0.0)
    assert quintic_profile(2.0, 2.0) == (1.0, 0.0, 0.0)
    s, s_dot, s_ddot = quintic_profile(1.0, 2.0)
    assert s == 0.5
    assert s_ddot == 0.0
    assert s_dot == pytest.approx(QUINTIC_PEAK_RATE / 2.0)
    assert quintic(1.0, 2.0) == (s, s_dot)


def test_quintic_derivatives_are_the_shape_derivatives_over_the_duration():
    h = 1e-6
    for tau in (0.1, 0.3, 0.7):
        s, ds, dds = quintic_shape(tau)
        assert ds == pytest.approx(
            (quintic_shape(tau + h)[0] - quintic_shape(tau - h)[0]) / (2 * h)
        )
        assert dds == pytest.approx(
            (quintic_shape(tau + h)[1] - quintic_shape(tau - h)[1]) / (2 * h)
        )
        assert quintic_profile(4.0 * tau, 4.0) == pytest.approx((s, ds / 4.0, dds / 16.0))


def test_quintic_rejects_a_non_positive_duration():
    with pytest.raises(ConfigError, match="duration"):
        quintic(0.5, 0.0)
