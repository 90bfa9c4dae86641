"""predict_joint_angles: the joints integrated over a piecewise-constant applied rate."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.control.prediction import OutputTiming, PublishedOutput, predict_joint_angles


def _brute_force(theta, rate, stamp, target, switches):
    """theta integrated on a 1 us grid over the applied rate (switches: (time, velocity))."""
    t = np.arange(stamp, target, 1e-6) + 0.5e-6
    velocity = np.tile(rate, (t.size, 1))
    for time, v in switches:
        velocity[t > time] = v
    return theta + velocity.sum(axis=0) * 1e-6


def test_the_output_acts_at_the_first_plant_update_after_it_arrives():
    timing = OutputTiming(latency=5e-4, plant_period=1e-3)
    # stamp 10.1 ms (a grid point); published at 15.3 ms, arrives 15.8 ms, acts at 16.1 ms
    assert timing.acting_time(0.0153, 0.0101) == pytest.approx(0.0161, abs=1e-12)
    # arriving on a grid point acts there
    assert timing.acting_time(0.0156, 0.0101) == pytest.approx(0.0161, abs=1e-12)
    assert OutputTiming(latency=5e-4).acting_time(0.0153, 0.0101) == pytest.approx(0.0158)


def test_without_outputs_the_measured_rate_runs_until_the_output_acts():
    theta, rate = np.array([0.1, -0.2]), np.array([0.5, 2.0])
    result = predict_joint_angles(
        theta, rate, 1.0101, 1.0153, [], OutputTiming(latency=5e-4, plant_period=1e-3)
    )
    assert result.acting_time == pytest.approx(1.0161)
    np.testing.assert_allclose(result.theta, theta + 0.006 * rate, atol=1e-12)


def test_an_output_published_after_the_stamp_switches_the_rate_where_it_acts():
    theta, rate, new = np.zeros(2), np.array([1.0, 0.0]), np.array([0.0, 3.0])
    timing = OutputTiming(latency=2e-4, plant_period=1e-3)
    old = PublishedOutput(0.0, np.array([9.0, 9.0]))  # acting before the stamp: in ``rate``
    outputs = [old, PublishedOutput(0.0024, new)]  # arrives 2.6 ms, acts at 3 ms
    result = predict_joint_angles(theta, rate, 0.002, 0.0071, outputs, timing)  # acts at 8 ms
    np.testing.assert_allclose(result.theta, [0.001, 0.015], atol=1e-12)


def test_an_output_acting_at_the_stamp_is_not_yet_in_the_measured_rate():
    """Lockstep with output_lead: the state at a pause carries the rate of the period before
    it; the output stamped at that instant (published a period earlier) runs from it."""
    period = 0.01
    timing = OutputTiming(latency=period)  # each output acts one period after its tick
    theta, before, next_ = np.array([0.2, -0.1]), np.array([1.0, 2.0]), np.array([-3.0, 0.5])
    # ticked at 0.99 s: acts at 1.00 s, the stamp of the state sampled for the 1.00 s tick
    outputs = [PublishedOutput(0.98, before), PublishedOutput(0.99, next_)]
    result = predict_joint_angles(theta, before, 1.0, 1.0, outputs, timing)
    assert result.acting_time == pytest.approx(1.01)
    np.testing.assert_allclose(result.theta, theta + period * next_, atol=1e-12)
    # a plant whose state already showed that output predicts the same
    same = predict_joint_angles(theta, next_, 1.0, 1.0, outputs, timing)
    np.testing.assert_allclose(same.theta, result.theta, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    stamp=st.floats(0.0, 1.0),
    age=st.floats(0.0, 0.02),
    latency=st.floats(0.0, 2e-3),
    period=st.sampled_from([0.0, 1e-3, 2e-3]),
    offsets=st.lists(st.floats(-0.01, 0.02), min_size=0, max_size=4),
    seed=st.integers(0, 1000),
)
def test_prediction_is_the_integral_of_the_applied_rate(stamp, age, latency, period, offsets, seed):
    rng = np.random.default_rng(seed)
    timing = OutputTiming(latency, period)
    now = stamp + age
    outputs = [PublishedOutput(stamp + o, rng.normal(size=3)) for o in sorted(offsets)]
    outputs = [o for o in outputs if o.time <= now]
    theta, rate = rng.normal(size=3), rng.normal(size=3)
    result = predict_joint_angles(theta, rate, stamp, now, outputs, timing)
    switches = [
        (timing.acting_time(o.time, stamp), o.velocity)
        for o in outputs
        # from the stamp on: one acting at the stamp is not in ``rate`` (the rate before it)
        if timing.acting_time(o.time, stamp) >= stamp - 1e-9
    ]
    expected = _brute_force(theta, rate, stamp, result.acting_time, switches)
    np.testing.assert_allclose(result.theta, expected, atol=1e-5)
    assert result.acting_time >= now + latency - 1e-9
    assert result.acting_time < now + latency + period + 1e-9


def test_a_plant_that_ends_each_output_at_rest_holds_still_after_its_horizon():
    """A streamed trajectory ends at rest 2 T after it acts: when the next output is late the
    plant stands still, and so does the prediction (the brute-force integral of the applied
    rate, which is zero past each output's end)."""
    theta, rate = np.array([0.3, -0.1]), np.array([0.4, -0.2])
    v1 = np.array([0.5, 0.1])
    horizon = 0.02
    timing = OutputTiming(horizon=horizon)
    outputs = [PublishedOutput(2.005, v1)]
    result = predict_joint_angles(theta, rate, 2.0, 2.090, outputs, timing)
    expected = theta + 0.005 * rate + horizon * v1  # v1 from 2.005 to 2.025, then at rest
    np.testing.assert_allclose(result.theta, expected, atol=1e-12)
    # the measured rate ends too: no output for 90 ms after the stamp
    alone = predict_joint_angles(theta, rate, 2.0, 2.090, [], timing)
    np.testing.assert_allclose(alone.theta, theta + horizon * rate, atol=1e-12)
    # outputs on time: the horizon changes nothing
    on_time = [PublishedOutput(2.005 + 0.01 * k, v1) for k in range(9)]
    held = predict_joint_angles(theta, rate, 2.0, 2.090, on_time, timing)
    free = predict_joint_angles(theta, rate, 2.0, 2.090, on_time, OutputTiming())
    np.testing.assert_allclose(held.theta, free.theta, atol=1e-12)
