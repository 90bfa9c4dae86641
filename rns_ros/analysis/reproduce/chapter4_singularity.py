"""Chapter 4, §4.3: the algorithmic singularity (Figs. 4.6–4.8).

ω = [0 −0.2 0] rad/s from the satellite-observation start with the plain pseudoinverse (eq. 4.9),
DLS with numerical filtering (eqs. 4.10-4.12, ε = 0.2, λ²_max = 2) and SC (eqs. 4.13-4.15,
b = 1.7), each run through the in-process closed loop without joint limits (the URDF-limited
pseudoinverse is a labelled second series). The thesis prints numbers only for the Fig. 4.7
singular region (1.71 s ≤ t ≤ 4.18 s) and the settings; the rest are trends in words, each
checked by a condition computed from our run.

Every windowed row of Figs. 4.6 and 4.7 is judged over the thesis' singular region
(:data:`THESIS_SINGULAR_WINDOW_S`), every row of Fig. 4.8 over the whole commanded run
(:data:`FIG4_8_WINDOW_S`); other windows (plain pinv's passes, the whole run) are reported in the
notes and values only. What the arm identification fitted (docs/arm_identification.md: the start
of the singular region, the singular pass there, joints 5 and 7 counter-rotating) is an input;
the base deviation under reactionless control and SC's speed factor are *by construction*. The
three figures share their cached runs; settings, choices and the other thresholds are those of
:mod:`rns_ros.analysis.reproduce.chapter4`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rns_ros.analysis.reproduce import plotting as plot
from rns_ros.analysis.reproduce import trace_windows as tw
from rns_ros.analysis.reproduce.chapter4 import (
    CHOICES_COMMON,
    ERROR_CONTRAST,
    HIGH_RATE_FACTOR,
    KEPT_SHARE,
    LOWER_WRIST_GAIN,
    SINGULARITY,
    SUPPRESSED_SHARE,
    THESIS_EPSILON,
    THESIS_LAMBDA2_MAX,
    THESIS_SC_GAIN,
    THESIS_SINGULAR_REGION_S,
    THESIS_TIME_TOLERANCE_S,
    UNDISTURBED_DEG,
    geometry_note,
    limits_choice,
    quick_choice,
)
from rns_ros.analysis.reproduce.registry import Comparison, Outcome, Reproduction, register_all
from rns_ros.analysis.reproduce.scenario_runs import (
    Run,
    Trace,
    recorded_run,
    run_settings,
    run_values,
    shipped_scenario,
)

#: Analysis window of Figs. 4.6 and 4.7 [s]: the thesis' singular region 1.71 s <= t <= 4.18 s
#: (§4.3.2, the two vertical lines of Fig. 4.7). §4.3.1 and §4.3.2 run the same conditions and
#: Fig. 4.6's vertical line lies inside it, so every windowed row of both figures uses it.
THESIS_SINGULAR_WINDOW_S = THESIS_SINGULAR_REGION_S
#: Analysis window of Fig. 4.8 [s]: the whole commanded run (the scenario's 25 s, the figure's
#: time axis as we run it). SC needs no singular region (§4.3.3), the thesis defines none for it,
#: and SC's run reaches the singularity at other times than pinv's and DLS's.
FIG4_8_WINDOW_S = (0.0, 25.0)
#: SC "follows the commanded direction": its largest axis error below this [deg] ...
FOLLOWED_AXIS_DEG = 1.0
#: ... and DLS's ("in contrast with the result from the DLS simulation") at least this many times
#: SC's.
AXIS_CONTRAST = 10.0
#: "An error appears in the speed": SC's speed factor b sigma_1 sigma_2 sigma_3 leaves this band
#: (a speed error above 10 %) [-].
SPEED_BAND = (0.9, 1.1)

_WINDOW_TEXT = f"{THESIS_SINGULAR_WINDOW_S[0]}-{THESIS_SINGULAR_WINDOW_S[1]} s"
_SC_WINDOW_TEXT = f"{FIG4_8_WINDOW_S[0]:g}-{FIG4_8_WINDOW_S[1]:g} s"


def _singularity_outcome(
    rows: list,
    values: dict,
    runs: list[Run],
    lines: list[float],
    quick: bool,
    window_choice: str,
    *extra_choices,
) -> Outcome:
    """The Outcome of Figs. 4.6-4.8: ``runs[0]`` is plotted with event lines at ``lines`` [s]."""
    return Outcome(
        tuple(rows),
        values,
        run_settings(SINGULARITY, runs, quick),
        (
            *CHOICES_COMMON,
            limits_choice(),
            *_singularity_choices(quick),
            window_choice,
            *extra_choices,
            quick_choice(quick),
        ),
        {"runs": runs[:1], "lines": lines},
    )


def _singularity_choices(quick: bool) -> tuple[str, ...]:
    """The choices of Figs. 4.6-4.8, with the plain-pinv run's singular intervals."""
    pinv = recorded_run(SINGULARITY, "pinv", quick)
    epsilon = pinv.settings["gains"]["epsilon"]
    regions = tw.intervals(pinv.trace.t_mid, pinv.trace.sigma_min < epsilon)
    return (
        f"Duration: the scenario file runs {shipped_scenario(SINGULARITY).duration:g} s (the "
        f"thesis gives none for Figs. 4.6-4.8); with plain pinv our arm is inside sigma_min(J-bar)"
        f" < {epsilon:g} during {regions} s.",
        f"Wrist gain: the thesis' k_g = {pinv.wrist_gain:g} (scenario "
        "default); SC multiplies the wrist term by det(J-bar J-bar^T) as eq. (4.15).",
    )


