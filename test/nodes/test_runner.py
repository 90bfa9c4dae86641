"""The shared node main(): Ctrl-C / SIGTERM end the spin with exit code 0 without raising inside
node code, while the Context still works, so destroy_node() can publish a final zero."""

from __future__ import annotations

import contextlib
import itertools
import os
import re
import signal
import threading
import time
from types import SimpleNamespace

import pytest
import rclpy
from rclpy.node import Node
from std_msgs.msg import String

from rns_ros.nodes.parameters import ParameterSpec, declare_parameters, warn_unknown_parameters
from rns_ros.nodes.runner import publish_copies, publish_last, run_node, stop_worker

#: What a node's parameters module defines, for the test nodes here.
TEST_NODE = SimpleNamespace(NODE_NAME="rns_runner_test", SUMMARY="", PARAMETERS=())


class _Busy(Node):
    """Publishes every millisecond; the signal comes from another thread after 0.3 s (``kill``)
    or is delivered by calling the installed handler inside a timer callback (``in_callback``:
    where a raising handler can land in rclpy's C++ message conversion, seen in CI as a
    RuntimeError and exit code 1)."""

    def __init__(self, signum: int, delivery: str) -> None:
        super().__init__("rns_runner_test")
        self.signum = signum
        self.delivery = delivery
        self.publisher = self.create_publisher(String, "rns_runner_test", 10)
        self.ticks = 0
        self.raised: list[BaseException] = []
        self.final: list[bool] = []
        self.create_timer(0.001, self._tick)
        if delivery == "kill":
            threading.Timer(0.3, os.kill, (os.getpid(), signum)).start()

    def _tick(self) -> None:
        self.ticks += 1
        self.publisher.publish(String(data="x" * 256))
        if self.delivery == "in_callback" and self.ticks == 100:
            try:
                signal.getsignal(self.signum)(self.signum, None)
            except BaseException as exc:  # whatever it is, it must not happen
                self.raised.append(exc)
        if self.ticks == 5000:  # still spinning 5 s on: stop the test run the hard way
            os.kill(os.getpid(), signal.SIGINT)

    def destroy_node(self) -> None:
        # what the controller does on shutdown: one last message, which needs a live Context
        self.final.append(rclpy.ok())
        self.publisher.publish(String(data="stop"))
        super().destroy_node()


