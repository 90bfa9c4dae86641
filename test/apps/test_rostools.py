"""rns_param / rns_topic (rns_ros.apps.param, .topic): ros2 param / ros2 topic without ros2cli,
with ros2cli Jazzy's arguments and output.

The controller runs in this process in a Harness spun by a background thread; the tools' main()
is called in the main thread (their own Context, joining the domain of the environment, as the
console scripts do). A few checks run the installed executables as a user would.
Domain: ROS_DOMAIN_ID + 4, loopback only.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

DOMAIN_ID = int(os.environ.get("ROS_DOMAIN_ID", "43")) + 4
REPO = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
ENV = {
    "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
    "ROS_DOMAIN_ID": str(DOMAIN_ID),
    "AMENT_PREFIX_PATH": str(REPO / ".venv"),
}


@pytest.fixture(autouse=True)
def _environment(monkeypatch):
    """The tools read the domain from the environment; restored after each test."""
    for key, value in ENV.items():
        monkeypatch.setenv(key, value)
    monkeypatch.delenv("ROS_STATIC_PEERS", raising=False)


class _Background:
    """A Harness spun by a daemon thread until :meth:`stop`."""

    def __init__(self, harness) -> None:
        self.harness = harness
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)

    def _spin(self) -> None:
        while not self._stop.is_set():
            self.harness.executor.spin_once(timeout_sec=0.01)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)


@pytest.fixture(scope="module")
def stack():
    """``.node``: the controller (/rns_controller); ``.probe``: a node publishing
    /rns_rostools_test (String ``tick``) at 50 Hz, and at 20 Hz /rns_rostools_joints (JointState
    of joints a, b at 0.5, 1.5 rad, frame ``base``) and /rns_rostools_counter (Int32 counting
    up)."""
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Int32, String

    from rns_ros.harness import Harness
    from rns_ros.nodes.controller import ControllerNode

    with pytest.MonkeyPatch.context() as patch:
        for key, value in ENV.items():
            patch.setenv(key, value)
        with Harness(domain_id=DOMAIN_ID) as harness:
            controller = harness.add(ControllerNode)
            probe = harness.probe("rns_rostools_probe")
            publisher = probe.create_publisher(String, "rns_rostools_test", 10)
            joints = probe.create_publisher(JointState, "rns_rostools_joints", 10)
            counter = probe.create_publisher(Int32, "rns_rostools_counter", 10)
            count = iter(range(1 << 30))

            def publish_more() -> None:
                state = JointState(name=["a", "b"], position=[0.5, 1.5])
                state.header.frame_id = "base"
                state.header.stamp = probe.get_clock().now().to_msg()
                joints.publish(state)
                counter.publish(Int32(data=next(count)))

            probe.create_timer(0.02, lambda: publisher.publish(String(data="tick")))
            probe.create_timer(0.05, publish_more)
            background = _Background(harness)
            background.start()
            try:
                yield SimpleNamespace(node=controller, probe=probe)
            finally:
                background.stop()


def _run(capsys, main, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


# --- rns_param -----------------------------------------------------------------------------------
def test_set_changes_the_controller_method_and_get_round_trips(stack, capsys):
    from rns_ros.apps.param import param_main

    code, out, err = _run(capsys, param_main, "set", "/rns_controller", "method", "sc")
    assert (code, out.strip(), err) == (0, "Set parameter successful", "")
    assert stack.node.get_parameter("method").value == "sc"
    assert stack.node.controller.settings.method.value == "sc"

    code, out, err = _run(capsys, param_main, "get", "rns_controller", "method")
    assert (code, out.strip(), err) == (0, "String value is: sc", "")
    code, out, _ = _run(capsys, param_main, "get", "/rns_controller", "method", "--hide-type")
    assert (code, out.strip()) == (0, "sc")

    code, out, _ = _run(capsys, param_main, "set", "/rns_controller", "method", "dls")
    assert code == 0
    assert stack.node.get_parameter("method").value == "dls"


def test_set_refuses_an_invalid_value_with_the_controllers_reason(stack, capsys):
    """As ros2 param set: the refusal on stderr, exit code 0."""
    from rns_ros.apps.param import param_main

    before = stack.node.get_parameter("method").value
    code, out, err = _run(capsys, param_main, "set", "/rns_controller", "method", "foo")
    assert (code, out) == (0, "")
    assert err.startswith("Setting parameter failed: ")
    assert err.count("\n") == 1
    assert "one of" in err
    assert "'foo'" in err
    assert stack.node.get_parameter("method").value == before

    # out of the descriptor's range: rclpy's reason
    code, out, err = _run(capsys, param_main, "set", "/rns_controller", "epsilon", "50")
    assert (code, out) == (0, "")
    assert "out of range" in err


def test_get_prints_arrays_as_ros2_does(stack, capsys):
    """Python's list: strings quoted, booleans True / False."""
    from rns_ros.apps.param import param_main

    code, out, err = _run(capsys, param_main, "get", "/rns_controller", "joints")
    assert (code, err) == (0, ""), err
    names = ", ".join(f"'joint_{k}'" for k in range(1, 8))
    assert out == f"String values are: [{names}]\n"
    code, out, _ = _run(capsys, param_main, "get", "/rns_controller", "joints", "--hide-type")
    assert out == f"[{names}]\n"
    code, out, _ = _run(capsys, param_main, "get", "/rns_controller", "immediate_reaction")
    assert out == "Boolean value is: True\n"


