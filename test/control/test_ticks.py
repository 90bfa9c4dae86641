"""Control ticks: instants served and caught up, commands released at their stamps, ticks that
wait for the command in force under a watchdog. No ROS: clocks and timers are fakes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rns_ros.control.ticks import (
    COMMANDS,
    AwaitedTicks,
    CommandSchedule,
    ServedTick,
    TickInstants,
    TickLateness,
    next_tick_in,
)
from rns_ros.core import ConfigError

MS = 1_000_000  # [ns]
PERIOD = 0.01  # [s]


class FakeClock:
    """A monotonic clock [s] the test sets."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class FakeWatchdog:
    """Records whether the countdown runs."""

    def __init__(self) -> None:
        self.running, self.resets = False, 0

    def reset(self) -> None:
        self.running, self.resets = True, self.resets + 1

    def cancel(self) -> None:
        self.running = False


# --- next_tick_in: a timer's next call on its grid -------------------------------------------


def test_next_tick_in_is_the_timer_delay_within_its_grid_else_none():
    assert next_tick_in(4 * MS, PERIOD) == pytest.approx(0.004)
    assert next_tick_in(14 * MS, PERIOD) == pytest.approx(0.014)  # late, still on its grid
    assert next_tick_in(16 * MS, PERIOD) is None  # badly late: assume the period
    assert next_tick_in(0, PERIOD) is None
    assert next_tick_in(None, PERIOD) is None  # cancelled timer


# --- TickInstants: the hold each tick ends, late ticks caught up ------------------------------


def test_each_served_tick_ends_the_hold_of_the_one_before():
    clock = FakeClock()
    ticks = TickInstants(PERIOD, monotonic=clock)
    assert ticks.serve(1000 * MS) == (100.0, None)  # first tick: nothing held before it
    clock.now = 100.5
    now, held = ticks.serve(1010 * MS)
    assert now == 100.5
    assert ticks.last_wall == 100.5
    assert held == pytest.approx(PERIOD)
    assert ticks.last == pytest.approx(1.01)
    with pytest.raises(ConfigError, match="period"):
        TickInstants(0.0)


@pytest.mark.parametrize("jump", [10**6 * 1000, -3200])  # [ms]: a stranger's /clock, a reset
def test_a_clock_jump_between_two_ticks_ends_no_hold_on_the_clock_difference(robot, jump):
    """The hold a tick ends is the difference of two clock readings: after a jump it says
    nothing of how long the output was held. The controller then ends no hold (theta_ref stays
    where the hold started, where a resync takes over) instead of theta_ref += 1e6 s theta_dot."""
    from rns_ros.control.controller import ControllerSettings, ReactionlessController
    from rns_ros.core.state import FreeFloatingState

    state = FreeFloatingState.compute(
        robot, robot.configuration(np.deg2rad([-90, -30, 0, -70, 180, -30, 0]))
    )
    controller = ReactionlessController(robot, ControllerSettings(period=PERIOD))
    ticks = TickInstants(PERIOD, monotonic=FakeClock())
    ticks.serve(5000 * MS)
    step = controller.step(state, [0.2, 0.0, 0.0])
    assert np.abs(step.joint_velocity).max() > 0.01
    _, held = ticks.serve((5000 + jump) * MS)
    assert not controller.end_hold(held)
    assert np.array_equal(controller.reference_positions, step.reference_positions)
    # within max(5 T, 0.05 s) a late tick still ends its hold
    controller.step(state, [0.2, 0.0, 0.0])
    assert controller.end_hold(controller.max_hold)
    assert controller.max_hold == pytest.approx(0.05)


def _lead_ticks(clock):
    return TickInstants(PERIOD, lead=PERIOD, monotonic=clock)


def test_a_tick_in_step_with_the_state_is_served_at_its_instant():
    clock = FakeClock()
    ticks = _lead_ticks(clock)
    for k in range(5):
        tick = (1000 + 10 * k) * MS
        # the state of a simulation in step is stamped at the tick, or up to the lead past it
        assert ticks.lead_instant(tick, tick + 10 * MS, clock()) == tick
        ticks.serve(tick)


