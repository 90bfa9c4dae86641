"""A :class:`~rns_ros.control.ptp.PtpPlan` as the samples of one multi-point JointTrajectory,
and the cubic a joint_trajectory_controller plays between them.

The samples lie on a uniform grid within each phase, phase ends included (every interpolated
segment stays inside one phase, so a reactionless phase is never blended with a joint-space
one): a phase of length L gets ceil(L / spacing) equal intervals. Each sample carries theta and
theta_dot of the plan; the last one is at rest (theta_dot = 0). Between samples a, b the
controller plays the cubic Hermite polynomial through (theta_a, theta_dot_a) and
(theta_b, theta_dot_b) (joint_trajectory_controller's "splines" with positions and velocities):
it leaves the reaction null space by O(spacing^4) in position, which
:mod:`rns_ros.analysis.ptp_spline_runs` measures as base attitude deviation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rns_ros.control.ptp import PtpPlan
from rns_ros.core.validation import positive


@dataclass(frozen=True)
class PlanSamples:
    """Samples of a plan.

    Attributes:
        t: times from the plan's start [s], shape (k,), strictly increasing, t[0] = 0,
            t[-1] = duration.
        theta: joint angles [rad], shape (k, n).
        theta_dot: joint velocities [rad/s], shape (k, n); the last row is zero.
    """

    t: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray


def sample_times(plan: PtpPlan, spacing: float) -> np.ndarray:
    """Sample times [s] (k,): each phase [start, end] cut into ceil(length / ``spacing``) equal
    intervals (``spacing`` [s] > 0 is the longest interval)."""
    spacing = positive(spacing, "spacing", "[s]")
    times = [0.0]
    for phase in plan.phases:
        length = phase.end - phase.start
        if length <= 0.0:
            continue
        count = max(math.ceil(length / spacing - 1e-9), 1)
        times.extend(phase.start + length * np.arange(1, count + 1) / count)
    return np.array(times)


def sample_plan(plan: PtpPlan, spacing: float) -> PlanSamples:
    """The plan at :func:`sample_times`; a sample on a phase end carries that phase's velocity
    at its end (the phases of the planners start and end at rest)."""
    t = sample_times(plan, spacing)
    references = [plan.sample(time) for time in t]
    theta = np.array([reference.theta for reference in references])
    theta_dot = np.array([reference.theta_dot for reference in references])
    theta_dot[-1] = 0.0
    return PlanSamples(t=t, theta=theta, theta_dot=theta_dot)


def hermite(samples: PlanSamples, time: float) -> tuple[np.ndarray, np.ndarray]:
    """(theta [rad], theta_dot [rad/s]) (n,) of the cubic Hermite interpolation of ``samples``
    at ``time`` [s] (clipped to the samples' span): on [t_a, t_b] with h = t_b - t_a and
    u = (time - t_a) / h,
    theta = h00 theta_a + h10 h theta_dot_a + h01 theta_b + h11 h theta_dot_b,
    h00 = 2u^3 - 3u^2 + 1, h10 = u^3 - 2u^2 + u, h01 = -2u^3 + 3u^2, h11 = u^3 - u^2."""
    t = samples.t
    time = min(max(float(time), t[0]), t[-1])
    b = min(max(int(np.searchsorted(t, time, side="right")), 1), t.size - 1)
    a = b - 1
    h = t[b] - t[a]
    u = (time - t[a]) / h
    pa, pb = samples.theta[a], samples.theta[b]
    va, vb = samples.theta_dot[a], samples.theta_dot[b]
    u2, u3 = u * u, u * u * u
    theta = (
        (2 * u3 - 3 * u2 + 1) * pa
        + (u3 - 2 * u2 + u) * h * va
        + (-2 * u3 + 3 * u2) * pb
        + (u3 - u2) * h * vb
    )
    theta_dot = (
        (6 * u2 - 6 * u) / h * pa
        + (3 * u2 - 4 * u + 1) * va
        + (-6 * u2 + 6 * u) / h * pb
        + (3 * u2 - 2 * u) * vb
    )
    return theta, theta_dot
