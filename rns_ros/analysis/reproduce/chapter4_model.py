"""Chapter 4, §4.1: the 7-DoF manipulator model and the structure of its reactionless motion.

* ``table4.1``: link masses m_i [kg] and principal inertia moments [kg m^2] of links 1-7 read from
  our model (Pinocchio's inertias of the URDF ``config/urdf/rns_7dof_arm.urdf``) next to the
  printed Table 4.1, and the manipulator attachment point of §4.1.1.
* ``fig4.2``: the two reactionless motion patterns of §4.1.2: (a) the predominant wrist motion
  theta_dot = [B(theta); E] theta_dot_W, B = -M~_P_omega_m^+ M~_W_omega_m (eq. 4.2), and (b) the
  elbow folding theta_dot = b [n(theta); 0], n spanning ker M~_P_omega_m (eq. 4.3), checked over
  the Fig. 4.1 pose, the satellite-observation start and random configurations.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from rns_ros.analysis.arm_geometry import INFERRED_GEOMETRY, build_model
from rns_ros.analysis.reproduce.registry import (
    Comparison,
    Outcome,
    Reproduction,
    register_all,
    resolution_choice,
)
from rns_ros.analysis.reproduce.scenario_runs import (
    ARM_SCALES,
    default_robot,
    resized_arm,
    thesis_robot,
)
from rns_ros.control.reactionless_path import positioning_null_vector, reactionless_path
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState

#: Table 4.1 as printed: m_i [kg] and (I_xi, I_yi, I_zi) [kg m^2] of links 1-7.
THESIS_MASSES = (30.0, 30.0, 45.0, 40.0, 20.0, 20.0, 25.0)
THESIS_MOMENTS = (
    (0.0671, 0.0671, 0.0851),
    (0.0843, 0.267, 0.267),
    (3.81, 3.81, 0.127),
    (0.113, 2.19, 2.19),
    (0.213, 0.213, 0.0250),
    (0.0250, 0.0292, 0.0292),
    (0.0990, 0.0990, 0.0313),
)
#: §4.1.1: the manipulator attachment point in the base CoM frame [m] (ETS-VII design).
THESIS_ATTACHMENT = (-0.79, -0.29, 1.0)
#: Half a unit of the last printed digit of the masses [kg] and of the attachment's x, y [m]
#: (the strictest of its printed digits).
MASS_TOLERANCE, ATTACHMENT_TOLERANCE = 0.05, 0.005
AXES = ("x", "y", "z")

#: §4.1.2 starting poses [deg]: Fig. 4.1's initial pose and the satellite-observation start.
NAMED_DEG = {
    "initial_fig4_1": (0.0,) * 7,
    "satellite_observation": (-90.0, -30.0, 0.0, -70.0, 180.0, -30.0, 0.0),
}
#: Random configurations (uniform within the URDF position limits) and their seed.
RANDOM_COUNT, QUICK_RANDOM_COUNT, SEED = 200, 20, 20240
#: Thresholds fixed before computing, judged on the median over the random configurations:
#: "<< 1" read as an order of magnitude below 1 for the largest singular value of B [-];
B_NORM_MAX = 0.1
#: joints 1-2 "relatively small": their share of the squared norm below half of the 0.5 an even
#: spread over the four positioning joints gives [-];
SHARE_12_MAX = 0.25
#: "approximately the elbow folding": joint 4 carries most of the squared norm of n [-].
ELBOW_SHARE_MIN = 0.5
#: Snapshot motions from the satellite-observation start: joint 5 turned by this [rad] in (a),
#: the elbow family followed over this arc length [rad] in (b); snapshots per motion.
WRIST_TURN, FOLD_ARC, SNAPSHOTS = math.pi / 2, 1.0, 5


# table 4.1 ----------------------------------------------------------------------------------
def link_inertias(robot: FreeFloatingModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Masses [kg] (n,), rotational inertias about the CoM in the link frames [kg m^2] (n, 3, 3)
    and principal moments [kg m^2] (n, 3, ascending) of the arm's links, from Pinocchio."""
    ids = [robot.model.getJointId(name) for name in robot.joint_names]
    masses = np.array([robot.model.inertias[j].mass for j in ids])
    inertia = np.array([robot.model.inertias[j].inertia for j in ids])
    return masses, inertia, np.linalg.eigvalsh(inertia)


