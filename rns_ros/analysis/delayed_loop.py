"""The DDS loop's timing, reproduced in process: where the base rotation over DDS comes from.

:func:`rns_ros.analysis.closed_loop.run_scenario` samples the robot at each tick and acts on the
output at once. Over DDS (``rns_demo``) four things differ, each reproduced here on the same
kinematic simulator (1 ms step) so that its share of the base deviation can be measured alone:

* **state age**: joint_states come on their own grid (``state_period``, ``state_phase``) and
  reach the controller ``state_latency`` after their stamp; the controller predicts them forward
  (``predict_state``).
* **output delay**: an output computed at t_k acts from the first simulator step at or after
  t_k + ``output_delay`` (topic latency, then the wait for the plant's next update).
* **cut holds**: with ``immediate_reaction`` a changed twist (every ``command_period``, arriving
  ``command_latency`` after it was sent) is served at once and the period restarts; a hold then
  lasts less than the T its midpoint correction assumed.
* **timer jitter**: timer ticks come ``timer_latency`` late. The law is told each output's
  hold (``told_hold``): the period T, the time to the timer's next grid instant, or that plus
  the timer's mean lateness (:class:`~rns_ros.control.ticks.TickLateness`, as
  ``rns_controller`` on the wall clock).

The controller part is the node's: :class:`~rns_ros.control.controller.ReactionlessController`
with :func:`~rns_ros.control.prediction.predict_joint_angles` to when its output acts.
``python -m rns_ros.analysis.delayed_loop`` prints the breakdown of docs/controller.md.
"""

from __future__ import annotations

import argparse
import heapq
import math
from dataclasses import dataclass, replace

import numpy as np

from rns_ros.control.controller import (
    ControllerSettings,
    HoldCorrection,
    ReactionlessController,
    angular_velocity_in_world,
)
from rns_ros.control.prediction import OutputTiming, PublishedOutput, predict_joint_angles
from rns_ros.control.scenario import Scenario, load_scenario
from rns_ros.control.ticks import TickLateness
from rns_ros.core.conventions import rotation_from_quaternion
from rns_ros.core.errors import ConfigError
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.sim.free_floating import FreeFloatingSimulator, SimulationMode

#: Simulator step [s] (rns_simulator's default).
SIMULATION_STEP = 1e-3
#: A controller that assumes its output acts at its tick (no latency, no update grid).
ACTS_AT_TICK = OutputTiming()
#: What the law is told of each output's hold (``told_hold`` of :func:`run_delayed_loop`): the
#: period; the time to the timer's next grid instant; that plus the timer's mean lateness.
TOLD_HOLDS = ("period", "grid", "expected")


@dataclass(frozen=True)
class LoopTiming:
    """Timing of one emulated DDS loop; all times in seconds.

    Attributes:
        state_period: joint_states period (simulated time), a multiple of the 1 ms step.
        state_phase: stamp of the first state after t = 0, in [0, state_period).
        state_latency: stamp to receipt by the controller, >= 0.
        output_delay: publish to receipt by the plant, which acts at its next 1 ms step, >= 0.
        predicted: what the controller assumes of that (its ``output_latency`` and
            ``plant_period``); the default: the output acts at its tick.
        command_period: operator twist period; None: the command is the profile at the
            middle of each hold (as in :func:`run_scenario`).
        command_latency: (low, high) of a twist's uniform send-to-receipt delay.
        timer_latency: (low, high) of a timer tick's uniform lateness.
        tick_phase: offset of the controller's timer grid from the plant's step grid, >= 0.
        immediate: serve a changed twist at once and restart the period (cut holds).
        seed: random generator seed of the latencies.
    """

    state_period: float = 0.01
    state_phase: float = 0.0
    state_latency: float = 0.0
    output_delay: float = 0.0
    predicted: OutputTiming = ACTS_AT_TICK
    command_period: float | None = None
    command_latency: tuple[float, float] = (0.0, 0.0)
    timer_latency: tuple[float, float] = (0.0, 0.0)
    tick_phase: float = 0.0
    immediate: bool = False
    seed: int = 0

    def __post_init__(self) -> None:
        values = {
            "state_latency": self.state_latency,
            "tick_phase": self.tick_phase,
            "output_delay": self.output_delay,
            "predicted.latency": self.predicted.latency,
            "predicted.plant_period": self.predicted.plant_period,
            **{f"command_latency[{i}]": v for i, v in enumerate(self.command_latency)},
            **{f"timer_latency[{i}]": v for i, v in enumerate(self.timer_latency)},
        }
        for name, value in values.items():
            if not (math.isfinite(value) and value >= 0.0):
                raise ConfigError(f"{name} must be a finite time >= 0 s, got {value!r}")
        steps = self.state_period / SIMULATION_STEP
        if not (self.state_period > 0.0 and abs(steps - round(steps)) < 1e-9 and steps >= 1):
            raise ConfigError(
                f"state_period must be a positive multiple of {SIMULATION_STEP} s, "
                f"got {self.state_period!r}"
            )
        if not 0.0 <= self.state_phase < self.state_period:
            raise ConfigError(
                f"state_phase must be in [0, {self.state_period}) s, got {self.state_phase!r}"
            )
        if self.command_period is not None and not self.command_period > 0.0:
            raise ConfigError(f"command_period must be > 0 s, got {self.command_period!r}")


