"""Chapter 3 results: the planar reactionless field (Fig. 3.1), nullclines and fixed points
(Fig. 3.2), the coupling-inertia determinant and CoM distance (Fig. 3.3). All numbers come from
:mod:`rns_ros.analysis.planar_field` (closed form); the bifurcation in r (§3.2.2) is in
:mod:`rns_ros.analysis.reproduce.chapter3_bifurcation`.

Importing this module registers ``fig3.1``, ``fig3.2`` and ``fig3.3``; :data:`REPRODUCTIONS`
holds them by id.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rns_ros.analysis.planar_field import (
    PlanarArm,
    classify,
    com_distance_map,
    critical_distance,
    det_map,
    fixed_points,
    integral_curve,
    torus_grid,
    torus_segments,
    wrap,
)
from rns_ros.analysis.reproduce import plotting as plot
from rns_ros.analysis.reproduce.registry import (
    Comparison,
    Outcome,
    Reproduction,
    register_all,
)

ARM = PlanarArm()  # Fig. 3.1 / §3.2.1 parameters, r = 0, ψ = 0

CHOICES = {
    "A-1.1": "A-1.1: θ1 is measured from the base x axis and θ2 relative to link 1, both "
    "counter-clockwise, so θ = 0 is the arm stretched along +x away from the base CoM (ψ = 0).",
    "A-1.2": "A-1.2: n(θ) = [−M~_2, M~_1]/|M~_ωm| (co-factor vector); the arrow sign is "
    "arbitrary (b may be negative) and ours gives θ̇2 > 0 where M~_1 > 0.",
    "A-1.3": "A-1.3: fixed points are the zeros of the un-normalized co-factor field "
    "[−M~_2, M~_1], drawn as intersections of the zero contours of M~_1 and M~_2.",
    "A-1.4": "A-1.4: θ1 on the horizontal and θ2 on the vertical axis over [−π, π]², "
    "25 × 25 arrows.",
    "A-1.5": "A-1.5: the thesis' 'two fixed points created' at r* are a mirror pair of "
    "degenerate (saddle-node) points; each splits, so there are four for r > r*.",
    "A-1.6": "A-1.6: 'manipulator CoM' is the links-only CoM (m_1 c_1 + m_2 c_2)/(m_1 + m_2), "
    "which is farthest from the base CoM at θ = 0.",
    "I_i": "Link moments I_i = 8.33 kg m² as in §3.2.1 (§5.2 says 8.3; r* moves < 1e-3 m).",
}

#: Fixed-point marker per class: (marker, colour).
MARKERS = {
    "saddle": ("X", "black"),
    "node": ("o", "darkgreen"),
    "focus": ("s", "purple"),
    "center": ("P", "orange"),
    "degenerate": ("D", "magenta"),
}

THETA1_LABEL, THETA2_LABEL = "θ1 [rad]", "θ2 [rad]"


def model_settings(arm: PlanarArm = ARM) -> dict:
    """The model parameters (PlanarArm fields) with units in the names."""
    fields = dataclasses.asdict(arm)
    return {
        "base_mass_kg": fields["base_mass"],
        "base_inertia_kg_m2": fields["base_inertia"],
        "link_lengths_m": list(fields["link_lengths"]),
        "link_masses_kg": list(fields["link_masses"]),
        "link_inertias_kg_m2": list(fields["link_inertias"]),
        "com_distances_m": list(fields["com_distances"]),
        "attach_angle_psi_rad": fields["attach_angle"],
    }


def points_json(points, r: float) -> list[dict]:
    return [
        {
            "r_m": r,
            "theta_rad": [float(v) for v in p.theta],
            "kind": p.kind,
            "stability": p.stability,
            "index": p.index,
        }
        for p in points
    ]


def _arrow_grid(arm: PlanarArm, n: int) -> dict:
    t1, t2, theta = torus_grid(n)
    field = arm.reactionless_field(theta)
    return {"t1": t1, "t2": t2, "u": field[..., 0], "v": field[..., 1]}


def _draw_arrows(ax, arrows: dict) -> None:
    spacing = arrows["t1"][1] - arrows["t1"][0]
    t1, t2 = np.meshgrid(arrows["t1"], arrows["t2"])
    ax.quiver(
        t1,
        t2,
        arrows["u"],
        arrows["v"],
        angles="xy",
        scale_units="xy",
        scale=1.0 / (0.75 * spacing),
        width=0.004,
        color="tab:blue",
    )


def _torus_axes(ax, title: str) -> None:
    ax.set_xlim(-np.pi, np.pi)
    ax.set_ylim(-np.pi, np.pi)
    ax.set_aspect("equal")
    plot.label_axes(ax, THETA1_LABEL, THETA2_LABEL, title)
    ticks = [-np.pi, -np.pi / 2, 0.0, np.pi / 2, np.pi]
    ax.set_xticks(ticks, ["−π", "−π/2", "0", "π/2", "π"])
    ax.set_yticks(ticks, ["−π", "−π/2", "0", "π/2", "π"])


def _draw_fixed_points(ax, points) -> None:
    seen = set()
    for p in points:
        marker, colour = MARKERS[p.kind]
        label = f"{p.kind} {p.stability}".strip()
        ax.plot(
            p.theta[0],
            p.theta[1],
            marker=marker,
            color=colour,
            markersize=7,
            linestyle="none",
            markerfacecolor=colour if p.stability != "unstable" else "none",
            label=None if label in seen else label,
            zorder=5,
        )
        seen.add(label)


# --- Fig. 3.1 ---------------------------------------------------------------------------------
def compute_fig3_1(quick: bool) -> Outcome:
    """The field at r = 0 with integral curves of dθ/ds = n(θ) (eq. 3.5, b = 1)."""
    arm = ARM
    arrows_n = 13 if quick else 25
    check_n = 61 if quick else 361
    step = 0.05 if quick else 0.01
    seeds = [(t1, -np.pi) for t1 in np.linspace(-np.pi, np.pi, 8, endpoint=False)]
    # one turn of θ2 per curve: |n2| ≥ 0.95 at r = 0, so arc length 2π/0.9 is enough
    curves = []
    for seed in seeds:
        curve = integral_curve(arm, seed, 2.0 * np.pi / 0.9, step)
        curves.append(curve[curve[:, 1] <= np.pi + 1e-12])
    _, _, theta = torus_grid(check_n)
    n = arm.reactionless_field(theta)
    symmetry = float(np.max(np.abs(n - n[:, :1])))
    coupling_norm = np.linalg.norm(arm.coupling_inertia(theta), axis=-1)
    points = fixed_points(arm)
    min_n2, max_n1 = float(np.abs(n[..., 1]).min()), float(np.abs(n[..., 0]).max())
    comparisons = (
        _symmetry_row(symmetry, check_n),
        _joint_2_row(min_n2, max_n1, check_n),
        Comparison.number(
            "fixed_point_count",
            0,
            len(points),
            "",
            tolerance=0.0,
            note="§3.2.1 'the system does not have any fixed points' (a count); min |M~_ωm| = "
            f"{coupling_norm.min():.2f} kg m² on the {check_n}² grid",
        ),
    )
    values = {
        "min_abs_n2": min_n2,
        "max_abs_n1": max_n1,
        "min_coupling_norm_kg_m2": float(coupling_norm.min()),
        "fixed_points": points_json(points, arm.attach_distance),
    }
    settings = {
        "attach_distance_r_m": arm.attach_distance,
        **model_settings(arm),
        "arrow_grid": [arrows_n, arrows_n],
        "check_grid": [check_n, check_n],
        "integral_curves": f"RK4 on dθ/ds = n(θ), step {step} rad, from θ = (−π + kπ/4, −π) "
        "for one turn of θ2",
    }
    return Outcome(
        comparisons,
        values,
        settings,
        (CHOICES["A-1.1"], CHOICES["A-1.2"], CHOICES["A-1.4"], CHOICES["I_i"]),
        {"arrows": _arrow_grid(arm, arrows_n), "curves": curves},
    )


#: largest change of the unit field n along θ1 that still counts as "independent of θ1": the
#: closed form has no θ1 term at r = 0, so only rounding remains [-]
SYMMETRY_TOLERANCE = 1e-12


def _symmetry_row(symmetry: float, check_n: int) -> Comparison:
    """§3.2.1 'rotational symmetry w.r.t. Joint 1': n(θ) does not change with θ1 at r = 0. An
    identity: with the arm attached at the base CoM, M~_ωm (eq. 3.3) has no θ1 term."""
    return Comparison.by_construction(
        "rotational_symmetry_joint_1",
        "field independent of θ1 ('rotational symmetry w.r.t. Joint 1')",
        f"max |n(θ1, θ2) − n(−π, θ2)| = {symmetry:.1e}",
        "",
        holds=symmetry <= SYMMETRY_TOLERANCE,
        note="at r = 0 the coupling inertia M~_ωm has no θ1 term, so the field cannot depend "
        f"on θ1; checked over a {check_n}² grid (change ≤ {SYMMETRY_TOLERANCE:g}, rounding)",
    )


def _joint_2_row(min_n2: float, max_n1: float, check_n: int) -> Comparison:
    """§3.2.1 'predominantly composed of Joint 2 motion': |n2| > |n1| at every grid point."""
    return Comparison.trend(
        "joint_2_dominant",
        "reactionless motion 'predominantly composed of Joint 2 motion'",
        f"min |n2| = {min_n2:.3f}, max |n1| = {max_n1:.3f}",
        "",
        holds=min_n2 > max_n1,
        note=f"holds when the smallest |n2| exceeds the largest |n1| over the {check_n}² grid",
    )


def plot_fig3_1(outcome: Outcome, figure) -> None:
    ax = figure.add_subplot()
    _draw_arrows(ax, outcome.figure_data["arrows"])
    for curve in outcome.figure_data["curves"]:
        for piece in torus_segments(curve):
            ax.plot(piece[:, 0], piece[:, 1], color="tab:red", linewidth=1.0)
    _torus_axes(ax, "n(θ) at r = 0 m (arrows) and integral curves (red)")


# --- Fig. 3.2 ---------------------------------------------------------------------------------
FIG3_2_DISTANCES = (0.5, 0.945, 1.5)


def compute_fig3_2(quick: bool) -> Outcome:
    """Fields (upper row) and nullclines with fixed points (lower row) at r = 0.5, 0.945, 1.5."""
    arrows_n = 13 if quick else 25
    contour_n = 91 if quick else 361
    panels, counts, minima_m1 = [], {}, {}
    for r in FIG3_2_DISTANCES:
        arm = ARM.at(r)
        t1, t2, theta = torus_grid(contour_n)
        joint_1, joint_2 = arm.nullcline_functions(theta)
        points = fixed_points(arm)
        counts[r] = len(points)
        minima_m1[r] = float(joint_2.min())
        panels.append(
            {
                "r": r,
                "arrows": _arrow_grid(arm, arrows_n),
                "t1": t1,
                "t2": t2,
                "joint_1": joint_1,
                "joint_2": joint_2,
                "points": points,
            }
        )
    critical = critical_distance(ARM)
    near = FIG3_2_DISTANCES[1]
    near_gap, far_gap = (_nearest_gap(panel["points"]) for panel in panels[1:])
    comparisons = (
        Comparison.number(
            "fixed_points_r0_5",
            0,
            counts[0.5],
            "",
            tolerance=0.0,
            note="§3.2.2 'there is no fixed point … Joint 2 never stops' (a count); min M~_1 = "
            f"{minima_m1[0.5]:.1f} kg m² at r = 0.5 m",
        ),
        _separation_row(panels[2]["points"], near_gap, far_gap),
    )
    values = {
        # r* and "two fixed points are created" are one claim of §3.2.2, judged in sec3.2.2
        "r_star_m": critical.r_star,
        "near_r_star": f"{counts[near]} fixed points at r = {near} m "
        f"({near - critical.r_star:.1e} m above r*), nearest pair {_gap_text(near_gap)} apart",
        "fixed_point_counts": {f"{r}": counts[r] for r in FIG3_2_DISTANCES},
        "fixed_points": [
            point for panel in panels for point in points_json(panel["points"], panel["r"])
        ],
        "min_M1_kg_m2": {f"{r}": minima_m1[r] for r in FIG3_2_DISTANCES},
    }
    settings = {
        "attach_distances_r_m": list(FIG3_2_DISTANCES),
        **model_settings(),
        "arrow_grid": [arrows_n, arrows_n],
        "nullcline_contour_grid": [contour_n, contour_n],
    }
    choices = (
        *(CHOICES[k] for k in ("A-1.1", "A-1.2", "A-1.3", "A-1.4", "A-1.5", "I_i")),
        "The bifurcation at r ≈ 0.945 m and the two fixed points it creates are judged once, in "
        "sec3.2.2; this figure shows them (values r_star_m, near_r_star).",
    )
    return Outcome(comparisons, values, settings, choices, {"panels": panels})


def _nearest_gap(points) -> float | None:
    """Smallest torus distance between two of ``points`` [rad]; None for fewer than two."""
    gaps = [
        float(np.linalg.norm(wrap(a.theta - b.theta)))
        for i, a in enumerate(points)
        for b in points[i + 1 :]
    ]
    return min(gaps) if gaps else None


def _gap_text(gap: float | None) -> str:
    return "—" if gap is None else f"{gap:.3f} rad"


def _separation_row(points, near_gap: float | None, far_gap: float | None) -> Comparison:
    """§3.2.2 'separation of the created fixed points' at r = 1.5 m: its nearest pair is farther
    apart than the nearest pair at r = 0.945 m."""
    kinds = ", ".join(sorted({f"{p.kind} {p.stability}".strip() for p in points}))
    return Comparison.trend(
        "separation_r1_5",
        "the created fixed points separate",
        f"{len(points)} fixed points ({kinds}), nearest pair {_gap_text(far_gap)} apart",
        "",
        holds=near_gap is not None and far_gap is not None and far_gap > near_gap,
        note="holds when the nearest pair at r = 1.5 m is farther apart than at r = 0.945 m "
        f"({_gap_text(near_gap)})",
    )


def plot_fig3_2(outcome: Outcome, figure) -> None:
    panels = outcome.figure_data["panels"]
    axes = figure.subplots(2, len(panels))
    for column, panel in enumerate(panels):
        label = "abc"[column]
        top, bottom = axes[0, column], axes[1, column]
        _draw_arrows(top, panel["arrows"])
        _torus_axes(top, f"({label}) field, r = {panel['r']} m")
        bottom.contour(panel["t1"], panel["t2"], panel["joint_1"], levels=[0.0], colors="red")
        bottom.contour(panel["t1"], panel["t2"], panel["joint_2"], levels=[0.0], colors="blue")
        _draw_fixed_points(bottom, panel["points"])
        _torus_axes(bottom, f"({label}) nullclines, r = {panel['r']} m")
    # one legend for all panels, below them: proxies for the contour colours + fixed points
    axes[1, 0].plot([], [], color="red", label=r"joint-1 nullcline ($\tilde M_2 = 0$)")
    axes[1, 0].plot([], [], color="blue", label=r"joint-2 nullcline ($\tilde M_1 = 0$)")
    handles = {}
    for ax in axes[1]:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    figure.legend(
        list(handles.values()), list(handles), loc="outside lower center", ncol=7, fontsize=8
    )


# --- Fig. 3.3 ---------------------------------------------------------------------------------
FIG3_3_DISTANCE = 1.5


def compute_fig3_3(quick: bool) -> Outcome:
    """det(M~_ωm M~_ωm^T) and the links-only CoM distance over θ at r = 1.5 m."""
    arm = ARM.at(FIG3_3_DISTANCE)
    n = 61 if quick else 361
    t1, t2, det = det_map(arm, n)
    _, _, distance = com_distance_map(arm, n)
    i, j = np.unravel_index(np.argmax(det), det.shape)
    di, dj = np.unravel_index(np.argmax(distance), distance.shape)
    argmax = [float(t1[j]), float(t2[i])]
    correlation = float(np.corrcoef(det.ravel(), distance.ravel())[0, 1])
    points = fixed_points(arm)
    # the grid locates a maximum only to within half its spacing
    half_step = float(t1[1] - t1[0]) / 2.0
    comparisons = (
        Comparison.number(
            "det_argmax_theta_rad",
            [0.0, 0.0],
            argmax,
            "rad",
            tolerance=half_step,
            note=f"§3.2.3 'maximum value at θ = 0'; max det = {det[i, j]:.5g} kg² m⁴ on a {n}² "
            "grid (tolerance half its spacing)",
        ),
        _com_distance_row([float(t1[dj]), float(t2[di])], float(distance.max()), half_step),
        _large_distance_row(det, distance, correlation),
        _fixed_points_distance_row(arm, points, distance),
        _dark_area_row(arm, (t1, t2, det), points),
    )
    values = {
        "det_max_kg2_m4": float(det[i, j]),
        "det_argmax_theta_rad": argmax,
        "com_distance_max_m": float(distance.max()),
        "com_distance_min_m": float(distance.min()),
        "pearson_det_distance": correlation,
        "det_median_kg2_m4": float(np.median(det)),
        "det_min_where_distance_above_median_kg2_m4": float(
            det[distance > np.median(distance)].min()
        ),
        "fixed_points": points_json(points, FIG3_3_DISTANCE),
    }
    settings = {
        "attach_distance_r_m": FIG3_3_DISTANCE,
        **model_settings(),
        "map_grid": [n, n],
    }
    return Outcome(
        comparisons,
        values,
        settings,
        (CHOICES["A-1.1"], CHOICES["A-1.6"], CHOICES["I_i"]),
        {"t1": t1, "t2": t2, "det": det, "distance": distance, "points": points},
    )


def _large_distance_row(det, distance, correlation: float) -> Comparison:
    """§3.2.3 'the determinant takes large values whenever the distance is relatively large':
    "large" is above the map's median, for both maps."""
    median = float(np.median(distance))
    large = distance > median
    det_median = float(np.median(det))
    weakest = np.unravel_index(np.argmin(np.where(large, det, np.inf)), det.shape)
    smallest = float(det[weakest])
    holds = smallest > det_median
    share = float(np.mean(det[large] > det_median))
    upper = distance > np.quantile(distance, 0.75)
    cause = (
        ""
        if holds
        else f"; fails at the area's edge: its smallest det lies at distance "
        f"{distance[weakest]:.4f} m, {distance[weakest] - median:.1e} m above the median; where "
        f"the distance is in its upper quartile det exceeds its median on "
        f"{float(np.mean(det[upper] > det_median)):.1%}"
    )
    return Comparison.trend(
        "det_large_where_distance_large",
        "determinant large whenever the distance is large",
        f"where the distance is above its median ({median:.3f} m), det ≥ {smallest:.4g} kg² m⁴ "
        f"(det median {det_median:.4g}); above the det median on {share:.1%} of that area",
        "",
        holds=holds,
        note="holds when det exceeds its median wherever the distance exceeds its median; "
        f"Pearson correlation of the two maps {correlation:.2f}{cause}",
    )


