"""Chapter 5, §5.2: how close reactionless motion is to the cheapest motion (Figs. 5.1-5.3).

Each result maps C_ratio of eq. (5.5) (reactionless kinetic energy over the minimum kinetic energy
with reaction wheels holding the base, both for unit joint speed) with
:mod:`rns_ros.analysis.energy_maps`:

* ``fig5.1``: the planar 2-DoF arm at r = 0.945 m over a 100 x 100 periodic (theta_1, theta_2)
  mesh (the thesis' 10K points).
* ``fig5.2``: the mean of that map when link masses/inertias scale by alpha and link CoM
  distances by beta (eqs. 5.6-5.7), 11 x 11 grid over [0.5, 1.5]^2.
* ``fig5.3``: the positioning subchain (joints 1-4) of the 7-DoF arm over the 50^4 grid (6.25e6
  points, eqs. 5.8-5.9), and the two (theta_3, theta_4) slices of the thesis figure. It uses all
  local cores, or a dask.distributed scheduler whose address is in the environment variable
  :data:`DASK_SCHEDULER_ENV` (``rns_reproduce run fig5.3 --dask-scheduler ADDRESS`` sets it).
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

from rns_ros.analysis import chain_energy_maps as cem
from rns_ros.analysis import energy_maps as em
from rns_ros.analysis.planar_field import fixed_points
from rns_ros.analysis.reproduce import plotting as plot
from rns_ros.analysis.reproduce.registry import (
    Comparison,
    Outcome,
    Reproduction,
    Verdict,
    number_verdict,
    register_all,
)

#: Environment variable naming a dask.distributed scheduler for fig5.3 (unset: local cores).
DASK_SCHEDULER_ENV = "RNS_REPRODUCE_DASK_SCHEDULER"

#: Thesis values: Fig. 5.1 mean C_ratio; Fig. 5.3 mean C_ratio and number of grid points.
THESIS_PLANAR_MEAN = 1.002
THESIS_SPATIAL_MEAN = 1.14
THESIS_SPATIAL_POINTS = 6_250_000
#: Fig. 5.3 slices (theta_1, theta_2) [rad]: (a) a typical one, (b) near a singularity.
SLICES = ((-3.05, 0.403), (-math.pi, 0.0))
#: Half a unit of the last printed digit of the thesis' means 1.002 and 1.14: the range of
#: means each printed number stands for [-].
PLANAR_MEAN_PRECISION, SPATIAL_MEAN_PRECISION = 5e-4, 5e-3
#: Exact bands of the excess over 1 (C_ratio >= 1, eq. 5.5), at most the close band of the
#: excess (10 %: 2e-4 of 0.002, 0.014 of 0.14). 1.14 is printed finely enough: half a unit of its
#: last digit. 1.002's half unit (5e-4) is wider than the close band of its excess, so its exact
#: band is half that close band [-].
PLANAR_EXCESS_TOLERANCE, SPATIAL_EXCESS_TOLERANCE = 1e-4, 5e-3
#: C_ratio within this of 1 counts as "≈ 1" (a tenth of the verdict rule's close band) [-].
NEAR_ONE = 0.01
#: Share of the planar mesh that must be ≈ 1 for "at almost all points" [-].
ALMOST_ALL = 0.95
#: C_ratio above which an error counts as "large" (50 % above the minimum energy) [-].
LARGE_ERROR = 1.5
#: Share of the planar mesh above LARGE_ERROR below which the large errors are "at specific
#: points" [-].
SPECIFIC_SHARE = 0.01
#: Grid spacings within which the planar maximum must lie from a zero of M~_ωm, where the thesis'
#: Discussion places the large errors [-].
FIXED_POINT_SPACINGS = 3.0

CHOICES = {
    "wheels": "A-3.1: the reaction wheels (I_r = 0.11 kg m² each, m_r = 10 kg) enter only as point "
    "masses at the base CoM: one wheel about the plane normal for the planar arm (base 1000 → "
    "1010 kg), three orthogonal wheels for the 7-DoF arm (base 2550 → 2580 kg, the base's "
    "rotational inertia about its CoM left as it is; it does not enter Λ).",
    "planar": "Planar model of §5.2: l_i = 1 m, m_i = 100 kg, I_i = 8.3 kg m² (the §5.2 value, "
    "not §3.2.1's 8.33), l_ci = l_i/2, attachment r = 0.945 m, ψ = 0; I_b does not enter Λ.",
    "grid": "A-3.2: periodic grids θ = −π + 2πk/N (the end point π repeats −π and is left "
    "out); N = 100 for the planar mesh.",
    "alpha_beta": "Eq. (5.6) as printed: α multiplies both link masses, the link inertias about "
    "their CoM stay 8.3 kg m²; β multiplies both link CoM distances l_ci = β l_i/2 (5.7); link "
    "lengths stay 1 m; α, β = 0.5, 0.6, ..., 1.5 (11 × 11). thesis_rest A-3.3's reading (I ∝ α, "
    "uniform density) is shown as a second, labelled table.",
    "spatial_grid": "4-DoF grid: θ1, θ3, θ4 = −π + 2πk/50 and θ2 = −π/2 + πk/50, k = 0..49 "
    "(6.25e6 points; the thesis' Δ = 0.125 and 0.0628 rad read as 2π/50 and π/50).",
    "wrist": "A-3.4: the wrist joints 5-7 are held at 0 and ride on link 4 as a rigid payload.",
    "ratio": "C_ratio = (n^T M~_m n) / σ_min(Λ) per unit joint speed, n the unit kernel vector of "
    "M~_ωm; σ_min by inverse iteration shifted by LAPACK's estimate (rns_ros.analysis."
    "energy_maps; equal to rns_ros.core.energy.c_ratio to 1e-9).",
}

PLANAR_KEYS = ("wheels", "planar", "grid", "ratio")


def _planar_settings(count: int) -> dict:
    arm = em.planar_arm()
    return {
        "attach_distance_r_m": arm.attach_distance,
        "base_mass_kg": arm.base_mass,
        "link_masses_kg": list(arm.link_masses),
        "link_inertias_kg_m2": list(arm.link_inertias),
        "com_distances_m": list(arm.com_distances),
        "wheel_inertia_kg_m2": em.WHEEL_INERTIA,
        "mesh": [count, count],
    }


def _theta_axes(ax, xlabel: str, ylabel: str, title: str, ylim=(-np.pi, np.pi)) -> None:
    ax.set_xlim(-np.pi, np.pi)
    ax.set_ylim(*ylim)
    plot.label_axes(ax, xlabel, ylabel, title)


def _colour_map(ax, figure, grid_x, grid_y, values, label: str = "C_ratio [-]"):
    from matplotlib.colors import LogNorm

    norm = LogNorm(vmin=1.0, vmax=max(float(np.max(values)), 1.0 + 1e-6))
    mesh = ax.pcolormesh(grid_x, grid_y, values, norm=norm, cmap="viridis", shading="nearest")
    figure.colorbar(mesh, ax=ax, label=label, shrink=0.85)


def mean_row(
    thesis: float, mean: float, precision: float, tolerance: float, note: str
) -> Comparison:
    """The mean C_ratio against the thesis' printed mean, compared on the excess over 1, the lower
    bound of C_ratio (eq. 5.5). ``precision`` is half a unit of the thesis' last printed digit;
    the note states the excess range the printed number stands for and where ours falls."""
    digits = round(-math.log10(2.0 * precision))
    low, high = thesis - precision - 1.0, thesis + precision - 1.0
    excess = mean - 1.0
    where = "inside it" if low <= excess < high else ("below it" if excess < low else "above it")
    note = (
        f"{note}; ours rounds to {mean:.{digits}f}; the printed {thesis:g} stands for an excess "
        f"over 1 in [{low:.4g}, {high:.4g}): ours, {excess:.4g}, lies {where}"
    )
    if number_verdict(thesis - 1.0, excess, tolerance) is Verdict.DIFFERENT:
        if where == "inside it":
            note += (
                "; the printed digits do not resolve 10 % of the excess, so a mean they allow "
                "can still be different"
            )
        else:
            note += "; the cause is open"
    return Comparison.excess(
        "c_ratio_mean", thesis, mean, "", bound=1.0, tolerance=tolerance, note=note
    )


def _open(note: str, holds: bool) -> str:
    """``note``, saying the cause is open when the trend fails."""
    return note if holds else f"{note}; the cause is open"


# --- Fig. 5.1 ---------------------------------------------------------------------------------
def compute_fig5_1(quick: bool) -> Outcome:
    """C_ratio of the planar arm over (θ1, θ2) (eq. 5.5)."""
    count = 40 if quick else 100
    arm = em.planar_arm()
    grid, ratio = em.planar_c_ratio_map(arm, count)
    mean, median, peak = float(ratio.mean()), float(np.median(ratio)), float(ratio.max())
    i, j = np.unravel_index(np.argmax(ratio), ratio.shape)
    argmax = [float(grid[j]), float(grid[i])]
    points = fixed_points(arm)
    nearest = min(
        float(np.linalg.norm((np.asarray(argmax) - p.theta + np.pi) % (2 * np.pi) - np.pi))
        for p in points
    )
    share = float(np.mean(ratio > 1.0 + NEAR_ONE))
    comparisons = (
        mean_row(
            THESIS_PLANAR_MEAN,
            mean,
            PLANAR_MEAN_PRECISION,
            PLANAR_EXCESS_TOLERANCE,
            f"Fig. 5.1 (§5.2); {count}² periodic mesh (A-3.2)",
        ),
        _near_one_row(ratio),
        _large_error_row(ratio, argmax, nearest / (2.0 * np.pi / count)),
    )
    values = {
        "c_ratio_mean": mean,
        "c_ratio_median": median,
        "c_ratio_max": peak,
        "c_ratio_argmax_theta_rad": argmax,
        "share_above_1_01": share,
        "fixed_points_theta_rad": [p.theta.tolist() for p in points],
    }
    figure_data = {"grid": grid, "ratio": ratio, "fixed_points": [p.theta for p in points]}
    return Outcome(
        comparisons,
        values,
        _planar_settings(count),
        tuple(CHOICES[k] for k in PLANAR_KEYS),
        figure_data,
    )


def _near_one_row(ratio: np.ndarray) -> Comparison:
    """Fig. 5.1: C_ratio ≈ 1 at almost all mesh points."""
    near = float(np.mean(np.abs(ratio - 1.0) <= NEAR_ONE))
    holds = near >= ALMOST_ALL
    note = (
        f"{near:.1%} of the points are within {NEAR_ONE:g} of 1 (qualitative from "
        f"{ALMOST_ALL:.0%}); median {float(np.median(ratio)):.6g}"
    )
    return Comparison.trend(
        "share_near_1",
        "'C_ratio ≈ 1 at almost all points' (§5.2)",
        round(near, 4),
        "",
        holds=holds,
        note=_open(note, holds),
    )


def _large_error_row(ratio: np.ndarray, argmax: list[float], spacings: float) -> Comparison:
    """Fig. 5.1: large C_ratio at a few points, next to a zero of M~_ωm (``spacings``: the
    distance of the maximum from the nearest zero [grid spacings])."""
    peak = float(ratio.max())
    large = float(np.mean(ratio > LARGE_ERROR))
    holds = peak > LARGE_ERROR and large < SPECIFIC_SHARE and spacings <= FIXED_POINT_SPACINGS
    note = (
        f"max at θ = ({argmax[0]:.3f}, {argmax[1]:.3f}) rad, {spacings:.1f} grid spacings from "
        f"the nearest zero of M~_ωm (fixed point of Fig. 3.2(b)); {large:.2%} of the points "
        f"exceed {LARGE_ERROR:g}; qualitative when the max exceeds {LARGE_ERROR:g}, fewer than "
        f"{SPECIFIC_SHARE:.0%} of the points do and the max lies within "
        f"{FIXED_POINT_SPACINGS:g} spacings of a zero"
    )
    return Comparison.trend(
        "c_ratio_max",
        "'large errors at specific points' (§5.2), around the singularities of M~_ωm (Discussion)",
        peak,
        "",
        holds=holds,
        note=_open(note, holds),
    )


def plot_fig5_1(outcome: Outcome, figure) -> None:
    data = outcome.figure_data
    ax = figure.add_subplot()
    _colour_map(ax, figure, data["grid"], data["grid"], data["ratio"])
    for k, theta in enumerate(data["fixed_points"]):
        ax.plot(*theta, "rx", markersize=8, label="M~_ωm = 0" if k == 0 else None)
    if data["fixed_points"]:
        ax.legend(fontsize=8, loc="upper right")
    ax.set_aspect("equal")
    _theta_axes(ax, "θ1 [rad]", "θ2 [rad]", "C_ratio (log colour scale), r = 0.945 m")


# --- Fig. 5.2 ---------------------------------------------------------------------------------
def compute_fig5_2(quick: bool) -> Outcome:
    """Mean C_ratio over the planar mesh for each (α, β) of eqs. (5.6)-(5.7)."""
    steps = 3 if quick else 11
    count = 30 if quick else 100
    alphas = np.round(np.linspace(0.5, 1.5, steps), 10)
    betas = alphas.copy()
    means = em.parameter_variation_map(alphas, betas, count)
    dense = em.parameter_variation_map(alphas, betas, count, scale_inertia=True)
    corners = {
        f"alpha_{a:g}_beta_{b:g}": float(means[i, j])
        for i, a in ((0, alphas[0]), (-1, alphas[-1]))
        for j, b in ((0, betas[0]), (-1, betas[-1]))
    }
    centre = float(means[steps // 2, steps // 2])
    comparisons = _fig5_2_comparisons(alphas, means, dense)
    values = {
        "alphas": alphas.tolist(),
        "betas": betas.tolist(),
        "c_ratio_mean_table": means.tolist(),
        "corners": corners,
        "c_ratio_mean_alpha_1_beta_1": centre,
        "c_ratio_mean_table_inertia_scaled": dense.tolist(),
    }
    settings = {
        **_planar_settings(count),
        "alpha_beta_grid": [steps, steps],
        "alpha_scales": "m_i (eq. 5.6); the second table also I_i",
        "beta_scales": "l_ci",
    }
    keys = (*PLANAR_KEYS, "alpha_beta")
    return Outcome(
        comparisons,
        values,
        settings,
        tuple(CHOICES[k] for k in keys),
        {"alphas": alphas, "betas": betas, "means": means, "dense": dense},
    )


def _falling_count(means: np.ndarray) -> int:
    """β columns of a table of means (rows α) whose largest α is below its smallest α."""
    return int(np.sum(means[-1] < means[0]))


def _fig5_2_comparisons(
    alphas: np.ndarray, means: np.ndarray, dense: np.ndarray
) -> tuple[Comparison, ...]:
    """Fig. 5.2's two claims on the table of means of eq. (5.6) (rows α, columns β); ``dense``
    is the table with I ∝ α, quoted in the notes."""
    steps = len(alphas)
    worst = float(np.max(np.abs(means - 1.0)))
    near = worst <= NEAR_ONE
    falling = int(np.sum(np.all(np.diff(means, axis=0) < 0.0, axis=0)))
    lower = _falling_count(means)
    dense_lower = _falling_count(dense)
    return (
        Comparison.trend(
            "c_ratio_mean_range",
            "'reactionless motion approximately coincides with instantaneous minimum motion even "
            "if the parameters are varied' (§5.2)",
            [float(means.min()), float(means.max())],
            "",
            holds=near,
            note=_open(
                f"min and max of the {steps} × {steps} table of means; the furthest is {worst:.3g} "
                f"from 1 (qualitative within {NEAR_ONE:g})",
                near,
            ),
        ),
        Comparison.trend(
            "decreasing_with_alpha",
            "'high equivalence can be observed when α takes large values' (§5.2)",
            f"the mean at α = {alphas[-1]:g} is below α = {alphas[0]:g} for {lower} of {steps} β "
            f"values; it falls monotonically with α for {falling}",
            "",
            holds=lower == steps,
            note=_alpha_note(lower, dense_lower, steps),
        ),
    )


def _alpha_note(lower: int, dense_lower: int, steps: int) -> str:
    """Why the α trend holds or not: eq. (5.6)'s masses alone against I ∝ α as well."""
    note = (
        "masses scaled as eq. (5.6) prints, inertias kept; qualitative when it is below for "
        f"every β. With I ∝ α as well (A-3.3) it is below for {dense_lower} of {steps}"
    )
    if lower == steps:
        return note
    if dense_lower == steps:
        return f"{note}: the claim needs the inertias scaled with the masses"
    return f"{note}; the cause is open"


