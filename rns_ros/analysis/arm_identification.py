"""Score a candidate 7-DoF geometry on each constraint the thesis text gives.

One function per constraint, each returning a :class:`Score` (value, pass/fail, thesis target):
the camera position at the 3-phase final configuration, the reactionless elbow family from the
3-phase initial and final configurations, the stowed pose and the deployments of section 4.5,
the DLS singular window of section 4.3.2 and the inspection scenarios of section 4.2.2. Geometry
and URDF: :mod:`rns_ros.analysis.arm_geometry`; method and results: docs/arm_identification.md.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.analysis.arm_geometry import Geometry, build_model
from rns_ros.analysis.closed_loop import PeriodSample, run_scenario
from rns_ros.control.reactionless_path import positioning_null_vector
from rns_ros.control.scenario import Scenario, load_scenario
from rns_ros.core.model import FreeFloatingModel

_ROOT = Path(__file__).resolve().parents[2]
SCENARIO_DIR = _ROOT / "config" / "scenarios"

#: Thesis targets (section 4.4.2, thesis_rest 2.3).
THESIS_EE_POSITION = np.array([-1.7, 0.45, 1.7])  # [m], base CoM frame
THREE_PHASE_INITIAL_DEG = (-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0)
THREE_PHASE_FINAL_DEG = (-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0)
#: Section 4.5: stowed configuration (eq. 4.19) [rad], elbow speed [rad/s] and duration [s].
STOWED = (math.pi / 2, -math.pi / 2, 0.0, -math.pi, math.pi, math.pi, 0.0)
DEPLOY_SPEED = 0.183
DEPLOY_TIME = 30.0
PARTIAL_FINAL_DEG = (90.0, 50.0, 0.0, -300.0, 0.0, 20.0, 0.0)
#: Section 4.3.2: DLS singular region epsilon and the thesis window [s].
SINGULAR_EPSILON = 0.2
THESIS_WINDOW = (1.71, 4.18)
#: Tolerances of the pass/fail decisions.
EE_TOLERANCE = 0.15  # [m]
N4_MIN = 0.05  # |n_4| below which eq. (4.17) counts as losing the theta_4 direction [-]
WINDOW_TOLERANCE = 0.5  # [s] on each end of the singular window
INSPECTION_TOLERANCE_DEG = 0.1  # final camera error [deg]
STOWED_N4_MIN = 0.3  # |n_4| at the stowed pose for "well-conditioned" [-]


@dataclass(frozen=True)
class Score:
    """One constraint: ``value`` (units in ``unit``), ``passed``, the thesis ``target`` (text),
    and ``shortfall`` >= 0 (0 when met; a continuous distance for ranking and optimisation)."""

    name: str
    value: float
    passed: bool
    target: str
    unit: str = ""
    shortfall: float = 0.0
    detail: str = ""


def _q(robot: FreeFloatingModel, theta) -> np.ndarray:
    return robot.configuration(theta)


def score_end_effector(robot: FreeFloatingModel) -> Score:
    """|p_camera - [-1.7, 0.45, 1.7]| [m] at the 3-phase final configuration (section 4.4.2),
    base CoM frame, base at rest (the 1.95 deg deviation of Table 4.2 is ignored)."""
    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, _q(robot, np.deg2rad(THREE_PHASE_FINAL_DEG)))
    position = data.oMf[robot.camera_frame_id].translation
    error = float(np.linalg.norm(position - THESIS_EE_POSITION))
    return Score(
        "ee_position",
        error,
        error <= EE_TOLERANCE,
        "[-1.7, 0.45, 1.7] m (0 m error)",
        "m",
        max(0.0, error - EE_TOLERANCE) + 0.1 * error,
        "p = " + np.array2string(position, precision=3),
    )


@dataclass(frozen=True)
class FoldPath:
    """Result of :func:`elbow_path`.

    Attributes:
        reached: the target theta_4 was reached before any turning point.
        theta4_end: theta_4 where the path stopped [rad] (target, extremum, or arc limit).
        min_n4: smallest |n_4| seen [-] (n unit null vector of M~_P_omega_m).
        max_ratio: largest max_i<4 |n_i / n_4|: joint 1-3 speed per unit elbow speed, eq. (4.17).
        arc: joint-space arc length travelled [rad].
        theta_end: configuration at the stop [rad] (7,).
    """

    reached: bool
    theta4_end: float
    min_n4: float
    max_ratio: float
    arc: float
    theta_end: np.ndarray


def elbow_path(
    robot: FreeFloatingModel,
    theta0,
    theta4_target: float,
    *,
    step: float = 0.01,
    max_arc: float = 12.0,
) -> FoldPath:
    """Follow the reactionless elbow family of eq. (4.3) from ``theta0`` towards theta_4 =
    ``theta4_target`` [rad] by arc length (RK2, ``step`` [rad]); wrist joints held.

    The direction starts with n_4 pointing towards the target and stays sign-continuous; the path
    stops at the target (reached), where n_4 changes sign (a turning point: eq. 4.17-4.18 cannot
    drive theta_4 further) or after ``max_arc`` [rad] of joint-space arc.
    """
    theta = np.array(theta0, dtype=float)
    sense = 1.0 if theta4_target > theta[3] else -1.0
    n = positioning_null_vector(robot, theta)
    n = n if n[3] * sense >= 0.0 else -n
    min_n4, max_ratio, arc = abs(n[3]), 0.0, 0.0
    while arc < max_arc:
        if abs(n[3]) > 1e-12:
            max_ratio = max(max_ratio, float(np.abs(n[:3] / n[3]).max()))
        mid = theta.copy()
        mid[:4] += 0.5 * step * n
        n_mid = positioning_null_vector(robot, mid)
        n_mid = n_mid if n_mid @ n >= 0.0 else -n_mid
        new = theta.copy()
        new[:4] += step * n_mid
        n_new = positioning_null_vector(robot, new)
        n_new = n_new if n_new @ n_mid >= 0.0 else -n_new
        arc += step
        min_n4 = min(min_n4, abs(n_new[3]))
        if (new[3] - theta4_target) * sense >= 0.0:
            fraction = (theta4_target - theta[3]) / (new[3] - theta[3])
            end = theta + fraction * (new - theta)
            return FoldPath(True, theta4_target, min_n4, max_ratio, arc, end)
        if n_new[3] * sense <= 0.0:
            return FoldPath(False, float(new[3]), min_n4, max_ratio, arc, new)
        theta, n = new, n_new
    return FoldPath(False, float(theta[3]), min_n4, max_ratio, arc, theta)


def _fold_score(name: str, path: FoldPath, start4: float, target4: float, target: str) -> Score:
    covered = (path.theta4_end - start4) / (target4 - start4)
    passed = path.reached and path.min_n4 >= N4_MIN
    shortfall = abs(target4 - path.theta4_end) + max(0.0, N4_MIN - path.min_n4) * 10.0
    return Score(
        name,
        math.degrees(path.theta4_end),
        passed,
        target,
        "deg (theta4 reached)",
        shortfall,
        f"covered {covered:.0%}, min|n4| {path.min_n4:.3f}, max|n_i/n4| {path.max_ratio:.1f}",
    )


def score_fold_phase_one(robot: FreeFloatingModel, step: float = 0.01) -> Score:
    """Phase I (section 4.4.1): reactionless fold from [-20 -40 0 -60 180 180 0] deg to
    theta_4 = -pi without a turning point."""
    theta0 = np.deg2rad(THREE_PHASE_INITIAL_DEG)
    path = elbow_path(robot, theta0, -math.pi, step=step)
    return _fold_score("fold_phase_I", path, theta0[3], -math.pi, "-180 deg, no turning point")


def score_fold_phase_three(robot: FreeFloatingModel, step: float = 0.01) -> Score:
    """Phase III (section 4.4.1): reactionless fold from [-120 50 0 -60 180 180 0] deg to
    theta_4 = -pi without a turning point."""
    theta0 = np.deg2rad(THREE_PHASE_FINAL_DEG)
    path = elbow_path(robot, theta0, -math.pi, step=step)
    return _fold_score("fold_phase_III", path, theta0[3], -math.pi, "-180 deg, no turning point")


def score_stowed(robot: FreeFloatingModel) -> Score:
    """Stowed pose [pi/2 -pi/2 0 -pi pi pi 0] rad (eq. 4.19) "well-conditioned for the reactionless
    motion": |n_4| there (the elbow can move reactionlessly) and sigma_3 / sigma_1 of
    M~_P_omega_m."""
    theta = np.array(STOWED)
    q = robot.configuration(theta)
    tilde = pin.computeCentroidalMap(robot.model, robot.data, q)[3:, 6:10]
    _, sigma, vt = np.linalg.svd(tilde)
    n4 = abs(float(vt[-1][3]))
    ratio = float(sigma[-1] / sigma[0])
    return Score(
        "stowed",
        n4,
        n4 >= STOWED_N4_MIN,
        "well-conditioned (|n4| >= 0.3)",
        "|n4|",
        max(0.0, STOWED_N4_MIN - n4),
        f"sigma3/sigma1 of M~_Pwm {ratio:.3f}",
    )


def score_full_deployment(robot: FreeFloatingModel, step: float = 0.01) -> Score:
    """Section 4.5.1: from the stowed pose, theta_4 rises 0.183 rad/s x 30 s (-pi -> 2.349 rad)
    along the reactionless family without a turning point."""
    theta0 = np.array(STOWED)
    target = theta0[3] + DEPLOY_SPEED * DEPLOY_TIME
    path = elbow_path(robot, theta0, target, step=step, max_arc=25.0)
    return _fold_score(
        "full_deployment", path, theta0[3], target, "134.6 deg (+0.183 rad/s x 30 s)"
    )


def score_partial_deployment(robot: FreeFloatingModel, step: float = 0.01) -> Score:
    """Section 4.5.2 Phase III: from [90 50 0 -300 0 20 0] deg, theta_4 up to -pi (the fold,
    A-2.11 reading) without a turning point."""
    theta0 = np.deg2rad(PARTIAL_FINAL_DEG)
    path = elbow_path(robot, theta0, -math.pi, step=step)
    return _fold_score("partial_deployment", path, theta0[3], -math.pi, "-180 deg, no turning")


def _scenario(name: str, wrist_gain: float = 100.0) -> Scenario:
    scenario = load_scenario(SCENARIO_DIR / f"{name}.yaml")
    controller = {**scenario.controller, "wrist_gain": wrist_gain}
    return dataclasses.replace(scenario, controller=controller)


def _run(robot: FreeFloatingModel, scenario: Scenario, coarse: bool, on_period=None):
    if coarse:
        return run_scenario(robot, scenario, rate=20.0, simulation_step=0.01, on_period=on_period)
    return run_scenario(robot, scenario, on_period=on_period)


@dataclass(frozen=True)
class SingularWindow:
    """sigma_min(J-bar) < epsilon intervals of the section 4.3.1 run.

    Attributes:
        start, end: first interval [s] (nan when none).
        intervals: every interval [(start, end)] [s].
        min_sigma: smallest sigma_min [-] and its time [s].
        counter_rotating: at the sigma_min period joints 5 and 7 turn in opposite directions and
            are the two fastest joints.
    """

    start: float
    end: float
    intervals: tuple[tuple[float, float], ...]
    min_sigma: float
    min_time: float
    counter_rotating: bool


def singular_window(robot: FreeFloatingModel, coarse: bool = True) -> SingularWindow:
    """Run ``algorithmic_singularity.yaml`` (omega = [0, -0.2, 0] rad/s, DLS, k_g = 100) and
    find where sigma_min(J-bar) < 0.2 (section 4.3.2)."""
    samples: list[tuple[float, float, np.ndarray]] = []

    def record(sample: PeriodSample) -> None:
        out = sample.step.output
        samples.append((sample.t, out.sigma_min, np.array(out.joint_velocity)))

    _run(robot, _scenario("algorithmic_singularity"), coarse, record)
    times = np.array([s[0] for s in samples])
    sigma = np.array([s[1] for s in samples])
    inside = sigma < SINGULAR_EPSILON
    intervals, k = [], 0
    while k < len(inside):
        if inside[k]:
            j = k
            while j + 1 < len(inside) and inside[j + 1]:
                j += 1
            intervals.append((float(times[k]), float(times[j])))
            k = j + 1
        else:
            k += 1
    low = int(np.argmin(sigma))
    rates = samples[low][2]
    fastest = set(np.argsort(-np.abs(rates))[:2].tolist())
    counter = bool(rates[4] * rates[6] < 0.0 and fastest == {4, 6})
    start, end = intervals[0] if intervals else (math.nan, math.nan)
    return SingularWindow(
        start, end, tuple(intervals), float(sigma[low]), float(times[low]), counter
    )


def score_singular_window(robot: FreeFloatingModel, coarse: bool = True) -> Score:
    """Section 4.3.1-4.3.2: the DLS singular region sigma_3 < 0.2 at 1.71-4.18 s and joints 5, 7
    counter-rotating near it. Value: the larger end mismatch [s] (inf when no window)."""
    window = singular_window(robot, coarse)
    if not window.intervals:
        mismatch = math.inf
        shortfall = 10.0 + max(0.0, window.min_sigma - SINGULAR_EPSILON) * 10.0
    else:
        mismatch = max(abs(window.start - THESIS_WINDOW[0]), abs(window.end - THESIS_WINDOW[1]))
        shortfall = max(0.0, mismatch - WINDOW_TOLERANCE) + 0.1 * mismatch
    shortfall += 0.0 if window.counter_rotating else 0.5
    passed = mismatch <= WINDOW_TOLERANCE and window.counter_rotating
    windows = ", ".join(f"{a:.2f}-{b:.2f}" for a, b in window.intervals) or "none"
    return Score(
        "singular_window",
        mismatch,
        passed,
        "1.71-4.18 s, joints 5/7 counter-rotate",
        "s (max end mismatch)",
        shortfall,
        f"windows {windows} s, min sigma {window.min_sigma:.3f} at {window.min_time:.2f} s, "
        f"5/7 counter-rotating {window.counter_rotating}",
    )


def score_inspection(robot: FreeFloatingModel, name: str, coarse: bool = True) -> Score:
    """Section 4.2.2 scenario ``name`` (satellite_observation / own_device_inspection) with
    k_g = 100: final camera error [deg] (thesis: task accomplished), wrist drift [m]."""
    result = _run(robot, _scenario(name), coarse)
    error = result.final_orientation_error_deg
    return Score(
        name,
        error,
        error <= INSPECTION_TOLERANCE_DEG and result.min_sigma >= SINGULAR_EPSILON,
        "camera on target (error ~0 deg), k_g = 100",
        "deg",
        max(0.0, error - INSPECTION_TOLERANCE_DEG) / 10.0
        + max(0.0, SINGULAR_EPSILON - result.min_sigma),
        f"wrist drift {result.max_wrist_drift:.3f} m, min sigma {result.min_sigma:.3f}",
    )


#: Cheap constraints (path integrals, no closed loop).
PATH_CONSTRAINTS = ("ee_position", "fold_phase_I", "fold_phase_III", "stowed", "full_deployment",
         "partial_deployment")  # fmt: skip
#: Closed-loop constraints.
CLOSED_LOOP_CONSTRAINTS = ("singular_window", "satellite_observation", "own_device_inspection")


def score_all(
    geometry: Geometry, *, closed_loop: bool = True, coarse: bool = True, step: float = 0.01
) -> dict[str, Score]:
    """Every score of ``geometry`` (the closed-loop ones only with ``closed_loop``)."""
    robot = build_model(geometry)
    scores = [
        score_end_effector(robot),
        score_fold_phase_one(robot, step),
        score_fold_phase_three(robot, step),
        score_stowed(robot),
        score_full_deployment(robot, step),
        score_partial_deployment(robot, step),
    ]
    if closed_loop:
        scores += [
            score_singular_window(robot, coarse),
            score_inspection(robot, "satellite_observation", coarse),
            score_inspection(robot, "own_device_inspection", coarse),
        ]
    return {score.name: score for score in scores}


def total_shortfall(scores: dict[str, Score]) -> float:
    """Ranking key: sum of the shortfalls (0 when every constraint is met)."""
    return float(sum(score.shortfall for score in scores.values()))
