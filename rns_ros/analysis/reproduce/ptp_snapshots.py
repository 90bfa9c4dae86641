"""Snapshots of the point-to-point motions (Figs. 4.11, 4.13-4.15): the arm's stick figures at
chosen times, and what they show (the elbow folds, the folded transfer, the joint-space line's
base disturbance), computed from a recorded :class:`~rns_ros.analysis.ptp_runs.PtpRun`. Where
the plan itself puts the arm (folded in Phase II, unfolded along the joint-space line) is *by
construction*; where the null vector moves the joints and where the base moves are trends."""

from __future__ import annotations

import math

import numpy as np

from rns_ros.analysis.ptp_runs import PtpRun
from rns_ros.analysis.reproduce import plotting as plot
from rns_ros.analysis.reproduce.registry import Comparison, Outcome
from rns_ros.analysis.reproduce.scenario_runs import thesis_robot
from rns_ros.control.ptp import PtpPlan

#: Joint 4 (the elbow) in zero-based joint order.
ELBOW = 3
#: Every how many recorded samples (0.01 s each) the reach is evaluated.
REACH_STRIDE = 10


def phase_at(plan: PtpPlan, t: float) -> str:
    """Name of the phase ``plan`` is in at ``t`` [s] (a phase's end belongs to the next one)."""
    return next((p.name for p in plan.phases if t < p.end), plan.phases[-1].name)


def snapshots(run: PtpRun, times: np.ndarray) -> dict:
    """Plot data of :func:`plot_snapshots`: the reference configurations of ``run`` at
    ``times`` [s] as stick figures (each (n + 2, 3) [m]), labelled with time and phase."""
    robot = thesis_robot()
    points = [robot.skeleton(robot.configuration(run.plan.sample(t).theta)) for t in times]
    labels = [f"t = {t:.1f} s ({phase_at(run.plan, t)})" for t in times]
    return {"run": run, "points": points, "labels": labels}


def snapshot_times(plan: PtpPlan) -> np.ndarray:
    """Each phase's start and middle, and the end [s]."""
    times = [t for p in plan.phases for t in (p.start, 0.5 * (p.start + p.end))]
    return np.array([*times, plan.duration])


def reach(run: PtpRun) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] (k,) and reach [m] (k,): distance from the joint 1 origin to the camera, every
    :data:`REACH_STRIDE` samples of ``run`` and at its end (small = folded arm)."""
    robot = thesis_robot()
    index = np.unique(np.r_[np.arange(0, len(run.t), REACH_STRIDE), len(run.t) - 1])
    reach = []
    for theta in run.theta[index]:
        points = robot.skeleton(robot.configuration(theta))
        reach.append(float(np.linalg.norm(points[-1] - points[1])))
    return run.t[index], np.array(reach)


def joint_travel(run: PtpRun) -> dict[str, np.ndarray]:
    """{phase: sum of |delta theta_i| over the phase [rad], shape (n,)} of the recorded run."""
    travel = {}
    for phase in run.plan.phases:
        inside = (run.t >= phase.start - 1e-9) & (run.t <= phase.end + 1e-9)
        travel[phase.name] = np.abs(np.diff(run.theta[inside], axis=0)).sum(axis=0)
    return travel


def elbow_share_row(travel: dict[str, np.ndarray], folds: tuple[str, ...]) -> Comparison:
    """The reactionless ``folds`` are the elbow folds: joint 4's share of the joint travel there
    exceeds its share in Phase II (the transfer between the folded configurations) [-]."""
    share = {name: float(t[ELBOW] / t.sum()) for name, t in travel.items()}
    holds = all(share[name] > share["II"] for name in folds)
    facts = "; ".join(
        f"Phase {name}: joint 4 travels {math.degrees(t[ELBOW]):.1f} deg, {share[name]:.0%} of "
        f"the joints' {math.degrees(t.sum()):.1f} deg (largest: joint {int(np.argmax(t)) + 1})"
        for name, t in travel.items()
    )
    return Comparison.trend(
        "elbow_share_of_joint_travel",
        f"Phase {' and '.join(folds)}: reactionless motion to/from the folded elbow theta_4 = -pi "
        "(§4.4.2); Phase II transfers between the folds",
        {name: round(value, 3) for name, value in share.items()},
        "",
        holds=holds,
        note=facts if holds else f"{facts}; the cause is open",
    )


def folded_row(
    times: np.ndarray,
    reach: np.ndarray,
    phase,
    ends: dict[str, float],
    theta4_deg: tuple[float, float],
) -> Comparison:
    """Phase II runs folded: its largest reach is below the reach at each of ``ends``
    ({name: time [s]}) [m]. By construction: the plan joins two folded configurations by a joint
    line in Phase II (``theta4_deg``: theta_4 at its start and end [deg]), so the reach there is
    the forward kinematics of a path folded by design; the row still checks it."""
    inside = (times >= phase.start) & (times <= phase.end)
    largest = float(reach[inside].max())
    at = {name: float(np.interp(t, times, reach)) for name, t in ends.items()}
    note = (
        "by construction: the plan starts Phase II at a folded configuration (the end of a fold "
        "at theta_4 = -pi or its most-folded turning point, or the stowed pose) and ends it at "
        f"the next fold, here theta_4 {theta4_deg[0]:.1f} -> {theta4_deg[1]:.1f} deg along a "
        "joint line, so the arm is folded there by design (§4.4.1: 'a folded arm configuration "
        "... was employed in Phase II'); joint 1 -> camera distance: "
        f"up to {largest:.3f} m in Phase II; "
        + ", ".join(f"{value:.3f} m at the {name}" for name, value in at.items())
    )
    return Comparison.by_construction(
        "folded_in_phase_II_m",
        "Phase II uses the folded configuration, which shortens the path of the arm's CoM (§4.4.1)",
        {"phase_II_max": round(largest, 4), **{name: round(v, 4) for name, v in at.items()}},
        "m",
        holds=largest < min(at.values()),
        note=note,
    )


def theta4_over(run: PtpRun, phase) -> tuple[float, float]:
    """theta_4 of ``run`` at the start and the end of ``phase`` [deg]."""
    elbow = run.theta[:, ELBOW]
    return (
        math.degrees(float(np.interp(phase.start, run.t, elbow))),
        math.degrees(float(np.interp(phase.end, run.t, elbow))),
    )


def phase_lines(ax, plan: PtpPlan, last: bool = False) -> None:
    """Dashed lines at the phase ends of ``plan`` (the last one too when ``last``)."""
    phases = plan.phases if last else plan.phases[:-1]
    plot.event_lines(ax, [phase.end for phase in phases], alpha=0.6)


def plot_snapshots(outcome: Outcome, figure) -> None:
    """Figs. 4.11/4.13-4.15: stick figures of the arm (base at the origin, its attitude at t = 0)
    at the snapshot times in three projections [m], and the run's base deviation [deg]."""
    data = outcome.figure_data
    axes = figure.subplots(2, 2)
    colors = [f"C{i}" for i in range(len(data["points"]))]
    for ax, (i, j), label in (
        (axes[0, 0], (0, 2), ("x [m]", "z [m]")),
        (axes[0, 1], (0, 1), ("x [m]", "y [m]")),
        (axes[1, 0], (1, 2), ("y [m]", "z [m]")),
    ):
        for points, color, text in zip(data["points"], colors, data["labels"], strict=True):
            ax.plot(points[:, i], points[:, j], "-o", color=color, ms=3, label=text)
        ax.plot(0.0, 0.0, "ks", ms=8)
        ax.set_xlabel(label[0])
        ax.set_ylabel(label[1])
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    run = data["run"]
    axes[1, 1].plot(run.t, np.rad2deg(run.base_deviation))
    phase_lines(axes[1, 1], run.plan)
    plot.time_axes(axes[1, 1], "base attitude deviation [deg]")
    axes[1, 1].grid(alpha=0.3)