def plot_fig5_2(outcome: Outcome, figure) -> None:
    data = outcome.figure_data
    ax = figure.add_subplot()
    mesh = ax.pcolormesh(data["betas"], data["alphas"], data["means"], shading="nearest")
    figure.colorbar(mesh, ax=ax, label="mean C_ratio [-]", shrink=0.85)
    if len(data["alphas"]) <= 11:
        for i, a in enumerate(data["alphas"]):
            for j, b in enumerate(data["betas"]):
                ax.text(b, a, f"{data['means'][i, j]:.4f}", ha="center", va="center", fontsize=5)
    ax.set_xlabel("β (link CoM distance scale) [-]")
    ax.set_ylabel("α (link mass scale, eq. 5.6) [-]")
    ax.set_title("mean C_ratio over the (θ1, θ2) mesh (link inertias kept)", fontsize=9)


# --- Fig. 5.3 ---------------------------------------------------------------------------------
def compute_fig5_3(quick: bool) -> Outcome:
    """C_ratio of the 7-DoF arm's positioning subchain over the 50^4 grid and two slices."""
    count = 8 if quick else 50
    slice_count = 24 if quick else 100
    scheduler = os.environ.get(DASK_SCHEDULER_ENV) or None
    workers = 1 if quick else None
    chain = cem.positioning_chain()
    grids = cem.positioning_grids(count)
    start = time.perf_counter()
    ratio = cem.chain_c_ratio_map(
        chain, grids, workers=workers, dask_scheduler=scheduler, progress=not quick
    )
    summary = em.MapSummary.of(ratio, time.perf_counter() - start)
    slice_grid = em.periodic_grid(slice_count)
    slices = [
        cem.chain_c_ratio_map(chain, [[t1], [t2], slice_grid, slice_grid], workers=1)[0, 0]
        for t1, t2 in SLICES
    ]
    where = f"{os.cpu_count()} local processes" if workers is None else "this process"
    if scheduler:
        where = f"dask scheduler {scheduler}"
    comparisons = _fig5_3_comparisons(summary, slice_grid, slices, count)
    values = _fig5_3_values(summary, slices)
    settings = {
        "model": "config/model.yaml (7-DoF arm), base 2550 + 30 kg wheels, wrist held at 0",
        "base_mass_kg": chain.base_mass,
        "body_masses_kg": chain.masses.tolist(),
        "wheel_inertia_kg_m2": em.WHEEL_INERTIA,
        "grid": [len(g) for g in grids],
        "slice_grid": [slice_count, slice_count],
        "computed_on": where,
    }
    keys = ("wheels", "spatial_grid", "wrist", "ratio")
    return Outcome(
        comparisons,
        values,
        settings,
        tuple(CHOICES[k] for k in keys),
        {"slice_grid": slice_grid, "slices": slices},
    )