@dataclass(frozen=True)
class DelayedLoopResult:
    """Figures of one emulated run.

    Attributes:
        max_base_deviation_deg: largest base attitude change from the start, sampled every
            step [deg].
        ticks: control outputs computed; shortest_hold_s / longest_hold_s: tick-to-tick
            extremes [s].
    """

    max_base_deviation_deg: float
    ticks: int
    shortest_hold_s: float
    longest_hold_s: float


def _tick_times(
    duration: float, period: float, timing: LoopTiming, arrivals: np.ndarray, rng
) -> list[float]:
    """Tick times [s]: a timer tick one period after the previous tick (late by
    timer_latency), and with ``immediate`` a tick at each twist's receipt ``arrivals`` (at
    least 1 ms after the previous tick, as MIN_TICK_INTERVAL of the node)."""
    if not (timing.immediate and arrivals.size):
        # a periodic timer: an absolute grid, each tick late by its own latency
        grid = timing.tick_phase + period * np.arange(int(duration / period) + 1)
        late = grid + rng.uniform(*timing.timer_latency, size=grid.size)
        return [float(t) for t in late if t <= duration]
    ticks, due, i = [], timing.tick_phase, 0
    while True:
        timer = due + rng.uniform(*timing.timer_latency)
        if i < len(arrivals) and arrivals[i] < timer:
            t, i = arrivals[i], i + 1
            if ticks and t - ticks[-1] < 1e-3:
                continue  # MIN_TICK_INTERVAL: served by the next tick
        else:
            t = timer
        if t > duration:
            return ticks
        ticks.append(t)
        due = t + period


def _command_at(
    scenario: Scenario, t: float, period: float, timing: LoopTiming, arrivals: np.ndarray
) -> np.ndarray:
    """Commanded camera angular velocity at tick ``t`` [rad/s], (3,): the operator's newest
    twist received by then (the profile at its send time), or the profile at mid-hold."""
    if timing.command_period is None:
        return scenario.angular_velocity(t + 0.5 * period)
    k = int(np.searchsorted(arrivals, t, side="right")) - 1
    return scenario.angular_velocity(k * timing.command_period) if k >= 0 else np.zeros(3)


def _command_arrivals(duration: float, timing: LoopTiming, rng) -> np.ndarray:
    """Arrival times [s] of the operator's twists at the controller (empty without them)."""
    if timing.command_period is None:
        return np.zeros(0)
    sent = timing.command_period * np.arange(int(duration / timing.command_period) + 1)
    return sent + rng.uniform(*timing.command_latency, size=sent.size)


def _told_hold(
    told: str, tick: float, period: float, timing: LoopTiming, lateness: TickLateness
) -> float | None:
    """The hold [s] the law is told for the output of ``tick`` [s] (``told``, one of
    :data:`TOLD_HOLDS`), moved onto the predicted update grid; None: the period."""
    if told == "period":
        return None
    grid = timing.tick_phase + period * (math.floor((tick - timing.tick_phase) / period) + 1)
    until_next = round((grid - tick) * 1e9)
    hold = until_next * 1e-9 if told == "grid" else lateness.hold(until_next)
    if hold is None:
        return None
    acting = timing.predicted.acting_time
    ends, starts = acting(tick + hold, 0.0), acting(tick, 0.0)
    return ends - starts if ends > starts else None


