"""Chapter 3 results: the planar reactionless field (Fig. 3.1), nullclines and fixed points
(Fig. 3.2), the coupling-inertia determinant and CoM distance (Fig. 3.3), and the bifurcation
in r (§3.2.2). All numbers come from :mod:`rns_ros.analysis.planar_field` (closed form).

Importing this module registers four results: ``fig3.1``, ``fig3.2``, ``fig3.3`` and
``bifurcation``; :data:`REPRODUCTIONS` holds them by id.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rns_ros.analysis.planar_field import (
    PlanarArm,
    com_distance_map,
    critical_distance,
    det_map,
    fixed_point_curve,
    fixed_points,
    integral_curve,
    torus_grid,
    torus_segments,
)
from rns_ros.analysis.reproduce import plotting as plot
from rns_ros.analysis.reproduce.registry import (
    Comparison,
    Outcome,
    Reproduction,
    Status,
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


def _model_settings(arm: PlanarArm = ARM) -> dict:
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


def _points_json(points, r: float) -> list[dict]:
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
        Comparison(
            "rotational_symmetry_joint_1",
            "field independent of θ1 ('rotational symmetry w.r.t. Joint 1')",
            f"max |n(θ1, θ2) − n(−π, θ2)| = {symmetry:.1e}",
            "",
            Status.EXACT,
            f"over a {check_n}² grid; M~_ωm at r = 0 has no θ1 term (closed form)",
        ),
        Comparison(
            "joint_2_dominant",
            "reactionless motion 'predominantly composed of Joint 2 motion'",
            f"min |n2| = {min_n2:.3f}, max |n1| = {max_n1:.3f}",
            "",
            Status.QUALITATIVE,
            "a claim in words; |n2| ≥ 0.95 everywhere (thesis_rest [V]: 0.952 / 0.306)",
        ),
        Comparison(
            "fixed_point_count",
            0,
            len(points),
            "",
            Status.EXACT if not points else Status.NOT_REPRODUCIBLE,
            f"'does not have any fixed points'; min |M~_ωm| = {coupling_norm.min():.2f} kg m²",
        ),
    )
    values = {
        "min_abs_n2": min_n2,
        "max_abs_n1": max_n1,
        "min_coupling_norm_kg_m2": float(coupling_norm.min()),
        "fixed_points": _points_json(points, arm.attach_distance),
    }
    settings = {
        "attach_distance_r_m": arm.attach_distance,
        **_model_settings(arm),
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
    near = [p for p in panels[1]["points"]]
    pair_gap = (
        float(min(np.linalg.norm(a.theta - b.theta) for a in near for b in near if a is not b))
        if len(near) > 1
        else None
    )
    far = panels[2]["points"]
    far_gap = float(min(np.linalg.norm(a.theta - b.theta) for a in far for b in far if a is not b))
    comparisons = (
        Comparison(
            "fixed_points_r0_5",
            0,
            counts[0.5],
            "",
            Status.EXACT,
            f"'no fixed point … Joint 2 never stops': min M~_1 = {minima_m1[0.5]:.1f} kg m² > 0, "
            "so there is no blue nullcline at r = 0.5 m",
        ),
        _r_star_row(critical),
        Comparison(
            "fixed_points_created_at_r_star",
            2,
            f"2 degenerate at r* (θ = ±({critical.theta[0][0]:.4f}, "
            f"{critical.theta[0][1]:.4f}) rad); {counts[0.945]} at r = 0.945 m in two pairs "
            f"{pair_gap:.3f} rad apart",
            "",
            Status.QUALITATIVE,
            "A-1.5: 0.945 m lies 1.2e-4 m above r*, where each of the two saddle-nodes has "
            "already split into a saddle and a node; at plot scale each pair is one point",
        ),
        Comparison(
            "separation_r1_5",
            "the created fixed points separate",
            f"{counts[1.5]} fixed points, nearest pair {far_gap:.2f} rad apart",
            "",
            Status.QUALITATIVE,
            "each saddle-node pair has separated into a saddle and a focus",
        ),
    )
    values = {
        "fixed_point_counts": {f"{r}": counts[r] for r in FIG3_2_DISTANCES},
        "fixed_points": [
            point for panel in panels for point in _points_json(panel["points"], panel["r"])
        ],
        "min_M1_kg_m2": {f"{r}": minima_m1[r] for r in FIG3_2_DISTANCES},
    }
    settings = {
        "attach_distances_r_m": list(FIG3_2_DISTANCES),
        **_model_settings(),
        "arrow_grid": [arrows_n, arrows_n],
        "nullcline_contour_grid": [contour_n, contour_n],
    }
    choices = tuple(CHOICES[k] for k in ("A-1.1", "A-1.2", "A-1.3", "A-1.4", "A-1.5", "I_i"))
    return Outcome(comparisons, values, settings, choices, {"panels": panels})


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
    point_distances = [float(arm.manipulator_com_distance(p.theta)) for p in points]
    point_dets = [float(arm.coupling_determinant(p.theta)) for p in points]
    median = float(np.median(distance))
    comparisons = (
        Comparison(
            "det_argmax_theta_rad",
            [0.0, 0.0],
            argmax,
            "rad",
            Status.EXACT,
            f"'maximum value at θ = 0'; max det = {det[i, j]:.5g} kg² m⁴ on a {n}² grid "
            "containing θ = 0",
        ),
        Comparison(
            "com_distance_argmax_theta_rad",
            [0.0, 0.0],
            [float(t1[dj]), float(t2[di])],
            "rad",
            Status.EXACT,
            f"'manipulator CoM … farthest away' at the extended arm; {distance.max():.3f} m "
            "(A-1.6)",
        ),
        Comparison(
            "det_large_where_distance_large",
            "determinant large whenever the distance is large",
            f"Pearson correlation of the two maps {correlation:.2f}",
            "",
            Status.QUALITATIVE,
            "a claim in words; the maps agree in shape, not in detail",
        ),
        Comparison(
            "fixed_points_in_small_distance_area",
            "no fixed point where the distance is large",
            f"fixed points at CoM distance {min(point_distances):.2f}–"
            f"{max(point_distances):.2f} m, below the map median {median:.2f} m",
            "",
            Status.QUALITATIVE,
            "a claim in words",
        ),
        Comparison(
            "dark_area_is_singular",
            "'the most dark area represents the singularities'",
            f"det at the {len(points)} fixed points ≤ {max(point_dets):.1e} kg² m⁴",
            "",
            Status.EXACT,
            "the minima of the det map are the zeros of M~_ωm",
        ),
    )
    values = {
        "det_max_kg2_m4": float(det[i, j]),
        "det_argmax_theta_rad": argmax,
        "com_distance_max_m": float(distance.max()),
        "com_distance_min_m": float(distance.min()),
        "pearson_det_distance": correlation,
        "fixed_points": _points_json(points, FIG3_3_DISTANCE),
    }
    settings = {
        "attach_distance_r_m": FIG3_3_DISTANCE,
        **_model_settings(),
        "map_grid": [n, n],
    }
    return Outcome(
        comparisons,
        values,
        settings,
        (CHOICES["A-1.1"], CHOICES["A-1.6"], CHOICES["I_i"]),
        {"t1": t1, "t2": t2, "det": det, "distance": distance, "points": points},
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


# --- bifurcation ------------------------------------------------------------------------------
BIFURCATION_DISTANCES = (0.946, 0.95, 1.0, 1.5, 3.0, 10.0, 100.0)


def compute_bifurcation(quick: bool) -> Outcome:
    """r* and the fixed points above it; the whole branch from the closed-form curve ρ(θ2)."""
    critical = critical_distance(ARM)
    records = []
    for r in BIFURCATION_DISTANCES:
        records += _points_json(fixed_points(ARM.at(r)), r)
    curve_n = 400 if quick else 4000
    s = np.linspace(1e-3, np.pi - 1e-3, curve_n)
    rho, theta1 = fixed_point_curve(ARM, s)
    far = [p for p in records if p["r_m"] == BIFURCATION_DISTANCES[-1]]
    far_theta2 = sorted(abs(p["theta_rad"][1]) for p in far)
    far_theta1 = sorted(abs(p["theta_rad"][0]) for p in far)
    counts = {r: sum(p["r_m"] == r for p in records) for r in BIFURCATION_DISTANCES}
    comparisons = (
        _r_star_row(critical),
        Comparison(
            "fixed_points_created",
            2,
            "2 degenerate at r*; 4 for every r > r* tried",
            "",
            Status.QUALITATIVE,
            "A-1.5: the thesis counts the created pair and does not state the total above r*",
        ),
        Comparison(
            "limit_theta2_rad",
            "two → θ2 = 0, the rest → θ2 = ±π as r → ∞",
            f"at r = {BIFURCATION_DISTANCES[-1]:g} m: |θ2| = "
            + ", ".join(f"{v:.4f}" for v in far_theta2),
            "rad",
            Status.EXACT,
            f"|θ2| → 0 and → π like 1/r; also |θ1| → π/2 ({far_theta1[0]:.4f}, "
            f"{far_theta1[-1]:.4f} at r = {BIFURCATION_DISTANCES[-1]:g} m)",
        ),
    )
    values = {
        "r_star_m": critical.r_star,
        "r_star_theta_rad": critical.theta.tolist(),
        "fixed_point_counts": {f"{r:g}": counts[r] for r in BIFURCATION_DISTANCES},
        "fixed_points": records,
    }
    settings = {
        **_model_settings(),
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
    Reproduction(
        "bifurcation",
        "§3.2.2",
        "fixed points of the reactionless field versus the attachment distance r",
        compute_bifurcation,
        plot_bifurcation,
        (11.0, 5.0),
    ),
)


def _r_star_row(critical) -> Comparison:
    """The critical attachment distance r* [m] next to the thesis' 'r ≈ 0.945 m' (§3.2.2)."""
    return Comparison(
        "r_star_m",
        0.945,
        critical.r_star,
        "m",
        Status.EXACT,
        "thesis 'r ≈ 0.945 m'; ours min_θ2 ρ(θ2) by brentq on dρ²/dθ2 = 0, θ2 tolerance "
        f"{critical.theta2_tolerance:g} rad (r* error ~1e-15 m): equal to the thesis' "
        "three digits",
    )