def _fig5_3_comparisons(
    summary: em.MapSummary, slice_grid: np.ndarray, slices: list[np.ndarray], count: int
) -> tuple[Comparison, ...]:
    """Fig. 5.3: the grid's mean and median, the two slices' claims and the grid size."""
    tail = f"median {summary.median:.4f}, p99 {summary.p99:.3g}, max {summary.maximum:.3g}"
    near = abs(summary.median - 1.0) <= NEAR_ONE
    return (
        mean_row(
            THESIS_SPATIAL_MEAN,
            summary.mean,
            SPATIAL_MEAN_PRECISION,
            SPATIAL_EXCESS_TOLERANCE,
            f"§5.2 (Fig. 5.3); {tail}: the mean comes from the tail",
        ),
        Comparison.trend(
            "c_ratio_median",
            "'Except few configurations, reactionless motion coincides with the energy minimum "
            "motion, as in the planar case' (§5.2)",
            summary.median,
            "",
            holds=near,
            note=_open(f"qualitative when the median is within {NEAR_ONE:g} of 1", near),
        ),
        *_slice_rows(slice_grid, slices),
        Comparison.input(
            "points",
            THESIS_SPATIAL_POINTS,
            summary.points,
            "",
            f"set: {count}^4 grid (eqs. 5.8-5.9 read as 50 values per joint)",
        ),
    )