@pytest.mark.parametrize("delivery", ["kill", "in_callback"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_ends_the_spin_with_exit_code_0_and_a_live_context_for_the_last_words(
    signum, delivery
):
    nodes: list[_Busy] = []

    def factory() -> _Busy:
        nodes.append(_Busy(signum, delivery))
        return nodes[-1]

    before = signal.getsignal(signum)
    code = run_node(factory, TEST_NODE, ["test"])
    assert code == 0
    assert nodes[0].raised == []  # the handler only asks the spin loop to stop
    assert nodes[0].final == [True]  # destroy_node ran before the Context was shut down
    assert signal.getsignal(signum) is before  # our handler is gone again
    assert not rclpy.ok()


# --- start-up failures: one line and exit code 2, never a traceback -----------------
class _Quiet(Node):
    def __init__(self) -> None:
        super().__init__("rns_runner_test")
        declare_parameters(self, (ParameterSpec("rate", 50.0, "Rate", "[Hz]", 1.0, 1000.0),))


@pytest.mark.parametrize(
    ("ros_args", "message"),
    [
        (["-p"], r"^rns_runner_test: invalid ROS arguments: Couldn't parse trailing -p"),
        (["--bogus"], r"^rns_runner_test: unknown ROS arguments \['--bogus'\]"),
        # raised inside Node.__init__ (rclpy declares use_sim_time itself)
        (["-p", "use_sim_time:=maybe"], r"^rns_runner_test: .*'use_sim_time' to 'maybe'"),
        (["-p", "rate:=0.0"], r"^rns_runner_test: parameter 'rate' out of range"),
    ],
)
def test_bad_ros_arguments_give_one_line_and_exit_code_2(capsys, ros_args, message):
    before = signal.getsignal(signal.SIGINT)
    code = run_node(_Quiet, TEST_NODE, ["t", "--ros-args", *ros_args])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1, err
    assert re.search(message, err), err
    assert signal.getsignal(signal.SIGINT) is before
    assert not rclpy.ok()


def test_unknown_overrides_are_warned_about_with_the_closest_name():
    args = ["t", "--ros-args", "-p", "ratee:=3.0", "-p", "use_sim_time:=true", "-p", "zzz:=1"]
    args += ["-p", "qos_overrides./x.publisher.depth:=3"]
    context = rclpy.Context()
    rclpy.init(args=args, context=context)
    try:
        node = Node("rns_runner_test", context=context)
        declare_parameters(node, (ParameterSpec("rate", 50.0, "Rate", "[Hz]", 1.0, 1000.0),))
        logged: list[str] = []

        class _Logger:
            def warning(self, text: str) -> None:
                logged.append(text)

        node.get_logger = _Logger  # type: ignore[method-assign]
        assert warn_unknown_parameters(node) == ["ratee", "zzz"]
        assert logged[0] == "unknown parameter 'ratee' is ignored; did you mean 'rate'?"
        assert logged[1].startswith("unknown parameter 'zzz' is ignored; valid names: [")
        assert "'rate'" in logged[1]
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)


def test_help_marks_the_parameters_that_change_at_run_time():
    """--help says which parameters the node applies while running: exactly the specs that are
    not read-only, and the controller applies each of them (its set-parameters callback)."""
    from rns_ros.nodes import controller_parameters as controller
    from rns_ros.nodes import simulator_parameters as simulator
    from rns_ros.nodes.runner import parameter_help

    for module in (controller, simulator):
        text = parameter_help(module.NODE_NAME, module.SUMMARY, module.PARAMETERS)
        marked = {line.split()[0] for line in text.splitlines() if line.endswith("[run time]")}
        assert marked == {spec.name for spec in module.PARAMETERS if not spec.read_only}
    assert {"method", "state_timeout", "max_angular_speed"} <= {
        spec.name for spec in controller.PARAMETERS if not spec.read_only
    }


# --- last words ----------------------------------------------------------------------------------
class _Logger:
    def __init__(self) -> None:
        self.warnings: list[str] = []

    def warn(self, text: str) -> None:
        self.warnings.append(text)


class _Node:
    def __init__(self) -> None:
        self.logger = _Logger()

    def get_logger(self) -> _Logger:
        return self.logger


class _Publisher:
    def __init__(self) -> None:
        self.waits: list[float] = []

    def wait_for_all_acked(self, timeout) -> bool:
        self.waits.append(timeout.nanoseconds * 1e-9)
        return True


def test_the_last_message_waits_for_acknowledgement_and_a_failure_is_only_logged():
    node, publisher, sent = _Node(), _Publisher(), []
    publish_last(node, lambda: sent.append("zero"), "zero torque", acked_by=publisher, timeout=0.2)
    assert sent == ["zero"]
    assert publisher.waits == [0.2]
    assert node.logger.warnings == []

    def broken() -> None:
        raise RuntimeError("context is not valid")

    publish_last(node, broken, "zero torque", acked_by=publisher)
    assert publisher.waits == [0.2]  # nothing published, nothing to wait for
    assert node.logger.warnings == ["could not publish the final zero torque: context is not valid"]


def test_copies_go_out_gap_apart():
    times: list[float] = []
    publish_copies(lambda: times.append(time.monotonic()), 3, 0.02)
    assert len(times) == 3
    assert all(later - earlier >= 0.02 for earlier, later in itertools.pairwise(times))


def test_a_worker_is_woken_and_joined():
    stop, wake = threading.Event(), threading.Event()

    def work() -> None:
        while not stop.is_set():
            wake.wait()

    thread = threading.Thread(target=work)
    thread.start()
    stop_worker(thread, stop, wake)
    assert stop.is_set()
    assert wake.is_set()
    assert not thread.is_alive()


#: A parent that starts rns_rerun_logger (saving an .rrd) as ProcessStack does, prints its pid
#: and waits to be killed.
_PARENT = """
import os, subprocess, sys, time
env = dict(os.environ, RNS_STOP_WITH_PARENT=str(os.getpid()))
logger = subprocess.Popen(
    [sys.argv[1], "--ros-args", "-p", "sink:=save", "-p", "rrd_path:=" + sys.argv[2]],
    env=env, stdout=open(sys.argv[3], "w"), stderr=subprocess.STDOUT,
)
print(logger.pid, flush=True)
time.sleep(600)
"""


def _ended(pid: int) -> bool:
    """The process is gone or a zombie nobody reaped yet."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except FileNotFoundError:
        return True


def test_a_node_stops_and_closes_its_recording_when_its_starter_is_killed(tmp_path):
    """kill -9 of the process that started a node (rns_demo, a test) with STOP_WITH_PARENT:
    the kernel's SIGINT stops the node as Ctrl-C does, and the .rrd it saved is complete."""
    import subprocess
    import sys
    from pathlib import Path

    from rns_ros.viz.readback import rrd_problem

    rrd, log = tmp_path / "run.rrd", tmp_path / "logger.log"
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    env.pop("RNS_STOP_WITH_PARENT", None)
    logger_bin = str(Path(sys.executable).parent / "rns_rerun_logger")
    parent = subprocess.Popen(
        [sys.executable, "-c", _PARENT, logger_bin, str(rrd), str(log)],
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    pid = int(parent.stdout.readline())
    try:
        deadline = time.monotonic() + 120.0
        while "recording to" not in log.read_text():
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.1)
        parent.kill()
        parent.wait()
        while not _ended(pid):
            assert time.monotonic() < deadline + 60.0, "the node runs on without its starter"
            time.sleep(0.1)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    assert "recording closed" in log.read_text()
    assert rrd_problem(rrd) is None
