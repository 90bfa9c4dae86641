"""Chapter 6, planar arc: labelled runs that explain our numbers next to the thesis' (no results
of its own; ``chapter6`` and ``chapter6_remarks`` use them).

* The fig6.4 ratio sweep: the peak-joint-speed ratio OS-C / RNS-C per factor (timing T_half,
  gains k_p/k_d, gravity on and compensated, start configuration on the self-motion), against
  the thesis' 4.22 / 0.73 = 5.78.
* The fig6.3 force comparison under a payload the controllers do not model: with a model-exact
  plant the same-instant force loop gives f = f_des for every controller, so only a model error
  can tell the controllers' force errors apart.

Every run is cached per process (``planar_run``), so fig6.3, fig6.4 and the remarks share them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from rns_ros.analysis.motion_force_runs import (
    CONTROL_PERIOD,
    CONTROLLERS,
    QUICK_PERIOD,
    THESIS_MOTION_GAINS,
    ClosedLoopRun,
    Controller,
    MotionGains,
    run_closed_loop,
)
from rns_ros.analysis.motion_force_variants import (
    GRAVITY,
    gravity_setup,
    planar_ik,
    with_payload,
)
from rns_ros.analysis.reproduce.registry import Comparison
from rns_ros.control.contact_tasks import ArcScenario, Setup

#: Thesis §6.2.1 (Fig. 6.4) peak joint speeds [rad/s], printed to two decimals.
THESIS_PEAK_RNS, THESIS_PEAK_OSC = 0.73, 4.22
#: The thesis' ratio of the two peaks [-].
THESIS_RATIO = THESIS_PEAK_OSC / THESIS_PEAK_RNS
#: A factor "reproduces" the thesis' ratio within this relative distance (the close band) [-].
RATIO_CLOSE = 0.10
#: A factor "leaves" the ratio when it moves it by less than this fraction [-].
RATIO_UNCHANGED = 0.05
#: Payload [kg] at the EE point of the plant, absent from every controller's model (20 % of the
#: last link's 10 kg).
PAYLOAD = 2.0
#: "Almost identical" force errors: the largest max |f_des - f| over the controllers at most this
#: factor of the smallest [-].
FORCE_IDENTICAL_FACTOR = 2.0
#: Elbow branch of our start configuration (theta_2 < 0, the thesis' shape [A-4.6]).
START_ELBOW = -1
OSC_VARIANTS = (Controller.OSC, Controller.OSC_KINEMATIC)


@dataclass(frozen=True)
class Factor:
    """One change of the planar set-up against the baseline of ``fig6.4``.

    Attributes:
        label: JSON key and note text.
        kind: "timing", "gains", "gravity" or "start".
        value: T_half [s]; (k_p [1/s^2], k_d [1/s]); g [m/s^2]; psi_0 [deg] (the last link's
            absolute angle at the start, the self-motion parameter; elbow as ours).
    """

    label: str
    kind: str
    value: float | tuple[float, float]


BASELINE = Factor("baseline", "baseline", 0.0)
_TIMING = Factor("T_half = 1 s", "timing", 1.0)
_GAINS = Factor("k_p = 400, k_d = 40", "gains", (400.0, 40.0))
GRAVITY_FACTOR = Factor(f"gravity {GRAVITY:g} m/s^2 (-y), compensated", "gravity", GRAVITY)
_STARTS = tuple(Factor(f"start psi_0 = {psi:g} deg", "start", psi) for psi in (30.0, 65.0, 90.0))
#: The sweep of the full run and of the quick run (tests).
FULL_FACTORS = (_TIMING, _GAINS, GRAVITY_FACTOR, *_STARTS)
QUICK_FACTORS = (_TIMING, GRAVITY_FACTOR, _STARTS[1])


def factors(quick: bool) -> tuple[Factor, ...]:
    return QUICK_FACTORS if quick else FULL_FACTORS


def period(quick: bool) -> float:
    return QUICK_PERIOD if quick else CONTROL_PERIOD


def scenario(factor: Factor, quick: bool) -> ArcScenario:
    """The arc of ``factor`` (one half cycle when quick)."""
    extra = {"half_cycles": 1} if quick else {}
    if factor.kind == "timing":
        return ArcScenario(half_cycle=float(factor.value), **extra)
    if factor.kind == "start":
        base = ArcScenario(**extra)
        setup = base.setup()
        start = setup.description["start_point_m"]
        q0 = planar_ik(setup.robot, start, math.radians(float(factor.value)), START_ELBOW)
        return ArcScenario(seed_deg=tuple(np.degrees(q0)), **extra)
    return ArcScenario(**extra)


def _setup(factor: Factor, quick: bool) -> Setup:
    setup = scenario(factor, quick).setup()
    return gravity_setup(setup, float(factor.value)) if factor.kind == "gravity" else setup


@functools.cache
def planar_run(factor: Factor, controller: Controller, quick: bool) -> ClosedLoopRun:
    """One controller on the planar arc changed by ``factor`` (cached per process)."""
    gains = MotionGains(*factor.value) if factor.kind == "gains" else THESIS_MOTION_GAINS
    return run_closed_loop(_setup(factor, quick), controller, dt=period(quick), motion_gains=gains)


@functools.cache
def payload_run(controller: Controller, quick: bool) -> ClosedLoopRun:
    """One controller on the planar arc, the plant carrying :data:`PAYLOAD` at the EE."""
    setup = scenario(BASELINE, quick).setup()
    plant = with_payload(setup.robot, PAYLOAD)
    return run_closed_loop(setup, controller, dt=period(quick), plant=plant)


# --------------------------------------------------------------------------- fig6.4 sweep


def ratio_sweep(quick: bool) -> dict[str, dict]:
    """{factor label: {"peak_rad_s": {controller: peak}, "ratio": {OS-C variant: ratio}}},
    the baseline first."""
    sweep = {}
    for factor in (BASELINE, *factors(quick)):
        peaks = {c: planar_run(factor, c, quick).peak_joint_speed for c in CONTROLLERS}
        sweep[factor.label] = {
            "peak_rad_s": {c.value: p for c, p in peaks.items()},
            "ratio": {c.value: peaks[c] / peaks[Controller.RNS_C] for c in OSC_VARIANTS},
        }
    return sweep


def _closest(sweep: dict, variant: str) -> tuple[str, float]:
    """(label, ratio) of the factor whose ratio is nearest the thesis' (relative)."""
    return min(
        ((label, row["ratio"][variant]) for label, row in sweep.items()),
        key=lambda item: abs(item[1] / THESIS_RATIO - 1.0),
    )