#: The analysis-window choice of Figs. 4.6 and 4.7.
THESIS_WINDOW_CHOICE = (
    f"Analysis window of Figs. 4.6 and 4.7: the thesis' singular region {_WINDOW_TEXT} (§4.3.2; "
    "§4.3.1 runs the same conditions and Fig. 4.6's vertical line lies inside it), fixed before "
    "the run and the same for every windowed row: the singularity and its determinants, the "
    "fastest joints, DLS's suppression of the joint speed, the tracking error and the base "
    "deviation in the region (periods whose mid-time lies in it). Whole-run and per-pass numbers "
    "are given in the notes and values for the reader; they decide no verdict."
)
#: The analysis-window choice of Fig. 4.8.
FIG4_8_WINDOW_CHOICE = (
    f"Analysis window of Fig. 4.8: the whole commanded run {FIG4_8_WINDOW_S[0]:g}-"
    f"{FIG4_8_WINDOW_S[1]:g} s (the figure's time axis as we run it), fixed before the run and "
    "the same for every row: the thesis defines no singular region for SC (§4.3.3: 'there is no "
    "need to define a singular region'), and SC's run reaches the singularity at other times "
    "than pinv's and DLS's."
)


# --------------------------------------------------------------------------- Fig. 4.6


def singular_point(trace: Trace) -> tuple[slice, int]:
    """(the periods of :data:`THESIS_SINGULAR_WINDOW_S`, the period of the smallest
    det(J-bar J-bar^T) in it): the point Figs. 4.6 and 4.7 are judged at."""
    window = tw.time_window(trace, THESIS_SINGULAR_WINDOW_S)
    return window, window.start + int(np.argmin(trace.det_algorithmic[window]))


def _singularity_time_row(trace: Trace, k: int, deepest: int) -> Comparison:
    """Thesis Fig. 4.6: the vertical line, inside the Fig. 4.7 region (same conditions). An
    input: the geometry was fitted to start the singular region at 1.71 s."""
    note = (
        f"fitted: the identified geometry was chosen to start the singular region sigma_min(J-bar)"
        f" < epsilon at the thesis' 1.71 s (docs/arm_identification.md), which places this line;"
        f" ours is the smallest det(J-bar J-bar^T) in the thesis' region {_WINDOW_TEXT}"
    )
    if deepest != k:
        note += (
            f"; the run passes again, deeper, at {trace.t_mid[deepest]:.3f} s (sigma_min "
            f"{trace.sigma_min[deepest]:.4f}), outside the thesis' region"
        )
    return Comparison.input(
        "singularity_time_s",
        f"vertical line inside {_WINDOW_TEXT} (the Fig. 4.7 region, same conditions)",
        float(trace.t_mid[k]),
        "s",
        note,
    )


def _approaches_zero_row(trace: Trace, k: int, deepest: int, epsilon: float) -> Comparison:
    """Thesis Fig. 4.6: det(J-bar J-bar^T) approaches 0 at the vertical line. An input: the
    geometry was fitted to enter the thesis' neighbourhood of the singularity (sigma_min < epsilon,
    eq. 4.12) at 1.71 s, which is this approach; how deep it goes is reported."""
    det = trace.det_algorithmic
    entering = np.flatnonzero(trace.sigma_min < epsilon)
    entry = (
        f"; where sigma_min first falls below epsilon = {epsilon:g} ({trace.t_mid[entering[0]]:.3f}"
        f" s) det is at {det[entering[0]] / det[0]:.2f} of its start"
        if entering.size
        else f"; sigma_min never falls below epsilon = {epsilon:g}"
    )
    return Comparison.input(
        "min_det_algorithmic",
        "approaches 0",
        float(det[k]),
        "",
        "fitted, not a result: the arm identification chose the geometry that enters the "
        f"singular region sigma_min(J-bar) < epsilon (§4.3.2's neighbourhood of the singularity) "
        "at the thesis' 1.71 s (docs/arm_identification.md; the runner-up without that pass was "
        "rejected), which is this approach; only its depth is not fitted: det(J-bar J-bar^T) "
        f"falls from {det[0]:.3f} at the start to {det[k]:.3g} ({det[k] / det[0]:.2f} of the "
        f"start, sigma_min {trace.sigma_min[k]:.3f}) at {trace.t_mid[k]:.3f} s{entry}; the run's "
        f"smallest is {det[deepest]:.2g} at {trace.t_mid[deepest]:.3f} s",
    )


def _not_singular_row(
    key: str,
    what: tuple[str, str],
    determinants: np.ndarray,
    trace: Trace,
    k: int,
    deepest: int,
    kind: str,
) -> Comparison:
    """Thesis Fig. 4.6: the determinant ``what`` = (name, unit) does not approach 0 at the
    algorithmic singularity (sample k, the smallest det(J-bar J-bar^T) in the thesis' region)."""
    name, unit = what
    ratio = tw.mean_singular_ratio(determinants, k)
    holds = ratio > KEPT_SHARE
    verdict = f"not {kind}" if holds else "it shrinks with det(J-bar J-bar^T); cause open"
    return Comparison.trend(
        key,
        "does not approach 0",
        float(determinants[k]),
        unit,
        holds=holds,
        note=f"{name} at {trace.t_mid[k]:.3f} s, the smallest det(J-bar J-bar^T) in the thesis' "
        f"region {_WINDOW_TEXT} (start {determinants[0]:.3g}; geometric-mean singular value at "
        f"{ratio:.2f} of its start, holds above {KEPT_SHARE:g}): {verdict}; at the run's deepest "
        f"pass ({trace.t_mid[deepest]:.3f} s, outside the region) it is at "
        f"{tw.mean_singular_ratio(determinants, deepest):.2f}.",
    )


