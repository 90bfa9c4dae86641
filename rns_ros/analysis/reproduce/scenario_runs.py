"""Closed-loop runs of the shipped scenarios for Figs. 4.4-4.8, recorded and cached per process.

A run plays ``config/scenarios/<name>.yaml`` through
:func:`rns_ros.analysis.closed_loop.run_scenario` (the controller core sampled at its rate, the
kinematic free-floating simulator at its RK4 step, midpoint hold) and records, per control
period, the time series the thesis plots (:class:`Trace`). :func:`run` caches one run per
(scenario, method, quick, k_g), so results that share a run compute it once.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import inspect
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.analysis.arm_geometry import IDENTIFIED_GEOMETRY, build_model
from rns_ros.analysis.closed_loop import ClosedLoopResult, PeriodSample, run_scenario
from rns_ros.control.camera_law import wrist_offset
from rns_ros.control.scenario import Scenario, load_scenario
from rns_ros.core import FreeFloatingModel, load_model
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.state import FreeFloatingState
from rns_ros.resources import config_dir, default_model_config

#: Quick runs (tests): controller rate [Hz] and simulator step [s]; the whole scenario still runs.
QUICK_RATE, QUICK_STEP = 50.0, 2e-3


@dataclass(frozen=True)
class Trace:
    """Time series of one closed-loop run, one row per control period.

    Attributes:
        t_mid: middle of each period [s] (controller quantities: theta_dot, sigma, determinants,
            omega_ref, the mean achieved omega over the period).
        t_end: end of each period [s] (state quantities: base deviation, wrist drift).
        theta_dot: commanded (= simulated, kinematic mode) joint velocities [rad/s], (N, n).
        omega_ref, omega_achieved: camera angular velocity commanded / achieved, world [rad/s].
        omega_error: |omega_achieved - omega_ref| [rad/s].
        axis_error_deg: angle between achieved and commanded rotation axis [deg] (nan at rest).
        base_deviation_deg: geodesic base attitude deviation [deg].
        base_rpy_deg: roll, pitch, yaw of R_b(0)^T R_b(t) [deg], (N, 3).
        wrist_drift: |p_w - p_w^init| [m].
        det_kinematic, det_coupling, det_algorithmic: the determinants of §4.3.1.
        sigma_min: sigma_min of J-bar (J_W_omega_e for the conventional baseline) [-].
        damping: DLS lambda^2 [-]; speed_scale: SC / limit speed factor [-].
        limit_scale: the joint-limit part of ``speed_scale`` alone, in [0, 1] [-] (below 1 when
            the URDF speed or position limits scaled the command down).
    """

    t_mid: np.ndarray
    t_end: np.ndarray
    theta_dot: np.ndarray
    omega_ref: np.ndarray
    omega_achieved: np.ndarray
    omega_error: np.ndarray
    axis_error_deg: np.ndarray
    base_deviation_deg: np.ndarray
    base_rpy_deg: np.ndarray
    wrist_drift: np.ndarray
    det_kinematic: np.ndarray
    det_coupling: np.ndarray
    det_algorithmic: np.ndarray
    sigma_min: np.ndarray
    damping: np.ndarray
    speed_scale: np.ndarray
    limit_scale: np.ndarray


@dataclass(frozen=True)
class Run:
    """One closed-loop run: its summary (``result``), time series and the settings used."""

    label: str
    result: ClosedLoopResult
    trace: Trace
    settings: dict

    @property
    def wrist_gain(self) -> float:
        """k_g of the wrist term (4.6) the run used [1/s]."""
        return self.settings["gains"]["wrist_gain"]


class TraceRecorder:
    """Collects :class:`PeriodSample` rows into a :class:`Trace`."""

    def __init__(self, state_0: FreeFloatingState) -> None:
        self.base_0 = state_0.base_rotation
        self.wrist_0 = wrist_offset(state_0)
        self.rows: list[PeriodSample] = []
        self.base: list[float] = []
        self.rpy: list[np.ndarray] = []
        self.wrist: list[float] = []

    def __call__(self, sample: PeriodSample) -> None:
        self.rows.append(sample)
        rotation = sample.state.base_rotation
        self.base.append(attitude_deviation(self.base_0, rotation))
        self.rpy.append(pin.rpy.matrixToRpy(self.base_0.T @ rotation))
        self.wrist.append(float(np.linalg.norm(wrist_offset(sample.state) - self.wrist_0)))

    def trace(self) -> Trace:
        rows = self.rows
        t = np.array([s.t for s in rows])
        period = np.array([s.period for s in rows])
        omega_ref = np.array([s.omega_ref for s in rows])
        achieved = np.array([s.achieved for s in rows])
        omega_achieved = achieved / period[:, None]
        speed = np.linalg.norm(omega_ref, axis=1)
        size = np.linalg.norm(achieved, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            cosine = np.einsum("ij,ij->i", omega_ref, achieved) / (speed * size)
        axis_error = np.rad2deg(np.arccos(np.clip(cosine, -1.0, 1.0)))
        axis_error[(speed < 1e-3) | (size == 0.0)] = np.nan
        outputs = [s.step.output for s in rows]
        return Trace(
            t_mid=t + 0.5 * period,
            t_end=t + period,
            theta_dot=np.array([s.step.joint_velocity for s in rows]),
            omega_ref=omega_ref,
            omega_achieved=omega_achieved,
            omega_error=np.linalg.norm(omega_achieved - omega_ref, axis=1),
            axis_error_deg=axis_error,
            base_deviation_deg=np.rad2deg(np.array(self.base)),
            base_rpy_deg=np.rad2deg(np.array(self.rpy)),
            wrist_drift=np.array(self.wrist),
            det_kinematic=np.array([o.determinants.kinematic for o in outputs]),
            det_coupling=np.array([o.determinants.coupling for o in outputs]),
            det_algorithmic=np.array([o.determinants.algorithmic for o in outputs]),
            sigma_min=np.array([o.sigma_min for o in outputs]),
            damping=np.array([o.damping for o in outputs]),
            speed_scale=np.array([o.speed_scale for o in outputs]),
            limit_scale=np.array([o.limit_scale for o in outputs]),
        )


@functools.cache
def default_robot() -> FreeFloatingModel:
    """The default 7-DoF model (config/model.yaml) with its URDF joint limits, loaded once per
    process: the product's limits, for the labelled "URDF limits" series."""
    return load_model(default_model_config())


