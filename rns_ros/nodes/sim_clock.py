"""Simulated time as builtin_interfaces/Time: the /clock and header stamps of the simulators."""

from __future__ import annotations

from builtin_interfaces.msg import Time as TimeMsg


def stamp_from_seconds(seconds: float) -> TimeMsg:
    """builtin_interfaces/Time for a simulated time [s], rounded to the nanosecond (so a time
    summed from steps, 1.9999999999 s, is 2 s: the tick a sim-time timer waits for)."""
    sec, nanosec = divmod(round(seconds * 1e9), 1_000_000_000)
    return TimeMsg(sec=int(sec), nanosec=int(nanosec))
