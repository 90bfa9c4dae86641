"""stamp_from_seconds: simulated time on /clock and in header stamps."""

from rns_ros.nodes.sim_clock import stamp_from_seconds


def test_clock_stamps_round_to_the_nanosecond():
    """Simulated time summed from 1 ms steps falls a hair short of whole seconds; the stamp is
    the whole second a sim-time timer waits for (not 1.999999999 s)."""
    t = 0.0
    for _ in range(2000):
        t += 0.001
    assert t != 2.0
    assert (stamp_from_seconds(t).sec, stamp_from_seconds(t).nanosec) == (2, 0)
    assert (stamp_from_seconds(0.0305).sec, stamp_from_seconds(0.0305).nanosec) == (0, 30_500_000)