def _known_state(
    robot: FreeFloatingModel,
    samples: list,
    outputs: list[PublishedOutput],
    tick: float,
    timing: LoopTiming,
) -> FreeFloatingState:
    """The robot as the controller knows it at ``tick`` [s]: the newest joint state received by
    then, predicted forward to ``tick`` from its stamp."""
    known = [s for s in samples[-3:] if s[0] <= tick] or samples[:1]
    _, stamp, q_s, v_s = known[-1]
    q = q_s.copy()
    if tick > stamp:
        q[7:] = predict_joint_angles(q_s[7:], v_s, stamp, tick, outputs, timing.predicted).theta
    return FreeFloatingState.compute(robot, q)


def run_delayed_loop(
    robot: FreeFloatingModel,
    scenario: Scenario,
    timing: LoopTiming,
    *,
    method: str | None = None,
    rate: float = 100.0,
    duration: float | None = None,
    hold_correction: HoldCorrection | str = HoldCorrection.MIDPOINT,
    told_hold: str = "period",
) -> DelayedLoopResult:
    """Run ``scenario`` (kinematic mode) with the DDS timing ``timing``; see the module doc.

    Args:
        method: DLS / SC (default: the scenario's); rate: control rate [Hz].
        duration: simulated time [s] (default: the scenario's).
        told_hold: one of :data:`TOLD_HOLDS`; ``grid`` and ``expected`` need a timer without
            ``immediate`` ticks (its grid is absolute), and the hold is moved onto the plant's
            predicted update grid as the node does.
    """
    if told_hold not in TOLD_HOLDS:
        raise ConfigError(f"told_hold must be one of {list(TOLD_HOLDS)}, got {told_hold!r}")
    if told_hold != "period" and timing.immediate:
        raise ConfigError(f"told_hold {told_hold!r} needs a timer without immediate ticks")
    period = 1.0 / rate
    lateness = TickLateness(period)
    duration = scenario.duration if duration is None else float(duration)
    rng = np.random.default_rng(timing.seed)
    settings = ControllerSettings(
        method=scenario.method() if method is None else method,
        gains=scenario.gains(None),
        period=period,
        hold_correction=hold_correction,
    )
    q0 = robot.configuration(scenario.initial_theta)
    simulator = FreeFloatingSimulator(
        robot,
        mode=SimulationMode.KINEMATIC,
        dt=SIMULATION_STEP,
        initial_q=q0,
        initial_momentum=np.zeros(6),
    )
    controller = ReactionlessController(robot, settings)
    state0 = FreeFloatingState.compute(robot, q0)
    controller.reset(state0)
    base_0 = state0.base_rotation

    arrivals = _command_arrivals(duration, timing, rng)
    ticks = _tick_times(duration, period, timing, arrivals, rng)
    state_steps = round(timing.state_period / SIMULATION_STEP)
    phase_steps = round(timing.state_phase / SIMULATION_STEP)
    # (receipt, stamp, q, v); the controller starts from the state at rest at t = 0
    samples = [(0.0, 0.0, q0.copy(), np.zeros(robot.n))]
    outputs: list[PublishedOutput] = []
    pending: list[tuple[int, int, np.ndarray]] = []  # heap of (acting step, order, theta_dot)
    worst, tick_index, last_tick = 0.0, 0, None
    holds = []
    steps = round(duration / SIMULATION_STEP)
    for k in range(steps + 1):
        t = k * SIMULATION_STEP
        if (k - phase_steps) % state_steps == 0 and k >= phase_steps and k > 0:
            samples.append(
                (t + timing.state_latency, t, simulator.q.copy(), simulator.v[6:].copy())
            )
        while tick_index < len(ticks) and ticks[tick_index] < t + SIMULATION_STEP:
            tick = ticks[tick_index]
            tick_index += 1
            if last_tick is not None:
                controller.end_hold(tick - last_tick)
                holds.append(tick - last_tick)
            last_tick = tick
            state = _known_state(robot, samples, outputs, tick, timing)
            omega = _command_at(scenario, tick, period, timing, arrivals)
            hold = _told_hold(told_hold, tick, period, timing, lateness)
            omega = angular_velocity_in_world(state, omega, scenario.frame)
            step = controller.step(state, omega, hold)
            outputs.append(PublishedOutput(tick, step.joint_velocity))
            acting = math.ceil((tick + timing.output_delay) / SIMULATION_STEP - 1e-9)
            heapq.heappush(pending, (acting, tick_index, step.joint_velocity))
        if k == steps:
            break
        while pending and pending[0][0] <= k:
            simulator.set_reference(velocities=heapq.heappop(pending)[2])
        simulator.step()
        base = rotation_from_quaternion(simulator.q[3:7])
        worst = max(worst, attitude_deviation(base_0, base))
    return DelayedLoopResult(
        max_base_deviation_deg=float(np.rad2deg(worst)),
        ticks=len(ticks),
        shortest_hold_s=float(min(holds)) if holds else math.nan,
        longest_hold_s=float(max(holds)) if holds else math.nan,
    )