def _fastest_joints_row(run: Run, peaks: dict) -> Comparison:
    """Thesis §4.3.1: near the singularity joints 5 and 7 rotate in opposite directions with
    high joint rates. An input (an arm-identification target); the note says what the run shows
    in the thesis' region: the two fastest joints at the peak |theta_dot_i|, their signs, and
    the peak against :data:`HIGH_RATE_FACTOR` x the run's median per-period peak."""
    trace = run.trace
    peak = peaks["thesis_window"]
    median = float(np.median(np.abs(trace.theta_dot).max(axis=1)))
    ratio = peak["peak_rad_s"] / median
    a, b = peak["their_rates_rad_s"]
    shown = peak["fastest_joints"] == [5, 7] and a * b < 0.0 and ratio >= HIGH_RATE_FACTOR
    whole = peaks["whole_run"]
    k = int(np.searchsorted(trace.t_mid, whole["time_s"]))
    kp = int(np.searchsorted(trace.t_mid, peak["time_s"]))
    note = (
        "fitted, not a result: 5/7 counter-rotation in this region is one of the facts the "
        "geometry was identified from (docs/arm_identification.md). The run "
        f"{'shows' if shown else 'does not show'} it: the peak |theta_dot_i| in the thesis' "
        f"region {_WINDOW_TEXT} is on joints {peak['fastest_joints'][0]} and "
        f"{peak['fastest_joints'][1]} ({a:+.3f}, {b:+.3f} rad/s), {ratio:.1f}x the run's median "
        f"per-period peak {median:.3f} rad/s (shown when the two fastest are 5 and 7, opposite, "
        f"at {HIGH_RATE_FACTOR:g}x or more); no joint limits. The deepest pass peaks at "
        f"{tw.joint_text(peaks['deepest_pass'])}; the whole run at {tw.joint_text(whole)}: "
        f"{tw.burst_note(trace, k, run.wrist_gain)}"
    )
    return Comparison.input(
        "fastest_joints_near_singularity",
        "joints 5 and 7, opposite directions, high rates",
        f"joints {peak['fastest_joints'][0]} and {peak['fastest_joints'][1]} at "
        f"{peak['time_s']:.3f} s: theta_dot_5 = {trace.theta_dot[kp, 4]:+.3f}, "
        f"theta_dot_7 = {trace.theta_dot[kp, 6]:+.3f} rad/s",
        "",
        note,
    )


def _pinv_peaks(pinv: Run) -> dict:
    """Plain pinv's peak |theta_dot_i| in the thesis' region, its deepest pass and the whole
    run."""
    trace, epsilon = pinv.trace, pinv.settings["gains"]["epsilon"]
    return {
        "thesis_window": tw.peak(trace, tw.time_window(trace, THESIS_SINGULAR_WINDOW_S)),
        "deepest_pass": tw.peak(trace, tw.deepest_pass(trace, epsilon)),
        "whole_run": tw.peak(trace, slice(0, len(trace.t_mid))),
    }


def _suppression(dls: Run, pinv: Run) -> dict:
    """pinv's peak |theta_dot_i| over DLS's (Fig. 4.7 run): in the thesis' region (the verdict's
    window) and over the whole run (for the reader)."""
    whole = slice(0, min(len(pinv.trace.t_mid), len(dls.trace.t_mid)))
    spans = {
        "thesis_window": (
            tw.time_window(dls.trace, THESIS_SINGULAR_WINDOW_S),
            tw.time_window(pinv.trace, THESIS_SINGULAR_WINDOW_S),
        ),
        "whole_run": (whole, whole),
    }
    result = {}
    for name, (dls_span, pinv_span) in spans.items():
        ours, theirs = tw.peak(dls.trace, dls_span), tw.peak(pinv.trace, pinv_span)
        result[name] = {
            "pinv_rad_s": theirs["peak_rad_s"],
            "dls_rad_s": ours["peak_rad_s"],
            "factor": theirs["peak_rad_s"] / ours["peak_rad_s"],
            "window_s": theirs["window_s"],
        }
    return result


def _urdf_series(run: Run) -> dict:
    """The labelled URDF-limits series of Fig. 4.6 (the product's limits, not the thesis')."""
    trace = run.trace
    command = np.abs(trace.theta_dot).max(axis=1) / trace.limit_scale
    return {
        "label": run.label,
        "joint_limits": run.settings["joint_limits"],
        "peak_joint_speed_rad_s": float(np.abs(trace.theta_dot).max()),
        "min_joint_limit_scale": float(trace.limit_scale.min()),
        "peak_command_before_scaling_rad_s": float(command.max()),
        "camera_turn_deg": run.result.achieved_angle_deg,
    }