def baseline_rows(
    late_change: dict, peak: dict, reach: dict, threshold: float
) -> tuple[Comparison, ...]:
    """Fig. 4.15 against Fig. 4.14 over the same times: the joint-space line keeps disturbing the
    base while the partial deployment is reactionless (``late_change``: change of the base
    deviation over the partial's Phase III [deg]; ``peak``: max deviation [deg]), and it swings
    the arm out while the partial one turns it folded (``reach``: mean reach over the partial's
    Phase II [m]; by construction: the forward kinematics of the two commanded paths); each
    {"partial_reactionless": ..., "baseline": ...}; ``threshold``: the share of the peak [-]
    above which the baseline still moves the base."""
    share = late_change["baseline"] / peak["baseline"]
    moving = (
        f"over the partial's Phase III the baseline's deviation changes by "
        f"{late_change['baseline']:.3f} deg ({share:.0%} of its {peak['baseline']:.3f} deg peak; "
        f"qualitative above {threshold:g}), the partial's by "
        f"{late_change['partial_reactionless']:.1e} deg"
    )
    swing = (
        "by construction: the reach is the forward kinematics of the two commanded paths: the "
        "partial deployment's Phase II joins the stowed fold (theta_4 = -180 deg) to the next "
        "fold, the joint-space line turns theta_4 straight towards the goal's -300 deg and so "
        "unfolds the elbow; mean joint 1 -> camera distance over the partial's Phase II: "
        f"baseline {reach['baseline']:.3f} m, partial {reach['partial_reactionless']:.3f} m"
    )
    extended = reach["baseline"] > reach["partial_reactionless"]
    return (
        Comparison.trend(
            "base_moves_throughout_deg",
            "'the joint space controller with straight line trajectory' (§4.5.2) is not "
            "reactionless: the base moves also where the partial deployment is reactionless",
            {k: round(v, 6) for k, v in late_change.items()},
            "deg",
            holds=share > threshold,
            note=moving if share > threshold else f"{moving}; the cause is open",
        ),
        Comparison.by_construction(
            "extended_while_turning_m",
            "the partial deployment turns the arm folded (its Phase II from the stowed, folded "
            "pose); the straight joint line unfolds the elbow meanwhile (§4.5.2, Figs. 4.14/4.15)",
            {k: round(v, 4) for k, v in reach.items()},
            "m",
            holds=extended,
            note=swing,
        ),
    )
