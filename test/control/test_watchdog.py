"""ClockWatch: a stopped simulated clock is reported after its timeout of wall time. ClockJumps:
a clock that goes back, jumps forward or has two publishers is not trusted until it runs
forward from one publisher again."""

from __future__ import annotations

import math

import pytest

from rns_ros.control.watchdog import CLOCK_SETTLE, ClockJumps, ClockWatch
from rns_ros.core import ConfigError


class WallClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_a_clock_that_stands_still_is_reported_after_the_timeout_only():
    wall = WallClock()
    watch = ClockWatch(1.0, wall)
    assert watch.check(0) is None  # no /clock yet
    wall.now += 5.0
    assert watch.check(0) is None  # never moved: a node waiting for its simulator
    assert watch.check(10_000_000) is None  # moved at wall 105
    wall.now += 0.9
    assert watch.check(10_000_000) is None
    wall.now += 0.2
    assert watch.check(10_000_000) == pytest.approx(1.1)
    assert watch.check(20_000_000) is None  # moves again
    wall.now += 0.5
    assert watch.check(20_000_000) is None


def test_a_clock_that_goes_back_has_moved():
    wall = WallClock()
    watch = ClockWatch(0.5, wall)
    watch.check(0)
    watch.check(5_000_000_000)
    wall.now += 0.6
    assert watch.check(1_000_000) is None  # a reset: /clock is alive


@pytest.mark.parametrize("timeout", [0.0, -1.0, math.nan, math.inf])
def test_the_timeout_must_be_finite_and_positive(timeout):
    with pytest.raises(ConfigError, match="clock timeout"):
        ClockWatch(timeout)


S = 1_000_000_000  # nanoseconds per second
SETTLE = round(CLOCK_SETTLE * S)


def test_the_first_reading_is_not_judged_and_steps_up_to_max_jump_are_normal():
    jumps = ClockJumps(max_jump=1.0)
    assert not jumps.jump(0, 10**6 * S)  # the first /clock: from 0 to wherever it starts
    assert not jumps.jump(10**6 * S, 10**6 * S + S)  # exactly max_jump
    assert jumps.fault(10**6 * S + S) is None


def test_a_forward_jump_is_a_fault_until_the_clock_has_run_on_past_it():
    jumps = ClockJumps(max_jump=1.0)
    jumps.jump(0, 5 * S)
    jumps.publishers(["/rns_simulator"])
    far = 5 * S + 10**6 * S
    assert jumps.jump(5 * S, far)
    fault = jumps.fault(far)
    assert "/clock jumped 1e+06 s forward" in fault
    assert "max_clock_jump 1 s" in fault
    assert "/clock published by /rns_simulator" in fault
    assert jumps.fault(far + SETTLE) is not None
    assert jumps.fault(far + SETTLE + 1) is None  # it ran on from there: trusted again


def test_a_clock_that_goes_back_is_a_fault_until_it_has_run_forward_again():
    jumps = ClockJumps(max_jump=1.0)
    jumps.jump(0, 5 * S)
    assert jumps.jump(5 * S, 1_800_000_000)  # a reset, or a second publisher behind
    assert "/clock jumped back 3.2 s (from 5.000 s to 1.800 s" in jumps.fault(1_800_000_000)
    assert jumps.fault(1_800_000_000 + SETTLE // 2) is not None
    # a stranger's reading in between begins the fault anew
    assert jumps.jump(1_800_000_000 + SETTLE // 2, 900 * S)
    assert jumps.jump(900 * S, 1_800_000_000 + SETTLE)
    assert jumps.fault(1_800_000_000 + 2 * SETTLE) is not None
    assert jumps.fault(1_800_000_000 + 2 * SETTLE + 1) is None


def test_two_publishers_are_a_fault_naming_them_until_one_is_left():
    jumps = ClockJumps()
    jumps.publishers(["/rns_simulator", "/stranger"])
    fault = jumps.fault(S)
    assert fault.startswith("2 publishers on /clock (/rns_simulator, /stranger)")
    jumps.jump(S, 10**6 * S)
    assert "jumped" in jumps.fault(10**6 * S)
    jumps.publishers(["/rns_simulator"])
    assert jumps.fault(10**6 * S + SETTLE + 1) is None


@pytest.mark.parametrize("max_jump", [0.0, -1.0, math.nan, math.inf])
def test_max_clock_jump_must_be_finite_and_positive(max_jump):
    with pytest.raises(ConfigError, match="max_clock_jump"):
        ClockJumps(max_jump)