def attachment_point(robot: FreeFloatingModel) -> np.ndarray:
    """Joint 1's origin relative to the base CoM, in base axes [m], shape (3,)."""
    joint = robot.model.getJointId(robot.joint_names[0])
    base = robot.model.parents[joint]
    return robot.model.jointPlacements[joint].translation - robot.model.inertias[base].lever


def printed_tolerance(value: float) -> float:
    """Half a unit of the last digit of ``value`` printed to 3 significant figures."""
    return 0.5 * 10.0 ** (math.floor(math.log10(abs(value))) - 2)


def _input_row(key: str, printed, ours, unit: str, tolerance: float, note: str) -> Comparison:
    """A Table 4.1 value next to ours: an *input* (our model is built from this table), its note
    saying whether ours still matches it within ``tolerance``."""
    gap = float(np.max(np.abs(np.asarray(ours, dtype=float) - np.asarray(printed, dtype=float))))
    check = (
        f"matches within {tolerance:.3g} {unit}"
        if gap <= tolerance
        else f"DIFFERS by {gap:.3g} {unit} (tolerance {tolerance:.3g})"
    )
    return Comparison.input(key, printed, ours, unit, f"{note}; set from this table: {check}")


def table_comparisons(masses, principal, attachment) -> list[Comparison]:
    """Table 4.1 rows, all *inputs* (the model's parameters were set from the table): each m_i
    [kg]; each printed moment [kg m^2] against our principal moment of the same rank (both
    sorted: frame-independent); the attachment point [m]."""
    rows = []
    for i, (printed, ours) in enumerate(zip(THESIS_MASSES, masses, strict=True)):
        rows.append(
            _input_row(
                f"m_{i + 1}_kg",
                printed,
                round(float(ours), 6),
                "kg",
                MASS_TOLERANCE,
                f"Table 4.1, link {i + 1}",
            )
        )
    for i, printed in enumerate(THESIS_MOMENTS):
        rank = np.argsort(printed, kind="stable")
        matched = np.empty(3)
        matched[rank] = np.sort(principal[i])
        for axis, value, ours in zip(AXES, printed, matched, strict=True):
            rows.append(
                _input_row(
                    f"I_{axis}{i + 1}_kgm2",
                    value,
                    float(f"{ours:.6g}"),
                    "kg m^2",
                    printed_tolerance(value),
                    f"Table 4.1, link {i + 1}: our principal moment of the same rank "
                    f"(sorted {np.round(np.sort(principal[i]), 6).tolist()})",
                )
            )
    rows.append(
        _input_row(
            "attachment_m",
            list(THESIS_ATTACHMENT),
            np.round(attachment, 6).tolist(),
            "m",
            ATTACHMENT_TOLERANCE,
            "§4.1.1: joint 1's origin from the base CoM in base axes (URDF joint_1 origin)",
        )
    )
    return rows


def _compute_table4_1(quick: bool) -> Outcome:
    robot = default_robot()
    masses, inertia, principal = link_inertias(robot)
    diagonal = np.einsum("nii->ni", inertia)
    products = float(np.abs(inertia - np.array([np.diag(d) for d in diagonal])).max())
    rotated = [
        i + 1 for i in range(robot.n) if not np.allclose(diagonal[i], THESIS_MOMENTS[i], atol=1e-9)
    ]
    attachment = attachment_point(robot)
    values = {
        "masses_kg": masses.tolist(),
        "moments_link_axes_kgm2": diagonal.tolist(),
        "principal_moments_kgm2": principal.tolist(),
        "max_product_of_inertia_kgm2": products,
        "links_with_axes_permuted": rotated,
        "total_arm_mass_kg": float(masses.sum()),
    }
    choices = (
        "Moments compared by rank (sorted principal moments, frame-independent): our link frames "
        f"put each link's distinct moment along z; links {rotated} list it about another axis "
        f"in the thesis (our largest product of inertia: {products:.1g} kg m^2).",
        "Tolerance of a moment: half a unit of its last printed digit (3 significant figures).",
    )
    settings = {"model": f"{robot.name} (config/urdf/rns_7dof_arm.urdf)", "source": "Pinocchio"}
    data = {"masses": masses, "principal": principal, "diagonal": diagonal}
    return Outcome(
        tuple(table_comparisons(masses, principal, attachment)), values, settings, choices, data
    )


