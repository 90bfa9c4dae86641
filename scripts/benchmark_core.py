#!/usr/bin/env python3
"""Time the math core on this machine: state computation, projections and inverses.

Usage: .venv/bin/python scripts/benchmark_core.py [--samples 2000]
Prints median and p99 per operation in microseconds. Numbers, not a test: nothing asserts them.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from rns_ros.core import (
    FreeFloatingState,
    damped_least_squares_inverse,
    load_model,
    reactionless_joint_velocity,
    singularity_consistent_inverse,
)
from rns_ros.resources import default_model_config


def measure(function, samples: int) -> tuple[float, float]:
    durations = []
    for _ in range(samples):
        start = time.perf_counter_ns()
        function()
        durations.append((time.perf_counter_ns() - start) / 1e3)
    durations.sort()
    return statistics.median(durations), durations[int(0.99 * (len(durations) - 1))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=2000, help="repetitions per operation")
    args = parser.parse_args()
    robot = load_model(default_model_config())
    q = robot.configuration(np.deg2rad([-90, -30, 0, -70, 180, -30, 0]))
    state = FreeFloatingState.compute(robot, q)
    restricted = state.restricted_jacobian
    theta_dot = np.full(robot.n, 0.1)

    operations = {
        "FreeFloatingState.compute": lambda: FreeFloatingState.compute(robot, q),
        "damped_least_squares_inverse": lambda: damped_least_squares_inverse(restricted),
        "singularity_consistent_inverse": lambda: singularity_consistent_inverse(restricted),
        "reactionless_joint_velocity": lambda: reactionless_joint_velocity(state, theta_dot),
    }
    print(f"{'operation':<34}{'median [us]':>12}{'p99 [us]':>12}")
    for name, function in operations.items():
        median, p99 = measure(function, args.samples)
        print(f"{name:<34}{median:>12.1f}{p99:>12.1f}")


if __name__ == "__main__":
    main()