def _fixed_points_distance_row(arm: PlanarArm, points, distance) -> Comparison:
    """§3.2.3 'there is no fixed point within the area where the distance is large': every
    fixed point has a CoM distance below the map's median."""
    median = float(np.median(distance))
    at_points = [float(arm.manipulator_com_distance(p.theta)) for p in points]
    return Comparison.trend(
        "fixed_points_in_small_distance_area",
        "no fixed point where the distance is large",
        f"{len(points)} fixed points at CoM distance "
        + (f"{min(at_points):.2f}–{max(at_points):.2f} m" if at_points else "—")
        + f"; map median {median:.2f} m",
        "",
        holds=bool(at_points) and max(at_points) < median,
        note="holds when every fixed point lies below the distance map's median",
    )


#: det at a fixed point relative to the map's maximum below which it counts as zero [-]
SINGULAR_FRACTION = 1e-9


def _dark_area_row(arm: PlanarArm, det_grid, points) -> Comparison:
    """§3.2.3 'the most dark area represents the singularities': det vanishes at the fixed
    points and the map's darkest cell lies within one grid diagonal of one of them. An identity:
    the fixed points are the zeros of M~_ωm (A-1.3), where det(M~_ωm M~_ωm^T) = |M~_ωm|² is
    zero, and det ≥ 0 everywhere."""
    t1, t2, det = det_grid
    i, j = np.unravel_index(np.argmin(det), det.shape)
    darkest = np.array([t1[j], t2[i]])
    offsets = [float(np.linalg.norm(wrap(darkest - p.theta))) for p in points]
    at_points = [float(arm.coupling_determinant(p.theta)) for p in points]
    diagonal = float(np.hypot(t1[1] - t1[0], t2[1] - t2[0]))
    holds = (
        bool(points)
        and max(at_points) <= SINGULAR_FRACTION * float(det.max())
        and min(offsets) <= diagonal
    )
    return Comparison.by_construction(
        "dark_area_is_singular",
        "'the most dark area represents the singularities'",
        f"det at the {len(points)} fixed points ≤ "
        + (f"{max(at_points):.1e} kg² m⁴; " if at_points else "—; ")
        + f"darkest cell {min(offsets, default=float('nan')):.3f} rad from a fixed point",
        "",
        holds=holds,
        note="the fixed points are the zeros of M~_ωm, so det is zero there by definition; "
        f"checked: det at every fixed point ≤ {SINGULAR_FRACTION:g} × its maximum and the "
        f"darkest cell within one grid diagonal ({diagonal:.3f} rad) of a fixed point",
    )


