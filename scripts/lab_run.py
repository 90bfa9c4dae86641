#!/usr/bin/env python3
"""The stack run the way a lab runs it, measured: numbers, not tests (nothing here asserts).

Usage:  .venv/bin/python scripts/lab_run.py [--scenario teleop|ptp|clock|all] [--repeat N]
                                            [--load] [--domain-id 56] [--load-domain-id 57]
                                            [--logs DIR] [--method NAME ...]

Every node is its console script from .venv/bin/, started by hand in its own process group with
a clean environment (PATH, HOME, ROS_*, RMW_IMPLEMENTATION=rmw_fastrtps_cpp: no
AMENT_PREFIX_PATH, no PYTHONPATH), localhost only, on --domain-id; a fresh stack per run. This
process measures with one rclpy node on that domain. Times are wall-clock seconds.

teleop  rns_simulator + rns_controller on the wall clock (method dls, then conventional): a
        held-out oblique turn streamed as TwistStamped on /cmd_twist at 50 Hz (stamped now,
        world frame), 0.1 rad/s about [1, -2, 1.5]/|.| for 10 s, then zeros for 3 s. Figures:
        the largest base attitude change [deg] from the first base_odom; the camera error [deg]
        at the end between exp(omega T) R_c0 (T: the commanded span of the stamps sent [s],
        world axes) and the measured camera attitude (rns_ros.core on joint_states + base_odom);
        the camera's turn [deg]; the controller's status tracking_error when the turn stops and at
        the end [deg]; the controller states seen.
ptp     rns_simulator + rns_ptp, per method: a held-out joint goal on /ptp_goal; the end state
        on ~/status (DONE, GOAL_MISSED, INVALID_GOAL; none within 120 s), the time to it [s],
        the largest final joint error [deg] against the goal sent (IJ-C and TJ-C steer the
        camera to a position target: they end ~2 deg off in the joints here) and, from DONE's
        message, against the plan's end, and the STALE_STATE, hold (a status
        saying "waiting" or "hold") and abandon (an active state followed by a fault) episodes.
clock   the lockstep pair as rns_demo runs it (sim time, lockstep, output_lead, await_commands),
        the controller's output_interface position, twists on simulated time; then a second
        /clock jumps +1e6 s three times and later runs backwards. Figures over every
        /joint_positions command: the largest distance past the URDF limits [rad] and
        |command - measured angle| [rad] (rns_simulator takes no position commands: the arm
        stays put), whether both processes live at the end, the controller's last status.

--load runs two busy loops and a second stack (rns_demo --no-record --real-time-factor 0,
looped, on --load-domain-id) beside the runs. Each row ends with the nodes seen on the domain
that are not this run's (another stack there mixes into the figures) and the load average.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile
from rclpy.signals import SignalHandlerOptions
from rclpy.time import Time
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rns_ros.core import FreeFloatingState, load_model
from rns_ros.nodes import controller_parameters, ptp_parameters
from rns_ros.resources import default_model_config
from rns_ros.runs.inspection import AWAIT_TIMEOUT

REPO = Path(__file__).resolve().parents[1]
BIN = REPO / ".venv" / "bin"
#: Operator stream: rate [Hz], speed [rad/s], axis (world), turn and stop durations [s].
TWIST_RATE, SPEED = 50.0, 0.1
AXIS = np.array([1.0, -2.0, 1.5]) / np.linalg.norm([1.0, -2.0, 1.5])
TURN, STOP = 10.0, 3.0
#: Held-out ptp goal [deg], tens of degrees from the simulator's default start
#: [-90, -30, 0, -70, 180, -30, 0] deg; the limit per goal [s].
PTP_GOAL_DEG = (-65.0, -50.0, 20.0, -45.0, 160.0, -10.0, 25.0)
PTP_LIMIT = 120.0
PTP_ENDS = ("DONE", "GOAL_MISSED", "INVALID_GOAL")
#: Time for the nodes to come up (imports, discovery) [s].
UP_TIMEOUT = 90.0
#: The lockstep pair as rns_demo runs it at its default 100 Hz (rns_ros.runs.inspection).
PERIOD, OPERATOR_LEAD = 0.01, 0.04
CLOCK_JUMP = 1e6


def clean_env(domain_id: int) -> dict[str, str]:
    """PATH, HOME, the ROS_* variables and RMW_IMPLEMENTATION, forced to loopback and
    ``domain_id``."""
    env = {key: value for key, value in os.environ.items() if key.startswith("ROS_")}
    env.update(PATH=os.environ.get("PATH", "/usr/bin:/bin"), HOME=os.environ.get("HOME", "/"))
    env.update(
        ROS_DOMAIN_ID=str(domain_id),
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        RMW_IMPLEMENTATION="rmw_fastrtps_cpp",
    )
    env.pop("ROS_LOCALHOST_ONLY", None)
    return env


def ros_value(value) -> str:
    """A parameter value as `-p name:=value` takes it."""
    return ("true" if value else "false") if isinstance(value, bool) else str(value)


class Groups:
    """Processes started in their own process groups; :meth:`stop` ends every group."""

    def __init__(self, log_dir: Path | None = None) -> None:
        self.processes: dict[subprocess.Popen, tuple[str, object]] = {}  # -> (name, log)
        self.log_dir = log_dir
        self.started = 0

    def start(self, name: str, argv: list[str], env: dict[str, str]) -> subprocess.Popen:
        """Start ``argv`` as a new session (its own group), output to a temporary file, or to
        ``log_dir``/NNN-name.log when given (kept)."""
        self.started += 1
        if self.log_dir is None:
            log = tempfile.TemporaryFile(mode="w+")  # noqa: SIM115 - closed in stop()
        else:
            path = self.log_dir / f"{self.started:03d}-{name}.log"
            log = path.open("w+")
        process = subprocess.Popen(
            argv, env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True
        )
        self.processes[process] = (name, log)
        return process

    def node(self, executable: str, env: dict[str, str], **parameters) -> subprocess.Popen:
        """Start a console script of the venv with ``--ros-args -p name:=value`` each."""
        arguments = [f"{key}:={ros_value(value)}" for key, value in parameters.items()]
        ros_args = ["--ros-args", *(a for p in arguments for a in ("-p", p))] if arguments else []
        return self.start(executable, [str(BIN / executable), *ros_args], env)

    def last_line(self, process: subprocess.Popen) -> str:
        """The last line ``process`` printed ('' if none)."""
        log = self.processes[process][1]
        log.seek(0)
        lines = log.read().strip().splitlines()
        return lines[-1] if lines else ""

    def stop(self, grace: float = 5.0) -> list[str]:
        """SIGINT to every group (as Ctrl-C), then SIGKILL after ``grace`` [s] to what is left
        of each; close the logs. Returns the names whose process needed SIGKILL (their DDS
        participants linger on the domain a while)."""
        self._signal(signal.SIGINT)
        self._wait(grace)
        killed = [
            name for process, (name, _log) in self.processes.items() if process.poll() is None
        ]
        self._signal(signal.SIGKILL)  # stragglers of the groups too
        self._wait(grace)
        for _name, log in self.processes.values():
            log.close()
        self.processes.clear()
        return killed

    def _signal(self, signum: int) -> None:
        for process in self.processes:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(process.pid, signum)

    def _wait(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        for process in self.processes:
            with contextlib.suppress(subprocess.TimeoutExpired):
                process.wait(max(deadline - time.monotonic(), 0.01))


def start_load(groups: Groups, load_domain: int) -> None:
    """Two busy loops and rns_demo (no recording, as fast as possible) looped on
    ``load_domain``."""
    for k in range(2):
        groups.start(
            f"busy{k}", ["timeout", "1500", "sh", "-c", "while :; do :; done"], clean_env(0)
        )
    demo = f"{BIN / 'rns_demo'} --no-record --real-time-factor 0 --domain-id {load_domain}"
    loop = f"while :; do {demo} >/dev/null 2>&1; sleep 0.2; done"
    groups.start("second stack", ["timeout", "1500", "sh", "-c", loop], clean_env(load_domain))


class Probe:
    """This process's measuring node: records the robot and the nodes' status, streams twists,
    goals and a second /clock."""

    def __init__(self, robot) -> None:
        self.robot = robot
        self.node = rclpy.create_node("lab_run_probe")
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        qos = QoSProfile(depth=100)
        self.twist = self.node.create_publisher(TwistStamped, "cmd_twist", QoSProfile(depth=50))
        self.goal = self.node.create_publisher(JointState, "ptp_goal", QoSProfile(depth=10))
        self.node.create_subscription(JointState, "joint_states", self._on_joints, qos)
        self.node.create_subscription(Odometry, "base_odom", self._on_odom, qos)
        self.node.create_subscription(Float64MultiArray, "joint_positions", self._on_command, qos)
        for topic in ("/rns_controller/status", "/rns_ptp/status"):
            self.node.create_subscription(DiagnosticArray, topic, self._on_status, qos)
        self.reset()

    def reset(self) -> None:
        """Forget everything recorded."""
        self.theta: np.ndarray | None = None  # newest joint angles [rad], model order
        self.stamp = 0.0  # newest joint_states stamp [s]
        self.odom: list[np.ndarray] = []  # base quaternions x y z w
        self.odom_stamps: list[float] = []  # their header stamps [s]
        self.commands: list[tuple[np.ndarray, np.ndarray]] = []  # (command, measured) [rad]
        self.status: list[tuple[str, str]] = []  # (state, message)
        self.tracking: list[float] = []  # rns_controller's tracking_error per status [rad]
        self.expected = ["lab_run_probe"]  # node names of this run (one each)
        self.foreign: set[str] = set()  # other nodes seen on the domain meanwhile
        self._graph_checked = 0.0

    def _on_joints(self, msg: JointState) -> None:
        by_name = dict(zip(msg.name, msg.position, strict=False))
        if all(name in by_name for name in self.robot.joint_names):
            self.theta = np.array([by_name[name] for name in self.robot.joint_names])
            self.stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9

    def _on_odom(self, msg: Odometry) -> None:
        o = msg.pose.pose.orientation
        self.odom.append(np.array([o.x, o.y, o.z, o.w]))
        self.odom_stamps.append(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9)

    def _on_command(self, msg: Float64MultiArray) -> None:
        if self.theta is not None:
            self.commands.append((np.array(msg.data, dtype=float), self.theta.copy()))

    def _on_status(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            values = {kv.key: kv.value for kv in status.values}
            self.status.append((values.get("state", "?"), status.message))
            if "tracking_error" in values:
                self.tracking.append(float(values["tracking_error"]))

    def check_graph(self) -> None:
        """Note the nodes on the domain beyond one of each :attr:`expected` (another stack or
        test on this domain shares the topics: its figures would be mixed in)."""
        names = [name for name, _namespace in self.node.get_node_names_and_namespaces()]
        for name in self.expected:
            if name in names:
                names.remove(name)
        self.foreign.update(names)
        self._graph_checked = time.monotonic()

    @property
    def state(self) -> str:
        """The newest status state ('' before any)."""
        return self.status[-1][0] if self.status else ""

    def spin_until(self, done: Callable[[], bool], timeout: float) -> bool:
        """Spin until ``done()`` or ``timeout`` [s] passed; whether it was done."""
        deadline = time.monotonic() + timeout
        while not done():
            if time.monotonic() >= deadline:
                return False
            if time.monotonic() - self._graph_checked > 1.0:
                self.check_graph()
            self.executor.spin_once(timeout_sec=min(0.01, deadline - time.monotonic()))
        return True

    def spin_for(self, seconds: float) -> None:
        """Spin for ``seconds`` [s]."""
        self.spin_until(lambda: False, seconds)

    def send_twist(self, speed: float, stamp) -> None:
        """``speed`` [rad/s] about AXIS, world frame, stamped ``stamp`` (builtin Time)."""
        msg = TwistStamped()
        msg.header.stamp, msg.header.frame_id = stamp, "world"
        msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = (speed * AXIS).tolist()
        self.twist.publish(msg)

    def wait_up(self, groups: Groups, processes, publisher) -> str:
        """Wait for joint_states, base_odom, a status past WAITING_FOR_STATE and a subscriber of
        ``publisher``; '' when up, else why not (one line)."""

        def missing() -> list[str]:
            checks = {
                "joint_states": self.theta is not None,
                "base_odom": bool(self.odom),
                "~/status": self.state not in ("", "WAITING_FOR_STATE"),
                "subscriber": publisher.get_subscription_count() > 0,
            }
            return [what for what, ok in checks.items() if not ok]

        def dead() -> list:
            return [process for process in processes if process.poll() is not None]

        self.spin_until(lambda: not missing() or dead(), UP_TIMEOUT)
        if dead():
            return f"{Path(dead()[0].args[0]).name} exited: {groups.last_line(dead()[0])[:100]}"
        return (
            f"not up within {UP_TIMEOUT:.0f} s: no {', no '.join(missing())}" if missing() else ""
        )


def quaternion_angle(q0: np.ndarray, q: np.ndarray) -> float:
    """Angle of q0^-1 q [rad] for unit quaternions (x y z w)."""
    return 2.0 * math.acos(min(1.0, abs(float(np.dot(q0, q)))))


def rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle of a^T b [rad] for rotation matrices."""
    return float(np.linalg.norm(pin.log3(a.T @ b)))


