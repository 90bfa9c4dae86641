"""Launch-free harness: run rns_ros nodes together without ``ros2 launch`` (not on PyPI).

Two ways to compose a stack, both confined to this machine (DDS discovery range LOCALHOST) and to
a domain of your choosing:

* :class:`Harness` - nodes in this process, on one executor with a private rclpy Context. Add node
  classes with parameter dicts, YAML parameter files and remappings, record topics as arrays, spin
  for a duration or until a condition, and tear everything down (also when a test fails: use it
  as a context manager). ``executor="events"`` spins them on rclpy's (experimental, C++)
  EventsExecutor instead of the SingleThreadedExecutor, which rebuilds its wait set in Python
  for every callback (``rns_demo`` runs use it)::

      from rns_ros.harness import Harness
      from rns_ros.nodes.simulator import SimulatorNode
      from rns_ros.nodes.controller import ControllerNode
      from sensor_msgs.msg import JointState

      with Harness(domain_id=77) as stack:
          stack.add(SimulatorNode, {"mode": "kinematic"})
          stack.add(ControllerNode, params_file="config/controller.yaml")
          joints = stack.record(JointState, "joint_states")
          stack.spin_until(lambda: len(joints) > 10, timeout=5.0)
          positions = joints.array(lambda m: m.position)   # (samples, 7)

* :class:`ProcessStack` - the installed console scripts (``rns_simulator`` ...) as subprocesses
  with ``--ros-args`` (``-p``, ``--params-file``, ``-r``), stopped with SIGINT like a terminal
  user would, killed if they do not exit.

Two stacks on one domain mix their clocks, states and commands. :func:`claim_domain` looks at
a domain's graph before a stack starts there and names any stack already running
(:func:`running_stack`); the claim's node stays on the graph while the stack runs, so a later
claim sees it too.
"""

from __future__ import annotations

import os
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import rclpy
import yaml
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from rclpy.task import Future

from rns_ros.cli import DOMAIN_ID_RANGE, STOP_WITH_PARENT, one_line
from rns_ros.core.errors import ConfigError, RnsError
from rns_ros.resources import apply_loopback_profile

#: DDS discovery never leaves the machine.
DISCOVERY_RANGE = "LOCALHOST"
#: Name of the node a :class:`Harness` records and publishes with (:meth:`Harness.probe`).
PROBE_NODE = "rns_harness_probe"
#: Executors a :class:`Harness` can spin its nodes on.
EXECUTORS = ("single_threaded", "events")
#: Recording QoS: best effort matches reliable and best-effort publishers alike; the history
#: keeps what arrives while this process waits for a core (10 000 messages: 20 s of a 500 Hz
#: stream), so a stalled recorder misses nothing.
RECORD_QOS = QoSProfile(depth=10_000, reliability=ReliabilityPolicy.BEST_EFFORT)
#: Node names of an rns_ros stack's nodes (the executables'), and the prefix of a claim's node
#: (:func:`claim_domain`; ``rns_demo`` names its claim ``rns_demo_<pid>``).
STACK_NODES = (
    "rns_simulator",
    "rns_controller",
    "rns_ptp",
    "rns_force_controller",
    "rns_attitude_control",
    "rns_operator",
    "rns_rerun_logger",
)
CLAIM_PREFIX = "rns_demo"
#: Topics whose publishers a second stack would mix with its own: the lockstep clock, the
#: robot states and every command stream.
STACK_TOPICS = (
    "/clock",
    "/joint_states",
    "/base_odom",
    "/cmd_twist",
    "/force_setpoint",
    "/joint_references",
    "/joint_velocities",
    "/joint_positions",
    "/joint_efforts",
    "/wheel_torque",
)
#: Wall time [s] a new node waits for DDS discovery before it reads the domain's graph (0.4 s
#: on localhost here).
DISCOVERY_WAIT = 2.0


def ros_environment(domain_id: int, base: Mapping[str, str] | None = None) -> dict[str, str]:
    """Environment for ROS processes: ``base`` (default os.environ) with the domain, localhost
    discovery without static peers, and the Fast DDS RMW (unless another is chosen)."""
    env = dict(os.environ if base is None else base)
    env["ROS_DOMAIN_ID"] = str(_domain(domain_id))
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = DISCOVERY_RANGE
    env.pop("ROS_STATIC_PEERS", None)  # peers would reach beyond this machine
    env.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    return env


