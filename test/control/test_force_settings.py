"""Force controller settings (rns_ros.control.force.settings): validation at the edge."""

from __future__ import annotations

import pytest
from force_cases import PLANAR

from rns_ros.control.force.controller import ForceTeleopController
from rns_ros.control.force.settings import ForceControlSettings
from rns_ros.core.errors import ConfigError


def test_sampled_force_is_rejected_for_k_f_of_one_or_more():
    with pytest.raises(ConfigError, match=r"k_f < 1.*e_\{k\+1\} = -k_f e_k.*predicted"):
        ForceControlSettings(force_measurement="sampled", k_f=5.0)
    with pytest.raises(ConfigError, match="k_f < 1"):
        ForceControlSettings(force_measurement="sampled", k_f=1.0)


def test_wrench_timeout_is_validated():
    with pytest.raises(ConfigError, match=r"wrench_timeout must be in \[0.0001, 10.0\] \[s\]"):
        ForceControlSettings(wrench_timeout=0.0)


def test_settings_errors_name_the_value():
    with pytest.raises(ConfigError, match="task_axes must be distinct names"):
        ForceControlSettings(task_axes=("x", "q"))
    with pytest.raises(ConfigError, match="no linear axis"):
        ForceControlSettings(task_axes=("wx", "wy", "wz"))
    with pytest.raises(ConfigError, match="method must be one of"):
        ForceControlSettings(method="pid")
    with pytest.raises(ConfigError, match="not task_axes"):
        ForceControlSettings(task_axes=("x", "y"), constrained_frame="world")
    with pytest.raises(ConfigError, match="exceed the 3 joints"):
        ForceTeleopController(PLANAR, ForceControlSettings())
