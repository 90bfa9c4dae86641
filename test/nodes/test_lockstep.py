"""LockstepPacer without DDS: a fake clock, events that advance it, a fake simulation."""

from __future__ import annotations

import pytest

from rns_ros.nodes.lockstep import (
    CALLBACK_POLL,
    CALLBACK_STEPS,
    LOCKSTEP_PATIENCE,
    MAX_STAMP_LAG,
    PAUSE_POLL,
    START_PATIENCE,
    LockstepPacer,
    Pace,
    pace_lead,
)

DT = 0.01


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class FakeEvent:
    """threading.Event whose wait() advances the fake clock by the timeout (nobody sets it)."""

    def __init__(self, clock: FakeClock) -> None:
        self.clock = clock
        self.flag = False
        self.waits: list[float] = []

    def is_set(self) -> bool:
        return self.flag

    def set(self) -> None:
        self.flag = True

    def clear(self) -> None:
        self.flag = False

    def wait(self, timeout: float) -> bool:
        self.waits.append(timeout)
        self.clock.now += timeout
        return self.flag


class FakeSimulator:
    def __init__(self) -> None:
        self.time = 0.0
        self.dt = DT


class FakeSimulation:
    """A SteppedSimulation that stops the pacer after ``steps`` steps."""

    def __init__(self, pacer: LockstepPacer, steps: int, *, forced_steps: bool = True) -> None:
        self.pacer = pacer
        self.left = steps
        self.forced_steps = forced_steps
        self.fault = False
        self.held = 0
        self.patience_calls = 0
        self.callback = False
        self.step_cost = 0.0  # wall time [s] a step takes
        self.times: list[float] = []  # wall time of each step

    def faulted(self) -> bool:
        return self.fault

    def publish_held_state(self) -> None:
        self.held += 1
        if self.held >= 3:
            self.pacer.stop.set()

    def advance(self) -> float | None:
        self.times.append(self.pacer.clock())
        self.pacer.simulator.time += DT
        self.pacer.clock.now += self.step_cost
        self.left -= 1
        if self.left <= 0:
            self.pacer.stop.set()
        return self.pacer.simulator.time

    def steps_in_callback(self) -> bool:
        return self.callback

    def patience_over(self) -> bool:
        self.patience_calls += 1
        return self.forced_steps


def _pacer(lockstep_period=0.0, real_time_factor=1.0, **kwargs) -> LockstepPacer:
    clock = FakeClock()
    return LockstepPacer(
        FakeSimulator(),
        lockstep_period=lockstep_period,
        real_time_factor=real_time_factor,
        publish_period=0.01,
        stop=FakeEvent(clock),
        wake=FakeEvent(clock),
        clock=clock,
        **kwargs,
    )


def test_pace_lead_is_the_wall_time_until_the_pace_reaches_a_simulated_time():
    pace = Pace(wall_anchor=10.0, sim_anchor=2.0, factor=4.0)
    assert pace_lead(pace, 2.0, 10.0) == 0.0
    assert pace_lead(pace, 6.0, 10.0) == pytest.approx(1.0)  # 4 s simulated = 1 s wall
    assert pace_lead(pace, 6.0, 11.5) == pytest.approx(-0.5)


def test_steps_follow_the_real_time_factor_on_wall_time():
    pacer = _pacer(real_time_factor=2.0)
    sim = FakeSimulation(pacer, steps=20)
    pacer.run(sim)
    start = sim.times[0]
    # step k starts once the pace has reached k steps: k dt / factor after the anchor
    assert sim.times == pytest.approx([start + k * DT / 2.0 for k in range(20)])
    assert pacer.pace == Pace(start, 0.0, 2.0)


def test_a_factor_of_zero_runs_without_waiting():
    pacer = _pacer(real_time_factor=0.0)
    sim = FakeSimulation(pacer, steps=50)
    pacer.run(sim)
    assert pacer.stop.waits == []
    assert pacer.pace is None  # stamps are publication times


def test_a_loop_far_behind_its_pace_reanchors_instead_of_sprinting():
    pacer = _pacer(real_time_factor=1.0)
    sim = FakeSimulation(pacer, steps=10)
    sim.step_cost = 0.2  # every step takes 20 times its simulated time
    pacer.run(sim)
    # each step ends 0.19 s further behind: the third is beyond MAX_STAMP_LAG, and the step
    # after it is anchored anew (steps 4, 7 and 10)
    assert 2 * (0.2 - DT) < MAX_STAMP_LAG < 3 * (0.2 - DT)
    assert pacer.stop.waits == []
    assert pacer.pace.wall_anchor == sim.times[9]
    assert pacer.pace.sim_anchor == pytest.approx(9 * DT)