def _plot_table4_1(outcome: Outcome, figure) -> None:
    data = outcome.figure_data
    axes = figure.subplots(1, 2)
    links = np.arange(1, 8)
    axes[0].bar(links - 0.2, THESIS_MASSES, 0.4, label="thesis (Table 4.1)", color="C7")
    axes[0].bar(links + 0.2, data["masses"], 0.4, label="ours (URDF via Pinocchio)", color="C0")
    axes[0].set_xlabel("link i")
    axes[0].set_ylabel("m_i [kg]")
    axes[0].legend(fontsize=7)
    axes[0].grid(alpha=0.3, axis="y")
    printed = np.sort(np.array(THESIS_MOMENTS), axis=1)
    for k in range(3):
        axes[1].semilogy(
            links,
            printed[:, k],
            "s",
            color="C7",
            ms=9,
            mfc="none",
            label="thesis" if k == 0 else None,
        )
        axes[1].semilogy(
            links,
            data["principal"][:, k],
            "o",
            color=f"C{k}",
            ms=4,
            label=f"ours, principal moment {k + 1} (ascending)",
        )
    axes[1].set_xlabel("link i")
    axes[1].set_ylabel("principal inertia moment [kg m^2]")
    axes[1].legend(fontsize=7)
    axes[1].grid(alpha=0.3, which="both")


# fig 4.2 ------------------------------------------------------------------------------------
def coupling(robot: FreeFloatingModel, theta) -> np.ndarray:
    """M~_omega_m of eq. (3.2) at ``theta`` [kg m^2], shape (3, n)."""
    q = robot.configuration(np.asarray(theta, dtype=float))
    return FreeFloatingState.compute(robot, q).coupling_angular_momentum_matrix


def wrist_map(robot: FreeFloatingModel, theta) -> np.ndarray:
    """B = -M~_P_omega_m^+ M~_W_omega_m of eq. (4.2) [-], shape (p, w): the positioning rates
    that cancel the angular momentum of unit wrist rates."""
    return _wrist_map(coupling(robot, theta), robot.subchains)


def _wrist_map(matrix: np.ndarray, chains) -> np.ndarray:
    """:func:`wrist_map` from M~_omega_m (3, n) and the robot's subchains."""
    return -np.linalg.pinv(matrix[:, chains.positioning]) @ matrix[:, chains.wrist]


def structure(robot: FreeFloatingModel, theta) -> dict[str, float]:
    """The §4.1.2 measures at ``theta`` [-]: |B|_2, |M~_W|_2 / |M~_P|_2, the largest share of
    joints 1-2 in a column of B and in n (squared norms), n_4^2, n_3^2, whether |n_4| is the
    largest component of n (1.0 or 0.0), and the smallest singular value of M~_P_omega_m
    [kg m^2]."""
    matrix, chains = coupling(robot, theta), robot.subchains
    b = _wrist_map(matrix, chains)
    n = positioning_null_vector(robot, theta)
    columns = np.sum(b[:2] ** 2, axis=0) / np.maximum(np.sum(b**2, axis=0), 1e-300)
    return {
        "b_norm": float(np.linalg.norm(b, 2)),
        "momentum_ratio": float(
            np.linalg.norm(matrix[:, chains.wrist], 2)
            / np.linalg.norm(matrix[:, chains.positioning], 2)
        ),
        "share12_b": float(columns.max()),
        "share12_n": float(n[0] ** 2 + n[1] ** 2),
        "elbow_share": float(n[3] ** 2),
        "share3_n": float(n[2] ** 2),
        "sigma3_p": float(np.linalg.svd(matrix[:, chains.positioning], compute_uv=False)[-1]),
        "elbow_largest": float(np.argmax(np.abs(n)) == 3),
    }


def random_configurations(robot: FreeFloatingModel, count: int) -> np.ndarray:
    """``count`` configurations uniform within the URDF position limits [rad], (count, n)."""
    rng = np.random.default_rng(SEED)
    return rng.uniform(robot.lower_limits, robot.upper_limits, size=(count, robot.n))


