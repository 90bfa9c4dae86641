"""Bytes that are not a message, sent by anyone on the domain: every node rejects them on every
topic it subscribes and goes on publishing (none may end with 'failed to deserialize')."""

from __future__ import annotations

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.parameter import Parameter
from rclpy.serialization import serialize_message
from rns_testing import Recorder, status_values
from sensor_msgs.msg import JointState

from rns_ros.nodes.attitude_control import AttitudeControlNode
from rns_ros.nodes.contact_simulator import ContactSimulatorNode
from rns_ros.nodes.controller import ControllerNode
from rns_ros.nodes.force_controller import ForceControllerNode
from rns_ros.nodes.link import LinkNode
from rns_ros.nodes.predictor import PredictorNode
from rns_ros.nodes.ptp import PtpNode
from rns_ros.nodes.rerun_logger import RerunLoggerNode
from rns_ros.nodes.simulator import SimulatorNode

#: Lengths a serialized message is cut to: 8 bytes (the encapsulation and part of the first
#: field), half its length.
CUTS = (8, 0.5)


def _node(ros, cls, **overrides):
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(cls(context=ros.context, parameter_overrides=parameters))


def _broken(msg_type) -> list[bytes]:
    """A default message of ``msg_type`` serialized and cut short, and one of garbage bytes."""
    whole = serialize_message(msg_type())
    cut = [whole[: int(c * len(whole)) if c < 1 else c] for c in CUTS]
    # as long as the message (a fixed-size type takes no more): little-endian CDR, all 0xff
    # (huge sequence lengths, NaN values)
    return [*cut, b"\x00\x01\x00\x00" + b"\xff" * (len(whole) - 4)]


def _flood(ros, node, seconds: float = 1.0) -> list[str]:
    """Publish :func:`_broken` bytes on every topic ``node`` subscribes (except /clock and
    parameter events: rclpy's own) every 50 ms for ``seconds`` (a best-effort reader drops what
    comes before it has matched the writer on its side); returns the topics."""
    probe = ros.probe()
    publishers = {}
    for subscription in node.subscriptions:
        topic = subscription.topic_name
        if topic in ("/clock", "/parameter_events"):
            continue
        publisher = probe.create_publisher(subscription.msg_type, topic, 10)
        assert ros.spin_until(lambda p=publisher: p.get_subscription_count() > 0, timeout=10.0)
        publishers[topic] = (publisher, _broken(subscription.msg_type))
    for _ in range(round(seconds / 0.05)):
        for publisher, broken in publishers.values():
            for data in broken:
                publisher.publish(data)
        ros.spin_for(0.05)  # a node that raised in a callback would raise out of the spin here
    return list(publishers)


def _keeps_publishing(ros, recorder: Recorder) -> None:
    count = len(recorder.messages)
    assert ros.spin_until(lambda: len(recorder.messages) > count, timeout=10.0)


@pytest.mark.parametrize(
    "overrides",
    [{}, {"command_interface": "velocity", "reaction_wheels": True}],
    ids=["trajectory", "velocity+wheels"],
)
def test_the_simulator_rejects_malformed_commands_and_runs_on(ros, overrides):
    node = _node(ros, SimulatorNode, **overrides)
    joints = Recorder(ros.probe(), JointState, "joint_states")
    topics = _flood(ros, node)
    assert topics
    _keeps_publishing(ros, joints)
    if not overrides:
        assert node._commands.malformed >= 1  # joint_references


def test_the_contact_simulator_rejects_malformed_torques_and_runs_on(ros):
    node = _node(ros, ContactSimulatorNode, lockstep_period=0.0)
    joints = Recorder(ros.probe(), JointState, "joint_states")
    assert _flood(ros, node)
    _keeps_publishing(ros, joints)


@pytest.mark.parametrize("stamped", [True, False], ids=["TwistStamped", "Twist"])
def test_the_controller_rejects_malformed_inputs_counts_them_and_runs_on(ros, stamped):
    """cmd_twist, joint_states and base_odom are read from their bytes: a cut message is
    rejected, counted in the status (rejected_messages) and logged; the controller goes on."""
    _node(ros, SimulatorNode)
    node = _node(ros, ControllerNode, twist_stamped=stamped)
    status = Recorder(ros.probe(), DiagnosticArray, "rns_controller/status")
    assert ros.spin_until(lambda: node._theta is not None, timeout=10.0)
    topics = _flood(ros, node)
    assert {"/cmd_twist", "/joint_states", "/base_odom"} <= set(topics)
    _keeps_publishing(ros, status)
    rejected = dict(
        item.split(": ")
        for item in status_values(status.messages[-1])["rejected_messages"].split(", ")
    )
    # depth-1 inputs: a burst may keep only its newest message; some of each topic are counted
    for topic in ("/joint_states", "/base_odom", *(["/cmd_twist"] if stamped else [])):
        assert int(rejected[topic]) >= 1


def test_the_force_controller_rejects_malformed_inputs_and_runs_on(ros):
    node = _node(ros, ForceControllerNode)
    diagnostics = Recorder(ros.probe(), DiagnosticArray, "/diagnostics")
    assert _flood(ros, node)
    _keeps_publishing(ros, diagnostics)


def test_ptp_rejects_malformed_inputs_and_runs_on(ros):
    _node(ros, SimulatorNode)
    node = _node(ros, PtpNode)
    diagnostics = Recorder(ros.probe(), DiagnosticArray, "/diagnostics")
    assert _flood(ros, node)
    _keeps_publishing(ros, diagnostics)


def test_attitude_control_rejects_malformed_inputs_and_runs_on(ros):
    _node(ros, SimulatorNode, reaction_wheels=True)
    node = _node(ros, AttitudeControlNode)
    status = Recorder(ros.probe(), DiagnosticArray, "rns_attitude_control/status")
    assert _flood(ros, node)
    _keeps_publishing(ros, status)


@pytest.mark.parametrize("ground", ["", "ground"], ids=["spacecraft", "with-ground-arms"])
def test_the_rerun_logger_rejects_malformed_inputs_and_records_on(ros, tmp_path, ground):
    _node(ros, SimulatorNode)
    node = _node(
        ros,
        RerunLoggerNode,
        sink="save",
        rrd_path=str(tmp_path / "x.rrd"),
        ground_namespace=ground,
    )
    assert ros.spin_until(lambda: node.recorder.counts["joints"] > 0, timeout=10.0)
    assert _flood(ros, node)
    count = node.recorder.counts["joints"]
    assert ros.spin_until(lambda: node.recorder.counts["joints"] > count, timeout=10.0)


def test_the_link_carries_malformed_bytes_as_they_are_and_runs_on(ros):
    """A radio link carries bits: the receivers judge them (the controller rejects them, above).
    The link itself neither parses nor stops."""
    node = _node(ros, LinkNode, status_period=0.1)
    status = Recorder(ros.probe(), DiagnosticArray, "rns_link/status")
    assert _flood(ros, node)
    _keeps_publishing(ros, status)
    values = status_values(status.messages[-1])
    assert int(values["uplink sent"]) > 0


def test_the_predictor_rejects_malformed_inputs_and_runs_on(ros):
    node = _node(ros, PredictorNode, status_period=0.1)
    status = Recorder(ros.probe(), DiagnosticArray, "rns_predictor/status")
    assert _flood(ros, node)
    _keeps_publishing(ros, status)
    assert status_values(status.messages[-1])["twists"] == "0"  # none taken