def _compute_fig4_6(quick: bool) -> Outcome:
    run = recorded_run(SINGULARITY, "pinv", quick)
    limited = recorded_run(SINGULARITY, "pinv", quick, urdf_limits=True)
    dls = recorded_run(SINGULARITY, "dls", quick)
    trace = run.trace
    _, k = singular_point(trace)
    deepest = int(np.argmin(trace.det_algorithmic))
    peaks = _pinv_peaks(run)
    suppression = _suppression(dls, run)
    series = _urdf_series(limited)
    rows = [
        _singularity_time_row(trace, k, deepest),
        _approaches_zero_row(trace, k, deepest, run.settings["gains"]["epsilon"]),
        _not_singular_row(
            "det_kinematic_at_singularity",
            ("det(J_omega_e J_omega_e^T)", ""),
            trace.det_kinematic,
            trace,
            k,
            deepest,
            "a kinematic singularity",
        ),
        _not_singular_row(
            "det_coupling_at_singularity",
            ("det(M~_omega_m M~_omega_m^T)", "(kg m^2)^6"),
            trace.det_coupling,
            trace,
            k,
            deepest,
            "a coupling-inertia singularity, so the singularity is algorithmic",
        ),
        _fastest_joints_row(run, peaks),
        Comparison.input(
            "peak_joint_speed_urdf_limits_rad_s",
            None,
            series["peak_joint_speed_rad_s"],
            "rad/s",
            f"the labelled series '{limited.label}': the same run with the product's URDF limits "
            f"(commands scaled down uniformly, scale down to {series['min_joint_limit_scale']:.4f}"
            f"; the command before the scaling peaks at "
            f"{series['peak_command_before_scaling_rad_s']:.1f} rad/s); not the thesis' setting, "
            f"shown for reference (unlimited run: {peaks['whole_run']['peak_rad_s']:.1f} rad/s)",
        ),
    ]
    values = run_values([run, limited])
    values["analysis_window_s"] = list(THESIS_SINGULAR_WINDOW_S)
    values["singularity_time_s"] = float(trace.t_mid[k])
    values["deepest_pass_time_s"] = float(trace.t_mid[deepest])
    values["determinants_at_singularity"] = {
        "kinematic": float(trace.det_kinematic[k]),
        "coupling_kg6m12": float(trace.det_coupling[k]),
        "algorithmic": float(trace.det_algorithmic[k]),
    }
    whole = peaks["whole_run"]
    values["pinv_peak_joint_speed_rad_s"] = whole["peak_rad_s"]
    values["pinv_peak_window"] = "whole run, no joint limits (per window: pinv_peaks)"
    values["pinv_peak_joints"] = whole["fastest_joints"]
    values["pinv_peak_time_s"] = whole["time_s"]
    values["pinv_peaks"] = peaks
    values["dls_suppression_factor"] = suppression["thesis_window"]["factor"]
    values["dls_suppression_window"] = (
        f"the thesis' singular region {_WINDOW_TEXT}, the Fig. 4.7 DLS run (whole run: suppression)"
    )
    values["suppression"] = suppression
    values["urdf_limits_series"] = series
    outcome = _singularity_outcome(
        rows, values, [run, limited], [float(trace.t_mid[k])], quick, THESIS_WINDOW_CHOICE
    )
    return dataclasses.replace(outcome, figure_data={**outcome.figure_data, "urdf": limited})


# --------------------------------------------------------------------------- Fig. 4.7


def _region_end_note(dls: Run, pinv: Run, start: float, end: float) -> str:
    """The first singular region of the DLS run [start, end] [s]: its depth, plain pinv's first
    pass, and why it may end before the thesis' 4.18 s."""
    epsilon = dls.settings["gains"]["epsilon"]
    trace, window = dls.trace, tw.first_pass(dls.trace, epsilon)
    k = window.start + int(np.argmin(trace.sigma_min[window]))
    pinv_window = tw.first_pass(pinv.trace, epsilon)
    pinv_t = pinv.trace.t_mid
    low, high = THESIS_SINGULAR_REGION_S
    note = (
        f"; the first lasts {end - start:.2f} s (thesis {high - low:.2f} s), sigma_min bottoms "
        f"at {trace.sigma_min[k]:.3f} at {trace.t_mid[k]:.3f} s; plain pinv's first pass "
        f"lasts {pinv_t[pinv_window.stop - 1] - pinv_t[pinv_window.start]:.2f} s"
    )
    if end < high - THESIS_TIME_TOLERANCE_S:
        note += "; the geometry was fitted to the start only: " + geometry_note("the end")
    return note


def _region_rows(dls: Run, pinv: Run) -> list[Comparison]:
    """Thesis Fig. 4.7: the singular region 1.71 s <= t <= 4.18 s; its start is an input (the
    geometry was fitted to it), its end a number."""
    epsilon = dls.settings["gains"]["epsilon"]
    regions = tw.intervals(dls.trace.t_mid, dls.trace.sigma_min < epsilon)
    start, end = regions[0] if regions else (None, None)
    low, high = THESIS_SINGULAR_REGION_S
    note = f"sigma_min(J-bar) < {epsilon:g} during {regions} s"
    if regions:
        note += _region_end_note(dls, pinv, start, end)
    return [
        Comparison.input(
            "singular_region_start_s",
            low,
            start,
            "s",
            "fitted: the identified geometry was chosen to start the region here "
            "(docs/arm_identification.md)",
        ),
        Comparison.number(
            "singular_region_end_s",
            high,
            end,
            "s",
            tolerance=THESIS_TIME_TOLERANCE_S,
            note=note + "; tolerance half the thesis' last printed digit",
        ),
    ]