def camera_rotation(robot, theta: np.ndarray, quaternion: np.ndarray) -> np.ndarray:
    """World <- camera rotation from joint angles [rad] and the base quaternion (x y z w)."""
    state = FreeFloatingState.compute(robot, robot.configuration(theta, (0, 0, 0), quaternion))
    return np.array(state.camera.rotation)


def run_teleop(probe: Probe, groups: Groups, env: dict[str, str], method: str) -> dict:
    """One teleop run (module docstring); a row of figures."""
    sim = groups.node("rns_simulator", env)
    ctrl = groups.node("rns_controller", env, method=method)
    why = probe.wait_up(groups, [sim, ctrl], probe.twist)
    if why:
        return {"note": why}
    r_c0 = camera_rotation(probe.robot, probe.theta, probe.odom[-1])
    first, stop_stamp, sent = None, None, 0
    begin = time.monotonic()
    while (elapsed := time.monotonic() - begin) < TURN + STOP:
        now = probe.node.get_clock().now()
        seconds = now.nanoseconds * 1e-9
        if elapsed < TURN:
            first = seconds if first is None else first
        elif stop_stamp is None:
            stop_stamp = seconds
            at_stop = probe.tracking[-1] if probe.tracking else math.nan
        probe.send_twist(SPEED if elapsed < TURN else 0.0, now.to_msg())
        sent += 1
        probe.spin_for(max(begin + sent / TWIST_RATE - time.monotonic(), 0.0))
    span = stop_stamp - first
    r_cmd = pin.exp3(SPEED * span * AXIS) @ r_c0
    r_end = camera_rotation(probe.robot, probe.theta, probe.odom[-1])
    base = max(quaternion_angle(probe.odom[0], q) for q in probe.odom)
    return {
        "base dev [deg]": f"{math.degrees(base):.3e}",
        "camera err [deg]": f"{math.degrees(rotation_angle(r_cmd, r_end)):.4g}",
        "turn [deg]": f"{math.degrees(rotation_angle(r_c0, r_end)):.2f}",
        "T cmd [s]": f"{span:.3f}",
        "track err stop/end [deg]": f"{math.degrees(at_stop):.3g}/"
        + (f"{math.degrees(probe.tracking[-1]):.3g}" if probe.tracking else "-"),
        "twists": sent,
        "states seen": states_seen(probe.status),
    }


