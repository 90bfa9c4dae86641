"""rns_param / rns_topic (rns_ros.apps.param, .topic): ros2 param / ros2 topic without ros2cli.

The controller runs in this process in a Harness spun by a background thread; the tools' main()
is called in the main thread (their own Context, joining the domain of the environment, as the
console scripts do). A few checks run the installed executables as a user would.
Domain 72 on loopback only, whatever the caller's environment says.
"""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

DOMAIN_ID = 72
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
    /rns_rostools_test at 50 Hz."""
    from std_msgs.msg import String

    from rns_ros.harness import Harness
    from rns_ros.nodes.controller import ControllerNode

    with pytest.MonkeyPatch.context() as patch:
        for key, value in ENV.items():
            patch.setenv(key, value)
        with Harness(domain_id=DOMAIN_ID) as harness:
            controller = harness.add(ControllerNode)
            probe = harness.probe("rns_rostools_probe")
            publisher = probe.create_publisher(String, "rns_rostools_test", 10)
            probe.create_timer(0.02, lambda: publisher.publish(String(data="tick")))
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
    from rns_ros.apps.param import param_main

    before = stack.node.get_parameter("method").value
    code, out, _ = _run(capsys, param_main, "set", "/rns_controller", "method", "foo")
    assert code == 1
    assert out.startswith("Setting parameter failed: ")
    assert "one of" in out
    assert "'foo'" in out
    assert stack.node.get_parameter("method").value == before

    # out of the descriptor's range: rclpy's reason
    code, out, _ = _run(capsys, param_main, "set", "/rns_controller", "epsilon", "50")
    assert code == 1
    assert "out of range" in out


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
def test_topic_list_shows_names_and_types(stack, capsys):
    from rns_ros.apps.topic import topic_main

    code, out, _ = _run(capsys, topic_main, "list")
    assert code == 0
    assert "/rns_controller/status [diagnostic_msgs/msg/DiagnosticArray]" in out.splitlines()


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