def test_lockstep_stands_one_period_in_until_the_first_command():
    """Before the first command the simulation steps in real time to one lockstep period and
    stands there (its state and /clock out) until a controller answers, one period on after
    each START_PATIENCE (a controller that subscribed late gets a tick): simulated time cannot
    run ahead of a controller that joins late."""
    pacer = _pacer(lockstep_period=0.03, real_time_factor=0.0)
    assert pacer.factor() == 1.0
    sim = FakeSimulation(pacer, steps=6)
    pacer.run(sim)
    times = sim.times
    for first in (0, 3):  # one period in real time, then the wait
        assert times[first : first + 3] == pytest.approx([times[first] + k * DT for k in range(3)])
    # the third step's period of real time, then the wait
    assert START_PATIENCE < times[3] - times[2] - DT <= START_PATIENCE + 2 * PAUSE_POLL
    assert pacer.command_sim_time == pytest.approx(0.03)  # the pause moved one period on
    assert sim.patience_calls == 0  # the node's patience is for a controller that answered
    assert pacer.awaiting_first
    with pacer.lock:
        assert pacer.pauses_here()
        pacer.command_received(pacer.simulator.time)
        assert not pacer.awaiting_first
        assert not pacer.pauses_here()
    assert pacer.factor() == 0.0


def test_lockstep_runs_in_real_time_once_its_command_was_dropped_or_reset():
    """A stale command dropped by the node or a reset leaves the simulation running in real
    time until commands come back (it does not stand as before the first command)."""
    pacer = _pacer(lockstep_period=DT, real_time_factor=0.0)
    pacer.command_received(0.0)
    pacer.simulator.time = 1.0
    assert pacer.pauses_here()
    pacer.last_command = None  # what a node does with a stale command
    assert not pacer.pauses_here()
    assert pacer.factor() == 1.0
    pacer.command_received(1.0)
    pacer.reset()
    pacer.simulator.time = 0.5
    assert not pacer.pauses_here()


def test_the_first_command_of_a_lockstep_leaves_the_pace_of_the_wait():
    pacer = _pacer(lockstep_period=0.05)
    pacer.reanchor = False
    pacer.command_received(0.02)
    assert pacer.reanchor
    assert pacer.last_command == pacer.clock.now
    assert pacer.command_sim_time == 0.02
    pacer.reanchor = False
    pacer.command_received(0.03)  # the next ones keep it
    assert not pacer.reanchor
    free = _pacer()
    free.reanchor = False
    free.command_received(0.0)
    assert not free.reanchor


def test_lockstep_pauses_a_period_past_the_newest_command():
    pacer = _pacer(lockstep_period=0.03)
    pacer.command_received(0.0)
    # the next step would end past the period: half a step early counts as there
    for sim_time, pauses in ((0.0, False), (0.02, False), (0.03 - 0.4 * DT, True), (0.03, True)):
        pacer.simulator.time = sim_time
        assert pacer.pauses_here() is pauses
    free = _pacer()
    free.command_received(0.0)
    free.simulator.time = 10.0
    assert not free.pauses_here()


def test_a_pause_waits_for_the_command_event_and_polls_for_the_patience():
    pacer = _pacer(lockstep_period=DT, real_time_factor=1.0)
    pacer.command_received(0.0)
    pacer.simulator.time = DT
    pacer.wake.set()
    sim = FakeSimulation(pacer, steps=1)
    assert pacer.pause_wait(sim) == PAUSE_POLL
    assert not pacer.wake.is_set()
    assert pacer.paused_since == pacer.clock.now
    pacer.real_time_factor = 0.0
    assert pacer.pause_wait(sim) == PAUSE_POLL  # the default idle poll
    callback_stepping = _pacer(lockstep_period=DT, real_time_factor=0.0, idle_poll=CALLBACK_POLL)
    callback_stepping.command_received(0.0)
    callback_stepping.simulator.time = DT
    assert callback_stepping.pause_wait(sim) == CALLBACK_POLL


