"""Link check for a split set-up: watch the robot over DDS from the operator's computer.

``rns_observer [--scenario NAME|FILE] [--json report.json] [--ros-args -r FROM:=TO]`` (also
``python -m rns_ros.apps.observer``, or ``ros2 run rns_ros rns_observer`` on a ROS install) joins
the ROS domain of its environment (``ROS_DOMAIN_ID``, ``ROS_AUTOMATIC_DISCOVERY_RANGE``,
``ROS_STATIC_PEERS`` are used as given, unlike :class:`rns_ros.harness.Harness`, which forces
localhost), records what the robot side publishes (``joint_states``, ``base_odom``,
``momentum``) and what the operator side sends (``cmd_twist``, ``joint_references``), and writes
a JSON report: per topic the message count, the publisher's rate (header stamps), the arrival
rate and longest arrival gap, and the serialized payload bytes, how long
the robot took to appear, and, with ``--scenario``, the run's figures
(:func:`rns_ros.analysis.recorded_run.run_figures`) plus the camera rotation between the first
and the last robot state. See docs/two_hosts.md.

Without ``--scenario`` it records for ``--duration`` seconds after the robot appears. With it, it
records until the operator has played the scenario's profile (by its twists' stamps) and then
fallen silent for ``--idle`` seconds (the scripted operator stops publishing after its zeros), so
start it before the operator.

Prints ``rns_observer: robot seen ...`` once the first joint state arrives, and
``rns_observer: first <topic> ...`` for each topic's first message (``joint_references`` shows
that the controller has the robot's state). Exit code 0 when the
robot was seen (and, with ``--scenario``, the commands came and went), 1 otherwise, 2 on bad
arguments.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import rclpy
from geometry_msgs.msg import TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.executors import SingleThreadedExecutor
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from rns_ros.analysis.recorded_run import run_figures
from rns_ros.cli import add_domain_id_argument, one_line, run_main, split_ros_args
from rns_ros.control.scenario import load_scenario
from rns_ros.core import ConfigError, RnsError, load_model
from rns_ros.core.state import FreeFloatingState
from rns_ros.harness import RECORD_QOS, TopicLog, ros_environment
from rns_ros.resources import (
    apply_loopback_profile,
    default_model_config,
    loopback_profile,
    scenario_path,
)
from rns_ros.runs.recorded import robot_arrays

#: Topics recorded: report key -> (message type, topic name).
TOPICS = {
    "joints": (JointState, "joint_states"),
    "odom": (Odometry, "base_odom"),
    "momentum": (WrenchStamped, "momentum"),
    "commands": (TwistStamped, "cmd_twist"),
    "references": (JointTrajectory, "joint_references"),
}
#: Environment variables that decide who this process can discover (echoed in the report).
DISCOVERY_VARIABLES = (
    "ROS_DOMAIN_ID",
    "ROS_AUTOMATIC_DISCOVERY_RANGE",
    "ROS_STATIC_PEERS",
    "RMW_IMPLEMENTATION",
)


def static_peer_environment(
    domain_id: int,
    peers: list[str],
    base: dict[str, str] | None = None,
    *,
    discovery_range: str = "LOCALHOST",
) -> dict[str, str]:
    """Environment for a node on one of two computers: ``peers`` are the other's IPs or names.

    With ``discovery_range`` LOCALHOST (default) a node sends no multicast: its discovery goes
    to 127.0.0.1 and to the peers only. (OFF would not do: Jazzy's rmw_fastrtps then turns
    discovery off and ignores ``ROS_STATIC_PEERS``.) See docs/two_hosts.md.
    """
    env = ros_environment(domain_id, base)  # domain and the Fast DDS RMW
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = discovery_range
    if env.get("FASTRTPS_DEFAULT_PROFILES_FILE") == str(loopback_profile()):
        del env["FASTRTPS_DEFAULT_PROFILES_FILE"]  # it keeps DDS on 127.0.0.1: no peer reached
    env["ROS_STATIC_PEERS"] = ";".join(peers)
    return env


def observe(args: argparse.Namespace) -> dict[str, Any]:
    """Record the topics as ``args`` says; return the report (see the module docstring)."""
    apply_loopback_profile()  # with localhost discovery, DDS sockets on 127.0.0.1 too
    context = rclpy.Context()
    try:  # argv[0] is a program name to rcl; remaps (-r) apply to the topics below
        rclpy.init(args=["rns_observer", *args.ros_args], context=context, domain_id=args.domain_id)
    except RuntimeError as exc:  # rcl's parse errors (RCLError derives from RuntimeError)
        raise ConfigError(f"invalid ROS arguments {args.ros_args}: {exc}") from None
    executor = SingleThreadedExecutor(context=context)
    node = rclpy.create_node("rns_observer", context=context)
    try:
        executor.add_node(node)
        logs = {key: TopicLog(topic) for key, (_, topic) in TOPICS.items()}
        for key, (msg_type, topic) in TOPICS.items():
            node.create_subscription(msg_type, topic, logs[key]._append, RECORD_QOS)
        start = time.monotonic()
        deadline = start + args.timeout

        announced: set[str] = set()

        def spin_until(condition, until: float) -> bool:
            while time.monotonic() < until:
                if condition():
                    return True
                executor.spin_once(timeout_sec=0.01)
                for log in logs.values():
                    if log.received and log.topic not in announced:
                        announced.add(log.topic)
                        after = log.received[0] - start
                        print(f"rns_observer: first {log.topic} after {after:.2f} s", flush=True)
            return bool(condition())

        seen = spin_until(lambda: len(logs["joints"]) > 0, min(deadline, start + args.wait))
        first_state = logs["joints"].received[0] - start if seen else None
        done = False
        if seen:
            print(f"rns_observer: robot seen after {first_state:.2f} s", flush=True)
            if args.scenario is None:
                spin_until(lambda: False, min(deadline, time.monotonic() + args.duration))
                done = True
            else:
                duration = load_scenario(scenario_path(args.scenario)).duration
                done = spin_until(
                    lambda: _commands_done(logs["commands"], args.idle, duration), deadline
                )
                spin_until(lambda: False, time.monotonic() + args.settle)
        else:
            print(f"rns_observer: no joint_states within {args.wait:g} s", flush=True)
    finally:
        executor.remove_node(node)
        node.destroy_node()
        executor.shutdown()
        rclpy.try_shutdown(context=context)
    report: dict[str, Any] = {
        "environment": {name: os.environ.get(name) for name in DISCOVERY_VARIABLES},
        "robot_seen": seen,
        "first_joint_state_after_s": first_state,
        "completed": bool(done),
        "topics": {log.topic: _topic_summary(log) for log in logs.values()},
        # where a stalled loop stops: commands, controller output, robot motion
        "first_motion_after_s": {
            "cmd_twist": _first(logs["commands"], start, lambda m: _norm(m.twist.angular)),
            "joint_references": _first(
                logs["references"],
                start,
                lambda m: max(map(abs, m.points[0].velocities), default=0),
            ),
            "joint_states": _first(
                logs["joints"], start, lambda m: max(map(abs, m.velocity), default=0)
            ),
        },
    }
    if args.scenario is not None and len(logs["joints"]) >= 2:
        report.update(_run_report(scenario_path(args.scenario), logs))
    return report


def _norm(v) -> float:
    return float(np.linalg.norm([v.x, v.y, v.z]))


def _first(log: TopicLog, start: float, size) -> float | None:
    """Receipt time [s after start] of the first message with ``size(msg) > 1e-9``, or None."""
    for msg, received in zip(log.messages, log.received, strict=True):
        if size(msg) > 1e-9:
            return received - start
    return None


def _commands_done(commands: TopicLog, idle: float, duration: float) -> bool:
    """The operator has played its profile and then sent nothing for ``idle`` [s] of wall time:
    its newest twist is at rest and stamped at least ``duration`` [s] (the scenario's) after its
    first moving one. The stamps count, not the arrivals: on simulated time a loaded machine
    can hold the operator for longer than ``idle`` mid-profile (receipt times stand in for
    unstamped twists)."""
    if not len(commands) or time.monotonic() - commands.received[-1] <= idle:
        return False
    moving = [_norm(m.twist.angular) + _norm(m.twist.linear) > 0.0 for m in commands.messages]
    if moving[-1] or not any(moving):
        return False
    stamps = commands.stamps()
    if not np.all(stamps > 0.0):
        stamps = np.asarray(commands.received, dtype=float)
    return bool(stamps[-1] - stamps[moving.index(True)] >= duration)


def _rate(times: np.ndarray) -> float:
    """Messages per second over ``times`` [s], shape (samples,); 0 without a span."""
    span = float(times[-1] - times[0]) if len(times) > 1 else 0.0
    return (len(times) - 1) / span if span > 0 else 0.0


def _topic_summary(log: TopicLog) -> dict[str, Any]:
    """Count, rates and payload of one topic.

    ``rate_hz`` is the publisher's rate, from the header stamps (what the robot sends, whatever
    the link or this process's scheduling does to the arrivals); where stamps are missing (zero)
    or do not increase it falls back to the arrivals. ``receipt_rate_hz`` and
    ``max_receipt_gap_s`` describe the arrivals: a stalled receiver that then drains a backlog
    shows a burst, a gap, or both, while the stamps still show the robot's own rate.
    """
    count = len(log)
    received = np.asarray(log.received, dtype=float)
    stamps = log.stamps() if count else np.zeros(0)
    stamped = count > 1 and bool(np.all(stamps > 0.0)) and bool(np.all(np.diff(stamps) > 0.0))
    return {
        "count": count,
        "rate_hz": _rate(stamps if stamped else received),
        "receipt_rate_hz": _rate(received),
        "max_receipt_gap_s": float(np.max(np.diff(received))) if count > 1 else 0.0,
        # what crossed the wire at least: the CDR payload, without RTPS / UDP / IP headers
        "payload_bytes": sum(len(serialize_message(msg)) for msg in log.messages),
    }


def _run_report(scenario_file: Path, logs: dict[str, TopicLog]) -> dict[str, Any]:
    """Figures of the run, from robot states whose joint_states and base_odom stamps match."""
    robot = load_model(default_model_config())
    try:
        data = robot_arrays(logs)
    except RnsError as exc:  # e.g. joint_states and base_odom never shared a stamp
        return {"scenario": str(scenario_file), "figures": None, "figures_error": str(exc)}
    figures = run_figures(robot, load_scenario(scenario_file), **data)
    first, last = (
        FreeFloatingState.compute(
            robot,
            robot.configuration(
                data["joint_positions"][i],
                data["base_positions"][i],
                data["base_orientations"][i] / np.linalg.norm(data["base_orientations"][i]),
            ),
        )
        for i in (0, -1)
    )
    # world-axes rotation vector taking the first camera orientation to the last one
    turned = pin.log3(last.camera.rotation @ first.camera.rotation.T)
    angle = float(np.linalg.norm(turned))
    return {
        "scenario": str(scenario_file),
        "figures": asdict(figures),
        "camera_rotation_deg": float(np.rad2deg(angle)),
        "camera_rotation_axis_world": (turned / angle).tolist() if angle > 0 else [0.0, 0.0, 0.0],
    }


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    argv, ros_args = split_ros_args(sys.argv[1:] if argv is None else list(argv))
    parser = argparse.ArgumentParser(
        prog="rns_observer",
        usage="%(prog)s [options] [--ros-args -r FROM:=TO]",
        epilog="--ros-args: remaps (-r joint_states:=arm/joint_states) apply to the topics.",
        description="Watch the robot's topics over DDS (e.g. from the operator's computer) and "
        "report counts, rates and, with --scenario, the run's figures as JSON.",
    )
    parser.add_argument("--scenario", default=None, help="scenario name or YAML the operator plays")
    parser.add_argument("--json", type=Path, default=None, help="report file (default: stdout)")
    parser.add_argument("--wait", type=float, default=30.0, help="give up on the robot after [s]")
    parser.add_argument(
        "--duration", type=float, default=3.0, help="record this long without --scenario [s]"
    )
    parser.add_argument(
        "--idle",
        type=float,
        default=0.5,
        help="the operator is done when silent this long after its profile's stamps [s]",
    )
    parser.add_argument("--settle", type=float, default=0.3, help="record this long after [s]")
    parser.add_argument("--timeout", type=float, default=120.0, help="overall limit [s]")
    add_domain_id_argument(parser, 0, "to watch")
    args = parser.parse_args(argv)
    args.ros_args = ros_args
    for name in ("wait", "duration", "idle", "settle", "timeout"):
        if getattr(args, name) < 0:
            parser.error(f"--{name} must be >= 0")
    return args


def main(argv: list[str] | None = None) -> int:
    """Exit code 2 with one line on stderr for bad options or configuration; 0 after Ctrl-C."""
    return run_main("rns_observer", lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    args = parse_args(argv)
    try:
        if args.scenario is not None:
            scenario_path(args.scenario)  # fail before waiting, not after
        report = observe(args)
    except RnsError as exc:
        print(f"rns_observer: {one_line(exc)}", file=sys.stderr)
        return 2
    text = json.dumps(report, indent=2) + "\n"
    if args.json is None:
        print(text, end="")
    else:
        args.json.write_text(text)
    return 0 if report["robot_seen"] and report["completed"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