def structure_comparisons(
    named: dict[str, dict], sampled: dict[str, np.ndarray], variants: dict[str, dict] | None = None
) -> list:
    """The §4.1.2 trends, each judged on the median over ``sampled`` (measure -> values over the
    random configurations) against its threshold; ``named`` gives the measures at the named
    poses for the notes, ``variants`` {arm: {measure: median}} the same medians on other arm
    geometries (:func:`geometry_variants`), for the cause of a trend that fails."""
    rows = []
    for key, quote, measure, threshold, below in (
        (
            "wrist_compensation_small",
            "the wrist subchain's angular momentum is 'far smaller' than "
            "the positioning subchain's, which 'can compensate' it with 'small compensating "
            "variations' (§4.1.2): |B|_2 << 1",
            "b_norm",
            B_NORM_MAX,
            True,
        ),
        (
            "joints_1_2_small_wrist",
            "'motions in Joints 1 and 2 will be relatively small' in the "
            "predominant wrist motion (§4.1.2): their share of each column of B",
            "share12_b",
            SHARE_12_MAX,
            True,
        ),
        (
            "joints_1_2_small_elbow",
            "'motions in Joints 1 and 2 will be relatively small' in the "
            "elbow motion (§4.1.2): their share of n",
            "share12_n",
            SHARE_12_MAX,
            True,
        ),
        (
            "elbow_folding",
            "the null motion 'approximately consists of the elbow folding/unfolding "
            "motion' (§4.1.2): joint 4's share of n",
            "elbow_share",
            ELBOW_SHARE_MIN,
            False,
        ),
    ):
        values = sampled[measure]
        median = float(np.median(values))
        worst = float(values.max() if below else values.min())
        passing = float(np.mean(values < threshold if below else values >= threshold))
        sign = "<" if below else ">="
        at = ", ".join(f"{name} {m[measure]:.3g}" for name, m in named.items())
        note = (
            f"median over {values.size} random configurations {median:.3g} (qualitative when "
            f"{sign} {threshold:g}, fixed before computing); worst {worst:.3g}; {passing:.0%} of "
            f"them {sign} {threshold:g}; at {at}"
        )
        if measure != "share12_b":
            sigma = ", ".join(f"{name} {m['sigma3_p']:.2g}" for name, m in named.items())
            note += (
                f"; sigma_3 of M~_P_omega_m [kg m^2]: {sigma}, random median "
                f"{np.median(sampled['sigma3_p']):.2g} (where it nears 0, ker "
                "M~_P_omega_m is 2-D: n is not unique and B is ill-conditioned)"
            )
        if measure == "b_norm":
            note += f"; |M~_W|_2 / |M~_P|_2 median {np.median(sampled['momentum_ratio']):.3g}"
        if measure == "elbow_share":
            note += (
                f"; |n_4| is the largest component in {np.mean(sampled['elbow_largest']):.0%}; "
                f"joint 3's median share {np.median(sampled['share3_n']):.3g}"
            )
        ours = {"median": round(median, 4), "worst": round(worst, 4)}
        ours |= {name: round(m[measure], 4) for name, m in named.items()}
        holds = median < threshold if below else median >= threshold
        if not holds:
            note += "; " + _geometry_cause(variants, measure, threshold, below)
        rows.append(Comparison.trend(key, quote, ours, "", holds=holds, note=note))
    return rows


def _geometry_cause(variants: dict | None, measure: str, threshold: float, below: bool) -> str:
    """Whether another arm geometry meets a failed trend: the cause, from those medians."""
    text = "the arm geometry is identified, not printed (docs/arm_identification.md)"
    if not variants:
        return text + ", so the cause is open"
    medians = {name: table[measure] for name, table in variants.items()}
    meets = [name for name, v in medians.items() if (v < threshold if below else v >= threshold)]
    text += "; the same median on other geometries (geometry_variants): " + ", ".join(
        f"{name} {v:.3g}" for name, v in medians.items()
    )
    if meets:
        return text + f": it holds on {', '.join(meets)}, so it is set by the arm's geometry"
    return text + (
        ": none meets it, so neither these link lengths nor the inferred layout explain it; "
        "the configurations the thesis means (it names none) are open"
    )