def test_after_the_patience_one_step_is_forced_and_the_pause_goes_on():
    pacer = _pacer(lockstep_period=DT, real_time_factor=1.0)
    pacer.command_received(0.0)
    pacer.simulator.time = DT
    sim = FakeSimulation(pacer, steps=1, forced_steps=True)
    pacer.run(sim)
    # waited in PAUSE_POLL slices for just over LOCKSTEP_PATIENCE, then one forced step
    assert sim.patience_calls == 1
    assert len(sim.times) == 1
    waited = sum(pacer.wake.waits)
    assert LOCKSTEP_PATIENCE < waited <= LOCKSTEP_PATIENCE + 2 * PAUSE_POLL
    assert pacer.paused_since == pytest.approx(sim.times[0])  # the next patience counts anew


def test_after_the_patience_a_node_that_drops_the_command_runs_on():
    pacer = _pacer(lockstep_period=DT, real_time_factor=1.0)
    pacer.command_received(0.0)
    pacer.simulator.time = DT
    sim = FakeSimulation(pacer, steps=1, forced_steps=False)
    sim.patience_over = lambda: setattr(pacer, "last_command", None) or False
    pacer.run(sim)
    assert len(sim.times) == 1
    assert pacer.paused_since is None


def test_a_command_callback_steps_to_the_pause_and_the_thread_only_waits():
    pacer = _pacer(lockstep_period=0.05, real_time_factor=0.0, idle_poll=CALLBACK_POLL)
    pacer.command_received(0.0)
    sim = FakeSimulation(pacer, steps=1000)
    sim.callback = True
    # the simulation thread leaves the steps to the callback while it runs
    assert pacer.pause_wait(sim) == CALLBACK_POLL
    pacer.wake.set()  # the callback handed on
    assert pacer.pause_wait(sim) is None
    pacer.wake.clear()
    pacer.run_to_pause(sim)
    assert len(sim.times) == 5
    assert pacer.pauses_here()
    assert not pacer.wake.is_set()  # paused: nothing to hand on
    assert pacer.pace is None


def test_a_long_period_is_handed_on_to_the_simulation_thread():
    pacer = _pacer(lockstep_period=10.0, real_time_factor=0.0)
    pacer.command_received(0.0)
    sim = FakeSimulation(pacer, steps=10**6)
    sim.callback = True
    pacer.run_to_pause(sim)
    assert len(sim.times) == CALLBACK_STEPS
    assert not pacer.pauses_here()
    assert pacer.wake.is_set()


def test_command_age_counts_simulated_time_in_lockstep_else_wall_time():
    lockstep = _pacer(lockstep_period=0.01)
    lockstep.simulator.time = 1.5
    lockstep.clock.now += 100.0
    assert lockstep.command_age(received=0.0, sim_received=1.0) == pytest.approx(0.5)
    free = _pacer()
    assert free.command_age(received=free.clock.now - 0.25, sim_received=0.0) == 0.25


def test_stamp_lead_is_clamped_to_one_step_ahead_and_the_largest_lag():
    pacer = _pacer(real_time_factor=2.0)
    assert pacer.stamp_lead(1.0) is None  # no pace yet: stamped when published
    pacer.pace = Pace(pacer.clock.now, 0.0, 2.0)
    assert pacer.stamp_lead(0.01) == pytest.approx(0.005)
    assert pacer.stamp_lead(1.0) == pytest.approx(DT / 2.0)
    assert pacer.stamp_lead(-10.0) == -MAX_STAMP_LAG


def test_a_faulted_simulation_publishes_its_held_state_at_the_publish_period():
    pacer = _pacer()
    sim = FakeSimulation(pacer, steps=1)
    sim.fault = True
    pacer.reanchor = False
    pacer.run(sim)
    assert sim.held == 3
    assert sim.times == []
    assert pacer.stop.waits == [0.01, 0.01, 0.01]
    assert pacer.reanchor


def test_a_reset_and_a_new_factor_reanchor_the_pace():
    pacer = _pacer(lockstep_period=0.01)
    pacer.command_received(0.5)
    pacer.reanchor = False
    pacer.reset()
    assert pacer.reanchor
    assert pacer.last_command is None
    assert pacer.command_sim_time == 0.0
    pacer.reanchor = False
    pacer.set_real_time_factor(3.0)
    assert pacer.reanchor
    assert pacer.real_time_factor == 3.0