def _slice_rows(slice_grid: np.ndarray, slices: list[np.ndarray]) -> list[Comparison]:
    """Fig. 5.3 (a) has no large errors, (b) near the singularity has them."""
    peaks = [float(s.max()) for s in slices]
    where = []
    for s in slices:
        i3, i4 = np.unravel_index(np.argmax(s), s.shape)
        where.append(
            f"max at (θ3, θ4) = ({slice_grid[i3]:.2f}, {slice_grid[i4]:.2f}) rad; "
            f"{float(np.mean(s > LARGE_ERROR)):.2%} of its {s.size} points exceed {LARGE_ERROR:g}"
        )
    quiet = peaks[0] <= LARGE_ERROR
    loud = peaks[1] > LARGE_ERROR and peaks[1] > peaks[0]
    (t1a, t2a), (_, t2b) = SLICES
    return [
        Comparison.trend(
            "slice_a_c_ratio_max",
            f"(a) at (θ1, θ2) = ({t1a}, {t2a}) rad: 'a distribution map … that does not include "
            "large errors' (§5.2)",
            peaks[0],
            "",
            holds=quiet,
            note=f"{where[0]}; qualitative when no point exceeds {LARGE_ERROR:g}"
            + ("" if quiet else _elbow_cause(slice_grid, slices[0])),
        ),
        Comparison.trend(
            "slice_b_c_ratio_max",
            f"(b) at (θ1, θ2) = (-π, {t2b:g}) rad, 'near the singularity': large errors (§5.2)",
            peaks[1],
            "",
            holds=loud,
            note=_open(
                f"{where[1]}; qualitative when its max exceeds {LARGE_ERROR:g} and slice (a)'s",
                loud,
            ),
        ),
    ]