def test_dump_prints_a_params_file_that_yaml_reads_back(stack, capsys, tmp_path):
    """ros2 param dump's layout: /NODE: ros__parameters: with every parameter, sorted, then a
    blank line; --output-dir writes the same YAML to DIR/<node>.yaml."""
    import yaml

    from rns_ros.apps.param import param_main

    code, out, err = _run(capsys, param_main, "dump", "/rns_controller")
    assert (code, err) == (0, ""), err
    assert out.startswith("/rns_controller:\n  ros__parameters:\n")
    assert out.endswith("\n\n")
    parameters = yaml.safe_load(out)["/rns_controller"]["ros__parameters"]
    assert list(parameters) == sorted(parameters)
    for name in ("method", "epsilon", "joints", "rate", "immediate_reaction"):
        assert parameters[name] == stack.node.get_parameter(name).value, name
    assert isinstance(parameters["epsilon"], float)

    code, out, err = _run(
        capsys, param_main, "dump", "rns_controller", "--output-dir", str(tmp_path / "params")
    )
    written = tmp_path / "params" / "rns_controller.yaml"
    assert (code, err) == (0, ""), err
    assert out == f"Saving to:  {written}\n"
    assert yaml.safe_load(written.read_text())["/rns_controller"]["ros__parameters"] == parameters


def test_load_restores_the_dumped_values_and_reports_each(stack, capsys, tmp_path):
    """Each parameter of the file set one by one, as ros2 param load: successes on stdout,
    refusals (read-only parameters) on stderr, exit code 0."""
    from rns_ros.apps.param import param_main

    code, out, _ = _run(capsys, param_main, "dump", "/rns_controller")
    assert code == 0
    saved = tmp_path / "controller.yaml"
    saved.write_text(out)
    before = {n: stack.node.get_parameter(n).value for n in ("method", "epsilon", "state_timeout")}
    for name, value in (("method", "sc"), ("epsilon", "0.5"), ("state_timeout", "0.4")):
        assert _run(capsys, param_main, "set", "/rns_controller", name, value)[0] == 0
    assert stack.node.get_parameter("method").value == "sc"

    code, out, err = _run(capsys, param_main, "load", "/rns_controller", str(saved))
    assert code == 0, err
    after = {n: stack.node.get_parameter(n).value for n in before}
    assert after == before
    assert "Set parameter method successful\n" in out
    assert "Set parameter epsilon successful\n" in out
    assert re.search(r"^Set parameter rate failed: .*read-only", err, re.M), err
    assert all(line.startswith("Set parameter ") for line in (out + err).splitlines())