def _com_distance_row(argmax: list[float], largest: float, half_step: float) -> Comparison:
    """§3.2.3 'extended-arm configuration s.t. the manipulator CoM is located farthest away':
    geometry, not dynamics. With ψ = 0 the stretched arm (θ = 0) points straight away from the
    base CoM, so the links-only CoM (A-1.6) is farthest there for any masses."""
    return Comparison.by_construction(
        "com_distance_argmax_theta_rad",
        [0.0, 0.0],
        argmax,
        "rad",
        holds=bool(np.max(np.abs(argmax)) <= half_step),
        note="the stretched arm along +x (ψ = 0, A-1.1) puts every link CoM farthest from the "
        f"base CoM; max distance {largest:.3f} m (A-1.6), located within half the grid "
        f"spacing ({half_step:.3g} rad)",
    )


def plot_fig3_3(outcome: Outcome, figure) -> None:
    data = outcome.figure_data
    axes = figure.subplots(1, 2)
    extent = (-np.pi, np.pi, -np.pi, np.pi)
    for ax, key, title, unit in (
        (
            axes[0],
            "det",
            r"(a) $\det(\tilde M_{\omega m}\tilde M_{\omega m}^T)$, r = 1.5 m",
            r"$\det(\tilde M_{\omega m}\tilde M_{\omega m}^T)$ [kg² m⁴]",
        ),
        (axes[1], "distance", "(b) manipulator CoM – base CoM distance, r = 1.5 m", "distance [m]"),
    ):
        image = ax.imshow(data[key], origin="lower", extent=extent, cmap="gray", aspect="equal")
        figure.colorbar(image, ax=ax, label=unit, shrink=0.8)
        for p in data["points"]:
            ax.plot(*p.theta, marker="x", color="red", markersize=6, linestyle="none")
        _torus_axes(ax, title)