def _suppression_row(dls: Run, pinv: Run) -> Comparison:
    """Thesis §4.3.2: "the growth of the joint velocity has been successfully suppressed", read
    as DLS's peak |theta_dot_i| in the thesis' singular region below :data:`SUPPRESSED_SHARE` of
    plain pinv's there (Fig. 4.6 run, same conditions, no joint limits)."""
    suppression = _suppression(dls, pinv)
    inside, whole = suppression["thesis_window"], suppression["whole_run"]
    holds = inside["dls_rad_s"] < SUPPRESSED_SHARE * inside["pinv_rad_s"]
    dls_window = tw.time_window(dls.trace, THESIS_SINGULAR_WINDOW_S)
    pinv_window = tw.time_window(pinv.trace, THESIS_SINGULAR_WINDOW_S)
    dls_peak = tw.peak(dls.trace, dls_window)
    kd = int(np.searchsorted(dls.trace.t_mid, dls_peak["time_s"]))
    sigma, damping = float(dls.trace.sigma_min[kd]), float(dls.trace.damping[kd])
    speed = float(np.linalg.norm(dls.trace.omega_ref[kd]))
    note = (
        f"largest |theta_dot_i| in the thesis' region {_WINDOW_TEXT}, no joint limits: pinv / "
        f"DLS = {inside['factor']:.2f} (holds when DLS's is below {SUPPRESSED_SHARE:g} of "
        f"pinv's). There pinv peaks at {tw.joint_text(tw.peak(pinv.trace, pinv_window))}; its "
        f"sigma_min in the region bottoms at {pinv.trace.sigma_min[pinv_window].min():.3f}. DLS "
        f"peaks at {tw.joint_text(dls_peak)}, at sigma_min {sigma:.3f} with lambda^2 = "
        f"{damping:.3g}; its sigma_min in the region bottoms at "
        f"{dls.trace.sigma_min[dls_window].min():.3f}. At that peak the damped u_3 term of eq. "
        f"(4.11) contributes at most sigma_3 / (sigma_3^2 + lambda^2) |omega_ref| = "
        f"{sigma / (sigma**2 + damping) * speed:.3f} rad/s (undamped, 1 / sigma_3 |omega_ref| "
        f"= {speed / sigma:.2f} rad/s)"
    )
    if not holds:
        note += (
            "; what makes DLS's rates this large there (the undamped terms of eq. 4.11 or the "
            "wrist term) is open"
        )
    pinv_whole = tw.peak(pinv.trace, slice(0, len(pinv.trace.t_mid)))
    k = int(np.searchsorted(pinv.trace.t_mid, pinv_whole["time_s"]))
    note += (
        f". Over the whole run (not the thesis' window) pinv / DLS = {whole['factor']:.1f}: pinv "
        f"peaks at {tw.joint_text(pinv_whole)}, "
        f"{tw.burst_note(pinv.trace, k, pinv.wrist_gain)}, after its deepest pass (sigma_min "
        f"{pinv.trace.sigma_min.min():.4f})"
    )
    return Comparison.trend(
        "peak_joint_speed_rad_s",
        "'growth of the joint velocity successfully suppressed'",
        {"dls": inside["dls_rad_s"], "pinv": inside["pinv_rad_s"]},
        "rad/s",
        holds=holds,
        note=note + ".",
    )


def _window_mask(trace: Trace, window_s: tuple[float, float]) -> np.ndarray:
    """True for the periods of ``window_s`` [s]."""
    inside = np.zeros(len(trace.t_mid), dtype=bool)
    inside[tw.time_window(trace, window_s)] = True
    return inside


def _tracking_error_row(dls: Run) -> Comparison:
    """Thesis §4.3.2: "an end-effector tracking error can be observed within the singular
    region", caused by the damping (none outside, where DLS is the exact inverse): the largest
    |omega_achieved - omega_ref| in the thesis' region at least :data:`ERROR_CONTRAST` times the
    largest outside it."""
    trace = dls.trace
    inside = _window_mask(trace, THESIS_SINGULAR_WINDOW_S)
    error_in = float(trace.omega_error[inside].max(initial=0.0))
    outside = np.where(inside, -1.0, trace.omega_error)
    j = int(np.argmax(outside))
    error_out = max(float(outside[j]), 0.0)
    holds = error_in > ERROR_CONTRAST * error_out
    note = (
        f"max |omega_achieved - omega_ref| in the thesis' region {_WINDOW_TEXT} vs "
        f"{error_out:.1e} rad/s outside it (holds at {ERROR_CONTRAST:g}x); the rotation axis is "
        f"off by up to {dls.result.max_axis_error_deg:.1f} deg and the camera ends "
        f"{dls.result.final_orientation_error_deg:.1f} deg from the target"
    )
    if not holds:
        note += f"; outside, the error peaks at {trace.t_mid[j]:.3f} s"
        if trace.damping[j] > 0.0:
            regions = tw.intervals(trace.t_mid, trace.damping > 0.0)
            note += (
                f", where our damping is already on (sigma_min {trace.sigma_min[j]:.3f}, "
                f"lambda^2 = {trace.damping[j]:.3g}): our DLS damps during {regions} s, not "
                f"over the thesis' {_WINDOW_TEXT} (the start is a fitted input, the end the "
                "singular_region_end_s row), and the damping's error comes with it"
            )
        else:
            note += "; cause open"
    return Comparison.trend(
        "max_angular_velocity_error_in_singular_region_rad_s",
        "'an end-effector tracking error can be observed within the singular region'",
        error_in,
        "rad/s",
        holds=holds,
        note=note + ".",
    )