def ratio_cause(sweep: dict, variant: str) -> str:
    """The cause sentence of one OS-C variant's peak row, from the computed sweep."""
    base = sweep[BASELINE.label]["ratio"][variant]
    kinds = {f.label: f.kind for f in FULL_FACTORS}
    parts = []
    for kinds_wanted, subject in (
        (("timing", "gains"), "timing and gains"),
        (("start",), "the start configuration"),
        (("gravity",), "gravity on and compensated (the thesis ran without)"),
    ):
        labels = [label for label in sweep if kinds.get(label) in kinds_wanted]
        if not labels:
            continue
        ratios = [sweep[label]["ratio"][variant] for label in labels]
        moves = any(abs(r / base - 1.0) >= RATIO_UNCHANGED for r in ratios)
        said = ", ".join(f"{label}: {r:.3g}" for label, r in zip(labels, ratios, strict=True))
        verb = "moves it" if moves else f"keeps it within {RATIO_UNCHANGED:.0%}"
        parts.append(f"{subject} {verb} ({said})")
    label, ratio = _closest(sweep, variant)
    text = (
        f"ratio sweep (values.ratio_sweep) from the baseline ratio {base:.3g}: "
        + "; ".join(parts)
        + f". Closest to the thesis' {THESIS_RATIO:.3g}: {label} ({ratio:.3g})"
    )
    if abs(ratio / THESIS_RATIO - 1.0) <= RATIO_CLOSE:
        return text + f", within {RATIO_CLOSE:.0%}: that factor reproduces the thesis' ratio"
    return (
        text + f"; no factor reaches it within {RATIO_CLOSE:.0%}, so the remaining cause is open "
        "(the thesis' own start configuration is not on its arc, A-4.6)"
    )


# --------------------------------------------------------------------------- fig6.3 payload


def payload_runs(quick: bool) -> dict[Controller, ClosedLoopRun]:
    return {c: payload_run(c, quick) for c in CONTROLLERS}


def force_spread_row(force_errors: dict[str, float], position_errors: dict[str, float]):
    """'Almost identical' force errors under the payload: largest over smallest max |f_des - f|
    over the controllers, criterion <= :data:`FORCE_IDENTICAL_FACTOR` (fixed before the runs)."""
    big, small = max(force_errors.values()), min(force_errors.values())
    spread = big / small if small > 0.0 else math.inf
    return Comparison.trend(
        "task_force_error_spread_payload",
        "'the order of end-effector position/force error are almost identical for the two "
        "controllers' (§6.2.1, Fig. 6.3), force part",
        spread,
        "",
        holds=spread <= FORCE_IDENTICAL_FACTOR,
        extension=True,
        note="an extension (the thesis never ran it): the plant carries a "
        f"{PAYLOAD:g} kg payload at the EE that no controller models, so the same-instant "
        "force loop is no longer exact; largest over smallest max |f_des - f| over the three "
        f"controllers (criterion <= {FORCE_IDENTICAL_FACTOR:g}): "
        + ", ".join(f"{k} {v:.3g} N" for k, v in force_errors.items())
        + "; max in-plane position errors "
        + ", ".join(f"{k} {v * 1e3:.3g} mm" for k, v in position_errors.items()),
    )


__all__ = [
    "BASELINE",
    "FULL_FACTORS",
    "GRAVITY_FACTOR",
    "PAYLOAD",
    "QUICK_FACTORS",
    "THESIS_PEAK_OSC",
    "THESIS_PEAK_RNS",
    "THESIS_RATIO",
    "Factor",
    "force_spread_row",
    "payload_runs",
    "planar_run",
    "ratio_cause",
    "ratio_sweep",
]