def _domain(domain_id: int | None) -> int:
    """``domain_id``, or ``ROS_DOMAIN_ID`` of the environment (else 0), checked."""
    if domain_id is None:
        domain_id = os.environ.get("ROS_DOMAIN_ID", "0")
    low, high = DOMAIN_ID_RANGE
    try:
        value = int(domain_id)
    except (TypeError, ValueError):
        value = None
    if value is None or not low <= value <= high:
        raise ConfigError(f"domain_id must be an integer in [{low}, {high}], got {domain_id!r}")
    return value


class TopicLog:
    """Every message of one topic with its receipt time (monotonic [s]); ``msg_type``: the
    message class (None: not known).

    A raw log (:meth:`Harness.record` with ``raw=True``) keeps the serialized
    messages and deserializes them on first use of :attr:`messages`: recording costs no Python
    message per sample, which in a fast lockstep run is CPU the stack under test needs.
    :meth:`latest_stamp` reads a raw message's header stamp without deserializing it. Bytes
    that are not a message of the type (anyone on the domain may send them) are dropped and
    counted in :attr:`rejected`. :meth:`tap` hands each message on as it arrives (a recording
    written during the run).
    """

    def __init__(self, topic: str, msg_type: type | None = None) -> None:
        self.topic = topic
        self.msg_type = msg_type
        self._messages: list[Any] = []
        self._raw: list[bytes] = []  # serialized, received after every one in _messages
        self.received: list[float] = []
        self.rejected = 0  # raw messages that did not deserialize (dropped)
        self._tap: Callable[[bytes, float], None] | None = None

    def _append(self, msg) -> None:
        self._messages.append(msg)
        self.received.append(time.monotonic())
        if self._tap is not None:
            self._tap(serialize_message(msg), self.received[-1])

    def _append_raw(self, data: bytes) -> None:
        self._raw.append(data)
        self.received.append(time.monotonic())
        if self._tap is not None:
            self._tap(data, self.received[-1])

    def tap(self, sink: Callable[[bytes, float], None]) -> None:
        """Hand every message to ``sink(serialized bytes, receipt time [s, monotonic])``: those
        logged so far at once, in receipt order, then each as it arrives (in the executor's
        thread). Raw bytes go on as received, undecoded."""
        logged = [serialize_message(msg) for msg in self._messages] + list(self._raw)
        for data, received in zip(logged, self.received, strict=True):
            sink(data, received)
        self._tap = sink

    @property
    def messages(self) -> list[Any]:
        """The messages in receipt order (a raw log deserializes what it has not yet)."""
        if self._raw:
            start = len(self._messages)
            received = self.received[:start]
            for data, at in zip(self._raw, self.received[start:], strict=True):
                msg = self.decode(data)
                if msg is None:
                    self.rejected += 1
                else:
                    self._messages.append(msg)
                    received.append(at)
            self.received, self._raw = received, []
        return self._messages

    def decode(self, data: bytes):
        """``data`` as a message, or None when the bytes are not one."""
        try:
            return deserialize_message(data, self.msg_type)
        except Exception:  # rclpy raises RMWError for bytes that are not the type
            return None

    @messages.setter
    def messages(self, messages: list[Any]) -> None:
        self._messages, self._raw = list(messages), []

    def __len__(self) -> int:
        return len(self._messages) + len(self._raw)

    def serialized(self, start: int = 0) -> list[bytes]:
        """The serialized messages from the ``start``-th on, in receipt order (a raw log's
        bytes as received; a plain log's messages serialized)."""
        done = len(self._messages)
        kept = [serialize_message(msg) for msg in self._messages[start:]]
        return kept + self._raw[max(start - done, 0) :]

    def latest(self):
        """The newest message, or None."""
        for data in reversed(self._raw):  # bad bytes are counted once :attr:`messages` reads them
            msg = self.decode(data)
            if msg is not None:
                return msg
        return self._messages[-1] if self._messages else None

    def latest_stamp(self) -> float | None:
        """Header stamp [s] of the newest message (one with a header first), or None."""
        if self._raw:
            stamp = cdr_header_stamp(self._raw[-1])
            if stamp is not None:
                return stamp
        latest = self.latest()
        return None if latest is None else header_seconds(latest)

    def array(self, field: Callable[[Any], Any]) -> np.ndarray:
        """``field(msg)`` of every message stacked: shape (samples, ...) as float."""
        return np.array([field(msg) for msg in self.messages], dtype=float)

    def stamps(self) -> np.ndarray:
        """Header stamps [s], shape (samples,) (messages with a header)."""
        return self.array(header_seconds)


