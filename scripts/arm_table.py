#!/usr/bin/env python3
"""Your arms through rns_demo, one table row each: numbers, not tests (nothing here asserts).

Usage:  .venv/bin/python scripts/arm_table.py MODEL.yaml [MODEL.yaml ...]
                                              [--domain-id 58] [--output DIR] [--no-roll]

For each model YAML, run as a user runs it (the console scripts of .venv/bin/, localhost only,
on --domain-id):

check   ``rns_model check MODEL``: its exit code and its last line (``ok: ...``, a warning, or
        the one-line refusal).
turn    a held-out scenario: the camera turns 20 deg about the oblique world axis
        [1, -2, 1.5] in 4 s from the model's initial_joint_positions, no wrist term
        (``rns_demo --model MODEL --scenario <it> --methods dls,conventional
        --real-time-factor 0 --no-record --summary``). Figures from the summary JSON: dls base
        deviation and camera error [deg], the conventional base deviation [deg] and its ratio
        to dls's, dls min sigma(J-bar) and time in the singular region [s].
roll    the default scenario (satellite_observation, a 180 deg roll written for the thesis'
        arm) with the default methods, recorded (``--output``): the exit code; per method the
        summary's ``ended`` (a joint limit, with the joint and the time) or ``done``, and the
        camera error [deg]; and, from each method's ROS 2 bag read with ``rosbags`` (a reader
        the project did not write), the largest distance any joint of the last
        ``/joint_states`` lies past its URDF limit [rad] (0: within).

Prints a Markdown table; the logs stay in --output.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml

BIN = Path(sys.executable).parent
#: the held-out turn
AXIS = [1.0, -2.0, 1.5]
TURN_DEG = 20.0


def _env(domain: int) -> dict[str, str]:
    keep = ("PATH", "HOME", "LANG", "TERM")
    env = {key: os.environ[key] for key in keep if key in os.environ}
    env.update(
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        ROS_DOMAIN_ID=str(domain),
        RMW_IMPLEMENTATION="rmw_fastrtps_cpp",
    )
    return env


def _run(command: list[str], domain: int, log: Path) -> int:
    with log.open("w") as out:
        done = subprocess.run(command, env=_env(domain), stdout=out, stderr=subprocess.STDOUT)
    return done.returncode


def _last_line(log: Path) -> str:
    lines = [line for line in log.read_text().splitlines() if line.strip()]
    return lines[-1] if lines else ""


def _turn_scenario(model: Path, folder: Path) -> Path:
    from rns_ros.core import load_model

    robot = load_model(model)
    scenario = {
        "name": "oblique_turn",
        "description": f"{TURN_DEG:g} deg about an oblique world axis in 4 s",
        "initial_joint_positions_deg": np.rad2deg(robot.initial_theta).round(6).tolist(),
        "frame": "world",
        "axis": AXIS,
        "angle_deg": TURN_DEG,
        "duration": 4.0,
        "controller": {"wrist_gain": 0.0},
    }
    path = folder / "oblique_turn.yaml"
    path.write_text(yaml.safe_dump(scenario))
    return path


def _past_limit(model: Path, bag: Path) -> float | None:
    """The largest distance [rad] any joint of the bag's last /joint_states lies past its
    URDF limit (0 when within), read with rosbags; None without a bag."""
    from rosbags.highlevel import AnyReader

    from rns_ros.core import load_model

    if not bag.is_dir():
        return None
    robot = load_model(model)
    last = None
    with AnyReader([bag]) as reader:
        connections = [c for c in reader.connections if c.topic == "/joint_states"]
        for connection, _, raw in reader.messages(connections=connections):
            last = reader.deserialize(raw, connection.msgtype)
    if last is None:
        return None
    index = {name: i for i, name in enumerate(last.name)}
    theta = np.array([last.position[index[name]] for name in robot.joint_names])
    past = np.maximum(theta - robot.upper_limits, robot.lower_limits - theta)
    return float(max(0.0, past.max()))


def measure(model: Path, args: argparse.Namespace) -> dict:
    name = model.parent.name or model.stem
    folder = args.output / name
    folder.mkdir(parents=True, exist_ok=True)
    row: dict = {"arm": name}
    code = _run([str(BIN / "rns_model"), "check", str(model)], args.domain_id, folder / "check.log")
    row["check"] = f"{code}: {_last_line(folder / 'check.log')[:90]}"
    if code != 0:
        return row
    summary = folder / "turn.json"
    demo = [str(BIN / "rns_demo"), "--model", str(model), "--domain-id", str(args.domain_id)]
    code = _run(
        [
            *demo,
            "--scenario",
            str(_turn_scenario(model, folder)),
            "--methods",
            "dls,conventional",
            "--real-time-factor",
            "0",
            "--no-record",
            "--summary",
            str(summary),
        ],
        args.domain_id,
        folder / "turn.log",
    )
    row["turn exit"] = code
    if summary.is_file():
        rows = {r["method"]: r for r in json.loads(summary.read_text())}
        dls, conventional = rows.get("dls"), rows.get("conventional")
        if dls:
            row["dls base [deg]"] = f"{dls['max_base_deviation_deg']:.2e}"
            row["dls camera [deg]"] = f"{dls['final_camera_error_deg']:.3f}"
            row["dls min sigma"] = f"{dls['min_sigma']:.3g}"
            row["dls singular [s]"] = f"{dls['singular_time_s']:.2f}"
        if conventional:
            row["conv base [deg]"] = f"{conventional['max_base_deviation_deg']:.2e}"
        if dls and conventional and dls["max_base_deviation_deg"] > 0.0:
            ratio = conventional["max_base_deviation_deg"] / dls["max_base_deviation_deg"]
            row["conv/dls"] = f"{ratio:.3g}"
    if args.no_roll:
        return row
    summary = folder / "roll.json"
    code = _run(
        [*demo, "--output", str(folder / "roll"), "--summary", str(summary)],
        args.domain_id,
        folder / "roll.log",
    )
    row["roll exit"] = code
    if summary.is_file():
        ends, past = [], []
        for r in json.loads(summary.read_text()):
            ended = r.get("ended") or "done"
            ends.append(f"{r['method']}: {ended}, camera {r['final_camera_error_deg']:.2f} deg")
            distance = _past_limit(model, folder / "roll" / r["method"])
            past.append("-" if distance is None else f"{distance:.1e}")
        row["roll"] = "; ".join(ends)
        row["past limit [rad]"] = " / ".join(past)
    else:
        row["roll"] = _last_line(folder / "roll.log")[:120]
    return row


def table(rows: list[dict]) -> str:
    columns = list(dict.fromkeys(key for row in rows for key in row))
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        lines.append("| " + " | ".join(str(row.get(c, "")) for c in columns) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("models", nargs="+", type=Path, help="model YAML files")
    parser.add_argument("--domain-id", type=int, default=58)
    parser.add_argument("--output", type=Path, default=None, help="logs and recordings")
    parser.add_argument("--no-roll", action="store_true", help="the turn only")
    args = parser.parse_args(argv)
    args.output = args.output or Path(tempfile.mkdtemp(prefix="arm_table."))
    rows = []
    for model in args.models:
        rows.append(measure(model.resolve(), args))
        print(table(rows[-1:]), flush=True)
    print(f"\nlogs: {args.output}\n")
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
