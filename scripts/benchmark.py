#!/usr/bin/env python3
"""rns_ros benchmarks on this machine: numbers, not tests (nothing here asserts).

Usage:  .venv/bin/python scripts/benchmark.py [--only core|simulator] [--samples N]

core       median / p99 of one FreeFloatingState, the DLS and SC inverses, one P_RNS projection.
simulator  step time (median, p99) of FreeFloatingSimulator at 1 ms RK4 in kinematic and dynamic
           mode while the joints move, and the real-time factor = dt / median step time.
           Goals (simulator issue): kinematic >= 20x, dynamic >= 10x real time.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rns_ros.core import (
    FreeFloatingState,
    damped_least_squares_inverse,
    load_model,
    reactionless_joint_velocity,
    singularity_consistent_inverse,
)
from rns_ros.core.fastmath import has_fast_solve
from rns_ros.core.simulation import FreeFloatingSimulator
from rns_ros.resources import default_model_config

SATELLITE_OBSERVATION_RAD = np.deg2rad([-90.0, -30.0, 0.0, -70.0, 180.0, -30.0, 0.0])


def timings(function, samples: int) -> np.ndarray:
    """Wall time of each call [us]."""
    durations = np.empty(samples)
    for i in range(samples):
        start = time.perf_counter_ns()
        function()
        durations[i] = (time.perf_counter_ns() - start) / 1e3
    return durations


def row(name: str, durations: np.ndarray, extra: str = "") -> str:
    median, p99 = np.median(durations), np.percentile(durations, 99)
    return f"{name:<34}{median:>12.1f}{p99:>12.1f}{extra}"


def core(robot, samples: int) -> None:
    q = robot.configuration(SATELLITE_OBSERVATION_RAD)
    state = FreeFloatingState.compute(robot, q)
    restricted = state.restricted_jacobian
    theta_dot = np.full(robot.n, 0.1)
    operations = {
        "FreeFloatingState.compute": lambda: FreeFloatingState.compute(robot, q),
        "damped_least_squares_inverse": lambda: damped_least_squares_inverse(restricted),
        "singularity_consistent_inverse": lambda: singularity_consistent_inverse(restricted),
        "reactionless_joint_velocity": lambda: reactionless_joint_velocity(state, theta_dot),
    }
    print(f"\n{'core':<34}{'median [us]':>12}{'p99 [us]':>12}")
    for name, function in operations.items():
        print(row(name, timings(function, samples)))


def simulator(robot, samples: int) -> None:
    print(f"\n{'simulator, dt = 1 ms RK4':<34}{'median [us]':>12}{'p99 [us]':>12}{'RTF':>10}")
    for mode in ("kinematic", "dynamic"):
        sim = FreeFloatingSimulator(
            robot, mode=mode, dt=1e-3, initial_q=robot.configuration(SATELLITE_OBSERVATION_RAD)
        )
        sim.set_reference(velocities=np.linspace(-0.3, 0.3, robot.n))
        durations = timings(sim.step, samples)
        factor = 1e3 / np.median(durations)
        print(row(f"step ({mode})", durations, f"{factor:>9.1f}x"))
    print(f"(fast 6x6 solve: {'on' if has_fast_solve() else 'off, numpy fallback'})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=("core", "simulator"), help="run one section")
    parser.add_argument("--samples", type=int, default=5000, help="repetitions per operation")
    args = parser.parse_args()
    robot = load_model(default_model_config())
    if args.only in (None, "core"):
        core(robot, args.samples)
    if args.only in (None, "simulator"):
        simulator(robot, args.samples)


if __name__ == "__main__":
    main()