def header_seconds(msg) -> float:
    """A stamped message's ``header.stamp`` [s]."""
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec


#: CDR encapsulation identifiers (the first two bytes of a serialized message) -> struct byte
#: order: plain CDR big- and little-endian (XCDR1), the encodings rmw_fastrtps writes.
_CDR_BYTE_ORDER = {b"\x00\x00": ">", b"\x00\x01": "<"}


def cdr_header_stamp(data: bytes) -> float | None:
    """The header stamp [s] of a serialized message whose first field is a std_msgs/Header, read
    from its CDR bytes: after the 4-byte encapsulation, ``stamp.sec`` (int32) and
    ``stamp.nanosec`` (uint32) come first. None for another encapsulation or too few bytes."""
    order = _CDR_BYTE_ORDER.get(bytes(data[:2]))
    if order is None or len(data) < 12:
        return None
    sec, nanosec = struct.unpack_from(order + "iI", data, 4)
    return sec + 1e-9 * nanosec


class Harness:
    """Nodes in this process on one executor with a private Context (see the module docstring).

    Args:
        domain_id: ROS domain [0, 232]; default: ``ROS_DOMAIN_ID`` of the environment, else 0.
        ros_args: global ROS arguments for every node of the stack, as a command line gives them
            (``["--ros-args", "-p", "rate:=50.0", "-r", "joint_states:=arm/joint_states"]``).
            Parameters given to :meth:`add` take precedence over them.
        executor: ``single_threaded`` (rclpy's SingleThreadedExecutor) or ``events`` (rclpy's
            experimental EventsExecutor: the same callbacks in the same thread, sim-time timers
            included, without the Python wait-set rebuild per callback; in a lockstep run that
            overhead was most of the wall time).

    Raises:
        ConfigError: ``domain_id`` out of range, an unknown ``executor``, or ``ros_args`` that
            rcl cannot parse.

    Sets ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and removes ``ROS_STATIC_PEERS`` in this
    process's environment before the Context starts, so nothing it creates is discoverable from
    other machines.
    """

    def __init__(
        self,
        domain_id: int | None = None,
        ros_args: Iterable[str] = (),
        executor: str = "single_threaded",
    ) -> None:
        if executor not in EXECUTORS:
            raise ConfigError(f"executor must be one of {list(EXECUTORS)}, got {executor!r}")
        os.environ.pop("ROS_STATIC_PEERS", None)
        if apply_loopback_profile() is None:  # the loopback profile counts as localhost
            os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = DISCOVERY_RANGE
            apply_loopback_profile()
        self.domain_id = _domain(domain_id)
        self.context = rclpy.Context()
        ros_args = list(ros_args)
        if ros_args and ros_args[0] != "--ros-args":
            raise ConfigError(f"ros_args must start with '--ros-args', got {ros_args}")
        try:
            # argv[0] is a program name to rcl
            rclpy.init(args=["harness", *ros_args], context=self.context, domain_id=self.domain_id)
        except RuntimeError as exc:  # rcl's parse errors (RCLError derives from RuntimeError)
            raise ConfigError(f"invalid ROS arguments {ros_args}: {exc}") from None
        if executor == "events":
            self.executor = EventsExecutor(context=self.context)
        else:
            self.executor = SingleThreadedExecutor(context=self.context)
        self.nodes: list[Node] = []
        self._probe: Node | None = None
        self._never = Future()  # spin_until_future_complete on it: spin for a time in one call
        #: called with each log :meth:`record` makes from then on (e.g. ``McapRecording.add``)
        self.on_record: list[Callable[[TopicLog], None]] = []

    # --- composition ----------------------------------------------------------------------------
    def add(
        self,
        node: Node | Callable[..., Node],
        parameters: Mapping[str, Any] | None = None,
        *,
        params_file: str | Path | None = None,
        remappings: Mapping[str, str] | None = None,
        name: str | None = None,
    ) -> Node:
        """Add a node: an instance (made with ``context=harness.context``) or a node class /
        factory accepting rclpy Node keyword arguments, built here with ``parameters`` (dict),
        a ``params_file`` (ROS 2 YAML), ``remappings`` ({from: to}) and an optional ``name``."""
        if not isinstance(node, Node):
            cli_args = []
            if params_file is not None:
                if not Path(params_file).is_file():
                    raise ConfigError(f"params_file not found: {params_file}")
                cli_args += ["--params-file", str(params_file)]
            for source, target in (remappings or {}).items():
                cli_args += ["-r", f"{source}:={target}"]
            if name is not None:
                cli_args += ["-r", f"__node:={name}"]
            overrides = [Parameter(key, value=value) for key, value in (parameters or {}).items()]
            node = node(
                context=self.context,
                parameter_overrides=overrides,
                cli_args=["--ros-args", *cli_args] if cli_args else None,
            )
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def detach(self, node: Node) -> None:
        """Stop spinning ``node`` without destroying it (the caller owns it now)."""
        self.executor.remove_node(node)
        self.nodes.remove(node)

    def probe(self, name: str = PROBE_NODE) -> Node:
        """A plain node of the harness for recording and publishing (created once per name)."""
        if self._probe is None or self._probe.get_name() != name:
            self._probe = self.add(rclpy.create_node(name, context=self.context))
        return self._probe

    def record(
        self, msg_type, topic: str, qos: QoSProfile = RECORD_QOS, *, raw: bool = False
    ) -> TopicLog:
        """Start recording ``topic`` now; returns the growing :class:`TopicLog`, handed first to
        each of :attr:`on_record`. ``raw``: keep the serialized messages and deserialize them
        when the log is read (cheaper while the stack runs)."""
        log = TopicLog(topic, msg_type)
        for hook in self.on_record:  # before the subscription: from the first message
            hook(log)
        if raw:
            self.probe().create_subscription(msg_type, topic, log._append_raw, qos, raw=True)
        else:
            self.probe().create_subscription(msg_type, topic, log._append, qos)
        return log

    # --- running --------------------------------------------------------------------------------
    def spin_until(
        self,
        condition: Callable[[], bool],
        timeout: float = 10.0,
        *,
        check_every: float | None = None,
    ) -> bool:
        """Spin until ``condition()`` holds or ``timeout`` [s] of wall time passes; returns it.

        ``check_every`` [s]: test the condition at most this often (callbacks run in between)
        instead of after every callback, for a costly condition while messages stream in fast.
        """
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return True
            if check_every is None:
                self.executor.spin_once(timeout_sec=0.01)
            else:
                self._spin(min(check_every, max(deadline - time.monotonic(), 0.0)))
        return bool(condition())

    def spin_for(self, duration: float) -> None:
        """Spin for ``duration`` [s] of wall time."""
        deadline = time.monotonic() + duration
        while (left := deadline - time.monotonic()) > 0.0:
            self._spin(left)

    def _spin(self, duration: float) -> None:
        """Run callbacks for ``duration`` [s] in one executor call (not one per callback)."""
        self.executor.spin_until_future_complete(self._never, timeout_sec=duration)

    def close(self) -> None:
        """Destroy every node (newest first), stop the executor and the Context."""
        while self.nodes:
            node = self.nodes.pop()
            self.executor.remove_node(node)
            node.destroy_node()
        self.executor.shutdown()
        rclpy.try_shutdown(context=self.context)

    def __enter__(self) -> Harness:
        return self

    def __exit__(self, *_exc) -> None:
        self.close()


