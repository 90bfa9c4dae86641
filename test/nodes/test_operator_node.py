"""rns_operator plays a scenario file as TwistStamped commands over DDS."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from geometry_msgs.msg import TwistStamped
from rclpy.parameter import Parameter

from rns_ros.core import ConfigError
from rns_ros.nodes.operator import PARAMETERS, OperatorNode
from rns_ros.resources import config_dir

SCENARIO = {
    "initial_joint_positions_deg": [0, 10, 0, 20, 0, 30, 0],
    "frame": "camera",
    "axis": [0, 1, 0],
    "angle_deg": 30.0,
    "duration": 1.0,
    "time_scaling": "piecewise",
    "segments": [[0.4, 0.5], [0.2, 0.0], [0.4, 0.5]],
}


def test_operator_publishes_the_profile_then_zeros(ros, tmp_path):
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(SCENARIO))
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode,
        {"scenario": str(path), "rate": 100.0, "start_delay": 0.0, "zero_duration": 0.3},
    )
    assert ros.spin_until(lambda: operator.finished, timeout=10.0)
    assert {m.header.frame_id for m in twists.messages} == {"camera"}
    rates = twists.array(lambda m: [m.twist.angular.x, m.twist.angular.y, m.twist.angular.z])
    stamps = twists.stamps()
    assert np.all(rates[:, [0, 2]] == 0.0)
    # the published rate integrates to the scenario angle (rectangle rule at 100 Hz)
    angle = np.sum(rates[:-1, 1] * np.diff(stamps))
    assert angle == pytest.approx(np.deg2rad(30.0), rel=0.05)
    # piecewise: 0.5 * 30 deg in 0.4 s, a pause, then the rest
    assert rates[:, 1].max() == pytest.approx(np.deg2rad(15.0) / 0.4, rel=1e-9)
    assert np.any(rates[:, 1] == 0.0)
    assert np.all(rates[-5:, 1] == 0.0)  # zeros after the profile
    count = len(twists)
    ros.spin_for(0.2)
    assert len(twists) == count  # then silence


def test_operator_waits_for_a_subscriber(ros):
    operator = ros.add(OperatorNode, {"start_delay": 0.0})
    ros.spin_for(0.3)
    assert not operator.started
    ros.record(TwistStamped, "cmd_twist")
    assert ros.spin_until(lambda: operator.started, timeout=5.0)


def test_unknown_scenario_is_a_clear_error(ros):
    with pytest.raises(ConfigError, match="neither a file nor one of"):
        OperatorNode(
            context=ros.context,
            parameter_overrides=[Parameter("scenario", value="nope")],
        )


def test_config_yaml_mirrors_the_declared_defaults():
    content = yaml.safe_load((config_dir() / "operator.yaml").read_text())
    assert content["/**"]["ros__parameters"] == {spec.name: spec.default for spec in PARAMETERS}