@functools.cache
def thesis_robot() -> FreeFloatingModel:
    """The default 7-DoF model without joint speed or position limits, as the thesis simulates
    it (its runs scale nothing down): the model every reproduction runs on unless it says
    otherwise. The URDF's limits are a product safety choice (:func:`default_robot`)."""
    return _without_limits(load_model(default_model_config()))


#: Upper-arm and forearm length factors of the labelled sensitivity runs (:func:`resized_arm`).
ARM_SCALES = (0.9, 1.1)


@functools.cache
def resized_arm(scale: float) -> FreeFloatingModel:
    """:func:`thesis_robot` with the upper arm and the forearm (links 3 and 4, the identified
    geometry's longest) ``scale`` times as long, masses and moments kept: how much a result
    depends on link lengths the thesis does not print."""
    lengths = list(IDENTIFIED_GEOMETRY.lengths)
    lengths[2] *= scale
    lengths[3] *= scale
    return _without_limits(
        build_model(dataclasses.replace(IDENTIFIED_GEOMETRY, lengths=tuple(lengths)))
    )


def _without_limits(model: FreeFloatingModel) -> FreeFloatingModel:
    robot = copy.copy(model)
    robot.velocity_limits = np.full(robot.n, np.inf)
    robot.lower_limits = np.full(robot.n, -np.inf)
    robot.upper_limits = np.full(robot.n, np.inf)
    return robot


def shipped_scenario(name: str, wrist_gain: float | None = None) -> Scenario:
    """``config/scenarios/<name>.yaml``; ``wrist_gain`` overrides its k_g."""
    scenario = load_scenario(config_dir() / "scenarios" / f"{name}.yaml")
    if wrist_gain is not None:
        controller = {**scenario.controller, "wrist_gain": float(wrist_gain)}
        scenario = dataclasses.replace(scenario, controller=controller)
    return scenario


def loop_settings(quick: bool) -> dict:
    """run_scenario's defaults (the thesis settings), coarser when quick."""
    defaults = {
        name: parameter.default
        for name, parameter in inspect.signature(run_scenario).parameters.items()
        if name in ("hold_correction", "hold_iterations", "rate", "mode", "simulation_step")
    }
    if quick:
        defaults.update(rate=QUICK_RATE, simulation_step=QUICK_STEP)
    return {key: getattr(value, "value", value) for key, value in defaults.items()}