def states_seen(status: list[tuple[str, str]]) -> str:
    """The distinct states of ``status``, in order of first appearance."""
    return ",".join(dict.fromkeys(state for state, _message in status))


def status_episodes(status: list[tuple[str, str]]) -> dict[str, int]:
    """STALE_STATE, hold and abandon episodes (a run of equal messages counts once)."""
    counts = {"stale": 0, "hold": 0, "abandon": 0}
    previous = ("", "")
    for state, message in status:
        if state == "STALE_STATE" and previous[0] != "STALE_STATE":
            counts["stale"] += 1
        holding = state != "WAITING_FOR_STATE" and any(
            word in message.lower()
            for word in ("waiting", "hold")  # HOLDING: its message too
        )
        if holding and not any(word in previous[1].lower() for word in ("waiting", "hold")):
            counts["hold"] += 1
        active = previous[0] in ("PLANNING", "MOVING", "CANCELLING", "SETTLING")
        fault = active and state in ("STALE_STATE", "CONFLICTING_STATE")
        if fault or ("abandon" in message.lower() and "abandon" not in previous[1].lower()):
            counts["abandon"] += 1
        previous = (state, message)
    return counts


def run_ptp(probe: Probe, groups: Groups, env: dict[str, str], method: str) -> dict:
    """One point-to-point goal with ``method`` (module docstring); a row of figures."""
    sim = groups.node("rns_simulator", env)
    ptp = groups.node("rns_ptp", env, method=method)
    why = probe.wait_up(groups, [sim, ptp], probe.goal)
    if why:
        return {"note": why}
    goal = np.deg2rad(PTP_GOAL_DEG)
    probe.status.clear()
    probe.goal.publish(JointState(name=list(probe.robot.joint_names), position=goal.tolist()))
    sent = time.monotonic()
    ended = probe.spin_until(lambda: probe.state in PTP_ENDS, PTP_LIMIT)
    took = time.monotonic() - sent
    probe.spin_for(0.5)  # the final joint_states
    error = np.degrees(np.abs(probe.theta - goal)).max()
    # DONE says how far the joints ended from the plan's end, where IJ-C/TJ-C's camera
    # position target put it
    last = probe.status[-1][1] if probe.status else ""
    done = re.search(r"goal reached \(within ([0-9.e+-]+) rad\)", last)
    to_plan = f"{math.degrees(float(done.group(1))):.3g}" if done else "-"
    return {
        "end": probe.state if ended else f"none ({probe.state})",
        "end message": probe.status[-1][1][:90] if probe.status else "",
        "to end [s]": f"{took:.1f}" if ended else f">{PTP_LIMIT:.0f}",
        "joint err [deg]": f"{error:.3g}",
        "plan end err [deg]": to_plan,
        **status_episodes(probe.status),
    }