def test_load_names_a_file_without_the_node_and_refuses_a_non_params_file(capsys, tmp_path):
    from rns_ros.apps.param import param_main

    other = tmp_path / "other.yaml"
    other.write_text("/rns_simulator:\n  ros__parameters:\n    rate: 100.0\n")
    code, out, err = _run(capsys, param_main, "load", "/rns_controller", str(other))
    assert (code, out) == (1, "")
    assert "has no section for /rns_controller (its sections: /rns_simulator)" in err
    assert err.count("\n") == 1
    plain = tmp_path / "plain.yaml"
    plain.write_text("[1, 2]\n")
    code, out, err = _run(capsys, param_main, "load", "/rns_controller", str(plain))
    assert (code, out) == (2, "")
    assert "not a params file" in err
    assert err.count("\n") == 1


def test_file_parameters_nest_groups_and_apply_the_wildcard_first(tmp_path):
    from rns_ros.apps.param import file_parameters

    params = tmp_path / "params.yaml"
    params.write_text(
        "/**:\n  ros__parameters:\n    use_sim_time: true\n    rate: 10.0\n"
        "rns_controller:\n  ros__parameters:\n    rate: 100.0\n    gains: {k: 2, d: [1, 2]}\n"
    )
    node = {"rate": 100.0, "gains.k": 2, "gains.d": [1, 2]}
    assert file_parameters(params, "/rns_controller") == node
    assert file_parameters(params, "/rns_controller", use_wildcard=True) == {
        "use_sim_time": True,
        **node,
    }


def test_set_types_values_like_ros2_param(stack, capsys):
    from rns_ros.apps.param import param_main

    # an integer for a double parameter is sent as a double (ros2 param would be refused)
    code, out, _ = _run(capsys, param_main, "set", "/rns_controller", "epsilon", "1")
    assert code == 0, out
    assert stack.node.get_parameter("epsilon").value == 1.0
    code, out, _ = _run(capsys, param_main, "set", "/rns_controller", "epsilon", "0.2")
    assert code == 0
    assert stack.node.get_parameter("epsilon").value == 0.2
    code, out, _ = _run(capsys, param_main, "get", "/rns_controller", "epsilon")
    assert out.strip() == "Double value is: 0.2"


def test_parse_parameter_value():
    from rcl_interfaces.msg import ParameterType as T

    from rns_ros.apps.param import parse_parameter_value as parse

    assert parse("true").type == T.PARAMETER_BOOL
    assert parse("3").integer_value == 3
    assert parse("0.5").double_value == 0.5
    assert parse("sc").string_value == "sc"
    assert list(parse("[1, 2]").integer_array_value) == [1, 2]
    assert list(parse("[0, 0.5]").double_array_value) == [0.0, 0.5]
    assert list(parse("[a, b]").string_array_value) == ["a", "b"]
    assert list(parse("[true, false]").bool_array_value) == [True, False]
    assert parse("{a: 1}").string_value == "{a: 1}"  # ros2 param crashes here
    assert parse("'unterminated").string_value == "'unterminated"
    assert parse("123", declared=T.PARAMETER_STRING).string_value == "123"
    assert parse("2", declared=T.PARAMETER_DOUBLE).double_value == 2.0


def test_parse_parameter_value_refuses_an_alias_bomb():
    from rns_testing import alias_bomb_flow

    from rns_ros.apps.param import parse_parameter_value as parse
    from rns_ros.tool_session import UsageError

    with pytest.raises(UsageError, match=r"^VALUE: more than \d+ YAML nodes"):
        parse(alias_bomb_flow())
    assert list(parse("[&a 1, *a]").integer_array_value) == [1, 1]  # a few aliases are YAML


def test_describe_shows_range_constraints_and_read_only(stack, capsys):
    from rns_ros.apps.param import param_main

    code, out, err = _run(capsys, param_main, "describe", "/rns_controller", "epsilon", "method")
    assert code == 0, err
    assert "Parameter name: epsilon" in out
    assert "Type: double" in out
    assert "Min value: 1e-06" in out
    assert "Max value: 10.0" in out
    assert "Read only: false" in out
    assert "Additional constraints: one of ['dls', 'sc', 'pinv', 'conventional']" in out
    code, out, _ = _run(capsys, param_main, "describe", "/rns_controller", "rate")
    assert "Read only: true" in out
    assert "Max value: 1000.0" in out

    code, out, err = _run(capsys, param_main, "describe", "/rns_controller", "no_such")
    assert code == 1
    assert "no_such" in err
    assert "not declared" in err