def test_a_simulation_ahead_of_the_ticks_is_caught_up_and_the_ticks_up_to_it_skipped():
    clock = FakeClock()
    ticks = _lead_ticks(clock)
    ticks.serve(ticks.lead_instant(1000 * MS, 1000 * MS, clock()))
    # the state is stamped 1.04 s: more than lead + T/2 past the tick of 1.01 s
    served = ticks.lead_instant(1010 * MS, 1040 * MS, clock())
    assert served == 1040 * MS
    ticks.serve(served)
    for tick in (1020, 1030, 1040):
        assert ticks.lead_instant(tick * MS, 1040 * MS, clock()) is None  # served already
    assert ticks.lead_instant(1050 * MS, 1050 * MS, clock()) == 1050 * MS


def test_a_state_farther_ahead_than_the_catch_up_limit_is_another_clock():
    clock = FakeClock()
    ticks = _lead_ticks(clock)
    assert ticks.lead_instant(1000 * MS, 2001 * MS, clock()) == 1000 * MS


def test_after_a_clock_reset_the_state_from_before_it_is_not_caught_up_to():
    clock = FakeClock()
    ticks = _lead_ticks(clock)
    ticks.serve(ticks.lead_instant(500 * MS, 500 * MS, clock()))
    clock.now += 0.1
    # /clock went back to 0: the newest state (0.5 s, received before) is from before the reset
    assert ticks.lead_instant(0, 500 * MS, clock() - 0.1) == 0
    ticks.serve(0)
    clock.now += 0.1
    # the first state after the reset, received after it, is caught up to as usual
    assert ticks.lead_instant(10 * MS, 40 * MS, clock()) == 40 * MS


# --- AwaitedTicks: ticks wait for the command in force, under a watchdog ----------------------


def test_a_tick_waits_for_its_command_in_force_and_is_served_with_the_commands_up_to_it():
    watchdog = FakeWatchdog()
    awaited = AwaitedTicks(watchdog)
    assert awaited.tick(10) == [ServedTick(10, [])]  # no operator: nothing to wait for
    assert awaited.push(10, "rest", moving=False) == []
    assert awaited.tick(20) == []  # what follows the rest is not known yet
    assert awaited.oldest_waiting == 20
    assert watchdog.running
    assert awaited.tick(30) == []  # waits behind the older tick
    assert awaited.push(25, "a", moving=True) == [ServedTick(20, ["rest"])]
    assert awaited.oldest_waiting == 30
    assert watchdog.running
    assert awaited.push(40, "b", moving=True) == [ServedTick(30, ["a"])]
    assert awaited.oldest_waiting is None
    assert not watchdog.running
    assert awaited.tick(40) == [ServedTick(40, ["b"])]


def test_the_watchdog_serves_the_waiting_ticks_with_the_newest_command():
    watchdog = FakeWatchdog()
    awaited = AwaitedTicks(watchdog)
    awaited.push(10, "a", moving=True)
    assert awaited.tick(10) == [ServedTick(10, ["a"])]
    assert awaited.tick(20) == []
    assert awaited.tick(30) == []
    assert watchdog.resets == 1  # started by the first waiting tick only
    assert awaited.give_up() == [ServedTick(20, []), ServedTick(30, [])]
    assert not watchdog.running
    assert awaited.give_up() == []  # nothing waits: a late alarm does nothing
    awaited.push(40, "stop", moving=False)  # a stop after motion is not waited on
    assert awaited.tick(50) == [ServedTick(50, ["stop"])]


def test_the_awaited_schedule_counts_the_commands_dropped():
    awaited = AwaitedTicks(FakeWatchdog(), max_waiting=2)
    for stamp in range(3):
        awaited.push(10**18 + stamp, stamp, moving=True)
    assert awaited.schedule.dropped == 1


# --- AwaitedTicks on several streams: every command in force known --------------------------

TWIST, FORCE = "cmd_twist", "force_setpoint"


