#!/usr/bin/env python3
"""rns_ros benchmarks on this machine: numbers, not tests (nothing here asserts).

Usage:  .venv/bin/python scripts/benchmark.py [--only core|simulator|controller] [--samples N]

core       median / p99 of one FreeFloatingState, the DLS and SC inverses, one P_RNS projection.
simulator  step time (median, p99) of FreeFloatingSimulator at 1 ms RK4 in kinematic and dynamic
           mode while the joints move, and the real-time factor = dt / median step time.
           Goals (simulator issue): kinematic >= 20x, dynamic >= 10x real time.
controller one evaluation of the law (4.5)/(4.15) per method, and one controller step (the law
           held over a 10 ms period) with the naive and the midpoint hold correction; "tick" adds
           the FreeFloatingState of the sampled robot, i.e. what rns_controller computes per period.
           Goal (controller issue): <= 100 us median step for dls and sc.
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
from rns_ros.core.control import reactionless_camera_control, wrist_offset
from rns_ros.core.controller import ControllerSettings, ReactionlessController
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


def controller(robot, samples: int) -> None:
    state = FreeFloatingState.compute(robot, robot.configuration(SATELLITE_OBSERVATION_RAD))
    omega = np.array([0.1, -0.05, 0.02])
    reference = wrist_offset(state) + 0.01
    print(f"\n{'controller (7 joints)':<34}{'median [us]':>12}{'p99 [us]':>12}{'goal':>10}")
    for method in ("dls", "sc", "pinv", "conventional"):
        print(
            row(
                f"law {method}",
                timings(
                    lambda method=method: reactionless_camera_control(
                        robot,
                        state,
                        omega,
                        method=method,
                        wrist_reference=reference,
                        limit_horizon=0.01,
                    ),
                    samples,
                ),
            )
        )
    for hold in ("naive", "midpoint"):
        for method in ("dls", "sc"):
            control = ReactionlessController(
                robot, ControllerSettings(method=method, hold_correction=hold)
            )
            control.reset(state)
            durations = timings(lambda control=control: control.step(state, omega), samples)
            met = "met" if np.median(durations) <= 100.0 else "missed"
            print(row(f"step {method} {hold}", durations, f"{met:>10}"))
    control = ReactionlessController(robot, ControllerSettings())
    control.reset(state)
    q = state.q

    def tick():
        control.step(FreeFloatingState.compute(robot, q), omega)

    print(row("tick dls midpoint (+ sampled state)", timings(tick, samples)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--only", choices=("core", "simulator", "controller"), help="run one section"
    )
    parser.add_argument("--samples", type=int, default=5000, help="repetitions per operation")
    args = parser.parse_args()
    robot = load_model(default_model_config())
    if args.only in (None, "core"):
        core(robot, args.samples)
    if args.only in (None, "simulator"):
        simulator(robot, args.samples)
    if args.only in (None, "controller"):
        controller(robot, args.samples)


if __name__ == "__main__":
    main()
