"""The outer loops (6.33)-(6.34) (rns_ros.control.motion_force.outer_loops)."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.control.motion_force.outer_loops import (
    ForceGains,
    MotionGains,
    force_loop,
    motion_loop,
)
from rns_ros.core import ConfigError, InputError


def test_outer_loops_6_33_and_6_34():
    gains = MotionGains()
    assert (gains.k_p, gains.k_d) == (100.0, 10.0)
    out = motion_loop(gains, [1.0, 0.0], [0.5, 0.0], [0.4, 0.1], [0.01, -0.02])
    assert np.allclose(out, [1.0 + 10 * 0.1 + 100 * 0.01, 10 * -0.1 + 100 * -0.02])
    assert np.allclose(force_loop(ForceGains(), [10.0], [8.0]), [20.0])  # 10 + 5 (10 - 8)


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: MotionGains(k_p=-1.0), r"k_p .*1/s\^2.*-1"),
        (lambda: MotionGains(k_d=float("nan")), r"k_d .*nan"),
        (lambda: ForceGains(k_f=-0.5), r"k_f .*>= 0.*-0.5"),
    ],
)
def test_bad_gains_raise_config_errors(build, match):
    with pytest.raises(ConfigError, match=match):
        build()


def test_bad_references_raise_input_errors():
    with pytest.raises(InputError, match="pose_error"):
        motion_loop(MotionGains(), [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0])