#: |M~_ωm| [kg m²] below which a point counts as a zero (its entries are ~1e2 kg m²)
ZERO_RESIDUAL = 1e-6
#: the thesis prints "r ≈ 0.945 m": three decimals, so half a unit of the last one [m]
R_STAR_TOLERANCE = 5e-4


def r_star_row(critical) -> Comparison:
    """The critical attachment distance r* [m] next to the thesis' 'r ≈ 0.945 m' (§3.2.2)."""
    return Comparison.number(
        "r_star_m",
        0.945,
        critical.r_star,
        "m",
        tolerance=R_STAR_TOLERANCE,
        note="§3.2.2 'r ≈ 0.945 m' (three decimals); ours min_θ2 ρ(θ2) by brentq on "
        f"dρ²/dθ2 = 0, θ2 tolerance {critical.theta2_tolerance:g} rad",
    )


def born_at_r_star(critical) -> int:
    """How many distinct degenerate zeros of M~_ωm the bifurcation creates at r* (A-1.5)."""
    arm = ARM.at(critical.r_star)
    born = [classify(arm, theta) for theta in critical.theta]
    zeros = {
        tuple(np.round(p.theta, 9))
        for p in born
        if p.kind == "degenerate" and p.residual <= ZERO_RESIDUAL
    }
    return len(zeros)


