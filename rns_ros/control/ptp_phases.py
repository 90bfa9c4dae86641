"""Reactionless point-to-point planners (thesis sections 4.4.1, 4.5): 3-phase, deployments.

* 3-phase: Phase I follows the reactionless elbow path from the start towards the fold
  theta_4 = ``fold_angle`` (FA-1); Phase III is the reactionless path from the goal towards the
  fold (FA-2), played backwards; Phase II is a quintic joint-space line FA-1 -> FA-2, the only
  phase that is not reactionless.
* partial deployment (section 4.5.2): Phase II from the stowed configuration to FA-2 of the
  goal, then Phase III.
* full deployment (section 4.5.1): one reactionless path from the stowed configuration.

A fold ends where theta_4 reaches ``fold_angle`` or at the first turning point where theta_4
turns back away from it (the most-folded configuration the path reaches), whichever comes first.
"""

from __future__ import annotations

import math

import numpy as np

from rns_ros.control.ptp import (
    PathSegment,
    PhaseInfo,
    PtpMethod,
    PtpPlan,
    PtpSettings,
    QuinticLine,
    check_configuration,
    line_duration,
    path_duration,
    stretch_note,
)
from rns_ros.control.reactionless_path import NullVector, ReactionlessPath, reactionless_path
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import positive


def _fold_note(name: str, path: ReactionlessPath, target: float) -> str:
    reached = math.degrees(float(path.end[3]))
    turns = ", ".join(f"{math.degrees(v):.1f}" for v in path.turning_points)
    if path.reached:
        text = f"fold {name}: theta_4 reaches {math.degrees(target):.1f} deg"
    elif path.turning_points:
        kind = (
            "smooth turning point"
            if path.turn_kinks[-1] < 0.1
            else f"turning point at a near rank drop of M~_P (tangent swings by "
            f"{path.turn_kinks[-1]:.2f} in one step)"
        )
        text = (
            f"fold {name}: {kind} at theta_4 = {reached:.1f} deg before "
            f"{math.degrees(target):.1f} deg; the fold ends there (most-folded configuration)"
        )
    else:
        text = f"fold {name}: arc limit reached at theta_4 = {reached:.1f} deg"
    extra = f"; turning points passed: {turns} deg" if path.turning_points and path.reached else ""
    return text + f" (arc {path.length:.3f} rad, min |n4| {path.min_n4:.3f})" + extra


def _fold(robot, theta, settings, name, nominal, reverse):
    path = reactionless_path(
        robot,
        theta,
        settings.fold_angle,
        step=settings.path_step,
        max_arc=settings.max_arc,
    )
    duration = path_duration(robot, path, positive(nominal, f"phase {name} duration", "[s]"))
    segment = PathSegment(path, duration, NullVector(robot), reverse)
    notes = [_fold_note(name, path, settings.fold_angle), *stretch_note(name, nominal, duration)]
    return path, segment, duration, notes


def plan_three_phase(
    robot: FreeFloatingModel, start: np.ndarray, goal: np.ndarray, settings: PtpSettings
) -> PtpPlan:
    """The 3-phase method (section 4.4.1) from ``start`` to ``goal`` [rad] (n,), both checked:
    fold I from the start, the quintic line FA-1 -> FA-2, fold III from the goal played backwards.
    """
    d1, d2, d3 = settings.phase_durations
    path1, seg1, t1, notes1 = _fold(robot, start, settings, "I", d1, reverse=False)
    path3, seg3, t3, notes3 = _fold(robot, goal, settings, "III", d3, reverse=True)
    fa1, fa2 = path1.end, path3.end
    nominal2 = positive(d2, "phase II duration", "[s]")
    t2 = line_duration(robot, fa2 - fa1, nominal2)
    phases = [
        PhaseInfo("I", 0.0, t1, True, float(fa1[3])),
        PhaseInfo("II", t1, t1 + t2, False, None),
        PhaseInfo("III", t1 + t2, t1 + t2 + t3, True, float(fa2[3])),
    ]
    notes = [*notes1, *notes3, *stretch_note("II", nominal2, t2)]
    segments = [seg1, QuinticLine(fa1, fa2, t2), seg3]
    return PtpPlan(PtpMethod.THREE_PHASE, phases, segments, notes, goal, start, settings.elbow_gain)


def plan_partial_deployment(
    robot: FreeFloatingModel, theta_stowed, theta_goal, settings: PtpSettings | None = None
) -> PtpPlan:
    """Partial reactionless deployment (section 4.5.2): Phase II joint-space line from the stowed
    configuration to the fold FA-2 of the goal, then Phase III, the reversed reactionless path from
    FA-2 to the goal (A-2.11/A-2.12/A-2.13: Phase II interpolates all joints, wrist included).

    Raises:
        InputError: bad stowed or goal configuration (names the joint).
    """
    settings = settings or PtpSettings()
    start = check_configuration(robot, theta_stowed, "theta_stowed")
    goal = check_configuration(robot, theta_goal, "theta_goal")
    _, d2, d3 = settings.phase_durations
    path3, seg3, t3, notes3 = _fold(robot, goal, settings, "III", d3, reverse=True)
    nominal2 = positive(d2, "phase II duration", "[s]")
    t2 = line_duration(robot, path3.end - start, nominal2)
    phases = [
        PhaseInfo("II", 0.0, t2, False, None),
        PhaseInfo("III", t2, t2 + t3, True, float(path3.end[3])),
    ]
    notes = [*notes3, *stretch_note("II", nominal2, t2)]
    segments = [QuinticLine(start, path3.end, t2), seg3]
    return PtpPlan(PtpMethod.THREE_PHASE, phases, segments, notes, goal, start, settings.elbow_gain)


def plan_deployment(
    robot: FreeFloatingModel, theta_stowed, settings: PtpSettings | None = None
) -> PtpPlan:
    """Full reactionless deployment from ``theta_stowed`` (section 4.5.1).

    The elbow path runs towards theta_4 = theta_4(0) + deploy_rate * deploy_duration (2.349 rad
    from the stowed -pi with the thesis' 0.183 rad/s x 30 s), or to its first turning point.
    Timing: a quintic in arc length over ``deploy_duration`` (stretched to the velocity limits),
    where the thesis holds theta_dot_4 constant: eq. (4.17) divides by n_4, and the quintic
    starts and ends at rest. The mean theta_dot_4 is noted.

    Raises:
        InputError: bad stowed configuration (names the joint).
    """
    settings = settings or PtpSettings()
    start = check_configuration(robot, theta_stowed, "theta_stowed")
    nominal = positive(settings.deploy_duration, "deploy_duration", "[s]")
    target = float(start[3] + settings.deploy_rate * nominal)
    path = reactionless_path(
        robot, start, target, step=settings.path_step, max_arc=max(settings.max_arc, 25.0)
    )
    duration = path_duration(robot, path, nominal)
    segment = PathSegment(path, duration, NullVector(robot), reverse=False)
    swept = float(path.end[3] - start[3])
    notes = [
        _fold_note("deploy", path, target),
        f"timing: quintic in arc length over {duration:.2f} s, mean theta_dot_4 "
        f"{swept / duration:.3f} rad/s (thesis: constant {settings.deploy_rate:g} rad/s)",
        *stretch_note("deploy", nominal, duration),
    ]
    phase = PhaseInfo("deploy", 0.0, duration, True, float(path.end[3]))
    return PtpPlan(
        PtpMethod.DEPLOY, [phase], [segment], notes, path.end, start, settings.elbow_gain
    )
