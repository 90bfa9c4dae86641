"""rns_demo: a short reactionless-motion scenario on the core, printed as a comparison table.

Interim main job (issue 2): starting from the thesis satellite-observation configuration
(section 4.2.2), the wrist joints sweep by a fixed angle with a quintic time scaling while the
satellite floats freely (kinematic mode, zero momentum). Two joint-velocity laws are compared:

* ``conventional``: positioning joints held, eq. (4.8) - the base turns;
* ``reactionless``: predominant wrist motion, eq. (4.2) - the positioning joints compensate.

Later issues replace this with the full DDS demo (simulator + controller + rerun).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from rns_ros.core import FreeFloatingState, RnsError, load_model, subchain_decomposition
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.momentum import coupling_angular_momentum
from rns_ros.core.simulation import FreeFloatingSimulator
from rns_ros.core.timing import quintic
from rns_ros.resources import default_model_config

SATELLITE_OBSERVATION_DEG = (-90.0, -30.0, 0.0, -70.0, 180.0, -30.0, 0.0)
WRIST_SWEEP_DEG = (60.0, -40.0, 90.0)
ETS_VII_ALLOWED_DEVIATION_DEG = 0.05  # thesis chapter 4, footnote 1


@dataclass(frozen=True)
class RunSummary:
    """Figures of one run (units in the field names)."""

    method: str
    max_base_attitude_deviation_deg: float
    camera_rotation_deg: float
    max_positioning_joint_speed_rad_s: float
    max_coupling_angular_momentum_kgm2_s: float
    wall_time_s: float


def run(method: str, duration: float, dt: float, config_path: Path) -> RunSummary:
    """Integrate one wrist sweep with ``method`` in {'conventional', 'reactionless'}."""
    robot = load_model(config_path)
    sweep = np.deg2rad(WRIST_SWEEP_DEG)
    positioning = robot.subchains.positioning

    def joint_velocity(t: float, q: np.ndarray) -> np.ndarray:
        state = FreeFloatingState.compute(robot, q)
        wrist_velocity = sweep * quintic(t, duration)[1]
        if method == "reactionless":
            return subchain_decomposition(robot, state).predominant_wrist_motion(wrist_velocity)
        theta_dot = np.zeros(robot.n)
        theta_dot[robot.subchains.wrist] = wrist_velocity
        return theta_dot

    start = time.perf_counter()
    simulator = FreeFloatingSimulator(
        robot, dt=dt, initial_q=robot.configuration(np.deg2rad(SATELLITE_OBSERVATION_DEG))
    )
    initial = state = FreeFloatingState.compute(robot, simulator.q)
    deviation = positioning_speed = coupling = 0.0
    for _ in range(round(duration / dt)):
        theta_dot = joint_velocity(simulator.time, simulator.q)
        positioning_speed = max(positioning_speed, np.abs(theta_dot[positioning]).max())
        coupling = max(coupling, np.linalg.norm(coupling_angular_momentum(state, theta_dot)))
        simulator.step(joint_velocity)
        state = FreeFloatingState.compute(robot, simulator.q)
        deviation = max(deviation, attitude_deviation(initial.base_rotation, state.base_rotation))
    camera_turn = attitude_deviation(initial.camera.rotation, state.camera.rotation)
    return RunSummary(
        method=method,
        max_base_attitude_deviation_deg=float(np.rad2deg(deviation)),
        camera_rotation_deg=float(np.rad2deg(camera_turn)),
        max_positioning_joint_speed_rad_s=float(positioning_speed),
        max_coupling_angular_momentum_kgm2_s=float(coupling),
        wall_time_s=time.perf_counter() - start,
    )


def format_table(rows: list[RunSummary]) -> str:
    header = (
        f"{'method':<14}{'max base dev [deg]':>20}{'camera turn [deg]':>19}"
        f"{'max |dθ_P| [rad/s]':>20}{'max |M~θ̇| [kg m²/s]':>22}{'wall [s]':>10}"
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        lines.append(
            f"{row.method:<14}{row.max_base_attitude_deviation_deg:>20.3e}"
            f"{row.camera_rotation_deg:>19.2f}{row.max_positioning_joint_speed_rad_s:>20.4f}"
            f"{row.max_coupling_angular_momentum_kgm2_s:>22.3e}{row.wall_time_s:>10.2f}"
        )
    return "\n".join(lines)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="rns_demo",
        description="Wrist sweep on a free-floating 7-DoF arm: conventional vs reactionless "
        "(thesis eq. 4.2 / 4.8), kinematic free-floating simulation with RK4.",
    )
    parser.add_argument("--duration", type=float, default=20.0, help="sweep time [s] (0, 600]")
    parser.add_argument("--dt", type=float, default=0.01, help="integration step [s] (0, 0.1]")
    parser.add_argument("--model", type=Path, default=None, help="model YAML (default: 7-DoF arm)")
    parser.add_argument("--summary", type=Path, default=None, help="also write the table as JSON")
    args = parser.parse_args(argv)
    if not 0.0 < args.duration <= 600.0:
        parser.error(f"--duration must be in (0, 600] s, got {args.duration}")
    if not 0.0 < args.dt <= 0.1:
        parser.error(f"--dt must be in (0, 0.1] s, got {args.dt}")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    config_path = args.model or default_model_config()
    try:
        rows = [
            run(m, args.duration, args.dt, config_path) for m in ("conventional", "reactionless")
        ]
    except RnsError as exc:
        print(f"rns_demo: {exc}", file=sys.stderr)
        return 2
    print(f"model: {config_path}")
    print(
        f"Wrist sweep {WRIST_SWEEP_DEG} deg over {args.duration:g} s from "
        f"{SATELLITE_OBSERVATION_DEG} deg, dt = {args.dt:g} s, zero momentum.\n"
    )
    print(format_table(rows))
    print(f"\nETS-VII allowed base attitude deviation: ±{ETS_VII_ALLOWED_DEVIATION_DEG} deg.")
    if args.summary:
        args.summary.write_text(json.dumps([asdict(row) for row in rows], indent=2) + "\n")
        print(f"summary written to {args.summary}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