def geometry_variants(thetas: np.ndarray) -> dict[str, dict[str, float]]:
    """Median of each :func:`structure` measure over ``thetas`` on the first, inferred geometry
    (straight and coaxial at theta = 0, no lateral offsets) and on the identified arm with the
    upper arm and forearm 0.9x / 1.1x as long (:func:`resized_arm`)."""
    arms = {"inferred": build_model(INFERRED_GEOMETRY)}
    arms |= {f"links 3-4 {scale:g}x": resized_arm(scale) for scale in ARM_SCALES}
    medians = {}
    for name, robot in arms.items():
        rows = [structure(robot, theta) for theta in thetas]
        medians[name] = {key: float(np.median([row[key] for row in rows])) for key in rows[0]}
    return medians


def wrist_motion(robot: FreeFloatingModel, theta0, steps: int = 60) -> np.ndarray:
    """Eq. (4.2) from ``theta0`` with theta_dot_W = e_1 (joint 5) over :data:`WRIST_TURN` [rad]:
    RK4 nodes of d theta / d s = [B(theta) e_1; e_1], shape (steps + 1, n) [rad]."""
    chains = robot.subchains
    direction = np.zeros(chains.wrist.size)
    direction[0] = 1.0

    def rate(theta):
        out = np.zeros(robot.n)
        out[chains.positioning] = wrist_map(robot, theta) @ direction
        out[chains.wrist] = direction
        return out

    h = WRIST_TURN / steps
    nodes = [np.asarray(theta0, dtype=float)]
    for _ in range(steps):
        theta = nodes[-1]
        k1 = rate(theta)
        k2 = rate(theta + 0.5 * h * k1)
        k3 = rate(theta + 0.5 * h * k2)
        k4 = rate(theta + h * k3)
        nodes.append(theta + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4))
    return np.array(nodes)


def fold_motion(robot: FreeFloatingModel, theta0) -> np.ndarray:
    """Eq. (4.3) from ``theta0``: the elbow family followed towards theta_4 = -pi over
    :data:`FOLD_ARC` [rad] of arc length; :data:`SNAPSHOTS` configurations [rad], (k, n)."""
    path = reactionless_path(robot, theta0, -math.pi, max_arc=FOLD_ARC, stop_at_turning_point=False)
    return np.array([path.at(s)[0] for s in np.linspace(0.0, path.length, SNAPSHOTS)])


@functools.cache
def _structure(quick: bool) -> tuple[dict, dict, dict]:
    robot = thesis_robot()
    named = {name: structure(robot, np.deg2rad(deg)) for name, deg in NAMED_DEG.items()}
    thetas = random_configurations(default_robot(), QUICK_RANDOM_COUNT if quick else RANDOM_COUNT)
    rows = [structure(robot, theta) for theta in thetas]
    sampled = {key: np.array([row[key] for row in rows]) for key in rows[0]}
    return named, sampled, geometry_variants(thetas)


def _compute_fig4_2(quick: bool) -> Outcome:
    robot = thesis_robot()
    named, sampled, variants = _structure(quick)
    start = np.deg2rad(NAMED_DEG["satellite_observation"])
    wrist = wrist_motion(robot, start, 20 if quick else 60)
    fold = fold_motion(robot, start)
    picks = np.linspace(0, len(wrist) - 1, SNAPSHOTS).round().astype(int)
    values = {
        "named": named,
        "random_median": {key: float(np.median(v)) for key, v in sampled.items()},
        "random_max": {key: float(v.max()) for key, v in sampled.items()},
        "random_min": {key: float(v.min()) for key, v in sampled.items()},
        "geometry_variants": variants,
        "wrist_motion_theta_deg": np.rad2deg(wrist[picks]).round(3).tolist(),
        "fold_motion_theta_deg": np.rad2deg(fold).round(3).tolist(),
    }
    settings = {
        "model": f"{robot.name} (config/urdf/rns_7dof_arm.urdf), no joint limits",
        "random_configurations": int(sampled["b_norm"].size),
        "seed": SEED,
        "thresholds": {
            "b_norm_max": B_NORM_MAX,
            "share12_max": SHARE_12_MAX,
            "elbow_share_min": ELBOW_SHARE_MIN,
        },
        "wrist_turn_deg": math.degrees(WRIST_TURN),
        "fold_arc_rad": FOLD_ARC,
    }
    choices = (
        "Positioning subchain P = joints 1-4, wrist W = joints 5-7 (§4.1.2); B by the "
        "Moore-Penrose pseudoinverse of M~_P_omega_m (eq. 4.2), n its unit null vector (4.3).",
        "Shares are of squared norms: joints 1-2 in each column of B (the largest of the three "
        "columns per configuration) and in n; joint 4's share is n_4^2, joint 3's n_3^2.",
        "Random configurations uniform within the URDF position limits (+-2 pi), fixed seed; each "
        "trend is judged on their median against a threshold fixed before computing.",
        resolution_choice(
            quick,
            f"{QUICK_RANDOM_COUNT} random configurations",
            f"{RANDOM_COUNT} random configurations",
        ),
    )
    points = {
        "wrist": [robot.skeleton(robot.configuration(t)) for t in wrist[picks]],
        "fold": [robot.skeleton(robot.configuration(t)) for t in fold],
    }
    data = {"points": points, "sampled": sampled}
    comparisons = structure_comparisons(named, sampled, variants)
    return Outcome(tuple(comparisons), values, settings, choices, data)


