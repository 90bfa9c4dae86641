"""Windows of a recorded closed-loop trace (:class:`~rns_ros.analysis.reproduce.scenario_runs.
Trace`) for the singularity figures (§4.3): stated time windows, the passes through
sigma_min < epsilon, peaks and accelerations inside them, and the notes that describe a burst."""

from __future__ import annotations

import numpy as np

from rns_ros.analysis.reproduce.scenario_runs import Trace
from rns_ros.core.errors import ConfigError


def intervals(t: np.ndarray, inside: np.ndarray) -> list[list[float]]:
    """[[start, end], ...] of the runs of True in ``inside`` sampled at ``t`` [s]."""
    return [[round(float(t[a]), 4), round(float(t[b - 1]), 4)] for a, b in runs_of(inside)]


def runs_of(inside: np.ndarray) -> list[tuple[int, int]]:
    """[(a, b), ...]: the index ranges [a, b) of the runs of True in ``inside``."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], inside.astype(int), [0]))))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def first_pass(trace: Trace, epsilon: float) -> slice:
    """The periods of the run's first pass through the singular region sigma_min < epsilon
    (eq. 4.12); the whole run if it never enters."""
    runs = runs_of(trace.sigma_min < epsilon)
    return slice(*runs[0]) if runs else slice(0, len(trace.t_mid))


#: Rounding allowance on a window's ends [s]: mid-period times are sums of float periods, so a
#: period whose mid-time is printed as the window's end may sit a few ulp beyond it.
TIME_ROUNDING_S = 1e-9


def time_window(trace: Trace, window_s: tuple[float, float]) -> slice:
    """The periods whose mid-time lies in ``window_s`` = (start, end) [s], both ends included:
    an analysis window stated before the run (the thesis' region, a figure's time axis).

    Raises:
        ConfigError: no period of the trace lies in the window.
    """
    low, high = window_s
    start = int(np.searchsorted(trace.t_mid, low - TIME_ROUNDING_S, side="left"))
    stop = int(np.searchsorted(trace.t_mid, high + TIME_ROUNDING_S, side="right"))
    if stop <= start:
        raise ConfigError(f"no control period lies in the analysis window {low:g}-{high:g} s")
    return slice(start, stop)


def acceleration(trace: Trace) -> np.ndarray:
    """max_i |theta_dot_i(k+1) - theta_dot_i(k)| / T between consecutive periods [rad/s^2]."""
    dt = np.diff(trace.t_mid)
    return (np.abs(np.diff(trace.theta_dot, axis=0)) / dt[:, None]).max(axis=1)


def mean_singular_ratio(determinants: np.ndarray, k: int) -> float:
    """(det_k / det_0)^(1/6): how far the geometric mean of the three singular values of a
    3-row matrix A moved from the start, det(A A^T) being the product of their squares."""
    return float((determinants[k] / determinants[0]) ** (1.0 / 6.0))


# --------------------------------------------------------------------------- Figs. 4.6-4.8


def pass_note(trace: Trace, window: slice) -> str:
    """'first pass a-b s' of ``window`` [s]."""
    return f"first pass {trace.t_mid[window.start]:.3f}-{trace.t_mid[window.stop - 1]:.3f} s"


def peak(trace: Trace, window: slice) -> dict:
    """The largest |theta_dot_i| within ``window``: ``peak_rad_s`` [rad/s], ``time_s`` [s], the
    two fastest joints of that period (1-based) and their rates [rad/s], ``window_s`` [s]."""
    rates = np.abs(trace.theta_dot[window]).max(axis=1)
    k = (window.start or 0) + int(np.argmax(rates))
    joints = sorted(int(i) + 1 for i in np.argsort(np.abs(trace.theta_dot[k]))[-2:])
    return {
        "peak_rad_s": float(rates.max()),
        "time_s": float(trace.t_mid[k]),
        "fastest_joints": joints,
        "their_rates_rad_s": [float(trace.theta_dot[k, j - 1]) for j in joints],
        "sigma_min": float(trace.sigma_min[k]),
        "window_s": [float(trace.t_mid[window][0]), float(trace.t_mid[window][-1])],
    }


def deepest_pass(trace: Trace, epsilon: float) -> slice:
    """The pass through sigma_min < epsilon holding the run's smallest sigma_min."""
    deepest = int(np.argmin(trace.sigma_min))
    for a, b in runs_of(trace.sigma_min < epsilon):
        if a <= deepest < b:
            return slice(a, b)
    return slice(deepest, deepest + 1)


def task_bound(trace: Trace, k: int) -> float:
    """Upper bound of the task part of the command at period k [rad/s]: |omega_ref| s /
    sigma_min, s the speed scale (SC's b sigma_1 sigma_2 sigma_3, 1 for pinv and DLS), since the
    pinv, DLS (eq. 4.11) and SC (eq. 4.13) inverses have a 2-norm of at most s / sigma_min.
    The rest of |theta_dot| comes from the null-space wrist term (4.6)."""
    speed = float(np.linalg.norm(trace.omega_ref[k]))
    return speed * float(trace.speed_scale[k]) / float(trace.sigma_min[k])


def burst_note(trace: Trace, k: int, wrist_gain: float) -> str:
    """What the command at period k is made of: its size against the task bound, and the wrist
    drift the period before and 0.1 s after it."""
    before = max(k - 1, 0)
    after = min(int(np.searchsorted(trace.t_mid, trace.t_mid[k] + 0.1)), len(trace.t_mid) - 1)
    return (
        f"|theta_dot| = {np.linalg.norm(trace.theta_dot[k]):.1f} rad/s at sigma_min "
        f"{trace.sigma_min[k]:.3f}, where the task part is at most "
        f"{task_bound(trace, k):.2f} rad/s: the rest is the wrist term (k_g = {wrist_gain:g}) "
        f"pulling the wrist back (drift {trace.wrist_drift[before]:.2f} m the period before, "
        f"{trace.wrist_drift[after]:.2f} m 0.1 s later)"
    )


def joint_text(peak: dict) -> str:
    (i, j), (a, b) = peak["fastest_joints"], peak["their_rates_rad_s"]
    return (
        f"{peak['peak_rad_s']:.3g} rad/s at {peak['time_s']:.3f} s on joints {i} and {j} "
        f"({a:+.2f}, {b:+.2f} rad/s)"
    )