class DomainInUseError(RnsError):
    """Another stack runs on the domain a stack is to start on.

    Attributes:
        domain_id: the domain.
        stack: its nodes and the stack topics they publish (:func:`running_stack`).
    """

    def __init__(self, domain_id: int, stack: str) -> None:
        super().__init__(f"domain {domain_id} already has a running stack ({stack})")
        self.domain_id = domain_id
        self.stack = stack


def _full_name(name: str, namespace: str) -> str:
    return f"{namespace.rstrip('/')}/{name}"


def running_stack(node: Node) -> str | None:
    """The stack in ``node``'s graph other than ``node``: '/a, /b publishing /clock,
    /joint_states' for the nodes named as a stack's (:data:`STACK_NODES`, claims) and those
    publishing :data:`STACK_TOPICS`, with the topics published; None when there is none."""
    own = _full_name(node.get_name(), node.get_namespace())
    names = {
        _full_name(name, namespace)
        for name, namespace in node.get_node_names_and_namespaces()
        if name in STACK_NODES or name.startswith(CLAIM_PREFIX)
    }
    topics = []
    for topic in STACK_TOPICS:
        publishers = {
            _full_name(info.node_name, info.node_namespace)
            for info in node.get_publishers_info_by_topic(topic)
        } - {own}
        if publishers:
            topics.append(topic)
            names |= publishers
    names.discard(own)
    if not names:
        return None
    nodes = ", ".join(sorted(names))
    return f"{nodes} publishing {', '.join(topics)}" if topics else nodes


