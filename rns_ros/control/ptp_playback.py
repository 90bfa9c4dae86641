"""Playback of a point-to-point plan (thesis sections 4.4-4.5) that stops, holds and resumes on
the plan's own path.

The plan's clock s [s] advances at the playback rate r in [0, 1] (plan seconds per second), and
the joints follow theta(t) = theta_plan(s(t)), theta_dot(t) = r(t) theta_dot_plan(s(t)). Scaling
r changes the timing only, never the path: in a reactionless phase theta_dot_plan lies in the
kernel of M~_omega_m (eq. 3.3, P_RNS of eq. 3.4), and so does r theta_dot_plan. A phase that is
slowed, held at rest or resumed therefore stays reactionless.

r changes at a constant slope between ticks: it rises to 1 at ``acceleration`` [1/s] while
playing (after a resume), falls to 0 at ``deceleration`` [1/s] on a cancel, and drops to 0 at
once on a hold (a stale input: the arm must stop now). Each tick gives the command to hold over
the next period, theta_dot = r_mid theta_dot_plan(s_mid) at mid-period (the hold correction of
the controller), and s advances by the integral of r over the time that command acted.

Given the measured angles theta_m and their age a, a tick adds the plan's position feedback
(eq. 4.18) on the error e = theta_plan(s_m) - theta_m, s_m the plan clock a seconds before the
tick: a joint state compares with where the plan was when it was measured, so a late one does
not read as a lag. The command is r_mid theta_dot_plan(s_mid) + k e, or in a reactionless
phase (r_mid sigma_dot(s_mid) + k n . e) n (:meth:`PtpPlan.track`), n the unit null vector at
the arm's own place on the path, theta_plan(s_mid - d), d = v . e / |v|^2 the lag along the
tangent v = d theta_plan / ds at s_m: the lag is made up in the reaction null space of the arm
where it is. An offset across the path cannot be (it would turn the base) and is kept; the
null vector is not taken at the measured angles themselves, whose neighbouring reactionless
curve can leave the path near a fold. s advances by what the commands should have played,
and the feedback makes up what a plant late or short on a command did not play. After the
end, :meth:`settle` gives the same feedback towards the plan's last sample.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from rns_ros.control.ptp import PtpPlan
from rns_ros.control.ptp_sampling import PlanSamples
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.validation import Choice, positive


class PlaybackMode(Choice):
    """What the playback does between ticks."""

    __label__ = "playback mode"

    PLAYING = "PLAYING"  # r rises to 1 at ``acceleration`` (stays at 1 once there)
    CANCELLING = "CANCELLING"  # r falls to 0 at ``deceleration``, then CANCELLED
    HOLDING = "HOLDING"  # r = 0 and s frozen: at rest on the path until resume()
    ENDED = "ENDED"  # s reached the plan's end
    CANCELLED = "CANCELLED"  # at rest on the path after a cancel


#: Ticks of plan-clock history kept to place a joint state's age (2.5 s at 100 Hz).
HISTORY_TICKS = 256

#: Plan time searched either side of a held s for the sample nearest the arm [s], and the
#: grid of that search [s] (0.002 rad apart at 0.2 rad/s).
LOCATE_WINDOW = 2.0
LOCATE_STEP = 0.01

#: |d theta_plan / ds|^2 [rad^2/s^2] below which the plan is at rest and a lag along it is
#: not estimated.
MIN_TANGENT_SQUARED = 1e-8

#: Modes in which the joints are at rest (zero velocity).
AT_REST = (PlaybackMode.HOLDING, PlaybackMode.ENDED, PlaybackMode.CANCELLED)


@dataclass(frozen=True)
class PlaybackStep:
    """The command of one tick, held over the period that follows.

    Attributes:
        theta: the plan at s [rad], shape (n,).
        theta_dot: joint velocity [rad/s], shape (n,): r_mid theta_dot_plan(s_mid) at
            mid-period; zero at rest.
        s: plan clock [s].
        rate: playback rate r at the tick [-].
        mode: the playback's mode after the tick.
    """

    theta: np.ndarray
    theta_dot: np.ndarray
    s: float
    rate: float
    mode: PlaybackMode

    @property
    def at_rest(self) -> bool:
        return self.mode in AT_REST


def ramp(rate: float, slope: float, dt: float) -> tuple[float, float]:
    """The playback rate after ``dt`` [s] at ``slope`` [1/s] from ``rate`` [-], clamped to
    [0, 1], and the plan time [s] covered meanwhile (the integral of r over ``dt``)."""
    if slope > 0.0:
        limit = (1.0 - rate) / slope
    elif slope < 0.0:
        limit = rate / -slope
    else:
        limit = math.inf
    ramped = min(dt, max(limit, 0.0))
    after = min(max(rate + slope * ramped, 0.0), 1.0)
    return after, 0.5 * (rate + after) * ramped + after * (dt - ramped)


class PlanPlayback:
    """Plays ``plan`` once per tick at a playback rate (see the module docstring).

    Args:
        plan: the plan to play, from s = 0 at r = 1 (the planners' plans start at rest).
        period: tick period [s] > 0: the command of a tick is held this long.
        acceleration: slope [1/s] > 0 of r after :meth:`resume` (0 to 1 in 1 / acceleration s).
        deceleration: slope [1/s] > 0 of r after :meth:`cancel`.
        velocity_limits: joint speed limits [rad/s] (n,), > 0 (inf: none); a command with the
            feedback is scaled down as a whole to stay within them, so its direction (the
            path's, reactionless) is kept, where a per-joint clip would bend it off the path.
            None: no limits.
    """

    def __init__(
        self,
        plan: PtpPlan,
        period: float,
        acceleration: float,
        deceleration: float,
        velocity_limits=None,
    ) -> None:
        self.plan = plan
        n = plan.start.size
        limits = np.full(n, np.inf) if velocity_limits is None else velocity_limits
        self.velocity_limits = np.asarray(limits, dtype=float)
        if self.velocity_limits.shape != (n,) or not np.all(self.velocity_limits > 0.0):
            raise ConfigError(
                f"velocity_limits must be {n} values > 0 rad/s, got {self.velocity_limits!r}"
            )
        self.period = positive(period, "period", "[s]")
        self.acceleration = positive(acceleration, "acceleration", "[1/s]")
        self.deceleration = positive(deceleration, "deceleration", "[1/s]")
        self.s = 0.0
        self.rate = 1.0
        self.mode = PlaybackMode.PLAYING
        self._slope = 0.0  # slope of r over the period since the last tick [1/s]
        self._time = 0.0  # playback time [s]: the sum of the elapsed times given
        # (playback time [s], s [s]) at the recent ticks, oldest first
        self._history: deque[tuple[float, float]] = deque([(0.0, 0.0)], maxlen=HISTORY_TICKS)

    def tick(self, elapsed: float, theta=None, age: float = 0.0) -> PlaybackStep:
        """The command for the period starting now, ``elapsed`` [s] >= 0 after the last tick
        (0 at the first tick and at the tick of a resume): over ``elapsed`` the last command
        acted, so s advances by the integral of r over it. With the angles ``theta`` [rad] (n,)
        measured ``age`` [s] >= 0 ago, theta_dot adds the plan's position feedback (module
        docstring)."""
        if not (math.isfinite(elapsed) and elapsed >= 0.0):
            raise InputError(f"elapsed must be a finite number >= 0 s, got {elapsed!r}")
        if self.mode in AT_REST:
            return self._at_rest()
        self._advance(elapsed)
        if self.s >= self.plan.duration:
            self.mode = PlaybackMode.ENDED
        elif self.mode is PlaybackMode.CANCELLING and self.rate <= 0.0:
            self.mode = PlaybackMode.CANCELLED
        if self.mode in AT_REST:
            return self._at_rest()
        playing = self.mode is PlaybackMode.PLAYING
        self._slope = self.acceleration if playing else -self.deceleration
        rate_mid, to_mid = ramp(self.rate, self._slope, 0.5 * self.period)
        if theta is None:
            middle = self.plan.sample(min(self.s + to_mid, self.plan.duration))
            theta_dot = rate_mid * np.asarray(middle.theta_dot, dtype=float)
        else:
            theta_dot = self._tracked(self.s + to_mid, rate_mid, theta, self._s_at(age))
        return PlaybackStep(
            theta=self.plan.angles(self.s),
            theta_dot=theta_dot,
            s=self.s,
            rate=self.rate,
            mode=self.mode,
        )

    def cancel(self) -> bool:
        """Slow to rest on the path (PLAYING -> CANCELLING); a held playback ends where it
        stands (HOLDING -> CANCELLED). False when there is nothing to cancel."""
        if self.mode is PlaybackMode.PLAYING:
            self.mode = PlaybackMode.CANCELLING
        elif self.mode is PlaybackMode.HOLDING:
            self.mode = PlaybackMode.CANCELLED
        else:
            return False
        return True

    def hold(self, elapsed: float) -> PlaybackStep:
        """Stop now: s advances by what the last command played over ``elapsed`` [s], then
        r = 0 and s is frozen (HOLDING; a cancelling playback is CANCELLED). The step is at
        rest at the plan's sample at s."""
        if self.mode in (PlaybackMode.PLAYING, PlaybackMode.CANCELLING):
            if not (math.isfinite(elapsed) and elapsed >= 0.0):
                raise InputError(f"elapsed must be a finite number >= 0 s, got {elapsed!r}")
            self._advance(elapsed)
            cancelling = self.mode is PlaybackMode.CANCELLING
            self.mode = PlaybackMode.CANCELLED if cancelling else PlaybackMode.HOLDING
            if self.s >= self.plan.duration:
                self.mode = PlaybackMode.ENDED
        self.rate, self._slope = 0.0, 0.0
        return self._at_rest()

    def path_error(self, theta) -> float:
        """Largest |theta_i - theta_plan,i(s)| [rad] of the measured angles ``theta`` (n,)."""
        reference = self.plan.sample(self.s).theta
        return float(np.abs(self._measured(theta) - reference).max())

    def _s_at(self, age: float) -> float:
        """s [s] ``age`` [s] >= 0 before the last tick, interpolated between ticks (held
        before the oldest kept; a hold leaves s where it stopped)."""
        if not (math.isfinite(age) and age >= 0.0):
            raise InputError(f"age must be a finite number >= 0 s, got {age!r}")
        times, values = zip(*self._history, strict=True)
        return float(np.interp(self._time - age, times, values))

    def settle(self, theta) -> PlaybackStep:
        """After the end (ENDED): the plan's last sample and the position feedback towards it
        [rad/s] (n,) for the measured angles ``theta`` [rad] (n,) (module docstring)."""
        if self.mode is not PlaybackMode.ENDED:
            raise InputError(f"only an ended playback settles, not one {self.mode.value}")
        step = self._at_rest()
        end = self.plan.duration
        return PlaybackStep(step.theta, self._tracked(end, 0.0, theta, end), step.s, 0.0, self.mode)

    def _tracked(self, s_mid: float, rate_mid: float, theta, s_measured: float) -> np.ndarray:
        """The command [rad/s] (n,) at mid-period plan time ``s_mid`` [s] for the angles
        ``theta`` [rad] (n,) measured at plan time ``s_measured`` [s] (module docstring)."""
        s_mid = min(s_mid, self.plan.duration)
        then = self.plan.sample(s_measured)
        error = then.theta - self._measured(theta)
        # the arm's own place on the path: the lag along the tangent v = d theta_plan / ds
        tangent = then.theta_dot
        squared = float(tangent @ tangent)
        lag = float(tangent @ error) / squared if squared > MIN_TANGENT_SQUARED else 0.0
        arm = self.plan.angles(min(max(s_mid - lag, 0.0), self.plan.duration))
        theta_dot = self.plan.track(s_mid, arm, error, rate_mid)
        scale = np.max(np.abs(theta_dot) / self.velocity_limits)
        return theta_dot / scale if scale > 1.0 else theta_dot

    def _measured(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        if theta.shape != self.plan.start.shape:
            raise InputError(f"theta must have shape {self.plan.start.shape}, got {theta.shape}")
        return theta

    def locate(self, theta, window: float = LOCATE_WINDOW) -> float:
        """HOLDING: move s to the plan time within ``window`` [s] of it whose sample is nearest
        the measured ``theta`` [rad] (n,) (on a grid of LOCATE_STEP), so the plan resumes where
        the arm stands on its path rather than making up a lag first. Returns the largest
        |theta_i - theta_plan,i(s)| [rad] there (:meth:`path_error`)."""
        if self.mode is not PlaybackMode.HOLDING:
            raise InputError(f"only a held playback is located, not one {self.mode.value}")
        theta = self._measured(theta)
        times = np.arange(
            max(self.s - window, 0.0), min(self.s + window, self.plan.duration), LOCATE_STEP
        )
        candidates = [self.s, *times.tolist()]
        errors = [float(np.abs(self.plan.angles(t) - theta).max()) for t in candidates]
        self.s = candidates[int(np.argmin(errors))]
        return min(errors)

    def resume(self) -> None:
        """HOLDING -> PLAYING from r = 0: the next tick (``elapsed`` 0) starts the rise of r
        at ``acceleration``; s goes on from where it was held, along the same path."""
        if self.mode is not PlaybackMode.HOLDING:
            raise InputError(f"only a held playback resumes, not one {self.mode.value}")
        self.mode = PlaybackMode.PLAYING
        # the arm stood at s through the hold, which the playback time leaves out
        self._history = deque([(self._time, self.s)], maxlen=HISTORY_TICKS)

    def resumed_samples(self, spacing: float) -> PlanSamples:
        """The rest of the plan from the held s, as played after :meth:`resume`: r rises from
        0 to 1 at ``acceleration`` a, so s(t) = s0 + a t^2 / 2 up to t = 1 / a, then
        s0 + 1 / (2 a) + (t - 1 / a). Samples at most ``spacing`` [s] apart in time, the end of
        the rise and every phase end included (a joint_trajectory_controller's cubic between
        two samples stays in one phase); theta = theta_plan(s(t)),
        theta_dot = r(t) theta_dot_plan(s(t)), the last sample at rest. Times from 0 [s]."""
        spacing = positive(spacing, "spacing", "[s]")
        a, s0, plan = self.acceleration, self.s, self.plan
        if s0 >= plan.duration:
            raise InputError(f"nothing of the plan is left at s = {s0:.6g} s (its end)")
        breaks = [s0 + 0.5 / a] + [p.end for p in plan.phases]
        breaks = sorted({b for b in breaks if s0 < b < plan.duration} | {plan.duration})
        times = [0.0]
        for end in (self._time_at(b) for b in breaks):
            count = max(math.ceil((end - times[-1]) / spacing - 1e-9), 1)
            times.extend(np.linspace(times[-1], end, count + 1)[1:])
        t = np.array(times)
        theta, theta_dot = [], []
        for time in t:
            rate, covered = ramp(0.0, a, time)
            reference = plan.sample(min(s0 + covered, plan.duration))
            theta.append(reference.theta)
            theta_dot.append(rate * np.asarray(reference.theta_dot, dtype=float))
        theta_dot[-1] = np.zeros_like(theta_dot[-1])
        return PlanSamples(t=t, theta=np.array(theta), theta_dot=np.array(theta_dot))

    def _time_at(self, s: float) -> float:
        """Time [s] after a resume at which the plan clock reaches ``s`` (the inverse of
        :meth:`resumed_samples`' s(t))."""
        a, covered = self.acceleration, s - self.s
        if covered <= 0.5 / a:
            return math.sqrt(2.0 * covered / a)
        return covered + 0.5 / a

    def _advance(self, elapsed: float) -> None:
        self.rate, covered = ramp(self.rate, self._slope, elapsed)
        self.s = min(self.s + covered, self.plan.duration)
        self._time += elapsed
        if elapsed > 0.0:
            self._history.append((self._time, self.s))

    def _at_rest(self) -> PlaybackStep:
        theta = np.asarray(self.plan.sample(self.s).theta, dtype=float)
        return PlaybackStep(theta, np.zeros_like(theta), self.s, 0.0, self.mode)