def _region_base_row(dls: Run) -> Comparison:
    """Thesis §4.3.2: "the base attitude does not deviate, even within the singular region":
    by construction (exact model, kinematic simulator, a DLS command in the null space of
    M~_omega_m, eq. 4.5), checked over the thesis' region against :data:`UNDISTURBED_DEG`."""
    trace = dls.trace
    base_in = float(
        trace.base_deviation_deg[_window_mask(trace, THESIS_SINGULAR_WINDOW_S)].max(initial=0.0)
    )
    holds = base_in < UNDISTURBED_DEG
    return Comparison.by_construction(
        "max_base_deviation_in_singular_region_deg",
        "'the base attitude does not deviate, even within the singular region'",
        base_in,
        "deg",
        holds=holds,
        note=f"largest base deviation in the thesis' region {_WINDOW_TEXT}; by construction: "
        "the controller inverts the simulator's own exact model in a kinematic simulation, and "
        "the damping of eq. (4.11) acts on J-bar, inside the null space of M~_omega_m (eq. 4.5), "
        "so the command stays reactionless in the region as outside it; not exactly 0 because "
        "the controller is sampled (midpoint hold, O(T^2)) and RK4 integrates the base; holds "
        f"below {UNDISTURBED_DEG:g} deg (whole run: {trace.base_deviation_deg.max():.2g} deg)",
    )


def _compute_fig4_7(quick: bool) -> Outcome:
    dls, pinv = recorded_run(SINGULARITY, "dls", quick), recorded_run(SINGULARITY, "pinv", quick)
    trace = dls.trace
    gains = dls.settings["gains"]
    regions = tw.intervals(trace.t_mid, trace.sigma_min < gains["epsilon"])
    rows = [
        Comparison.input(
            "epsilon_lambda2_max",
            [THESIS_EPSILON, THESIS_LAMBDA2_MAX],
            [gains["epsilon"], gains["lambda2_max"]],
            "",
            "our settings: the thesis' singular region and maximum damping of §4.3.2, eq. (4.12) "
            "with the sigma^4 term",
        ),
        *_region_rows(dls, pinv),
        _suppression_row(dls, pinv),
        _tracking_error_row(dls),
        _region_base_row(dls),
    ]
    values = run_values([dls, pinv])
    values["analysis_window_s"] = list(THESIS_SINGULAR_WINDOW_S)
    values["singular_region_s"] = regions
    values["max_damping_applied"] = dls.result.max_damping
    values["suppression"] = _suppression(dls, pinv)
    return _singularity_outcome(
        rows,
        values,
        [dls, pinv],
        [x for r in regions for x in r],
        quick,
        THESIS_WINDOW_CHOICE,
        "Singular region: the control periods whose mid-period sigma_min(J-bar) < epsilon, "
        "drawn as vertical lines at their first and last period.",
    )


# --------------------------------------------------------------------------- Fig. 4.8


def _sc_window(trace: Trace) -> slice:
    """The periods of :data:`FIG4_8_WINDOW_S`."""
    return tw.time_window(trace, FIG4_8_WINDOW_S)


def _max_axis_error(run: Run) -> float:
    """Largest axis error in :data:`FIG4_8_WINDOW_S` [deg] (periods at rest have none)."""
    errors = run.trace.axis_error_deg[_sc_window(run.trace)]
    return float(np.nan_to_num(errors, nan=0.0).max(initial=0.0))


def _max_acceleration(run: Run) -> float:
    """Largest |delta theta_dot_i| / T between consecutive periods of :data:`FIG4_8_WINDOW_S`
    [rad/s^2]."""
    window = _sc_window(run.trace)
    steps = tw.acceleration(run.trace)[window.start : max(window.stop - 1, window.start)]
    return float(steps.max(initial=0.0))


def _lower_gain_cause(claim: str, holds: bool, drift: float, gain: float) -> str:
    """The cause of a fig4.8 trend that fails at the thesis' k_g, from the labelled runs at
    :data:`LOWER_WRIST_GAIN`: ``claim`` is what they show, ``holds`` whether the trend holds
    there, ``drift`` [m] SC's max wrist drift at the thesis' ``gain``."""
    if not holds:
        return f"; with k_g = {LOWER_WRIST_GAIN:g} (labelled runs) {claim}: the cause is open"
    return (
        f"; with k_g = {LOWER_WRIST_GAIN:g} (labelled runs) {claim}, and the trend holds: the "
        f"cause is the wrist term k_g (p_w - p_w^init) at k_g = {gain:g} on a wrist the "
        f"singular pass has carried {drift:.2f} m away, which outweighs the task command"
    )


