"""Time scalings s(t) of the thesis scenarios (section 4.2.2: a fifth-order spline)."""

from __future__ import annotations

from rns_ros.core.validation import positive

#: Peak of the quintic's s_dot times its duration: max s_dot = 15 / (8 T) at t = T / 2 [-].
QUINTIC_PEAK_RATE = 15.0 / 8.0


def quintic_shape(tau: float) -> tuple[float, float, float]:
    """Rest-to-rest quintic s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5, tau clamped to [0, 1].

    Returns:
        (s, ds/dtau, d2s/dtau2) [-].
    """
    tau = min(max(tau, 0.0), 1.0)
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    ds = 30.0 * tau**2 * (1.0 - tau) ** 2
    dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau)
    return s, ds, dds


def quintic_profile(t: float, duration: float) -> tuple[float, float, float]:
    """The quintic at time ``t`` [s] of a rest-to-rest motion of ``duration`` T [s], tau = t / T.

    Returns:
        (s [-], s_dot [1/s], s_ddot [1/s^2]).
    """
    s, ds, dds = quintic_shape(t / duration)
    return s, ds / duration, dds / duration**2


def quintic(t: float, duration: float) -> tuple[float, float]:
    """(s [-], s_dot [1/s]) of :func:`quintic_profile`; s_dot peaks at
    :data:`QUINTIC_PEAK_RATE` / T at t = T / 2.

    Raises:
        ConfigError: ``duration`` not finite and > 0.
    """
    s, s_dot, _ = quintic_profile(t, positive(duration, "duration", "[s]"))
    return s, s_dot