def test_list_names_the_parameters(stack, capsys):
    from rns_ros.apps.param import param_main

    code, out, _ = _run(capsys, param_main, "list", "/rns_controller")
    assert code == 0
    names = out.split()
    assert "method" in names
    assert "epsilon" in names
    assert names == sorted(names)

    code, out, _ = _run(capsys, param_main, "list")
    assert code == 0
    # every node, then its parameters indented under it
    block = out.split("/rns_controller:\n", 1)[1].split("\n/", 1)[0].split("\n")
    assert "  command_timeout" in block
    assert all(line.startswith("  ") for line in block if line)


def test_missing_node_and_parameter_are_one_line_exit_1(stack, capsys, monkeypatch):
    """A missing node: exit 1, one line, after waiting --timeout for it (the wait the session was
    asked for, not the wall time it took); a missing parameter likewise."""
    from rns_ros.apps.param import param_main
    from rns_ros.tool_session import ToolSession

    waits = []
    spin_until = ToolSession.spin_until

    def recorded(session, done, timeout):
        waits.append(timeout)
        return spin_until(session, done, timeout)

    monkeypatch.setattr(ToolSession, "spin_until", recorded)
    code, out, err = _run(capsys, param_main, "get", "/nobody", "x", "--timeout", "0.5")
    assert code == 1
    assert out == ""
    assert err.count("\n") == 1
    assert "node /nobody not found within 0.5 s" in err
    assert waits == [0.5]  # one wait for the node's services, --timeout long
    monkeypatch.undo()

    code, out, err = _run(capsys, param_main, "get", "/rns_controller", "no_such")
    assert code == 1
    assert err.count("\n") == 1
    assert "no_such" in err


@pytest.mark.parametrize(
    "argv",
    [
        [],
        ["frobnicate"],
        ["get", "/rns_controller"],
        ["set", "/rns_controller", "method"],
        ["get", "/rns_controller", "method", "--timeout", "-1"],
        ["get", "/no body", "method"],
    ],
)
def test_bad_usage_is_one_line_exit_2(argv, capsys):
    from rns_ros.apps.param import param_main

    code, out, err = _run(capsys, param_main, *argv)
    assert code == 2
    assert out == ""
    assert err.startswith("rns_param: "), err
    assert err.count("\n") == 1, err


# --- rns_topic -----------------------------------------------------------------------------------
def test_topic_list_prints_names_and_with_t_types(stack, capsys):
    """As ros2 topic list: one name a line (scripts read them); -t adds [type]; -c counts."""
    from rns_ros.apps.topic import topic_main

    code, out, _ = _run(capsys, topic_main, "list")
    assert code == 0
    lines = out.splitlines()
    assert "/rns_controller/status" in lines
    assert all(re.fullmatch(r"/\S+", line) for line in lines), out
    code, out, _ = _run(capsys, topic_main, "list", "-t")
    assert code == 0
    assert "/rns_controller/status [diagnostic_msgs/msg/DiagnosticArray]" in out.splitlines()
    code, out, _ = _run(capsys, topic_main, "list", "--count-topics")
    assert code == 0
    assert int(out) >= 5  # the controller's and the probe's