def test_a_tick_waits_for_the_command_in_force_on_every_stream_then_gets_them_by_stamp():
    """A twist and a force setpoint stream: the tick at 20 is served once both streams hold a
    command stamped at or after it, with the commands of both merged by stamp (equal stamps in
    the order of the streams)."""
    watchdog = FakeWatchdog()
    awaited = AwaitedTicks(watchdog, streams=(TWIST, FORCE))
    assert awaited.tick(10) == [ServedTick(10, [])]  # no operator: nothing to wait for
    assert awaited.push(10, "v10", moving=True, stream=TWIST) == []
    assert awaited.push(10, "f10", moving=True, stream=FORCE) == []
    assert awaited.tick(20) == []
    assert awaited.awaited_streams() == [TWIST, FORCE]
    assert awaited.push(20, "v20", moving=True, stream=TWIST) == []  # the force is not known
    assert awaited.awaited_streams() == [FORCE]
    assert awaited.push(30, "f30", moving=True, stream=FORCE) == [
        ServedTick(20, ["v10", "f10", "v20"])
    ]
    assert not watchdog.running
    assert awaited.push(30, "v30", moving=True, stream=TWIST) == []
    assert awaited.tick(30) == [ServedTick(30, ["v30", "f30"])]


def test_a_stream_without_commands_yet_is_not_waited_for():
    """An operator that sends twists before its force task starts: the force stream holds no
    command, so nothing is waited for there (no force setpoint is in force)."""
    awaited = AwaitedTicks(FakeWatchdog(), streams=(TWIST, FORCE))
    awaited.push(20, "zero", moving=True, stream=TWIST)
    assert awaited.tick(20) == [ServedTick(20, ["zero"])]
    assert awaited.tick(30) == []
    assert awaited.push(30, "f30", moving=True, stream=FORCE) == []  # the twist is awaited
    assert awaited.push(40, "v40", moving=True, stream=TWIST) == [ServedTick(30, ["f30"])]


def test_the_watchdog_restarts_only_for_the_streams_waited_on_and_gives_up_on_them():
    """A force stream that stalls while twists keep coming is given up on: the twists do not
    restart the watchdog; the alarm releases the force stream alone (the twists are still
    awaited at the next tick) and serves the tick with the newest setpoint."""
    watchdog = FakeWatchdog()
    awaited = AwaitedTicks(watchdog, streams=(TWIST, FORCE))
    awaited.push(10, "v10", moving=True, stream=TWIST)
    awaited.push(10, "f10", moving=True, stream=FORCE)
    assert awaited.tick(20) == []
    assert watchdog.resets == 1
    awaited.push(20, "v20", moving=True, stream=TWIST)  # awaited: restarts
    assert watchdog.resets == 2
    awaited.push(30, "v30", moving=True, stream=TWIST)  # the tick waits for the force only
    assert watchdog.resets == 2
    assert awaited.give_up() == [ServedTick(20, ["v10", "f10", "v20"])]
    assert not watchdog.running
    assert awaited.tick(30) == [ServedTick(30, ["v30"])]  # the force stream is released
    assert awaited.tick(40) == []  # the twist stream is not
    assert awaited.awaited_streams() == [TWIST]
    assert watchdog.running
    assert awaited.push(40, "f40", moving=True, stream=FORCE) == []  # not awaited: no restart
    assert watchdog.resets == 3
    assert awaited.push(40, "v40", moving=True, stream=TWIST) == [ServedTick(40, ["v40", "f40"])]


def test_streams_are_named_once_each_and_a_single_stream_is_the_default():
    assert list(AwaitedTicks(FakeWatchdog()).schedules) == [COMMANDS]
    awaited = AwaitedTicks(FakeWatchdog(), streams=(TWIST, FORCE))
    assert awaited.schedule is awaited.schedules[TWIST]
    with pytest.raises(KeyError):
        awaited.push(10, "x", moving=True, stream="joy")
    for streams in ((), (TWIST, TWIST)):
        with pytest.raises(ConfigError, match="streams"):
            AwaitedTicks(FakeWatchdog(), streams=streams)


