"""rns_operator plays a scenario file as TwistStamped commands over DDS."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from geometry_msgs.msg import TwistStamped
from rclpy.parameter import Parameter

from rns_ros.core import ConfigError
from rns_ros.harness import ProcessStack
from rns_ros.nodes.operator import FINAL_ZEROS, PARAMETERS, OperatorNode
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


#: A slow roll that is still playing when the tests below stop the operator.
LONG_SCENARIO = {**SCENARIO, "time_scaling": "constant", "duration": 30.0, "segments": None}


def _long_scenario(tmp_path):
    path = tmp_path / "long.yaml"
    path.write_text(yaml.safe_dump({k: v for k, v in LONG_SCENARIO.items() if v is not None}))
    return path


def _angular(msg: TwistStamped) -> tuple[float, float, float]:
    return (msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z)


def test_operator_destroyed_mid_scenario_sends_zero_twists(ros, tmp_path):
    """Without them the controller would hold the last rate for its command_timeout, then ramp."""
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode, {"scenario": str(_long_scenario(tmp_path)), "start_delay": 0.0}
    )
    assert ros.spin_until(lambda: len(twists) >= 5, timeout=10.0)
    assert any(_angular(twists.latest()))  # moving: 1 deg/s about camera y
    ros.detach(operator)
    count = len(twists)
    operator.destroy_node()
    ros.spin_for(0.3)
    after = twists.messages[count:]
    zeros = [m for m in after if not any(_angular(m))]
    assert after, "nothing after destroy_node"
    assert not any(_angular(after[-1])), [_angular(m) for m in after]
    assert 1 <= len(zeros) <= FINAL_ZEROS
    assert {m.header.frame_id for m in zeros} == {"camera"}


def test_operator_destroyed_before_its_profile_sends_nothing(ros, tmp_path):
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode, {"scenario": str(_long_scenario(tmp_path)), "start_delay": 60.0}
    )
    assert ros.spin_until(lambda: operator.started, timeout=10.0)
    ros.detach(operator)
    operator.destroy_node()
    ros.spin_for(0.3)
    assert len(twists) == 0


def test_ctrl_c_on_the_installed_operator_sends_a_zero_twist(ros, tmp_path):
    """.venv/bin/rns_operator (run_node: SIGINT only sets a flag, destroy_node runs while the
    Context is alive), interrupted mid-scenario like a terminal user would."""
    twists = ros.record(TwistStamped, "cmd_twist")
    with ProcessStack(ros.domain_id) as stack:
        process = stack.start(
            "rns_operator", {"scenario": str(_long_scenario(tmp_path)), "start_delay": 0.0}
        )
        assert ros.spin_until(lambda: len(twists) >= 5, timeout=30.0), stack.output(process)
        assert any(_angular(twists.latest()))
        count = len(twists)
        codes = stack.stop()  # SIGINT
        ros.spin_for(0.3)
        output = stack.output(process)
    assert codes == [0], output
    after = twists.messages[count:]
    assert after, f"nothing after Ctrl-C; output:\n{output}"
    assert not any(_angular(after[-1])), output


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
