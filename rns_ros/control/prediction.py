"""Where the joints will be when the next output takes effect.

A sampled controller evaluates the law for the configuration theta_s of its newest joint state,
stamped t_s, but the output it computes at t_k only starts to act on the plant at a_k > t_k: the
command travels over DDS (latency l) and then waits for the plant's next update. A plant that
updates every p seconds on a grid through its state stamps (rns_simulator: every 1 ms step;
ros2_control: every update) acts on it at

    a_k = t_s + p * ceil((t_k + l - t_s) / p)        (p = 0: a_k = t_k + l).

The midpoint hold of :mod:`rns_ros.control.controller` is reactionless to second order only
when the hold starts where the law assumed; starting at a_k instead of t_k shifts the evaluation
point by (a_k - t_k) theta_dot and leaves a first-order residue of 2 (a_k - t_k) / T of the naive
hold's error (T = period); predicting a_k removes it (magnitudes:
:mod:`rns_ros.analysis.delayed_loop`, docs/controller.md).

Between t_s and a_k the plant runs at the rate it had at t_s until the first of the controller's
own outputs published after t_s takes effect, then at each later output from its acting time on:

    theta(a_k) = theta_s + integral_{t_s}^{a_k} theta_dot_applied(tau) dtau.

A plant that ends each output at rest after a horizon h (a streamed JointTrajectory: 2 T; the
position interface: T) holds still from a + h on when the next output is late; the rate
measured at t_s ends at t_s + h at the latest.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

#: Slack of the update-grid rounding [s]: an arrival this close after a grid point counts as
#: on it (stamps and clocks are nanosecond integers, their sums carry float rounding).
GRID_SLACK = 1e-9


class PublishedOutput(NamedTuple):
    """One joint-velocity output as the controller published it.

    Attributes:
        time: publish time on the node clock [s].
        velocity: theta_dot commanded [rad/s], shape (n,), model joint order.
    """

    time: float
    velocity: np.ndarray


class OutputTiming(NamedTuple):
    """How the plant takes an output.

    Attributes:
        latency: publish to receipt by the plant, l [s], >= 0.
        plant_period: the plant's update period p [s], >= 0; 0: it acts on receipt.
        horizon: h, how long one output acts without a newer one before the plant holds
            still [s], > 0; inf: until the next one.
    """

    latency: float = 0.0
    plant_period: float = 0.0
    horizon: float = math.inf

    def acting_time(self, published: float, grid_origin: float) -> float:
        """a = first plant update at or after ``published`` + latency, on the update grid
        through ``grid_origin`` (a state stamp) [s]."""
        arrival = published + self.latency
        if self.plant_period <= 0.0:
            return arrival
        steps = math.ceil((arrival - grid_origin) / self.plant_period - GRID_SLACK)
        return grid_origin + steps * self.plant_period


class Prediction(NamedTuple):
    """Attributes: theta: joint angles when the output acts [rad], (n,); acting_time: a [s]."""

    theta: np.ndarray
    acting_time: float


def predict_joint_angles(
    theta: np.ndarray,
    rate: np.ndarray,
    stamp: float,
    now: float,
    outputs: Sequence[PublishedOutput],
    timing: OutputTiming,
) -> Prediction:
    """Joint angles when an output published at ``now`` takes effect.

    Args:
        theta: measured joint angles at ``stamp`` [rad], shape (n,).
        rate: measured joint rates at ``stamp`` [rad/s], shape (n,): what the plant ran at then.
        stamp, now: sample time and publish time, one clock [s]; ``now`` >= ``stamp``.
        outputs: the controller's recent outputs, oldest first. Those acting before ``stamp``
            are already in ``rate``; one acting at the stamp itself is not (a plant publishes
            the rate it ran at up to the stamp: rns_simulator's state at a lockstep pause
            comes before the next output), and if it were, replacing the rate by the same
            velocity from the stamp on changes nothing.
        timing: latency and update grid of the plant (the grid runs through ``stamp``).

    Returns:
        theta at the acting time a of eq. (module docstring), and a.
    """
    target = timing.acting_time(now, stamp)
    # newest first, back to the last output already acting at the stamp (``rate`` shows it)
    later = []
    for output in reversed(outputs):
        starts = timing.acting_time(output.time, stamp)
        if starts < stamp - GRID_SLACK:
            break
        if starts < target:
            later.append((starts, output.velocity))
    predicted = np.array(theta, dtype=float)
    velocity = np.asarray(rate, dtype=float)
    since = stamp
    for starts, output_velocity in reversed(later):
        predicted += max(min(starts, since + timing.horizon) - since, 0.0) * velocity
        velocity, since = output_velocity, starts
    predicted += max(min(target, since + timing.horizon) - since, 0.0) * velocity
    return Prediction(predicted, target)


__all__ = ["OutputTiming", "Prediction", "PublishedOutput", "predict_joint_angles"]
