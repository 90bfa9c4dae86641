"""Plan samples for one multi-point JointTrajectory (rns_ros.control.ptp_sampling)."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.control.ptp_sampling import PlanSamples, hermite, sample_plan, sample_times

START = np.deg2rad([-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0])
GOAL = np.deg2rad([-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0])


@pytest.fixture(scope="module")
def plan(robot):
    return plan_ptp(robot, START, GOAL, "three_phase")


def test_samples_cover_each_phase_evenly_with_its_ends(plan):
    spacing = 0.7
    t = sample_times(plan, spacing)
    assert t[0] == 0.0
    assert t[-1] == pytest.approx(plan.duration)
    assert np.all(np.diff(t) > 0.0)
    assert np.diff(t).max() <= spacing + 1e-12
    for phase in plan.phases:
        assert np.min(np.abs(t - phase.end)) < 1e-12
        inside = np.diff(t[(t >= phase.start - 1e-12) & (t <= phase.end + 1e-12)])
        assert np.ptp(inside) < 1e-9  # equal intervals within a phase
    samples = sample_plan(plan, spacing)
    assert not np.any(samples.theta_dot[-1])
    np.testing.assert_allclose(samples.theta[-1], plan.sample(plan.duration).theta)


def test_hermite_passes_the_samples_and_is_exact_for_a_cubic():
    """Through each sample with its rate; a cubic polynomial sampled anywhere comes back whole
    (the interpolation error is O(h^4) in general)."""
    t = np.array([0.0, 0.3, 1.0, 1.2, 2.0])
    coefficients = np.array([[0.5, -1.0], [1.0, 0.2], [-2.0, 0.7], [0.8, -0.1]])  # (4, n)

    def cubic(x):
        powers = np.array([1.0, x, x * x, x**3])
        rates = np.array([0.0, 1.0, 2 * x, 3 * x * x])
        return powers @ coefficients, rates @ coefficients

    samples = PlanSamples(
        t=t,
        theta=np.array([cubic(x)[0] for x in t]),
        theta_dot=np.array([cubic(x)[1] for x in t]),
    )
    for x in np.linspace(0.0, 2.0, 41):
        theta, theta_dot = hermite(samples, x)
        np.testing.assert_allclose(theta, cubic(x)[0], atol=1e-12)
        np.testing.assert_allclose(theta_dot, cubic(x)[1], atol=1e-11)