def test_topic_list_verbose_counts_publishers_and_subscribers(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, _ = _run(capsys, topic_main, "list", "-v")
    assert code == 0
    published, subscribed = out.split("\n\n")[:2]
    assert published.startswith("Published topics:\n")
    assert " * /rns_controller/status [diagnostic_msgs/msg/DiagnosticArray] 1 publisher" in (
        published.splitlines()
    )
    assert subscribed.startswith("Subscribed topics:\n")
    assert " * /cmd_twist [geometry_msgs/msg/TwistStamped] 1 subscriber" in subscribed.splitlines()


def test_echo_once_prints_the_controller_status_as_yaml(stack, capsys):
    import yaml

    from rns_ros.apps.topic import topic_main

    code, out, err = _run(capsys, topic_main, "echo", "/rns_controller/status", "--once")
    assert code == 0, err
    assert out.endswith("---\n")
    assert out.count("---\n") == 1
    status = yaml.safe_load(out.removesuffix("---\n"))
    assert set(status) == {"header", "status"}
    keys = [value["key"] for value in status["status"][0]["values"]]
    assert "state" in keys
    assert isinstance(status["status"][0]["level"], int)  # a `byte`, not !!binary


def test_echo_count(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, _ = _run(capsys, topic_main, "echo", "rns_rostools_test", "--count", "3")
    assert code == 0
    assert out == "data: tick\n---\n" * 3


def test_echo_takes_the_type_as_second_argument(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(
        capsys, topic_main, "echo", "rns_rostools_test", "std_msgs/msg/String", "--once"
    )
    assert (code, err) == (0, ""), err
    assert out == "data: tick\n---\n"


def test_echo_field_prints_the_field_as_ros2(stack, capsys):
    """A message field as YAML; a string its text; a sequence Python's value of it."""
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(
        capsys, topic_main, "echo", "/rns_rostools_joints", "--field", "header.frame_id", "--once"
    )
    assert (code, err, out) == (0, "", "base\n---\n")
    code, out, _ = _run(
        capsys, topic_main, "echo", "/rns_rostools_joints", "--field", "header.stamp", "--once"
    )
    assert re.fullmatch(r"sec: \d+\nnanosec: \d+\n---\n", out), out
    code, out, _ = _run(
        capsys, topic_main, "echo", "/rns_rostools_joints", "--field", "position", "--once"
    )
    assert out == "array('d', [0.5, 1.5])\n---\n"


def test_echo_a_field_the_type_lacks_is_one_line_exit_1(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(capsys, topic_main, "echo", "/rns_rostools_joints", "--field", "pose.x")
    assert (code, out) == (1, "")
    assert err == (
        "rns_topic: Invalid field 'pose.x': 'JointState' object has no attribute 'pose'\n"
    )


def test_echo_csv_is_one_line_of_every_field(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(
        capsys, topic_main, "echo", "/rns_rostools_joints", "--csv", "--count", "2"
    )
    assert (code, err) == (0, ""), err
    lines = out.splitlines()
    assert len(lines) == 2
    for line in lines:  # stamp, frame_id, name[], position[], velocity[] (empty), effort[]
        assert re.fullmatch(r"\d+,\d+,base,a,b,0\.5,1\.5,,", line), line


def test_echo_no_arr_no_str_and_flow_style(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(
        capsys, topic_main, "echo", "/rns_rostools_joints", "--no-arr", "--no-str", "--once"
    )
    assert (code, err) == (0, ""), err
    lines = out.splitlines()
    assert "  frame_id: '<string length: <4>>'" in lines
    assert "name: '<sequence type: string, length: 2>'" in lines
    assert "position: '<sequence type: double, length: 2>'" in lines
    code, out, _ = _run(capsys, topic_main, "echo", "rns_rostools_test", "--flow-style", "--once")
    assert out == "{data: tick}\n---\n"


def test_echo_filter_prints_only_the_messages_it_accepts(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(
        capsys, topic_main, "echo", "/rns_rostools_counter", "--filter", "m.data % 5 == 0",
        "--count", "3",
    )  # fmt: skip
    assert (code, err) == (0, ""), err
    values = [int(v) for v in re.findall(r"^data: (\d+)$", out, re.M)]
    assert len(values) == 3
    assert all(v % 5 == 0 for v in values)
    assert values == sorted(values)


@pytest.mark.parametrize(
    ("expr", "code", "words"),
    [("m.data ==", 2, "is not a Python expression"), ("m.nope", 1, "AttributeError")],
)
def test_echo_a_bad_filter_is_one_line(stack, capsys, expr, code, words):
    from rns_ros.apps.topic import topic_main

    got, out, err = _run(capsys, topic_main, "echo", "/rns_rostools_counter", "--filter", expr)
    assert (got, out) == (code, "")
    assert err.startswith("rns_topic: --filter ")
    assert words in err
    assert err.count("\n") == 1


def test_echo_message_info_comes_before_each_message(stack, capsys):
    import yaml

    from rns_ros.apps.topic import topic_main

    code, out, err = _run(capsys, topic_main, "echo", "rns_rostools_test", "-i", "--once")
    assert (code, err) == (0, ""), err
    info, message, rest = out.split("---\n")
    assert rest == ""
    assert {"source_timestamp", "received_timestamp"} <= set(yaml.safe_load(info))
    assert message == "data: tick\n"


def test_echo_qos_options_override_what_the_publishers_offer(stack, capsys):
    """A latched message: --qos-durability transient_local gets it; volatile does not, and
    --timeout then ends the echo with exit code 0, as ros2."""
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from std_msgs.msg import String

    from rns_ros.apps.topic import topic_main

    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    publisher = stack.probe.create_publisher(String, "rns_rostools_latched_qos", latched)
    publisher.publish(String(data="urdf"))
    code, out, err = _run(
        capsys, topic_main, "echo", "rns_rostools_latched_qos", "std_msgs/msg/String",
        "--qos-profile", "system_default", "--qos-reliability", "reliable",
        "--qos-durability", "transient_local", "--qos-depth", "1", "--once",
    )  # fmt: skip
    assert (code, err, out) == (0, "", "data: urdf\n---\n")
    code, out, err = _run(
        capsys, topic_main, "echo", "rns_rostools_latched_qos", "std_msgs/msg/String",
        "--qos-durability", "volatile", "--timeout", "2",
    )  # fmt: skip
    assert (code, err, out) == (0, "", "")


def test_qos_choices_are_rclpys_short_keys():
    """Spelled out for the parser (built before rclpy loads): kept equal to rclpy's."""
    from rclpy import qos

    from rns_ros import tool_qos

    ours = [
        tool_qos.QOS_PROFILES,
        tool_qos.QOS_HISTORY,
        tool_qos.QOS_RELIABILITY,
        tool_qos.QOS_DURABILITY,
        tool_qos.QOS_LIVELINESS,
    ]
    kinds = [
        qos.QoSPresetProfiles,
        qos.QoSHistoryPolicy,
        qos.QoSReliabilityPolicy,
        qos.QoSDurabilityPolicy,
        qos.QoSLivelinessPolicy,
    ]
    assert ours == [tuple(kind.short_keys()) for kind in kinds]


def test_configured_qos_overrides_a_copy_of_the_preset():
    from rclpy.qos import DurabilityPolicy, QoSPresetProfiles, ReliabilityPolicy

    from rns_ros.apps.topic import _topic_parser
    from rns_ros.tool_qos import configured_qos

    args = _topic_parser().parse_args(
        ["pub", "/x", "std_msgs/msg/Bool", "--qos-profile", "sensor_data", "--qos-depth", "3",
         "--qos-durability", "transient_local"]
    )  # fmt: skip
    qos = configured_qos(args)
    assert (qos.depth, qos.reliability) == (3, ReliabilityPolicy.BEST_EFFORT)
    assert qos.durability == DurabilityPolicy.TRANSIENT_LOCAL
    preset = QoSPresetProfiles.get_from_short_key("sensor_data")
    assert (preset.depth, preset.durability) == (5, DurabilityPolicy.VOLATILE)


def test_messages_as_ros2_prints_them_with_no_arr_and_csv():
    from geometry_msgs.msg import PoseWithCovariance
    from std_msgs.msg import UInt8MultiArray

    from rns_ros.ros_messages import message_to_csv, message_to_dict

    pose = PoseWithCovariance()
    assert message_to_dict(pose, no_arr=True)["covariance"] == "<array type: double[36]>"
    assert message_to_csv(pose, 2) == "0.0,0.0,0.0,0.0,0.0,0.0,1.0,0.0,0.0,..."
    data = UInt8MultiArray(data=[1, 2, 3])
    assert message_to_dict(data, no_arr=True)["data"] == "<sequence type: uint8, length: 3>"
    assert message_to_csv(data) == ",0,1,2,3"  # layout: no dims, offset 0; then the data


def test_echo_gets_a_latched_message_published_before_it_started(stack, capsys):
    """robot_description style: published once, transient local; echo adapts its QoS."""
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from std_msgs.msg import String

    from rns_ros.apps.topic import topic_main

    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    publisher = stack.probe.create_publisher(String, "rns_rostools_latched", latched)
    publisher.publish(String(data="urdf"))
    code, out, err = _run(capsys, topic_main, "echo", "rns_rostools_latched", "--once")
    assert code == 0, err
    assert out == "data: urdf\n---\n"


def test_message_to_dict_truncates_like_ros2():
    from sensor_msgs.msg import JointState

    from rns_ros.apps.topic import message_to_dict

    msg = JointState(name=["a"] * 200, position=[0.5] * 3)
    full = message_to_dict(msg, truncate=None)
    assert len(full["name"]) == 200
    assert full["position"] == [0.5, 0.5, 0.5]
    short = message_to_dict(msg)
    assert len(short["name"]) == 129
    assert short["name"][-1] == "..."


def test_hz_measures_a_50_hz_publisher(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(
        capsys, topic_main, "hz", "/rns_rostools_test", "--duration", "3.2", "--window", "100"
    )
    assert code == 0, err
    rates = [float(r) for r in re.findall(r"^average rate: ([\d.]+)$", out, re.M)]
    assert len(rates) == 3, out
    # how fast a loaded machine delivers is not this test's business (test_rate_stats checks
    # the arithmetic on given stamps): one report per second, each of a moving topic
    assert all(rate > 0.0 for rate in rates), out
    assert re.search(r"min: [\d.]+s max: [\d.]+s std dev: [\d.]+s window: \d+", out)


def test_missing_topic_is_one_line_exit_1(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, err = _run(capsys, topic_main, "echo", "/no_such_topic", "--timeout", "0.3")
    assert code == 1
    assert out == ""
    assert err.count("\n") == 1
    assert "topic /no_such_topic not found within 0.3 s" in err


def test_rate_stats():
    from rns_ros.apps.topic import RateStats

    stats = RateStats(window=3)
    assert stats.summary() is None
    for stamp in (0.0, 0.1, 0.2, 0.3, 0.5):  # the window keeps the last 3 intervals
        stats.add(stamp)
    summary = stats.summary()
    assert summary.startswith("average rate: 7.500\n")
    assert "min: 0.100s max: 0.200s" in summary
    assert "window: 4" in summary


# --- the installed executables -------------------------------------------------------------------
def _installed(name: str) -> str:
    path = BIN / name
    if not path.exists():
        pytest.skip(f"{path} not installed (run `make venv`)")
    return str(path)


def _environ() -> dict[str, str]:
    import os

    return {**os.environ, **ENV}


@pytest.mark.parametrize("name", ["rns_param", "rns_topic", "rns_service"])
def test_installed_scripts_answer_help_and_reject_bad_usage(name):
    script = _installed(name)
    result = subprocess.run(
        [script, "--help"], capture_output=True, text=True, timeout=30, env=_environ()
    )
    assert result.returncode == 0
    assert result.stdout.startswith(f"usage: {name}")
    result = subprocess.run(
        [script, "bogus"], capture_output=True, text=True, timeout=30, env=_environ()
    )
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr.startswith(f"{name}: ")
    assert result.stderr.count("\n") == 1


def test_installed_rns_topic_exits_0_quietly_on_ctrl_c():
    process = subprocess.Popen(
        [_installed("rns_topic"), "hz", "/no_such_topic", "--timeout", "30"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_environ(),
    )
    try:
        time.sleep(2.0)  # imports and rclpy.init done, waiting for the topic
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=10)
    finally:
        process.kill()
    assert (process.returncode, out, err) == (0, "", "")


def test_installed_rns_param_in_a_bad_domain_is_one_line_exit_2():
    result = subprocess.run(
        [_installed("rns_param"), "get", "/rns_controller", "method"],
        capture_output=True,
        text=True,
        timeout=30,
        env={**_environ(), "ROS_DOMAIN_ID": "not-a-number"},
    )
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1
    assert "ROS_DOMAIN_ID" in result.stderr
