"""RNS-C on the chapter-6 wall task with a chapter-7 null-space term or another virtual mass.

The runs behind ``ext-fig6.8-ch7`` (:mod:`rns_ros.analysis.reproduce.chapter7_wall`) and the cause
in ``fig6.8``'s note (:func:`velocity_level_cause`). Registers nothing, so that chapter 6 can
quote these runs without importing a later chapter module.
"""

from __future__ import annotations

import functools

import numpy as np

from rns_ros.analysis.motion_force_runs import (
    VIRTUAL_MASS,
    ClosedLoopRun,
    Controller,
    NullSpaceTerm,
    run_closed_loop,
)
from rns_ros.control.contact_tasks import WALL_STROKE, WallScenario
from rns_ros.core.errors import SimulationDivergedError

#: Damper gain times the control period [-]: the held damper acceleration gives
#: P theta_dot_(k+1) ~ (1 - k_d dt) P theta_dot_k, stable for k_d dt < 2, deadbeat at 1.
DAMPER_GAIN_PERIOD = 1.0
#: The OS-C readings RNS-C is compared with (fig6.8).
OSC_VARIANTS = (Controller.OSC, Controller.OSC_KINEMATIC)


@functools.cache
def rns_run(mass: float, term: NullSpaceTerm, strokes: int, dt: float) -> ClosedLoopRun | str:
    """RNS-C with m_hat = ``mass`` [kg] and ``term`` on the wall of ``strokes`` strokes at the
    control period ``dt`` [s]; the simulator's message instead when it stops the run."""
    gain = DAMPER_GAIN_PERIOD / dt if term is NullSpaceTerm.DAMPER else None
    try:
        return run_closed_loop(
            WallScenario(strokes=strokes),
            Controller.RNS_C,
            dt=dt,
            virtual_mass=mass,
            null_space=term,
            damper_gain=gain,
        )
    except SimulationDivergedError as error:
        return str(error)


def like(baseline: ClosedLoopRun, mass: float, term: NullSpaceTerm) -> ClosedLoopRun | str:
    """The RNS-C run of ``baseline``'s wall task and period with ``mass`` and ``term``
    (``baseline`` itself for fig6.8's m_hat without a term)."""
    if term is NullSpaceTerm.NONE and mass == VIRTUAL_MASS:
        return baseline
    return rns_run(float(mass), term, int(baseline.description["strokes"]), baseline.dt)


def per_stroke(run: ClosedLoopRun) -> tuple[list[float], list[float]]:
    """Peak joint speed within each stroke and ||P_hat_RNS theta_dot|| at its end [rad/s]."""
    strokes = max(1, round(float(run.t[-1]) / WALL_STROKE))
    peaks, left = [], []
    for k in range(strokes):
        inside = (run.t >= k * WALL_STROKE - 1e-9) & (run.t <= (k + 1) * WALL_STROKE + 1e-9)
        peaks.append(float(run.joint_speed[inside].max()))
        left.append(float(run.null_space_velocity[np.flatnonzero(inside)[-1]]))
    return peaks, left


def rounded(values) -> list[float]:
    return [round(float(v), 3) for v in values]


def min_ratio(osc: dict, run: ClosedLoopRun) -> float:
    """The smaller OS-C peak joint speed over ``run``'s [-]."""
    return min(o.peak_joint_speed for o in osc.values()) / run.peak_joint_speed


def velocity_level_cause(runs: dict, threshold: float) -> str:
    """A sentence for fig6.8's note: its RNS-C run again with (7.13), from computed runs.

    Args:
        runs: fig6.8's {Controller: ClosedLoopRun} (RNS-C with m_hat = 1e5 kg and no term).
        threshold: fig6.8's criterion on OS-C / RNS-C [-].
    """
    baseline = runs[Controller.RNS_C]
    osc = {c: runs[c] for c in OSC_VARIANTS}
    run = like(baseline, VIRTUAL_MASS, NullSpaceTerm.VELOCITY_LEVEL)
    if isinstance(run, str):
        return f"RNS-C with chapter 7's velocity-level term (7.13) stopped: {run}."
    before, after = min_ratio(osc, baseline), min_ratio(osc, run)
    sentence = (
        f"RNS-C with chapter 7's velocity-level term (7.13) on the same task (result "
        f"ext-fig6.8-ch7) keeps ||P_hat_RNS theta_dot|| below "
        f"{float(run.null_space_velocity.max()):.3g} rad/s and peaks at "
        f"{rounded(per_stroke(run)[0])} rad/s per stroke (without: "
        f"{rounded(per_stroke(baseline)[0])}), smallest OS-C / RNS-C {before:.3g} -> "
        f"{after:.3g}: "
    )
    if after > threshold:
        return sentence + "RNS-C's undamped null-space velocity is the cause."
    largest = max(o.peak_joint_speed for o in osc.values())
    drift = (
        "the undamped null-space velocity explains the drop of the ratio over the strokes but "
        if after > before
        else "removing the undamped null-space velocity does not raise the ratio, and "
    )
    return sentence + (
        f"{drift}the ratio stays below {threshold:g} without it; it is bounded by the OS-C peaks "
        f"(largest {largest:.3g} rad/s), which chapter 7 does not change; why they are that low "
        "is open."
    )


__all__ = [
    "DAMPER_GAIN_PERIOD",
    "OSC_VARIANTS",
    "like",
    "min_ratio",
    "per_stroke",
    "rns_run",
    "rounded",
    "velocity_level_cause",
]