def clock_time(seconds: float):
    """builtin Time of ``seconds`` [s] (negative clamped to 0)."""
    return Time(nanoseconds=max(round(seconds * 1e9), 0)).to_msg()


#: rns_simulator and rns_controller parameters of the lockstep pair (rns_demo's, with the
#: controller's output_interface position).
LOCKSTEP_SIM = {"publish_clock": True, "lockstep_period": PERIOD, "step_size": PERIOD}
LOCKSTEP_CTRL = {
    "use_sim_time": True,
    "output_lead": PERIOD,
    "await_commands": True,
    "await_timeout": AWAIT_TIMEOUT,
}


def run_clock(probe: Probe, groups: Groups, env: dict[str, str], method: str) -> dict:
    """The lockstep pair with a second, jumping /clock (module docstring); a row of figures."""
    sim = groups.node("rns_simulator", env, **LOCKSTEP_SIM)
    ctrl = groups.node(
        "rns_controller", env, method=method, output_interface="position", **LOCKSTEP_CTRL
    )
    why = probe.wait_up(groups, [sim, ctrl], probe.twist)
    if why:
        return {"note": why}
    start = time.monotonic()
    disturb_clock(probe)
    return {
        **command_figures(probe),
        "sim alive": "yes" if sim.poll() is None else f"no ({sim.returncode})",
        "ctrl alive": "yes" if ctrl.poll() is None else f"no ({ctrl.returncode})",
        "stream [s]": f"{time.monotonic() - start:.1f}",
        "states seen": states_seen(probe.status),
        "last status": probe.status[-1][1] if probe.status else "(no status)",
    }


