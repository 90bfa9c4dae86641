"""Chapter 3, §3.2.2: the fixed points of the planar reactionless field versus the attachment
distance r (two are created at r* ≈ 0.945 m and separate towards θ2 → 0 and ±π), from
:mod:`rns_ros.analysis.planar_field` (closed form). Registers ``sec3.2.2``, the bifurcation claim
of §3.2.2.
"""

from __future__ import annotations

import numpy as np

from rns_ros.analysis.planar_field import (
    critical_distance,
    fixed_point_curve,
    fixed_points,
)
from rns_ros.analysis.reproduce.chapter3 import (
    ARM,
    CHOICES,
    THETA1_LABEL,
    THETA2_LABEL,
    created_row,
    model_settings,
    points_json,
    r_star_row,
)
from rns_ros.analysis.reproduce.registry import Comparison, Outcome, Reproduction, register_all

# --- bifurcation ------------------------------------------------------------------------------
BIFURCATION_DISTANCES = (0.946, 0.95, 1.0, 1.5, 3.0, 10.0, 100.0)


def compute_bifurcation(quick: bool) -> Outcome:
    """r* and the fixed points above it; the whole branch from the closed-form curve ρ(θ2)."""
    critical = critical_distance(ARM)
    records = []
    for r in BIFURCATION_DISTANCES:
        records += points_json(fixed_points(ARM.at(r)), r)
    curve_n = 400 if quick else 4000
    s = np.linspace(1e-3, np.pi - 1e-3, curve_n)
    rho, theta1 = fixed_point_curve(ARM, s)
    counts = {r: sum(p["r_m"] == r for p in records) for r in BIFURCATION_DISTANCES}
    above = ", ".join(f"{counts[r]} at {r:g} m" for r in BIFURCATION_DISTANCES)
    comparisons = (
        r_star_row(critical),
        created_row(
            critical,
            f"above r*: {above}; the thesis does not state the total above r*",
            key="fixed_points_created",
        ),
        _limit_row(records),
    )
    values = {
        "r_star_m": critical.r_star,
        "r_star_theta_rad": critical.theta.tolist(),
        "fixed_point_counts": {f"{r:g}": counts[r] for r in BIFURCATION_DISTANCES},
        "fixed_points": records,
    }
    settings = {
        **model_settings(),
        "r_values_m": list(BIFURCATION_DISTANCES),
        "branch_samples": curve_n,
        "method": "fixed points: roots of ρ(θ2) = r per monotone piece of ρ (brentq) + Newton "
        "polish; r* = min ρ via brentq on dρ²/dθ2",
    }
    choices = (CHOICES["A-1.1"], CHOICES["A-1.3"], CHOICES["A-1.5"], CHOICES["I_i"])
    figure_data = {
        "rho": rho,
        "theta1": theta1,
        "theta2": s,
        "s_star": float(critical.theta[0][1]),
        "r_star": critical.r_star,
        "records": records,
    }
    return Outcome(comparisons, values, settings, choices, figure_data)


#: distance [rad] to θ2 = 0 or ±π within which the fixed points at the largest tabulated r count
#: as at their limit (they approach it like 1/r: ~5e-3 rad at r = 100 m)
LIMIT_TOLERANCE = 0.01


def _limit_row(records) -> Comparison:
    """§3.2.2 'when r → ∞, two of the fixed points converge to θ2 → 0 rad and the rest to θ2 → ±π
    rad': along the tabulated r the lower |θ2| branch falls, the upper one rises, and at the
    largest r two are within :data:`LIMIT_TOLERANCE` of 0 and the rest of π."""
    by_r: dict[float, list[float]] = {}
    for point in records:
        by_r.setdefault(point["r_m"], []).append(abs(point["theta_rad"][1]))
    distances = sorted(by_r)
    low = np.array([min(by_r[r]) for r in distances])
    high = np.array([max(by_r[r]) for r in distances])
    far = sorted(by_r[distances[-1]])
    far_theta1 = sorted(abs(p["theta_rad"][0]) for p in records if p["r_m"] == distances[-1])
    holds = (
        len(far) > 2
        and far[1] < LIMIT_TOLERANCE
        and min(far[2:]) > np.pi - LIMIT_TOLERANCE
        and bool(np.all(np.diff(low) < 0.0) and np.all(np.diff(high) > 0.0))
    )
    return Comparison.trend(
        "limit_theta2_rad",
        "two → θ2 = 0, the rest → θ2 = ±π as r → ∞",
        f"at r = {distances[-1]:g} m: |θ2| = " + ", ".join(f"{v:.4f}" for v in far),
        "rad",
        holds=holds,
        note=f"holds when min |θ2| falls and max |θ2| rises over r = {distances[0]:g}–"
        f"{distances[-1]:g} m and at {distances[-1]:g} m two are within {LIMIT_TOLERANCE:g} rad "
        f"of 0 and the rest of π; also |θ1| = {far_theta1[0]:.4f}–{far_theta1[-1]:.4f} there "
        "(→ π/2)",
    )


def plot_bifurcation(outcome: Outcome, figure) -> None:
    data = outcome.figure_data
    axes = figure.subplots(1, 2, sharex=True)
    rho, theta1, theta2, s_star = data["rho"], data["theta1"], data["theta2"], data["s_star"]
    shown = rho <= 200.0
    branches = (
        (theta2 > s_star, "saddles", "black"),
        (theta2 <= s_star, "nodes → foci", "tab:green"),
    )
    for ax, coordinate, label in (
        (axes[0], theta1, THETA1_LABEL),
        (axes[1], theta2, THETA2_LABEL),
    ):
        for mask, name, colour in branches:
            keep = mask & shown
            ax.plot(rho[keep], coordinate[keep], color=colour, label=name)
            ax.plot(rho[keep], -coordinate[keep], color=colour, linestyle="--")
        for record in data["records"]:
            ax.plot(
                record["r_m"],
                record["theta_rad"][0 if ax is axes[0] else 1],
                marker="o",
                color="tab:red",
                markersize=3,
                linestyle="none",
            )
        ax.axvline(
            data["r_star"], color="gray", linestyle=":", label=f"r* = {data['r_star']:.6f} m"
        )
        for level in (-np.pi, -np.pi / 2, 0.0, np.pi / 2, np.pi):
            ax.axhline(level, color="lightgray", linewidth=0.6, zorder=0)
        ax.set_xscale("log")
        ax.set_xlim(0.9, 200.0)
        ax.set_ylim(-np.pi - 0.2, np.pi + 0.2)
        ax.set_xlabel("attachment distance r [m]")
        ax.set_ylabel(label)
    axes[0].legend(fontsize=7, loc="center right")
    axes[0].set_title("fixed-point θ1 (dashed: mirror images)", fontsize=9)
    axes[1].set_title("fixed-point θ2 (dots: tabulated r)", fontsize=9)


REPRODUCTIONS = register_all(
    Reproduction(
        "sec3.2.2",
        "§3.2.2",
        "fixed points of the reactionless field versus the attachment distance r",
        compute_bifurcation,
        plot_bifurcation,
        (11.0, 5.0),
    ),
)