@functools.cache  # unbounded: one run per (scenario, method, quick, k_g, limits)
def recorded_run(
    name: str,
    method: str,
    quick: bool,
    wrist_gain: float | None = None,
    urdf_limits: bool = False,
) -> Run:
    """Run scenario ``name`` with ``method`` (``wrist_gain`` overrides the file's k_g) on
    :func:`thesis_robot`, or with ``urdf_limits`` on :func:`default_robot` (commands scaled
    down to the URDF's joint limits; label suffix ``_urdf_limits``)."""
    robot = default_robot() if urdf_limits else thesis_robot()
    scenario = shipped_scenario(name, wrist_gain)
    loop = loop_settings(quick)
    state_0 = FreeFloatingState.compute(robot, robot.configuration(scenario.initial_theta))
    recorder = TraceRecorder(state_0)
    result = run_scenario(robot, scenario, method=method, on_period=recorder, **loop)
    gains = dataclasses.asdict(scenario.gains())
    label = method if wrist_gain is None else f"{method}_kg{wrist_gain:g}"
    label += "_urdf_limits" if urdf_limits else ""
    settings = {"method": method, "gains": gains, "joint_limits": _limits_used(urdf_limits), **loop}
    return Run(label, result, recorder.trace(), settings)


def _limits_used(urdf_limits: bool) -> str:
    return (
        "URDF speed and position limits (commands scaled down uniformly)"
        if urdf_limits
        else "none (as in the thesis' simulations)"
    )


def scenario_settings(name: str) -> dict:
    """The JSON settings of scenario ``name`` (start, command, overrides)."""
    scenario = shipped_scenario(name)
    return {
        "scenario": f"config/scenarios/{name}.yaml",
        "initial_joint_positions_deg": np.round(np.rad2deg(scenario.initial_theta), 6).tolist(),
        "frame": scenario.frame.value,
        "axis": scenario.axis.tolist(),
        "angle_deg": float(np.rad2deg(scenario.angle)),
        "duration_s": scenario.duration,
        "time_scaling": scenario.time_scaling.value,
        "scenario_controller_overrides": dict(scenario.controller),
    }


def model_settings() -> dict:
    robot = default_robot()
    return {"model": f"{robot.name} (config/urdf/rns_7dof_arm.urdf, {robot.n} joints)"}


def run_values(runs: list[Run]) -> dict:
    """The JSON values every result carries, as {method: value} dicts."""

    def each(function):
        return {run.label: function(run) for run in runs}

    return {
        "max_base_deviation_deg": each(lambda r: r.result.max_base_deviation_deg),
        "max_base_rpy_deg": each(
            lambda r: dict(
                zip(("roll", "pitch", "yaw"), np.abs(r.trace.base_rpy_deg).max(axis=0), strict=True)
            )
        ),
        "final_camera_error_deg": each(lambda r: r.result.final_orientation_error_deg),
        "max_axis_error_deg": each(lambda r: r.result.max_axis_error_deg),
        "rms_angular_velocity_error_rad_s": each(lambda r: r.result.rms_tracking_error),
        "achieved_angle_deg": each(lambda r: r.result.achieved_angle_deg),
        "max_wrist_drift_m": each(lambda r: r.result.max_wrist_drift),
        "max_joint_speed_rad_s": each(lambda r: r.result.max_joint_speed),
        "min_sigma": each(lambda r: r.result.min_sigma),
        "max_damping": each(lambda r: r.result.max_damping),
        "speed_scale_range": each(lambda r: [r.result.min_speed_scale, r.result.max_speed_scale]),
        "min_joint_limit_scale": each(lambda r: float(r.trace.limit_scale.min())),
        "min_det_algorithmic": each(lambda r: r.result.min_algorithmic_determinant),
        "min_det_kinematic": each(lambda r: r.result.min_kinematic_determinant),
        "min_det_coupling_kg6m12": each(lambda r: r.result.min_coupling_determinant),
        "max_coupling_momentum_kgm2_s": each(lambda r: r.result.max_coupling_momentum),
        "momentum_drift": each(lambda r: r.result.momentum_drift),
        "periods": each(lambda r: r.result.steps),
    }


def run_settings(name: str, runs: list[Run], quick: bool) -> dict:
    """The JSON settings of a result on scenario ``name``: scenario, methods, loop, model."""
    first = runs[0].settings
    return {
        **scenario_settings(name),
        "methods": {
            run.label: {
                "method": run.settings["method"],
                "joint_limits": run.settings["joint_limits"],
                **run.settings["gains"],
            }
            for run in runs
        },
        "controller_rate_hz": first["rate"],
        "simulation_step_s": first["simulation_step"],
        "simulation_mode": first["mode"],
        "hold_correction": first["hold_correction"],
        "hold_iterations": first["hold_iterations"],
        **model_settings(),
        "quick": quick,
    }