def disturb_clock(probe: Probe) -> None:
    """Twists on simulated time (3 s), a second /clock jumping +CLOCK_JUMP three times (2 s),
    twists (2 s), that /clock running backwards at 5 s/s (1 s), twists (2 s), then zeros with
    the second /clock gone (2 s); durations in wall-clock seconds."""
    next_stamp = probe.stamp + OPERATOR_LEAD
    jumps = []

    def stream(seconds: float, speed: float = SPEED, extra: Callable | None = None) -> None:
        """Twists on a 20 ms grid of simulated time, each sent OPERATOR_LEAD before its stamp;
        ``extra(elapsed [s])`` every wall-clock 20 ms."""
        nonlocal next_stamp
        begin = time.monotonic()
        while (elapsed := time.monotonic() - begin) < seconds:
            while next_stamp <= probe.stamp + OPERATOR_LEAD:
                probe.send_twist(speed, clock_time(next_stamp))
                next_stamp += 1.0 / TWIST_RATE
            if extra is not None:
                extra(elapsed)
            probe.spin_for(1.0 / TWIST_RATE)

    def jump(elapsed: float) -> None:
        if len(jumps) < 3 and elapsed >= 0.5 * len(jumps):
            clock.publish(Clock(clock=clock_time(probe.stamp + CLOCK_JUMP)))
            jumps.append(elapsed)

    def backwards(elapsed: float) -> None:
        clock.publish(Clock(clock=clock_time(probe.stamp - 5.0 * elapsed - 0.1)))

    stream(3.0)
    # the second /clock exists from here on only: the nodes may check the graph for it
    clock = probe.node.create_publisher(Clock, "/clock", QoSProfile(depth=1))
    try:
        stream(2.0, extra=jump)
        stream(2.0)
        stream(1.0, extra=backwards)
        stream(2.0)
    finally:
        probe.node.destroy_publisher(clock)
    stream(2.0, speed=0.0)


