"""Drawing shared by the reproductions: the headless figure, axes set-up, time-series panels and
labelled series, and the closed-loop trace panels of Figs. 4.4-4.8.

Chapter modules draw on the matplotlib ``Figure`` that :func:`save_figure` hands them; every
helper here takes an ``Axes`` and arrays (or a recorded run) and draws one thing.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

#: Floor for deviations, errors and energies that can be exactly zero (log scales, ratios).
FLOOR = 1e-12
#: Resolution of the written PNG [dots per inch].
DPI = 110
#: Title font size of a panel [pt].
TITLE_SIZE = 9
#: Joint velocity label for :func:`joint_lines`, the joint number as subscript.
THETA_DOT_LABEL = r"$\dot\theta_{}$"

_METHOD_COLORS = {"dls": "C0", "conventional": "C3", "pinv": "C4", "sc": "C1"}
_AXIS_NAMES = ("x", "y", "z")


# --------------------------------------------------------------------------- figure


def save_figure(path: Path, size: tuple[float, float], title: str, draw: Callable) -> None:
    """Draw ``draw(figure)`` on a headless figure of ``size`` [in] titled ``title``; write PNG."""
    import matplotlib

    matplotlib.use("Agg")  # headless: no display is needed or used
    from matplotlib.figure import Figure

    figure = Figure(figsize=size, layout="constrained")
    draw(figure)
    figure.suptitle(title, fontsize=10)
    figure.savefig(path, dpi=DPI)


# --------------------------------------------------------------------------- axes


def label_axes(ax, xlabel: str | None, ylabel: str, title: str | None = None) -> None:
    """Axis labels (no x label when None: a shared axis), and the panel title at
    :data:`TITLE_SIZE` when given."""
    if xlabel is not None:
        ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title, fontsize=TITLE_SIZE)


def time_axes(ax, ylabel: str, title: str | None = None) -> None:
    """A panel against time t [s]."""
    label_axes(ax, "t [s]", ylabel, title)


def event_lines(ax, times: Iterable[float], alpha: float = 0.7) -> None:
    """Dashed vertical lines at ``times`` [s] (phase ends, singular-region edges)."""
    for x in times:
        ax.axvline(x, color="k", lw=0.8, ls="--", alpha=alpha)


def legend_grid(ax, **legend) -> None:
    """Small legend (``fontsize`` 7 unless given) and a light grid."""
    ax.legend(**{"fontsize": 7, **legend})
    ax.grid(alpha=0.3)


# --------------------------------------------------------------------------- series


def floored(values: np.ndarray, floor: float = FLOOR) -> np.ndarray:
    """``values`` raised to ``floor`` so that zeros can be drawn on a log scale."""
    return np.maximum(values, floor)


def joint_lines(ax, t: np.ndarray, rates: np.ndarray, label: str = "joint {}", **style) -> None:
    """One line per joint (column of ``rates``, shape (N, n)), labelled ``label.format(i)``
    with the joint number i = 1..n."""
    for i in range(rates.shape[1]):
        ax.plot(t, rates[:, i], label=label.format(i + 1), **style)


# --------------------------------------------------------------------------- closed-loop traces


def method_color(label: str) -> str:
    """Colour of a run labelled by its control method (``dls``, ``conventional``, ...)."""
    return _METHOD_COLORS.get(label, "C2")


def method_name(run) -> str:
    """Legend name of a recorded run: its method, with k_g for the reactionless ones."""
    method = run.settings["method"]
    if method == "conventional":
        return "conventional (4.7-4.8)"
    return f"{method} (k_g = {run.wrist_gain:g})"


def trace_joint_velocities(ax, run, lines=()) -> None:
    """Commanded joint velocities theta_dot [rad/s] of one run."""
    joint_lines(ax, run.trace.t_mid, run.trace.theta_dot, lw=1.0)
    event_lines(ax, lines)
    time_axes(ax, r"$\dot\theta$ [rad/s]", f"joint velocities, {method_name(run)}")
    ax.legend(fontsize=6, ncol=4, loc="best")


def trace_base_deviation(ax, runs, lines=(), allowance: float | None = None) -> None:
    """Geodesic base attitude deviation [deg] of each run, log scale, with the ETS-VII
    ``allowance`` [deg] as a dotted line when given."""
    for run in runs:
        ax.semilogy(
            run.trace.t_end,
            floored(run.trace.base_deviation_deg),
            color=method_color(run.label),
            label=method_name(run),
        )
    if allowance is not None:
        ax.axhline(allowance, color="k", ls=":", lw=1, label="ETS-VII allowance")
    event_lines(ax, lines)
    time_axes(ax, "deviation [deg]", "base attitude deviation (geodesic angle)")
    ax.legend(fontsize=6)


def trace_angular_velocity(ax, runs, lines=()) -> None:
    """Achieved camera angular velocity per axis [rad/s], one line style per run, against the
    commanded one (dashed black)."""
    first = runs[0].trace
    for j in range(3):
        ax.plot(first.t_mid, first.omega_ref[:, j], color="k", ls="--", lw=1.0, zorder=3)
    styles = ("-", ":", "-.")
    for run, style in zip(runs, styles[: len(runs)], strict=True):
        for j in range(3):
            ax.plot(
                run.trace.t_mid,
                run.trace.omega_achieved[:, j],
                color=f"C{j}",
                ls=style,
                lw=1.2,
                label=f"{_AXIS_NAMES[j]}, {method_name(run)}",
            )
    ax.plot([], [], color="k", ls="--", label="commanded")
    event_lines(ax, lines)
    title = "end-effector angular velocity: achieved vs commanded"
    time_axes(ax, r"$\omega_e$ [rad/s]", title)
    ax.legend(fontsize=6, ncol=2)


def trace_angular_velocity_error(ax, runs, lines=(), axis_error=False) -> None:
    """|omega_achieved - omega_ref| [rad/s], log scale; with ``axis_error`` also the angle
    between achieved and commanded rotation axis [deg] on a twin axis."""
    for run in runs:
        ax.semilogy(
            run.trace.t_mid,
            floored(run.trace.omega_error),
            color=method_color(run.label),
            label=method_name(run),
        )
    event_lines(ax, lines)
    title = r"angular velocity error $|\omega_e - \omega_e^{ref}|$"
    time_axes(ax, "error [rad/s]", title)
    if axis_error:
        twin = ax.twinx()
        for run in runs:
            twin.plot(
                run.trace.t_mid, run.trace.axis_error_deg, color="C7", lw=0.8, label="axis error"
            )
        twin.set_ylabel("rotation-axis error [deg]", color="C7")
        twin.legend(fontsize=6, loc="lower right")
    ax.legend(fontsize=6, loc="upper left")


def trace_wrist_drift(ax, runs) -> None:
    """Wrist drift |p_w - p_w^init| [m] of each run."""
    for run in runs:
        ax.plot(
            run.trace.t_end,
            run.trace.wrist_drift,
            color=method_color(run.label),
            label=method_name(run),
        )
    time_axes(ax, "drift [m]", r"wrist drift $|p_w - p_w^{init}|$")
    ax.legend(fontsize=6)


def _twin_series(ax, t, values, ylabel: str, label: str) -> None:
    twin = ax.twinx()
    twin.plot(t, values, color="C5", label=label)
    twin.set_ylabel(ylabel, color="C5")
    twin.legend(fontsize=6, loc="lower right")


def trace_sigma(ax, runs, lines=(), extra=None) -> None:
    """sigma_min of J-bar (J_W_omega_e for the conventional run) against epsilon; ``extra`` =
    "damping" or "speed" adds the first run's DLS lambda^2 or SC speed factor on a twin axis."""
    for run in runs:
        what = "J_W_omega_e" if run.settings["method"] == "conventional" else "J-bar"
        ax.plot(
            run.trace.t_mid,
            run.trace.sigma_min,
            color=method_color(run.label),
            label=f"{method_name(run)}: {what}",
        )
    epsilon = runs[0].settings["gains"]["epsilon"]
    ax.axhline(epsilon, color="k", ls=":", lw=1, label=rf"$\varepsilon$ = {epsilon:g}")
    event_lines(ax, lines)
    time_axes(ax, r"$\sigma_{min}$ [-]", r"smallest singular value $\sigma_{min}$")
    ax.set_ylim(bottom=0.0)
    trace = runs[0].trace
    if extra == "damping":
        _twin_series(ax, trace.t_mid, trace.damping, r"DLS damping $\lambda^2$ [-]", r"$\lambda^2$")
    elif extra == "speed":
        _twin_series(
            ax, trace.t_mid, trace.speed_scale, "achieved / commanded speed [-]", "speed scale"
        )
    ax.legend(fontsize=6, loc="upper left")


def trace_determinants(ax, run, lines=()) -> None:
    """The three determinants of §4.3.1 of one run, log scale."""
    trace = run.trace
    ax.semilogy(trace.t_mid, trace.det_kinematic, label=r"det($J_{\omega e}J_{\omega e}^T$) [-]")
    ax.semilogy(trace.t_mid, trace.det_algorithmic, label=r"det($\bar J \bar J^T$) [-]")
    ax.semilogy(
        trace.t_mid,
        trace.det_coupling,
        label=r"det($\tilde M_{\omega m}\tilde M_{\omega m}^T$) [(kg m$^2$)$^6$]",
    )
    event_lines(ax, lines)
    time_axes(ax, "determinant [see legend]", "determinants of §4.3.1")
    ax.legend(fontsize=6)