def claim_domain(domain_id: int | None, name: str, wait: float = DISCOVERY_WAIT) -> Harness:
    """A :class:`Harness` on ``domain_id`` holding one node ``name``, once ``wait`` [s] of DDS
    discovery found no other stack there (:func:`running_stack`). Keep it open while the stack
    runs: its node shows the domain taken to a later claim. Start the claim's ``name`` with
    :data:`CLAIM_PREFIX` and make it unique (two claims at once see each other).

    Raises:
        DomainInUseError: a stack already runs on the domain (closed again then).
        ConfigError: ``domain_id`` out of range.
    """
    harness = Harness(domain_id)
    try:
        node = harness.probe(name)
        time.sleep(wait)  # discovery runs in DDS's own threads
        stack = running_stack(node)
        if stack is not None:
            raise DomainInUseError(harness.domain_id, stack)
    except BaseException:
        harness.close()
        raise
    return harness


class ProcessStack:
    """Installed rns_ros executables as subprocesses (see the module docstring).

    Args:
        domain_id: ROS domain of every process.
        bin_dir: folder of the executables; default: next to this Python, else PATH.
        base_env: environment to start from (default: this process's), e.g. what sourcing a
            colcon ``install/setup.bash`` gives; the domain and LOCALHOST discovery are set on it.
    """

    def __init__(
        self,
        domain_id: int,
        bin_dir: str | Path | None = None,
        base_env: Mapping[str, str] | None = None,
    ) -> None:
        self.env = ros_environment(domain_id, base_env)
        # a process that ends without stopping its stack (kill -9) takes the stack with it:
        # each node then closes what it writes, as on Ctrl-C
        self.env[STOP_WITH_PARENT] = str(os.getpid())
        self.bin_dir = Path(bin_dir) if bin_dir else Path(sys.executable).parent
        self.processes: list[subprocess.Popen] = []
        self._logs: dict[int, Any] = {}
        self._names: dict[int, str] = {}  # pid -> executable, kept after stop()
        self._stop_timeouts: dict[int, float] = {}  # pid -> [s], where not stop()'s timeout

    def command(
        self,
        executable: str,
        parameters: Mapping[str, Any] | None = None,
        *,
        params_file: str | Path | None = None,
        remappings: Mapping[str, str] | None = None,
        extra: Iterable[str] = (),
        ros_args: Iterable[str] = (),
    ) -> list[str]:
        """The argument vector that starts ``executable`` with these ROS arguments
        (``extra``: before ``--ros-args``; ``ros_args``: more ROS arguments, after the others,
        e.g. ``["-p", "rate:=50.0"]``)."""
        path = self.bin_dir / executable
        program = str(path) if path.exists() else shutil.which(executable)
        if program is None:
            raise ConfigError(f"executable {executable!r} not found in {self.bin_dir} or on PATH")
        # the file first: rcl applies ROS arguments in order, so -p overrides what it sets
        arguments = [] if params_file is None else ["--params-file", str(params_file)]
        for key, value in (parameters or {}).items():
            text = yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("...")
            arguments += ["-p", f"{key}:={text.strip()}"]
        for source, target in (remappings or {}).items():
            arguments += ["-r", f"{source}:={target}"]
        arguments += list(ros_args)
        return [program, *extra, *(["--ros-args", *arguments] if arguments else [])]

    def start(
        self,
        executable: str,
        parameters=None,
        *,
        stop_timeout: float | None = None,
        **options,
    ) -> subprocess.Popen:
        """Start one executable (arguments as :meth:`command`). Its output goes to a temporary
        file (a pipe nobody reads would block a chatty process): see :meth:`output`.
        ``stop_timeout`` [s]: how long :meth:`stop` waits for it after SIGINT (default: its
        ``timeout``), e.g. for a recorder that writes out what it holds as it closes."""
        log = tempfile.TemporaryFile(mode="w+")  # noqa: SIM115 - closed on exit
        process = subprocess.Popen(
            self.command(executable, parameters, **options),
            env=self.env,
            stdout=log,
            stderr=subprocess.STDOUT,
            text=True,
        )
        self._logs[process.pid] = log
        self._names[process.pid] = executable
        if stop_timeout is not None:
            self._stop_timeouts[process.pid] = stop_timeout
        self.processes.append(process)
        return process

    def problems(self, limit: int = 5) -> list[str]:
        """The first ``limit`` WARN / ERROR log lines of each process started so far (stopped
        ones included), each prefixed with its executable: what a watchdog or a rejected
        command said during a run."""
        lines = []
        for pid, name in self._names.items():
            found = [
                line
                for line in self._text(pid).splitlines()
                if "[WARN]" in line or "[ERROR]" in line
            ]
            lines += [f"{name}: {line}" for line in found[:limit]]
        return lines

    def output(self, process: subprocess.Popen) -> str:
        """Everything ``process`` printed so far."""
        return self._text(process.pid)

    def _text(self, pid: int) -> str:
        log = self._logs[pid]
        log.flush()
        log.seek(0)
        return log.read()

    def exited(self) -> bool:
        """Whether a process of the stack has exited (a node that failed to start, or died)."""
        return any(process.poll() is not None for process in self.processes)

    def exit_report(self) -> str:
        """': <executable> exited (code c): <its last line>' for each process that exited, on
        one line, or '' while all run (for an error that says why a stack stopped). A node's
        start-up failure is its one-line error; a crash, the last line of its traceback."""
        reports = []
        for process in self.processes:
            code = process.poll()
            if code is None:
                continue
            lines = [line for line in self.output(process).splitlines() if line.strip()]
            last = one_line(lines[-1]) if lines else "no output"
            reports.append(f"{self._names[process.pid]} exited (code {code}): {last}")
        return f": {'; '.join(reports)}" if reports else ""

    def stop(self, timeout: float = 5.0) -> list[int]:
        """SIGINT every process, wait up to ``timeout`` [s] each (or its own ``stop_timeout``),
        kill the rest (an ERROR line in its output, for :meth:`problems`); exit codes."""
        for process in self.processes:
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        codes = []
        for process in self.processes:
            patience = self._stop_timeouts.get(process.pid, timeout)
            try:
                codes.append(process.wait(timeout=patience))
            except subprocess.TimeoutExpired:
                process.kill()
                codes.append(process.wait())
                log = self._logs[process.pid]
                log.seek(0, os.SEEK_END)
                log.write(f"[ERROR] still running {patience:g} s after SIGINT: killed\n")
        self.processes.clear()
        return codes

    def __enter__(self) -> ProcessStack:
        return self

    def __exit__(self, *_exc) -> None:
        self.stop()
        for log in self._logs.values():
            log.close()
        self._logs.clear()
        self._names.clear()