#: The timing of loopback DDS on the 2-core machine (docs/controller.md): states at 100 Hz
#: reaching the controller 0.5 ms after their stamp, outputs reaching the plant 0.5 ms after they
#: are published (then acting at its next 1 ms step), 50 Hz operator twists 0.3-1.5 ms in
#: flight, timer ticks 0.05-0.5 ms late, the controller's timer grid 0.3 ms off the plant's.
DDS_TIMING = LoopTiming(
    state_phase=0.003,
    state_latency=5e-4,
    output_delay=5e-4,
    command_period=0.02,
    command_latency=(3e-4, 1.5e-3),
    timer_latency=(5e-5, 5e-4),
    tick_phase=3e-4,
    immediate=True,
)
#: What rns_controller predicts by default: its output_latency and plant_period.
NODE_PREDICTION = OutputTiming(latency=5e-4, plant_period=1e-3)

#: (label, timing) rows of :func:`breakdown`: one DDS effect at a time, then all of them.
BREAKDOWN = (
    ("in process (run_scenario timing)", LoopTiming()),
    (
        "state age 3 ms + 0.5 ms in flight, predicted",
        LoopTiming(state_phase=0.003, state_latency=5e-4),
    ),
    (
        "output 0.5 ms in flight + next step, not predicted",
        LoopTiming(output_delay=5e-4, tick_phase=3e-4),
    ),
    (
        "output 0.5 ms in flight + next step, predicted",
        LoopTiming(output_delay=5e-4, tick_phase=3e-4, predicted=NODE_PREDICTION),
    ),
    (
        "50 Hz twists, cut holds (immediate), next step predicted",
        replace(
            DDS_TIMING,
            state_phase=0.0,
            state_latency=0.0,
            output_delay=0.0,
            predicted=OutputTiming(plant_period=1e-3),
        ),
    ),
    ("all of DDS, timer ticks only, not predicted", replace(DDS_TIMING, immediate=False)),
    ("all of DDS, immediate reaction, not predicted", DDS_TIMING),
    (
        "all of DDS, timer ticks only, predicted",
        replace(DDS_TIMING, immediate=False, predicted=NODE_PREDICTION),
    ),
    (
        "all of DDS, immediate reaction, predicted",
        replace(DDS_TIMING, predicted=NODE_PREDICTION),
    ),
)


def breakdown(robot: FreeFloatingModel, scenario: Scenario, methods=("dls", "sc")) -> str:
    """A table: max base deviation [deg] per :data:`BREAKDOWN` row and method."""
    lines = [f"{'timing':<52}" + "".join(f"{m:>12}" for m in methods)]
    for label, timing in BREAKDOWN:
        row = [run_delayed_loop(robot, scenario, timing, method=m) for m in methods]
        lines.append(f"{label:<52}" + "".join(f"{r.max_base_deviation_deg:>12.2e}" for r in row))
    return "\n".join(lines)


def main(argv=None) -> int:
    from rns_ros.core import load_model
    from rns_ros.resources import default_model_config, scenario_path

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="satellite_observation")
    parser.add_argument("--methods", default="dls,sc")
    args = parser.parse_args(argv)
    robot = load_model(default_model_config())
    scenario = load_scenario(scenario_path(args.scenario))
    print(breakdown(robot, scenario, tuple(args.methods.split(","))))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