def _acceleration_row(
    runs: dict[str, Run], no_wrist: Run, lower: dict[str, Run] | None = None
) -> Comparison:
    """Thesis §4.3.3 on SC: "the rapid change of the joint velocity can be avoided", read as SC's
    largest |delta theta_dot_i| / T over :data:`FIG4_8_WINDOW_S` below plain pinv's (Fig. 4.6,
    the untreated singularity); DLS's is given for reference."""
    peak = {label: _max_acceleration(run) for label, run in runs.items()}
    holds = peak["sc"] < peak["pinv"]
    in_pass = ", ".join(f"{label} {_pass_acceleration(run):.2f}" for label, run in runs.items())
    pinv = runs["pinv"]
    j = int(np.argmax(tw.acceleration(pinv.trace)))
    note = (
        f"largest |delta theta_dot_i| / T between periods over the whole run ({_SC_WINDOW_TEXT}),"
        " no joint limits (holds when SC's is below pinv's); "
        f"{_where_fastest_change(runs['sc'])}; pinv's is at "
        f"{pinv.trace.t_mid[j]:.2f} s, {tw.burst_note(pinv.trace, j + 1, pinv.wrist_gain)}"
        f"; in each run's first pass through the singular region: {in_pass} rad/s^2; without the "
        f"wrist term (k_g = 0) SC's is {_max_acceleration(no_wrist):.2f} rad/s^2, "
        f"but that run never enters the region (sigma_min >= {no_wrist.trace.sigma_min.min():.3f})"
    )
    return Comparison.trend(
        "max_joint_acceleration_rad_s2",
        "'the rapid change of the joint velocity can be avoided' (against the untreated "
        "singularity, Fig. 4.6)",
        {"sc": peak["sc"], "pinv": peak["pinv"]},
        "rad/s^2",
        holds=holds,
        note=note + ("" if holds else _acceleration_cause(runs["sc"], lower)) + ".",
    )


def _acceleration_cause(sc: Run, lower: dict[str, Run] | None) -> str:
    if lower is None:
        return "; why the wrist term grows this large is open"
    peak = {label: _max_acceleration(run) for label, run in lower.items()}
    claim = f"SC's is {peak['sc']:.3g} and pinv's {peak['pinv']:.3g} rad/s^2"
    return _lower_gain_cause(
        claim, peak["sc"] < peak["pinv"], sc.result.max_wrist_drift, sc.wrist_gain
    )


def _pass_acceleration(run: Run) -> float:
    """Largest |delta theta_dot| / T within the run's first pass through sigma_min < epsilon."""
    window = tw.first_pass(run.trace, run.settings["gains"]["epsilon"])
    return float(
        tw.acceleration(run.trace)[window.start : max(window.stop - 1, window.start + 1)].max()
    )


def _where_fastest_change(run: Run) -> str:
    """Where the run's largest |delta theta_dot| / T happens: time, joint and what the command
    after the change is made of."""
    trace = run.trace
    k = int(np.argmax(tw.acceleration(trace)))
    joint = int(np.argmax(np.abs(np.diff(trace.theta_dot, axis=0))[k])) + 1
    return (
        f"SC's is at {trace.t_mid[k]:.2f} s on joint {joint}, SC's speed factor "
        f"{trace.speed_scale[k + 1]:.2f}, {tw.burst_note(trace, k + 1, run.wrist_gain)}"
    )


def _follows(sc_deg: float, dls_deg: float) -> bool:
    """SC's axis error below :data:`FOLLOWED_AXIS_DEG` and DLS's above :data:`AXIS_CONTRAST` x
    SC's [deg]."""
    return sc_deg < FOLLOWED_AXIS_DEG and dls_deg > AXIS_CONTRAST * sc_deg


def _axis_row(sc: Run, dls: Run, no_wrist: Run, lower: dict[str, Run] | None = None) -> Comparison:
    """Thesis §4.3.3: SC follows the commanded direction y, in contrast with DLS, over
    :data:`FIG4_8_WINDOW_S`."""
    axis = {run.label: _max_axis_error(run) for run in (sc, dls)}
    follows = _follows(axis["sc"], axis["dls"])
    trace = sc.trace
    errors = np.nan_to_num(trace.axis_error_deg)
    k = int(np.argmax(errors))
    window = tw.first_pass(trace, sc.settings["gains"]["epsilon"])
    through = float(errors[: window.stop].max())
    note = (
        "largest angle between achieved and commanded rotation axis over one period, over the "
        f"whole run ({_SC_WINDOW_TEXT}), no joint limits (holds when SC's is below "
        f"{FOLLOWED_AXIS_DEG:g} deg and DLS's above {AXIS_CONTRAST:g}x SC's)"
    )
    if not follows:
        note += (
            f"; SC's is at {trace.t_mid[k]:.3f} s, {tw.burst_note(trace, k, sc.wrist_gain)}; "
            "up to the "
            f"end of SC's {tw.pass_note(trace, window)} it is {through:.3g} deg; without the wrist "
            f"term (k_g = 0) SC's is {_max_axis_error(no_wrist):.2g} deg (that run never "
            "enters the region)"
        )
        if lower is None:
            note += "; why the wrist term grows this large is open"
        else:
            lower_axis = {label: _max_axis_error(run) for label, run in lower.items()}
            claim = f"SC's is {lower_axis['sc']:.3g} deg and DLS's {lower_axis['dls']:.3g} deg"
            held = _follows(lower_axis["sc"], lower_axis["dls"])
            note += _lower_gain_cause(claim, held, sc.result.max_wrist_drift, sc.wrist_gain)
    return Comparison.trend(
        "max_axis_error_deg",
        "SC follows the commanded direction y; DLS does not",
        axis,
        "deg",
        holds=follows,
        note=note + ".",
    )