def elbow_distance(theta4: np.ndarray) -> np.ndarray:
    """Distance [rad] of each theta_4 to the nearest of 0 and pi (straight or folded elbow, where
    the positioning chain loses a rank), shape of ``theta4``."""
    return np.abs(np.angle(np.exp(2j * np.asarray(theta4)))) / 2.0


def _elbow_cause(slice_grid: np.ndarray, c_ratio: np.ndarray) -> str:
    """Where a slice's large C_ratio values lie relative to the elbow singularities."""
    _, i4 = np.nonzero(c_ratio > LARGE_ERROR)
    distance = elbow_distance(slice_grid[i4])
    away = c_ratio[:, elbow_distance(slice_grid) > distance.max()]
    return (
        f"; every point above {LARGE_ERROR:g} lies within {distance.max():.2f} rad of theta_4 in "
        f"{{0, pi}} (median {np.median(distance):.3f} rad), the straight and folded elbow where "
        f"the positioning chain loses a rank; the rest of the slice peaks at "
        f"{away.max() if away.size else float('nan'):.2f}: the large values are the elbow "
        "singularities this slice crosses"
    )


def _fig5_3_values(summary: em.MapSummary, slices: list[np.ndarray]) -> dict:
    """The JSON values of Fig. 5.3: map statistics, throughput and per-slice statistics."""
    return {
        "c_ratio_mean": summary.mean,
        "c_ratio_median": summary.median,
        "c_ratio_p99": summary.p99,
        "c_ratio_max": summary.maximum,
        "c_ratio_min": summary.minimum,
        "points": summary.points,
        "wall_s": summary.wall_s,
        "points_per_s": summary.points / summary.wall_s if summary.wall_s > 0 else None,
        "slices": [
            {
                "theta1_rad": t1,
                "theta2_rad": t2,
                "c_ratio_mean": float(s.mean()),
                "c_ratio_median": float(np.median(s)),
                "c_ratio_max": float(s.max()),
            }
            for (t1, t2), s in zip(SLICES, slices, strict=True)
        ],
    }


