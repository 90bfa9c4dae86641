#!/usr/bin/env python3
"""rns_ros benchmarks on this machine: numbers, not tests (nothing here asserts).

Usage:  .venv/bin/python scripts/benchmark.py [--only core|simulator|controller|force_controller]
                                              [--samples N]
        .venv/bin/python scripts/benchmark.py --only latency [--commands N] [--rates HZ ...]
                                              [--domain-id ID]
        .venv/bin/python scripts/benchmark.py --only cratio [--workers N]
        .venv/bin/python scripts/benchmark.py --only lockstep [--runs N] [--domain-id ID]
        .venv/bin/python scripts/benchmark.py --only publish [--publish-rates HZ ...]
                                              [--seconds S] [--domain-id ID]

core       median / p99 of one FreeFloatingState, the DLS and SC inverses, one P_RNS projection.
simulator  step time (median, p99) of FreeFloatingSimulator at 1 ms RK4 in kinematic and dynamic
           mode while the joints move, and the real-time factor = dt / median step time.
           Goals: kinematic >= 20x, dynamic >= 10x real time.
controller one evaluation of the law (4.5)/(4.15) per method, and one controller step (the law
           held over a 10 ms period) with the naive and the midpoint hold correction, both steps
           timed alternately in one loop, with the ratio midpoint / naive of the medians (goal:
           <= 1.7 for dls and sc, on any machine). "steady" repeats one state (the
           midpoint's extrapolated predictor is then exact); "along own_device" steps through the
           2000 periods of that scenario (recorded once, ~2 s), with the midpoint's mean
           evaluations per step. "tick" adds the FreeFloatingState of the sampled robot, i.e.
           what rns_controller computes per period. Goal (controller issue): <= 100 us median
           step for dls and sc.
force_controller  rns_force_controller's step (median, p99) for rns and os on the 7-DoF wall task
           (one 2.5 s stroke closed around the contact simulator, 1 ms period) as a share of the
           1 ms budget, and the contact simulator's RK4 step. Both must fit one period for the
           1 kHz torque loop; over DDS the lockstep loop rate is in `rns_demo --scenario
           wall_contact`'s table.
latency    end to end, over DDS on localhost: an operator twist's publish() on cmd_twist to the
           reception of the first joint_references that reflects it, p50 / p99 / max / mean over
           --commands (default 1000) commands, per controller rate (default 100 and 500 Hz).
           Goal: p99 <= one control period + 2 ms. Opt-in (not in the default run): it starts
           ROS processes and takes ~30-40 s per rate with a responsive controller, up to ~2.5 min
           per rate when it stalls (each lost command costs MATCH_TIMEOUT).
lockstep   `rns_demo --real-time-factor 0` over DDS (satellite observation, dls, every node its own
           process): the task's wall time (21.3 s simulated) side by side (the default) and in
           turn (--no-output-lead), with the base deviation, alternated --runs times (default 3)
           with the in-process core loop over the same 21.3 s (rns_ros.analysis.closed_loop, one
           RK4 step per period, as the demo's simulator). Goal: >= 10x real time
           side by side. The machine's speed varies here from hour to hour, and the four-process
           lockstep slows down more than the one-process loop (task / in-process loop was ~3 in
           a quiet hour, 5-6 in a slower one): the loop's time says which hour it was. "run"
           is the whole side-by-side demo run (node start-up, task, figures): what a batch of
           runs costs per run. Opt-in (~20 s a run).
cratio     the chapter-5 C_ratio map of the 7-DoF positioning subchain (Fig. 5.3,
           rns_ros.analysis.energy_maps): points per second on a 1/10 sub-grid (5 of the 50
           theta_2 values, 625000 points) in one process and on --workers local processes
           (default: one per core), then the wall time of the full 50^4 = 6.25e6-point map on
           those processes. Goal: full map < 60 s on the 2-core dev VM. Opt-in (~30 s).
publish    rns_simulator at real_time_factor 1 (kinematic, at rest), in this process beside a
           recorder on one executor, as the node tests run it: the rate at which joint_states
           arrive on the wall clock, per --publish-rates (default 100 and 500 Hz), over --seconds
           (default 2) after 0.5 s for discovery, with the arrival intervals (p50 / p99 / max).
           Goal: within 10 % of publish_rate. (The tests check the rate on the stamps, in
           simulated time.) Opt-in (~3 s per rate).

Latency method (measure_latency):
  * rns_controller runs as a subprocess (the installed console script, its own executor as
    deployed: rns_ros.nodes.runner's EventsExecutor), with method dls, wrist_gain (k_g) 0,
    the given rate, all other parameters at their defaults (midpoint hold, predict_state on).
    Both sides are forced onto ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and --domain-id
    (default 55): the environment variables are overwritten, not defaulted.
  * This process has one plain node on a private Context and a SingleThreadedExecutor spun in
    the main loop (no threads): it publishes a static joint_states (the satellite-observation
    angles, zero velocities, reliable, 100 Hz, as the simulator would), the twists (TwistStamped
    in the world frame, best effort depth 1 like rns_operator) and receives joint_references
    (best effort, depth 10). With a fixed configuration and k_g = 0 the controller's output
    velocity is a fixed function of omega, so a reference identifies its command by its velocities.
  * Commands are about world x with 8 codes: command k is +-LATENCY_SPEEDS[(k // 2) % 4], sign +
    for even k, so consecutive commands always differ. Before measuring, each code is held until
    two consecutive references agree: that velocity vector is the code's signature. A reference
    reflects command k when its velocities are within MATCH_TOLERANCE (relative) of code k's
    signature, while the codes are >= 20 % apart.
  * Closed loop: command k is sent, the main loop spins until the first reference matching it
    arrives (or MATCH_TIMEOUT = 0.45 s, below the controller's 0.5 s command_timeout: counted as
    lost, left out of the percentiles, and "met" requires none lost), then waits a random
    15-25 ms (uniform, seeded) before command k + 1 (about 35-45 commands/s with a responsive
    controller). The random gap spans a multiple of both control periods, so the send instant is
    uniformly spread over the controller's timer phase; only one command is ever in flight, so
    the controller's depth-1 subscription never drops one.
  * Latency = time.perf_counter() at the reference's subscription callback minus just before
    publish(). It includes: our serialization and DDS to the controller, the controller's executor
    picking the twist up, the tick (state, midpoint law, status, publish; with the default
    immediate_reaction a changed command is served at once, otherwise it waits for the next
    timer tick, uniform in [0, T)), DDS back, and our own executor's
    wake-up and deserialization (not subtracted). The lines under the table split each latency at
    the controller's publish: the reference's header stamp (the controller's system clock, same
    machine) against time.time() at our callback gives "controller publish -> our callback" (DDS
    plus our executor, ~1-1.5 ms p50 on the 2-core dev VM), the rest is "send -> controller
    publish". They also give the interval between references (should be the period) and the
    controller process's CPU load (/proc) during the measurement.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from geometry_msgs.msg import TwistStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from rns_ros.analysis.closed_loop import run_scenario
from rns_ros.control.camera_law import reactionless_camera_control, wrist_offset
from rns_ros.control.controller import ControllerSettings, ReactionlessController
from rns_ros.control.scenario import load_scenario
from rns_ros.core import (
    FreeFloatingState,
    damped_least_squares_inverse,
    load_model,
    reactionless_joint_velocity,
    singularity_consistent_inverse,
)
from rns_ros.core.fastmath import has_fast_solve
from rns_ros.harness import Harness, ProcessStack
from rns_ros.resources import config_dir, default_model_config, scenario_path
from rns_ros.sim.free_floating import FreeFloatingSimulator

#: Control period = contact simulator step of the force-controller benchmark [s].
FORCE_STEP = 1e-3
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
    run = _recorded_run(robot, "own_device_inspection", 20.0)
    for method in ("dls", "sc"):
        for case, sequence in (("steady", [(state, omega)] * samples), ("along own_device", run)):
            durations, evaluations = _alternating_steps(robot, method, sequence)
            for hold in ("naive", "midpoint"):
                met = "met" if np.median(durations[hold]) <= 100.0 else "missed"
                print(row(f"step {method} {hold} ({case})", durations[hold], f"{met:>10}"))
            ratio = np.median(durations["midpoint"]) / np.median(durations["naive"])
            means = np.mean(durations["midpoint"]) / np.mean(durations["naive"])
            goal = "met" if ratio <= 1.7 else "missed"
            print(
                f"  midpoint / naive {ratio:.2f} (goal <= 1.7: {goal}), means {means:.2f}, "
                f"{evaluations:.2f} midpoint evaluations per step"
            )
    control = ReactionlessController(robot, ControllerSettings())
    control.reset(state)
    q = state.q

    def tick():
        control.step(FreeFloatingState.compute(robot, q), omega)

    print(row("tick dls midpoint (+ sampled state)", timings(tick, samples)))


def _recorded_run(robot, name: str, duration: float) -> list:
    """(sampled state, omega_ref) of each period of the first ``duration`` [s] of a scenario run
    in process (midpoint, 100 Hz, kinematic mode)."""
    scenario = load_scenario(config_dir() / "scenarios" / f"{name}.yaml")
    samples = []
    run_scenario(robot, dataclasses.replace(scenario, duration=duration), on_period=samples.append)
    states = [FreeFloatingState.compute(robot, robot.configuration(scenario.initial_theta))]
    states += [sample.state for sample in samples[:-1]]
    return [(state, sample.omega_ref) for state, sample in zip(states, samples, strict=True)]


def _alternating_steps(robot, method: str, sequence) -> tuple[dict, float]:
    """Step a naive and a midpoint controller through ``sequence`` of (state, omega), timing
    them alternately (same machine load for both): (durations [us] per hold, mean midpoint
    evaluations per step)."""
    controllers = {
        hold: ReactionlessController(robot, ControllerSettings(method=method, hold_correction=hold))
        for hold in ("naive", "midpoint")
    }
    for control in controllers.values():
        control.reset(sequence[0][0])
    durations = {hold: np.empty(len(sequence)) for hold in controllers}
    midpoint = controllers["midpoint"]
    evaluate, count = midpoint._midpoint_rates, [0]

    def counted(*args):
        count[0] += 1
        return evaluate(*args)

    for i, (state, omega) in enumerate(sequence):
        for hold, control in controllers.items():
            start = time.perf_counter_ns()
            control.step(state, omega)
            durations[hold][i] = (time.perf_counter_ns() - start) / 1e3
    midpoint.reset(sequence[0][0])
    midpoint._midpoint_rates = counted  # count outside the timed loop
    for state, omega in sequence:
        midpoint.step(state, omega)
    return durations, count[0] / len(sequence)


# --- latency ------------------------------------------------------------------------------------
#: Command speeds about world x [rad/s]; command k is +-LATENCY_SPEEDS[(k // 2) % 4] (+ for even k).
LATENCY_SPEEDS = (0.10, 0.15, 0.20, 0.25)
LATENCY_CODES = 2 * len(LATENCY_SPEEDS)
#: A reference matches a code when |v - signature| <= MATCH_TOLERANCE |signature|.
MATCH_TOLERANCE = 1e-3
#: A command whose reference has not arrived after this [s] is lost: below the controller's
#: command_timeout (0.5 s), after which the held command ramps down and matches no code.
MATCH_TIMEOUT = 0.45
#: Random pause after a command's reference arrived, before the next command [s].
LATENCY_GAP = (0.015, 0.025)
#: Publish rate of the static joint_states [Hz].
JOINT_STATE_RATE = 100.0
#: Goal: p99 latency <= one control period + this [s].
LATENCY_MARGIN = 2e-3
BEST_EFFORT_1 = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)


def code_of(k: int) -> int:
    """Code (0..LATENCY_CODES-1) of command k."""
    return k % LATENCY_CODES


def code_speed(code: int) -> float:
    """Angular speed about world x of a code [rad/s]: even codes +, odd codes -."""
    return (1.0 if code % 2 == 0 else -1.0) * LATENCY_SPEEDS[code // 2]


@dataclass
class LatencyRun:
    """One measure_latency run.

    Attributes:
        rate: controller rate [Hz].
        latencies: twist publish() -> first matching reference's callback [s], per command
            (command order; NaN for a lost command).
        matched: command index of each match, in the order the matches happened.
        decoded: code of every reference received while measuring (-1: matches no code).
        intervals: time between consecutive references received while measuring [s].
        transport: controller publish (the matching reference's header stamp) -> our callback
            (wall clock) [s], per command (NaN for a lost command).
        mismatch: largest |v - signature| / |signature| of the matching references.
        duration: wall time of the measurement [s].
        controller_cpu: CPU time of the controller process during the measurement / duration.
    """

    rate: float
    latencies: np.ndarray
    matched: list[int]
    decoded: list[int]
    intervals: np.ndarray
    transport: np.ndarray
    mismatch: float
    duration: float
    controller_cpu: float

    @property
    def period(self) -> float:
        return 1.0 / self.rate

    @property
    def lost(self) -> int:
        return int(np.count_nonzero(np.isnan(self.latencies)))

    @property
    def goal(self) -> float:
        return self.period + LATENCY_MARGIN


class _LatencyProbe:
    """The measuring side: one node on the harness's executor, spun by this class's loop."""

    def __init__(self, stack: Harness, joint_names: Sequence[str]) -> None:
        self.executor = stack.executor
        node = stack.probe("rns_latency_probe")
        self.clock = node.get_clock()
        self.twist = node.create_publisher(TwistStamped, "cmd_twist", BEST_EFFORT_1)
        self.joints = node.create_publisher(JointState, "joint_states", QoSProfile(depth=10))
        self.joint_state = JointState(
            name=list(joint_names),
            position=SATELLITE_OBSERVATION_RAD.tolist(),
            velocity=[0.0] * len(joint_names),
        )
        node.create_subscription(
            JointTrajectory,
            "joint_references",
            self._on_reference,
            QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT),
        )
        self.signatures: np.ndarray | None = None  # (codes, n) once calibrated
        self.recent: deque[np.ndarray] = deque(maxlen=2)
        self.received = 0
        # (perf_counter, code) of every reference while recording
        self.log: list[tuple[float, int]] | None = None
        self.pending: int | None = None  # code awaited
        self.sent = 0.0
        self.arrived = 0.0
        self.transport = 0.0
        self.mismatch = 0.0
        self.next_state = time.perf_counter()

    def _on_reference(self, msg: JointTrajectory) -> None:
        now = time.perf_counter()
        wall = time.time()
        velocity = np.asarray(msg.points[0].velocities, dtype=float) if msg.points else None
        self.received += 1
        if velocity is None:
            return
        self.recent.append(velocity)
        if self.signatures is None:
            return
        errors = np.linalg.norm(self.signatures - velocity, axis=1) / self._norms
        code = int(np.argmin(errors))
        if errors[code] > MATCH_TOLERANCE:
            code = -1
        if self.log is not None:
            self.log.append((now, code))
        if self.pending is not None and code == self.pending:
            self.pending = None
            self.arrived = now
            self.transport = wall - (msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)
            self.mismatch = max(self.mismatch, float(errors[code]))

    def calibrate(self, signatures: np.ndarray) -> None:
        self.signatures = signatures
        self._norms = np.linalg.norm(signatures, axis=1)

    def send(self, speed: float, code: int | None = None) -> None:
        msg = TwistStamped()
        msg.header.frame_id = "world"
        msg.header.stamp = self.clock.now().to_msg()
        msg.twist.angular.x = speed
        self.pending = code
        self.sent = time.perf_counter()
        self.twist.publish(msg)

    def spin_until(self, condition: Callable[[], bool], deadline: float) -> bool:
        """Spin (and publish joint_states on time) until condition() or perf_counter deadline."""
        while True:
            now = time.perf_counter()
            if now >= self.next_state:
                self.joint_state.header.stamp = self.clock.now().to_msg()
                self.joints.publish(self.joint_state)
                self.next_state = max(self.next_state + 1.0 / JOINT_STATE_RATE, now)
            if condition():
                return True
            if now >= deadline:
                return False
            wait = min(deadline, self.next_state) - time.perf_counter()
            self.executor.spin_once(timeout_sec=max(wait, 0.0))


def measure_latency(
    rate: float,
    commands: int,
    domain_id: int,
    joint_names: Sequence[str],
    *,
    seed: int = 0,
    executable: str = "rns_controller",
    match_timeout: float = MATCH_TIMEOUT,
    parameters: dict | None = None,
) -> LatencyRun:
    """End-to-end twist -> joint reference latency against an rns_controller subprocess at
    ``rate`` [Hz] (method in the module docstring). ``executable``: another program taking the
    controller's ``--ros-args`` (a name in the venv / on PATH, or a path), for comparisons.
    ``match_timeout`` [s] and extra controller ``parameters`` (e.g. a longer command_timeout
    with a longer match_timeout: stalls then delay commands instead of losing them).

    Raises:
        RuntimeError: the controller did not start, or a code could not be calibrated.
    """
    # Both sides: never beyond this machine, only this domain (overwrite, do not default).
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ["ROS_DOMAIN_ID"] = str(domain_id)
    rng = np.random.default_rng(seed)
    with ProcessStack(domain_id) as processes, Harness(domain_id) as stack:
        probe = _LatencyProbe(stack, joint_names)
        controller = processes.start(
            executable,
            # predict_state and tracking_gain off: this probe's joint state stands still
            # while the controller would predict the joints on along its own outputs and turn
            # the camera toward the attitude the commands add up to, and a constant twist must
            # give a constant output to be recognised
            {
                "method": "dls",
                "rate": float(rate),
                "wrist_gain": 0.0,
                "predict_state": False,
                "tracking_gain": 0.0,
                **(parameters or {}),
            },
        )

        def fail(what: str) -> RuntimeError:
            return RuntimeError(f"{what} (rate {rate} Hz):\n{processes.output(controller)}")

        started = probe.spin_until(
            lambda: probe.received >= 3 or controller.poll() is not None,
            time.perf_counter() + 30.0,
        )
        if not started or controller.poll() is not None:
            raise fail("rns_controller published no joint_references")
        signatures = []
        for code in range(LATENCY_CODES):
            for _attempt in range(5):
                before = probe.recent[-1].copy()
                probe.send(code_speed(code))
                start = probe.received

                def steady(start=start, before=before) -> bool:
                    # a new, nonzero velocity, twice in a row
                    last = probe.recent[-1]
                    return (
                        probe.received - start >= 2
                        and np.linalg.norm(last) > 0.0
                        and not np.allclose(last, before, rtol=1e-6, atol=0.0)
                        and np.allclose(last, probe.recent[-2], rtol=1e-9, atol=0.0)
                    )

                if probe.spin_until(steady, time.perf_counter() + 1.0):
                    signatures.append(probe.recent[-1].copy())
                    break
            else:
                raise fail(f"no steady joint_references for code {code}")
        signatures = np.array(signatures)
        norms = np.linalg.norm(signatures, axis=1)
        gaps = np.linalg.norm(signatures[:, None] - signatures[None], axis=2) / norms[:, None]
        if gaps[~np.eye(LATENCY_CODES, dtype=bool)].min() < 100 * MATCH_TOLERANCE:
            raise fail(f"code signatures too close to tell apart: {signatures}")
        probe.calibrate(signatures)

        latencies = np.full(commands, np.nan)
        transport = np.full(commands, np.nan)
        matched = []
        probe.log = []
        begin = next_send = time.perf_counter()
        cpu = _cpu_seconds(controller.pid)
        for k in range(commands):
            probe.spin_until(lambda: False, next_send)
            code = code_of(k)
            probe.send(code_speed(code), code)
            if probe.spin_until(lambda: probe.pending is None, probe.sent + match_timeout):
                latencies[k] = probe.arrived - probe.sent
                transport[k] = probe.transport
                matched.append(k)
            probe.pending = None
            next_send = time.perf_counter() + rng.uniform(*LATENCY_GAP)
        duration = time.perf_counter() - begin
        cpu = (_cpu_seconds(controller.pid) - cpu) / duration
        log = np.array(probe.log, dtype=float).reshape(-1, 2)
        probe.log = None
    return LatencyRun(
        rate=float(rate),
        latencies=latencies,
        matched=matched,
        decoded=log[:, 1].astype(int).tolist(),
        intervals=np.diff(log[:, 0]),
        transport=transport,
        mismatch=probe.mismatch,
        duration=duration,
        controller_cpu=cpu,
    )


def latency(robot, commands: int, rates: Sequence[float], domain_id: int) -> list[LatencyRun]:
    runs = [measure_latency(rate, commands, domain_id, robot.joint_names) for rate in rates]
    print(
        f"\nlatency: cmd_twist publish() -> first joint_references reflecting it "
        f"(rns_controller subprocess, dls, k_g = 0, domain {domain_id}, localhost)"
    )
    header = ("rate [Hz]", "period [ms]", "n", "lost", "p50 [ms]", "p99 [ms]", "max [ms]")
    print("".join(f"{h:>12}" for h in (*header, "mean [ms]", "goal [ms]", "met")))
    for run in runs:
        ms = run.latencies[~np.isnan(run.latencies)] * 1e3
        p50, p99, top, mean = _stats(ms)
        met = "yes" if p99 <= run.goal * 1e3 and run.lost == 0 else "no"
        print(
            f"{run.rate:>12.0f}{run.period * 1e3:>12.2f}{len(ms):>12d}{run.lost:>12d}"
            + "".join(f"{value:>12.2f}" for value in (p50, p99, top, mean, run.goal * 1e3))
            + f"{met:>12}"
        )
    print("split at the controller's publish (its header stamp vs wall clock), p50 / p99 [ms]:")
    for run in runs:
        inbound = _stats((run.latencies - run.transport) * 1e3)
        outbound = _stats(run.transport * 1e3)
        gaps = _stats(run.intervals * 1e3)
        print(
            f"  {run.rate:.0f} Hz: send -> controller publish {inbound[0]:.2f} / {inbound[1]:.2f}, "
            f"controller publish -> our callback {outbound[0]:.2f} / {outbound[1]:.2f}; "
            f"reference interval {gaps[0]:.2f} / {gaps[1]:.2f} (max {gaps[2]:.1f}); controller "
            f"CPU {run.controller_cpu:.0%} of a core; {len(run.latencies)} commands in "
            f"{run.duration:.1f} s"
        )
    return runs


def _stats(values: np.ndarray) -> tuple[float, float, float, float]:
    """p50, p99, max, mean of the finite values (NaN if none)."""
    values = values[np.isfinite(values)]
    if not len(values):
        return (np.nan,) * 4
    p50, p99 = np.percentile(values, [50, 99])
    return float(p50), float(p99), float(values.max()), float(values.mean())


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far [s] (Linux /proc; NaN elsewhere)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return float("nan")


def cratio(workers: int | None) -> None:
    from rns_ros.analysis import chain_energy_maps as cem

    chain = cem.positioning_chain()
    grids = cem.positioning_grids(50)
    sub = [grids[0], grids[1][::10], grids[2], grids[3]]
    cores = os.cpu_count() or 1
    label = f"{workers or cores} processes"
    print(f"\n{'C_ratio map, 4-DoF (Fig. 5.3)':<34}{'points':>12}{'wall [s]':>12}{'points/s':>12}")
    cem.chain_c_ratio_map(chain, [g[:2] for g in grids], workers=1)  # warm-up
    runs = (
        ("1/10 sub-grid, 1 process", sub, 1),
        (f"1/10 sub-grid, {label}", sub, workers),
        (f"full map, {label}", grids, workers),
    )
    for name, grid, count in runs:
        start = time.perf_counter()
        values = cem.chain_c_ratio_map(chain, grid, workers=count)
        wall = time.perf_counter() - start
        print(f"{name:<34}{values.size:>12}{wall:>12.2f}{values.size / wall:>12.0f}")
    print(f"full map mean C_ratio {values.mean():.6f} (goal: wall < 60 s; {cores} cores here)")


def lockstep(runs: int, domain_id: int) -> None:
    """See the module docstring (lockstep)."""
    from rns_ros.apps.demo import parse_args  # the demo's own run, as `rns_demo` makes it
    from rns_ros.runs import inspection as demo

    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    scenario_file = scenario_path("satellite_observation")
    scenario = load_scenario(scenario_file)
    robot = load_model(default_model_config())
    settle = demo.OPERATOR_ZERO_DURATION + demo.SETTLE
    simulated = scenario.duration + settle
    common = ["--methods", "dls", "--real-time-factor", "0", "--no-record"]
    modes = {"side by side": "--output-lead", "in turn": "--no-output-lead"}
    print(
        f"\nlockstep over DDS: {scenario_file.stem}, dls, {simulated:.1f} s simulated, domain "
        f"{domain_id}, localhost; goal: side by side >= 10x real time"
    )
    print(
        f"{'run':>4}{'in-process [s]':>16}"
        + "".join(f"{name + ' [s]':>20}{'x real time':>13}{'/ in-process':>14}" for name in modes)
        + f"{'base dev [deg]':>16}{'run [s]':>10}"
    )
    factors = {name: [] for name in modes}
    runs_wall = []
    for k in range(runs):
        start = time.perf_counter()
        run_scenario(robot, scenario, method="dls", simulation_step=0.01, settle=settle)
        reference = time.perf_counter() - start
        line, deviations = f"{k + 1:>4}{reference:>16.2f}", []
        for name, flag in modes.items():
            args = parse_args([*common, flag, "--domain-id", str(domain_id)])
            row = demo.run_method("dls", args, scenario_file)
            factors[name].append(simulated / row.task_wall_s)
            deviations.append(row.figures.max_base_deviation_deg)
            if name == "side by side":
                runs_wall.append(row.wall_time_s)
            line += (
                f"{row.task_wall_s:>20.2f}{simulated / row.task_wall_s:>13.1f}"
                f"{row.task_wall_s / reference:>14.2f}"
            )
        print(line + f"{max(deviations):>16.2e}{runs_wall[-1]:>10.1f}", flush=True)
    for name, values in factors.items():
        print(
            f"{name}: x real time min / median / max {min(values):.1f} / "
            f"{float(np.median(values)):.1f} / {max(values):.1f}"
        )
    print(
        "whole run side by side (start-up, task, figures) [s] min / median / max "
        f"{min(runs_wall):.1f} / {float(np.median(runs_wall)):.1f} / {max(runs_wall):.1f}"
    )


def publish_rate(rates: Sequence[float], seconds: float, domain_id: int) -> None:
    """See the module docstring (publish)."""
    from rns_ros.nodes.simulator import SimulatorNode

    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    print(
        f"\n{'rns_simulator joint_states, wall clock':<40}{'measured [Hz]':>14}{'p50 [ms]':>10}"
        f"{'p99 [ms]':>10}{'max [ms]':>10}"
    )
    for rate in rates:
        with Harness(domain_id) as stack:
            stack.add(SimulatorNode, {"publish_rate": float(rate)})
            states = stack.record(JointState, "joint_states")
            if not stack.spin_until(lambda log=states: len(log) > 10, timeout=20.0):
                print(f"{f'publish_rate {rate:g} Hz':<40}  no joint_states within 20 s")
                continue
            stack.spin_for(0.5)  # discovery bursts pass
            start = len(states.received)
            stack.spin_for(seconds)
        window = np.array(states.received[start:])
        intervals = np.diff(window) * 1e3
        measured = (len(window) - 1) / (window[-1] - window[0])
        print(
            f"{f'publish_rate {rate:g} Hz':<40}{measured:>14.2f}{np.median(intervals):>10.2f}"
            f"{np.percentile(intervals, 99):>10.2f}{intervals.max():>10.2f}"
        )


def force_controller(samples: int) -> None:
    """rns_force_controller's step (rns_ros.control.force.controller) on the LWR wall task, one
    stroke closed around the in-process ContactSimulator, and the simulator's contact step."""
    from rns_ros.control.contact_tasks import WallScenario
    from rns_ros.control.force.commands import (
        ForceSetpoint,
        JointMeasurement,
        TwistCommand,
        WrenchSample,
    )
    from rns_ros.control.force.controller import ForceTeleopController
    from rns_ros.control.force.settings import CommandFrame, ForceControlSettings
    from rns_ros.sim.contact import ContactSimulator

    setup = WallScenario(strokes=1).setup()
    zero = np.zeros(3)
    steps = min(samples, round(setup.duration / FORCE_STEP))
    print(
        f"\n{'force controller, LWR wall, 1 kHz':<34}{'median [us]':>12}{'p99 [us]':>12}"
        f"{'budget':>10}"
    )
    for method in ("rns", "os"):
        control = ForceTeleopController(
            setup.robot, ForceControlSettings(method=method, nominal_period=FORCE_STEP)
        )
        sim = ContactSimulator(
            setup.robot, setup.constraint, initial_q=setup.initial_q, dt=FORCE_STEP
        )
        control_times, sim_times = np.empty(steps), np.empty(steps)
        for i in range(steps):
            t, stamp = i * FORCE_STEP, round(i * FORCE_STEP * 1e9)
            reference = setup.reference(t)
            control.set_twist(TwistCommand(reference.velocity, zero, CommandFrame.WORLD, stamp, t))
            force = setup.force(t) * sim.contact_normal()
            control.set_force(ForceSetpoint(force, zero, CommandFrame.WORLD, t))
            wrench = sim.wrist_wrench()
            control.add_wrench(WrenchSample(stamp, wrench[:3], wrench[3:]))
            measurement = JointMeasurement(stamp, sim.q, sim.v, sim.torque.copy())
            start = time.perf_counter_ns()
            out = control.step(measurement, t)
            control_times[i] = (time.perf_counter_ns() - start) / 1e3
            sim.set_torque(out.torque)
            start = time.perf_counter_ns()
            sim.step()
            sim_times[i] = (time.perf_counter_ns() - start) / 1e3
        share = np.median(control_times) / (FORCE_STEP * 1e6)
        print(row(f"step ({method})", control_times, f"{share:>9.0%}"))
    print(row("contact simulator step (RK4)", sim_times, f"{np.median(sim_times) / 1e3:>9.0%}"))
    print("(budget: share of the 1 ms control period; the DDS loop rate is in rns_demo's table)")


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="Without --only: core, simulator and controller. latency is opt-in (--only "
        "latency): it starts rns_controller subprocesses and takes ~0.5-2.5 min per rate. "
        "cratio (~30 s on 2 cores), lockstep (~20 s a run) and publish (~3 s a rate) are opt-in "
        "too.",
    )
    parser.add_argument(
        "--only",
        choices=(
            "core",
            "simulator",
            "controller",
            "force_controller",
            "latency",
            "cratio",
            "lockstep",
            "publish",
        ),
        help="run one section (latency only this way)",
    )
    parser.add_argument("--samples", type=int, default=5000, help="repetitions per operation")
    parser.add_argument(
        "--commands", type=int, default=1000, help="latency: operator commands per rate"
    )
    parser.add_argument(
        "--rates",
        type=float,
        nargs="+",
        default=[100.0, 500.0],
        help="latency: controller rates [Hz]",
    )
    parser.add_argument(
        "--domain-id",
        type=int,
        default=55,
        help="latency, lockstep: ROS_DOMAIN_ID of every node",
    )
    parser.add_argument("--runs", type=int, default=3, help="lockstep: runs of each mode")
    parser.add_argument(
        "--publish-rates",
        type=float,
        nargs="+",
        default=[100.0, 500.0],
        help="publish: rns_simulator publish_rate values [Hz]",
    )
    parser.add_argument(
        "--seconds", type=float, default=2.0, help="publish: measured wall time per rate [s]"
    )
    parser.add_argument(
        "--workers", type=int, default=None, help="cratio: local processes (default: one per core)"
    )
    args = parser.parse_args()
    if args.only == "cratio":
        cratio(args.workers)
        return
    if args.only == "lockstep":
        lockstep(args.runs, args.domain_id)
        return
    if args.only == "publish":
        publish_rate(args.publish_rates, args.seconds, args.domain_id)
        return
    robot = load_model(default_model_config())
    if args.only in (None, "core"):
        core(robot, args.samples)
    if args.only in (None, "simulator"):
        simulator(robot, args.samples)
    if args.only in (None, "controller"):
        controller(robot, args.samples)
    if args.only in (None, "force_controller"):
        force_controller(args.samples)
    if args.only == "latency":
        latency(robot, args.commands, args.rates, args.domain_id)


if __name__ == "__main__":
    main()