def created_row(critical, detail: str, key: str = "fixed_points_created_at_r_star"):
    """§3.2.2 'two fixed points are created' at r ≈ 0.945 m, against our count at r*."""
    born = born_at_r_star(critical)
    return Comparison.number(
        key,
        2,
        born,
        "",
        tolerance=0.0,
        note="§3.2.2 'two fixed points are created' (a count); ours: distinct degenerate zeros "
        f"of M~_ωm at r* = {critical.r_star:.6f} m (A-1.5); {detail}",
    )


REPRODUCTIONS = register_all(
    Reproduction(
        "fig3.1",
        "Fig. 3.1",
        "reactionless vector field of the planar 2-DoF arm attached at the base CoM (r = 0)",
        compute_fig3_1,
        plot_fig3_1,
        (6.5, 6.5),
    ),
    Reproduction(
        "fig3.2",
        "Fig. 3.2",
        "vector field and nullclines (red joint 1, blue joint 2) at r = 0.5, 0.945, 1.5 m",
        compute_fig3_2,
        plot_fig3_2,
        (12.0, 8.5),
    ),
    Reproduction(
        "fig3.3",
        "Fig. 3.3",
        "det(M~_ωm M~_ωm^T) and manipulator–base CoM distance at r = 1.5 m",
        compute_fig3_3,
        plot_fig3_3,
        (11.0, 5.0),
    ),
)