def _speed_row(sc: Run) -> Comparison:
    """Thesis §4.3.3: "an error only appears in the speed along the path": SC's speed factor
    b sigma_1 sigma_2 sigma_3 of eq. (4.13) leaves :data:`SPEED_BAND` over
    :data:`FIG4_8_WINDOW_S`. By construction: J-bar J-bar^+ = b sigma_1 sigma_2 sigma_3 E for
    the SC inverse (4.13)-(4.14), a property of the method the thesis states before it
    simulates; the factor is the controller's own."""
    scale = sc.trace.speed_scale[_sc_window(sc.trace)]
    low, high = float(scale.min()), float(scale.max())
    holds = low < SPEED_BAND[0] or high > SPEED_BAND[1]
    return Comparison.by_construction(
        "speed_scale_range",
        "'an error only appears in the speed along the path'",
        [low, high],
        "",
        holds=holds,
        note="by construction: eq. (4.13)-(4.14) give J-bar J-bar^+ = b sigma_1 sigma_2 sigma_3 "
        "E, so the commanded speed is scaled by b sqrt(det(J-bar J-bar^T)) (natural motion), "
        "a property of the method stated before the thesis simulates it; this is the controller's "
        f"own factor over the whole run ({_SC_WINDOW_TEXT}), no joint limits, which departs from "
        "1 wherever det(J-bar J-bar^T) does from 1/b^2 (holds outside "
        f"{SPEED_BAND[0]:g}-{SPEED_BAND[1]:g}); whether only the speed is off is the "
        f"max_axis_error_deg row; the camera turns {sc.result.achieved_angle_deg:.0f} deg of the "
        f"commanded {np.rad2deg(abs(shipped_scenario(SINGULARITY).angle)):.0f} deg",
    )


def _compute_fig4_8(quick: bool) -> Outcome:
    runs = {m: recorded_run(SINGULARITY, m, quick) for m in ("sc", "dls", "pinv")}
    no_wrist = recorded_run(SINGULARITY, "sc", quick, 0.0)
    lower = {m: recorded_run(SINGULARITY, m, quick, LOWER_WRIST_GAIN) for m in runs}
    sc, dls = runs["sc"], runs["dls"]
    trace = sc.trace
    window = _sc_window(trace)
    k = window.start + int(np.argmin(trace.det_algorithmic[window]))
    rows = [
        Comparison.input(
            "sc_gain_b",
            THESIS_SC_GAIN,
            sc.settings["gains"]["sc_gain"],
            "",
            "our setting: the thesis' empirically chosen b of eq. (4.13)",
        ),
        _axis_row(sc, dls, no_wrist, lower),
        _speed_row(sc),
        _acceleration_row(runs, no_wrist, lower),
    ]
    values = run_values(list(runs.values()))
    values["analysis_window_s"] = list(FIG4_8_WINDOW_S)
    values["max_joint_acceleration_rad_s2"] = {
        label: _max_acceleration(run) for label, run in runs.items()
    }
    values["sc_without_wrist_term"] = {
        "label": no_wrist.label,
        "max_axis_error_deg": _max_axis_error(no_wrist),
        "max_joint_acceleration_rad_s2": _max_acceleration(no_wrist),
        "min_sigma": no_wrist.result.min_sigma,
    }
    values["lower_wrist_gain"] = {
        label: {
            "wrist_gain": run.wrist_gain,
            "max_axis_error_deg": _max_axis_error(run),
            "max_joint_acceleration_rad_s2": _max_acceleration(run),
            "max_wrist_drift_m": run.result.max_wrist_drift,
        }
        for label, run in lower.items()
    }
    values["singularity_time_s"] = float(trace.t_mid[k])
    return _singularity_outcome(
        rows, values, list(runs.values()), [float(trace.t_mid[k])], quick, FIG4_8_WINDOW_CHOICE
    )


#: The twin-axis series drawn next to sigma_min per method of Figs. 4.6-4.8.
_SIGMA_EXTRA = {"dls": "damping", "sc": "speed"}


def _plot_singularity(outcome: Outcome, figure) -> None:
    """Figs. 4.6-4.8: one run with event lines at the singularity / singular region."""
    run, lines = outcome.figure_data["runs"][0], outcome.figure_data["lines"]
    axes = figure.subplots(3, 2)
    plot.trace_joint_velocities(axes[0, 0], run, lines)
    plot.trace_determinants(axes[0, 1], run, lines)
    plot.trace_angular_velocity(axes[1, 0], [run], lines)
    plot.trace_angular_velocity_error(axes[1, 1], [run], lines, axis_error=True)
    plot.trace_base_deviation(axes[2, 0], [run], lines)
    extra = _SIGMA_EXTRA.get(run.settings["method"])
    plot.trace_sigma(axes[2, 1], [run], lines, extra)
    limited = outcome.figure_data.get("urdf")
    if limited is not None:
        axes[0, 0].plot(
            limited.trace.t_mid,
            np.abs(limited.trace.theta_dot).max(axis=1),
            color="k",
            ls="--",
            lw=1.0,
            label=r"max$_i|\dot\theta_i|$, URDF limits (not the thesis')",
        )
        axes[0, 0].legend(fontsize=6, ncol=4, loc="best")


REPRODUCTIONS = register_all(
    Reproduction(
        "fig4.6",
        "Fig. 4.6",
        "algorithmic singularity with the plain pseudoinverse",
        _compute_fig4_6,
        _plot_singularity,
        (11.0, 10.0),
    ),
    Reproduction(
        "fig4.7",
        "Fig. 4.7",
        "algorithmic singularity with the DLS inverse (numerical filtering)",
        _compute_fig4_7,
        _plot_singularity,
        (11.0, 10.0),
    ),
    Reproduction(
        "fig4.8",
        "Fig. 4.8",
        "algorithmic singularity with the Singularity-Consistent method",
        _compute_fig4_8,
        _plot_singularity,
        (11.0, 10.0),
    ),
)
