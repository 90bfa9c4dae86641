"""Time scalings s(t) used by the thesis scenarios (section 4.2.2: a fifth-order spline)."""

from __future__ import annotations

from rns_ros.core.validation import positive


def quintic(t: float, duration: float) -> tuple[float, float]:
    """Rest-to-rest quintic s(t) = 10 tau^3 - 15 tau^4 + 6 tau^5, tau = t / T, clamped to [0, 1].

    Returns:
        (s [-], s_dot [1/s]); s_dot peaks at 15 / (8 T) at t = T / 2.
    """
    duration = positive(duration, "duration", "[s]")
    tau = min(max(t / duration, 0.0), 1.0)
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    s_dot = 30.0 * tau**2 * (1.0 - tau) ** 2 / duration
    return s, s_dot