def command_figures(probe: Probe) -> dict:
    """Over every /joint_positions command recorded: how many, how many not finite (or of the
    wrong length), the largest distance past the URDF limits [rad] and the largest
    |command - measured angle| [rad]."""
    lower, upper = probe.robot.lower_limits, probe.robot.upper_limits
    past, gap, nonfinite = 0.0, 0.0, 0
    for command, measured in probe.commands:
        if command.shape != measured.shape or not np.isfinite(command).all():
            nonfinite += 1
            continue
        past = max(past, float(np.max(np.maximum(lower - command, command - upper))))
        gap = max(gap, float(np.abs(command - measured).max()))
    return {
        "commands": len(probe.commands),
        "non-finite": nonfinite,
        "past limit [rad]": f"{past:.3g}",
        "max |cmd-meas| [rad]": f"{gap:.3g}",
    }


SCENARIOS = {"teleop": run_teleop, "ptp": run_ptp, "clock": run_clock}


def methods(scenario: str) -> list[str]:
    """The methods a scenario runs: dls and (if the controller has it) conventional; every ptp
    method of rns_ptp; dls for the clock pair."""
    if scenario == "ptp":
        return list(next(s for s in ptp_parameters.PARAMETERS if s.name == "method").choices)
    if scenario == "clock":
        return ["dls"]
    choices = next(s for s in controller_parameters.PARAMETERS if s.name == "method").choices
    return ["dls", *(["conventional"] if "conventional" in choices else [])]