def plot_fig5_3(outcome: Outcome, figure) -> None:
    data = outcome.figure_data
    axes = figure.subplots(1, 2)
    for ax, (t1, t2), values, label in zip(axes, SLICES, data["slices"], "ab", strict=True):
        # rows of a slice are θ3, columns θ4: θ3 on the horizontal axis
        _colour_map(ax, figure, data["slice_grid"], data["slice_grid"], values.T)
        ax.set_aspect("equal")
        _theta_axes(ax, "θ3 [rad]", "θ4 [rad]", f"({label}) θ1 = {t1:.3f}, θ2 = {t2:.3f} rad")


REPRODUCTIONS = register_all(
    Reproduction(
        "fig5.1",
        "Fig. 5.1",
        "C_ratio of the planar 2-DoF arm over (θ1, θ2), r = 0.945 m",
        compute_fig5_1,
        plot_fig5_1,
        (6.5, 5.5),
    ),
    Reproduction(
        "fig5.2",
        "Fig. 5.2",
        "mean C_ratio of the planar arm under link mass (α) and CoM distance (β) scaling",
        compute_fig5_2,
        plot_fig5_2,
        (7.5, 6.0),
    ),
    Reproduction(
        "fig5.3",
        "Fig. 5.3",
        "C_ratio of the 7-DoF positioning subchain: 50⁴-grid statistics and two (θ3, θ4) slices",
        compute_fig5_3,
        plot_fig5_3,
        (11.0, 5.0),
    ),
)