@given(
    gaps=st.lists(st.integers(1, 40), min_size=1, max_size=40),
    leads=st.lists(st.integers(0, 60), min_size=40, max_size=40),
    interleave=st.lists(st.booleans(), min_size=80, max_size=80),
    period=st.integers(1, 30),
)
def test_two_streams_every_served_tick_has_the_newest_command_of_each_stamped_before_it(
    gaps, leads, interleave, period
):
    """One operator publishes a twist and a force setpoint per sample, each on its own topic:
    each topic's messages arrive in stamp order, but how the two topics interleave is drawn at
    random (one may run samples ahead of the other). Once each stream has a command (stamped
    0 here, before the first tick: a stream that has sent nothing is not waited for), each
    served tick gets, on both streams, the newest command stamped at or before it, whatever
    the arrivals."""
    stamps = [int(stamp) for stamp in np.cumsum(gaps)]
    # the instant of the operator's clock each sample goes out at, in stamp order
    published = np.maximum.accumulate(
        [stamp - lead for stamp, lead in zip(stamps, leads, strict=False)]
    ).tolist()
    pending = {TWIST: list(zip(published, stamps, strict=True)), FORCE: []}
    pending[FORCE] = list(pending[TWIST])
    arrivals = []  # (published at, stream, stamp), in the order they reach the controller
    for twist_next in interleave:
        stream = TWIST if twist_next else FORCE
        if not pending[stream]:
            stream = FORCE if stream == TWIST else TWIST
        if pending[stream]:
            arrivals.append((pending[stream][0][0], stream, pending[stream].pop(0)[1]))
    arrivals += [
        (when, stream, stamp) for stream in (TWIST, FORCE) for when, stamp in pending[stream]
    ]
    awaited = AwaitedTicks(FakeWatchdog(), streams=(TWIST, FORCE))
    for stream in (TWIST, FORCE):
        awaited.push(0, (stream, 0), moving=True, stream=stream)
    stamps.insert(0, 0)
    served: list[ServedTick] = []
    k = 0

    def deliver() -> None:
        nonlocal k
        _, stream, stamp = arrivals[k]
        served.extend(awaited.push(stamp, (stream, stamp), moving=True, stream=stream))
        k += 1

    ticks = list(range(0, stamps[-1] + 2 * period, period))
    for tick in ticks:
        while k < len(arrivals) and arrivals[k][0] <= tick:
            deliver()  # what the operator published before the clock reached the tick
        served.extend(awaited.tick(tick))
        while awaited.oldest_waiting is not None:  # the tick waits: messages still come in
            if k == len(arrivals):
                served.extend(awaited.give_up())  # the streams ended (the watchdog's alarm)
                break
            deliver()
    assert [tick.instant for tick in served] == ticks
    in_force = {TWIST: None, FORCE: None}
    for tick in served:
        for stream, stamp in tick.commands:
            in_force[stream] = stamp
        expected = max((stamp for stamp in stamps if stamp <= tick.instant), default=None)
        assert in_force == {TWIST: expected, FORCE: expected}


# --- CommandSchedule: twists stamped ahead, released at their stamps -------------------------


def test_a_schedule_releases_each_command_at_its_stamp_and_waits_for_the_next_one():
    schedule = CommandSchedule()
    assert schedule.ready(10)  # no stream: nothing to wait for
    assert schedule.due(10) == []
    schedule.push(0, "zero", moving=False)
    schedule.push(20, "a", moving=True)
    schedule.push(40, "b", moving=True)
    assert schedule.ready(10)
    assert schedule.due(10) == ["zero"]
    assert schedule.ready(30)
    assert schedule.due(30) == ["a"]
    assert schedule.ready(40)
    assert schedule.due(40) == ["b"]
    # b asks for motion and nothing stamped at or after 50 came: the command in force is unknown
    assert not schedule.ready(50)
    schedule.push(60, "c", moving=True)
    assert schedule.ready(50)  # b is still in force at 50
    assert schedule.due(50) == []


def test_a_schedule_waits_on_a_resting_start_but_not_on_a_stop_and_can_give_up_waiting():
    schedule = CommandSchedule()
    schedule.push(0, "rest", moving=False)  # a profile starts at rest: its next sample matters
    assert not schedule.ready(10)
    schedule.push(10, "a", moving=True)
    assert not schedule.ready(20)
    schedule.release_all()  # the stream stalled or ended: serve with what there is
    assert schedule.ready(20)
    assert schedule.ready(1000)
    schedule.push(20, "b", moving=True)  # a newer command: waiting resumes
    assert not schedule.ready(30)
    schedule.push(40, "stop", moving=False)
    assert schedule.ready(10**9)  # the operator's stream may end on a stop