def print_table(scenario: str, rows: list[dict]) -> None:
    """One table per scenario, columns from the rows' keys."""
    keys = list(dict.fromkeys(key for row in rows for key in row))
    widths = {k: max(len(k), *(len(str(row.get(k, "-"))) for row in rows)) for k in keys}
    print(f"\n{scenario}")
    print("  ".join(f"{k:<{widths[k]}}" for k in keys).rstrip())
    for row in rows:
        print("  ".join(f"{row.get(k, '-')!s:<{widths[k]}}" for k in keys).rstrip())


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Arguments; a bad one: one line on stderr, exit 2."""
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="\n".join(__doc__.splitlines()[5:]),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )

    def error(message: str) -> None:
        print(f"lab_run.py: error: {message}", file=sys.stderr)
        raise SystemExit(2)

    parser.error = error
    parser.add_argument("--scenario", choices=(*SCENARIOS, "all"), default="all")
    parser.add_argument("--repeat", type=int, default=1, help="runs of each scenario/method")
    parser.add_argument("--load", action="store_true", help="busy loops + a second stack beside")
    parser.add_argument("--domain-id", type=int, default=56, help="ROS_DOMAIN_ID of the stack")
    parser.add_argument("--load-domain-id", type=int, default=57, help="of the second stack")
    parser.add_argument(
        "--logs", type=Path, help="keep each node's output, the statuses and the base attitude here"
    )
    parser.add_argument("--method", action="append", help="only this method (repeatable)")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        error(f"--repeat must be >= 1, got {args.repeat}")
    for name in ("domain_id", "load_domain_id"):
        if not 0 <= getattr(args, name) <= 232:
            error(f"--{name.replace('_', '-')} must be in [0, 232], got {getattr(args, name)}")
    if args.domain_id == args.load_domain_id:
        error(f"--domain-id and --load-domain-id must differ, both are {args.domain_id}")
    for executable in ("rns_simulator", "rns_controller", "rns_ptp", "rns_demo"):
        if not (BIN / executable).exists():
            error(f"{BIN / executable} not found: run `make demo` once to create the venv")
    return args


def run_once(probe: Probe, stack: Groups, env: dict, scenario: str, method: str, run: int) -> dict:
    """Run ``run`` of ``scenario`` with ``method`` on a fresh stack, stopped after it: its row."""
    probe.reset()
    probe.expected += ["rns_simulator", "rns_ptp" if scenario == "ptp" else "rns_controller"]
    started = time.monotonic()
    try:
        figures = SCENARIOS[scenario](probe, stack, env, method)
        probe.check_graph()
    finally:
        killed = stack.stop()
        if stack.log_dir is not None:  # the statuses seen, one line each (state: message)
            path = stack.log_dir / f"{stack.started:03d}-status.log"
            path.write_text("".join(f"{state}: {message}\n" for state, message in probe.status))
            if probe.odom:  # the base's attitude change from the first base_odom, per stamp
                rows = (
                    f"{stamp:.4f},{math.degrees(quaternion_angle(probe.odom[0], q)):.4e}\n"
                    for stamp, q in zip(probe.odom_stamps, probe.odom, strict=True)
                )
                odom = stack.log_dir / f"{stack.started:03d}-base.csv"
                odom.write_text("stamp [s],base attitude change [deg]\n" + "".join(rows))
    probe.spin_for(0.5)  # what the stopped nodes sent is not the next run's
    return {
        "method": method,
        "run": run,
        **figures,
        "foreign nodes": ",".join(sorted(probe.foreign)) or "none",
        "SIGKILLed": ",".join(killed) or "none",
        "wall [s]": f"{time.monotonic() - started:.1f}",
        "load1": f"{os.getloadavg()[0]:.2f}",
    }


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    env = clean_env(args.domain_id)
    os.environ.update({key: env[key] for key in env if key.startswith(("ROS_", "RMW_"))})
    signal.signal(signal.SIGTERM, signal.default_int_handler)  # cleanup as on Ctrl-C
    scenarios = list(SCENARIOS) if args.scenario == "all" else [args.scenario]
    if args.logs is not None:
        args.logs.mkdir(parents=True, exist_ok=True)
    load, stack = Groups(), Groups(args.logs)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)  # Ctrl-C: KeyboardInterrupt
    probe = Probe(load_model(default_model_config()))
    print(
        f"lab_run: domain {args.domain_id}, localhost, rmw_fastrtps_cpp, nodes from {BIN}; "
        f"load: {f'on (second stack on domain {args.load_domain_id})' if args.load else 'off'}; "
        f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start",
        flush=True,
    )
    probe.spin_for(2.0)  # discovery
    if probe.foreign:
        print(f"lab_run: already on domain {args.domain_id}: {', '.join(sorted(probe.foreign))}")
    try:
        if args.load:
            start_load(load, args.load_domain_id)
        for scenario in scenarios:
            rows, begin = [], time.monotonic()
            for method in [m for m in methods(scenario) if m in (args.method or [m])]:
                for run in range(1, args.repeat + 1):
                    rows.append(run_once(probe, stack, env, scenario, method, run))
                    print(f"  {scenario}: {rows[-1]}", flush=True)
            print_table(scenario, rows)
            print(f"({scenario}: {time.monotonic() - begin:.0f} s of wall time)", flush=True)
    except KeyboardInterrupt:
        print("lab_run: interrupted; stopping every process started", file=sys.stderr)
        return 130
    finally:
        stack.stop()
        load.stop()
        probe.node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