def _skeletons(ax, points, title: str) -> None:
    for k, skeleton in enumerate(points):
        ax.plot(*skeleton.T, "-o", color=f"C{k}", ms=2, label=f"snapshot {k + 1}")
    ax.scatter([0.0], [0.0], [0.0], marker="s", color="k", s=30)
    ax.set_xlabel("x [m]", fontsize=7)
    ax.set_ylabel("y [m]", fontsize=7)
    ax.set_zlabel("z [m]", fontsize=7)
    ax.tick_params(labelsize=6)
    ax.set_title(title, fontsize=9)
    ax.set_box_aspect(np.ptp(np.vstack(points), axis=0) + 0.2)


def _plot_fig4_2(outcome: Outcome, figure) -> None:
    data = outcome.figure_data
    grid = figure.add_gridspec(2, 4, height_ratios=(1.6, 1.0))
    turn = f"(a) predominant wrist motion: joint 5 +{math.degrees(WRIST_TURN):.0f} deg"
    _skeletons(figure.add_subplot(grid[0, :2], projection="3d"), data["points"]["wrist"], turn)
    fold = f"(b) elbow folding: {FOLD_ARC:g} rad of arc along n"
    _skeletons(figure.add_subplot(grid[0, 2:], projection="3d"), data["points"]["fold"], fold)
    sampled = data["sampled"]
    for k, (measure, threshold, label) in enumerate(
        (
            ("b_norm", B_NORM_MAX, "|B|_2 [-]"),
            ("share12_b", SHARE_12_MAX, "joints 1-2 share of a column of B [-]"),
            ("share12_n", SHARE_12_MAX, "joints 1-2 share of n [-]"),
            ("elbow_share", ELBOW_SHARE_MIN, "joint 4 share of n, n_4^2 [-]"),
        )
    ):
        ax = figure.add_subplot(grid[1, k])
        values = sampled[measure]
        if measure == "b_norm":  # spans orders of magnitude near rank drops of M~_P_omega_m
            ax.hist(values, bins=np.geomspace(values.min(), values.max(), 25), color="C0")
            ax.set_xscale("log")
        else:
            ax.hist(values, bins=25, color="C0", alpha=0.8)
        ax.axvline(threshold, color="k", ls="--", lw=1, label="threshold")
        ax.axvline(np.median(sampled[measure]), color="C3", lw=1.2, label="median")
        ax.set_xlabel(label, fontsize=8)
        ax.set_ylabel("random configurations", fontsize=8)
        ax.legend(fontsize=6)
        ax.grid(alpha=0.3)


REPRODUCTIONS = register_all(
    Reproduction(
        "table4.1",
        "Table 4.1",
        "dynamic model parameters: link masses and principal inertia moments",
        _compute_table4_1,
        _plot_table4_1,
        (10.0, 4.5),
    ),
    Reproduction(
        "fig4.2",
        "Fig. 4.2",
        "reactionless motion patterns: predominant wrist motion and elbow folding",
        _compute_fig4_2,
        _plot_fig4_2,
        (13.0, 8.0),
    ),
)