def test_a_command_stamped_back_replaces_the_waiting_ones():
    schedule = CommandSchedule()
    for stamp in (100, 120, 140):
        schedule.push(stamp, stamp, moving=True)
    schedule.push(90, "final stop", moving=False)  # e.g. an operator stopped, stamped now
    assert schedule.newest == 90
    assert schedule.due(200) == ["final stop"]


def test_a_schedule_holds_at_most_max_waiting_commands():
    schedule = CommandSchedule(max_waiting=3)
    for stamp in range(5):  # e.g. a publisher stamping years ahead
        schedule.push(10**18 + stamp, stamp, moving=True)
    assert schedule.dropped == 2
    assert schedule.due(10**19) == [2, 3, 4]
    with pytest.raises(ConfigError, match="max_waiting"):
        CommandSchedule(max_waiting=0)


@given(
    gaps=st.lists(st.integers(1, 40), min_size=1, max_size=40),
    leads=st.lists(st.integers(0, 60), min_size=40, max_size=40),
    period=st.integers(1, 30),
)
def test_a_ready_tick_always_serves_the_newest_command_stamped_before_it(gaps, leads, period):
    """Commands stamped on any increasing grid, each published any time before its stamp up to
    a lead (an operator's process that gets the core late publishes late), ticks on another
    grid: whenever a tick is ready, the command in force is the newest stamped at or before it,
    whatever the arrival times."""
    stamps = list(np.cumsum(gaps))
    # one publisher: commands go out in stamp order, each no earlier than the one before
    published = np.maximum.accumulate(
        [stamp - lead for stamp, lead in zip(stamps, leads, strict=False)]
    )
    arrivals = list(zip(published.tolist(), stamps, strict=True))
    schedule, in_force, k = CommandSchedule(), None, 0
    for tick in range(0, stamps[-1] + 2 * period, period):
        while k < len(arrivals) and arrivals[k][0] <= tick:
            schedule.push(arrivals[k][1], arrivals[k][1], moving=True)
            k += 1
        while not schedule.ready(tick):  # the tick waits for the next command to arrive
            if k == len(arrivals):
                schedule.release_all()  # the stream ended (a controller's wait times out)
                break
            schedule.push(arrivals[k][1], arrivals[k][1], moving=True)
            k += 1
        released = schedule.due(tick)
        if released:
            in_force = released[-1]
        expected = max((s for s in stamps if s <= tick), default=None)
        assert in_force == expected


# --- TickLateness: the hold told is the time to the next call plus the mean lateness ---------


def test_on_time_calls_are_told_the_time_to_the_next_call():
    lateness = TickLateness(PERIOD)
    for _ in range(50):
        assert lateness.hold(10 * MS) == pytest.approx(0.010)
    assert lateness.hold(3 * MS) == pytest.approx(0.003 + 0.05 * 0.007)  # this call 7 ms late


def test_calls_late_by_4_ms_are_told_holds_4_ms_longer_once_the_mean_has_settled():
    lateness = TickLateness(PERIOD, smoothing=0.05)
    holds = [lateness.hold(6 * MS) for _ in range(200)]
    assert holds[0] == pytest.approx(0.006 + 0.05 * 0.004)
    assert holds[-1] == pytest.approx(0.010, abs=1e-6)  # 6 ms to the grid + 4 ms late
    assert np.all(np.diff(holds) > 0.0)


def test_a_call_later_than_a_period_counts_as_one_period_late_and_off_grid_is_none():
    lateness = TickLateness(PERIOD, smoothing=1.0)
    assert lateness.hold(14 * MS) == pytest.approx(0.014)  # past its grid point: not late
    assert lateness.hold(None) is None  # a cancelled timer
    assert lateness.hold(16 * MS) is None  # off its grid
    assert lateness.mean == 0.0


@pytest.mark.parametrize(
    ("period", "smoothing", "message"),
    [(0.0, 0.05, "tick period"), (PERIOD, 0.0, "smoothing"), (PERIOD, 1.5, "smoothing")],
)
def test_tick_lateness_rejects_bad_settings(period, smoothing, message):
    with pytest.raises(ConfigError, match=message):
        TickLateness(period, smoothing)
