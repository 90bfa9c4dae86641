"""In-process closed loop: :class:`ReactionlessController` driving :class:`FreeFloatingSimulator`.

No ROS: the controller samples the simulated robot every period, its output is held (kinematic
mode: joint velocities; dynamic mode: the servo reference) while the simulator integrates at its
own finer step. Used by the tests, the benchmark and the docs to measure the thesis scenarios.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.control.camera_law import ControlGains, Method, wrist_offset
from rns_ros.control.controller import (
    ControllerSettings,
    ControllerStep,
    HoldCorrection,
    ReactionlessController,
    angular_velocity_in_world,
)
from rns_ros.control.scenario import Scenario
from rns_ros.core.errors import ConfigError
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import positive
from rns_ros.sim.free_floating import FreeFloatingSimulator, SimulationMode

#: Periods commanding less than this rate [rad/s] do not count for the axis error (at rest the
#: achieved rotation is servo noise with no meaningful direction).
_AXIS_MIN_RATE = 1e-3


@dataclass(frozen=True)
class ClosedLoopResult:
    """Figures of one closed-loop scenario run (angles in degrees as the names say).

    Attributes:
        max_base_deviation_deg: largest base attitude change from the start [deg].
        final_orientation_error_deg: camera orientation vs the commanded target at the end [deg].
        max_axis_error_deg: largest angle between the achieved and the commanded rotation axis
            over one period, where the command turns (direction fidelity, SC's promise) [deg].
        rms_tracking_error: RMS of |omega_achieved - omega_ref| over the periods [rad/s].
        achieved_angle_deg: camera rotation achieved along the command, summed over the periods
            (signed by the commanded direction, so it can exceed 180) [deg].
        max_wrist_drift: largest |p_w - p_w^init| (wrist relative to the base) [m].
        max_joint_speed: largest |theta_dot_i| commanded [rad/s].
        min_sigma: smallest sigma_min of J-bar seen [-].
        max_damping: largest DLS lambda^2 applied [-].
        min_speed_scale: smallest speed scale applied (SC and joint limits) [-].
        max_speed_scale: largest speed scale applied [-] (SC can exceed 1).
        min_algorithmic_determinant: smallest det(J-bar J-bar^T) [-] and its time [s].
        min_kinematic_determinant: smallest det(J_omega_e J_omega_e^T) [-].
        min_coupling_determinant: smallest det(M~_omega_m M~_omega_m^T) [(kg m^2)^6].
        max_coupling_momentum: largest |M~_omega_m theta_dot| predicted [kg m^2/s].
        momentum_drift: |h_G(end) - h_G(0)| [SI].
        max_servo_error: largest |theta_ref - theta| over the run [rad] (dynamic mode cost).
        steps: control periods run.
    """

    max_base_deviation_deg: float
    final_orientation_error_deg: float
    max_axis_error_deg: float
    rms_tracking_error: float
    achieved_angle_deg: float
    max_wrist_drift: float
    max_joint_speed: float
    min_sigma: float
    max_damping: float
    min_speed_scale: float
    max_speed_scale: float
    min_algorithmic_determinant: float
    min_algorithmic_determinant_time: float
    min_kinematic_determinant: float
    min_coupling_determinant: float
    max_coupling_momentum: float
    momentum_drift: float
    max_servo_error: float
    steps: int


@dataclass(frozen=True)
class PeriodSample:
    """One control period of :func:`run_scenario`, for time series (``on_period``).

    Attributes:
        t: start of the period [s].
        period: its length [s].
        omega_ref: commanded camera angular velocity, world axes [rad/s], shape (3,).
        step: what the controller output (joint velocities, determinants, sigma_min...).
        achieved: camera rotation vector over the period, world axes [rad], shape (3,)
            (achieved / period is the mean achieved angular velocity).
        state: the robot at the end of the period.
    """

    t: float
    period: float
    omega_ref: np.ndarray
    step: ControllerStep
    achieved: np.ndarray
    state: FreeFloatingState


def run_scenario(
    robot: FreeFloatingModel,
    scenario: Scenario,
    *,
    method: Method | str | None = None,
    gains: ControlGains | None = None,
    hold_correction: HoldCorrection | str = HoldCorrection.MIDPOINT,
    hold_iterations: int = 1,
    rate: float = 100.0,
    mode: SimulationMode | str = SimulationMode.KINEMATIC,
    simulation_step: float = 1e-3,
    settle: float = 0.0,
    on_period: Callable[[PeriodSample], None] | None = None,
) -> ClosedLoopResult:
    """Run ``scenario`` in closed loop and measure it.

    Args:
        method, gains: default to the scenario's overrides on top of DLS / thesis gains.
        hold_correction, hold_iterations: see :class:`ControllerSettings`.
        rate: control rate [Hz]; the simulator takes round(1 / (rate * simulation_step)) steps per
            period, so 1 / rate must be a multiple of ``simulation_step``.
        mode: simulator mode.
        simulation_step: simulator step [s].
        settle: extra time after the command ends, zero command [s].
        on_period: called with a :class:`PeriodSample` after every period (time series).
    """
    period, substeps = _period_and_substeps(rate, simulation_step)
    settings = ControllerSettings(
        method=scenario.method() if method is None else method,
        gains=scenario.gains(gains),
        period=period,
        hold_correction=hold_correction,
        hold_iterations=hold_iterations,
    )
    q0 = robot.configuration(scenario.initial_theta)
    state = FreeFloatingState.compute(robot, q0)
    simulator = FreeFloatingSimulator(
        robot, mode=mode, dt=period / substeps, initial_q=q0, initial_momentum=np.zeros(6)
    )
    momentum_0 = simulator.centroidal_momentum()
    controller = ReactionlessController(robot, settings)
    controller.reset(state)
    base_0, camera_0 = state.base_rotation, state.camera.rotation
    wrist_0 = controller.wrist_reference

    figures = _Figures()
    steps = round((scenario.duration + settle) / period)
    for k in range(steps):
        t = k * period
        # the command sampled at the middle of the hold integrates the profile to O(T^3)
        omega = angular_velocity_in_world(
            state, scenario.angular_velocity(t + 0.5 * period), scenario.frame
        )
        step = controller.step(state, omega)
        out = step.output
        if simulator.mode is SimulationMode.KINEMATIC:
            simulator.set_reference(velocities=step.joint_velocity)
        else:
            simulator.set_reference(step.reference_positions, step.joint_velocity)
        camera_before = state.camera.rotation
        _hold(simulator, substeps, figures)
        state = FreeFloatingState.compute(robot, simulator.q)
        achieved = pin.log3(state.camera.rotation @ camera_before.T)
        figures.record_step(out, step.joint_velocity, omega, achieved, period, t)
        if on_period is not None:
            on_period(PeriodSample(t, period, omega, step, achieved, state))
        figures.base = max(figures.base, attitude_deviation(base_0, state.base_rotation))
        if wrist_0 is not None:
            figures.wrist = max(figures.wrist, float(np.linalg.norm(wrist_offset(state) - wrist_0)))

    target = scenario.target_rotation(camera_0, base_0, scenario.duration)
    momentum_drift = float(np.linalg.norm(simulator.centroidal_momentum() - momentum_0))
    return figures.result(target, state, momentum_drift, steps)


def _period_and_substeps(rate: float, simulation_step: float) -> tuple[float, int]:
    """(control period [s], simulator steps per period); ConfigError unless 1 / rate is a
    multiple of ``simulation_step`` [s]."""
    period = 1.0 / positive(rate, "rate", "Hz")
    substeps = round(period / positive(simulation_step, "simulation_step", "s"))
    if substeps < 1 or abs(substeps * simulation_step - period) > 1e-9 * period:
        raise ConfigError(
            f"the control period 1/rate = {period} s must be a multiple of simulation_step "
            f"{simulation_step} s"
        )
    return period, substeps


def _hold(simulator: FreeFloatingSimulator, substeps: int, figures: _Figures) -> None:
    """Integrate one control period with the reference held; track the servo error."""
    for _ in range(substeps):
        simulator.step()
        figures.servo_error = max(
            figures.servo_error,
            float(np.abs(simulator.reference.positions - simulator.q[7:]).max()),
        )


class _Figures:
    """Running extrema of one run (mutable accumulator, private)."""

    def __init__(self) -> None:
        self.base = self.wrist = self.axis = self.joint_speed = self.damping = 0.0
        self.coupling = self.squared_error = self.servo_error = self.max_scale = 0.0
        self.angle = 0.0
        self.sigma = self.min_scale = np.inf
        self.det_algorithmic = self.det_kinematic = self.det_coupling = np.inf
        self.det_algorithmic_time = 0.0

    def record_step(self, out, theta_dot, omega, achieved, period, t) -> None:
        self.joint_speed = max(self.joint_speed, float(np.abs(theta_dot).max()))
        self.sigma = min(self.sigma, out.sigma_min)
        self.damping = max(self.damping, out.damping)
        self.min_scale = min(self.min_scale, out.speed_scale)
        self.max_scale = max(self.max_scale, out.speed_scale)
        self.coupling = max(self.coupling, float(np.linalg.norm(out.coupling_momentum)))
        self.squared_error += float(np.sum((achieved / period - omega) ** 2))
        speed = float(np.linalg.norm(omega))
        if speed > _AXIS_MIN_RATE:
            along = float(omega @ achieved) / speed
            self.angle += along
            magnitude = float(np.linalg.norm(achieved))
            if magnitude > 0.0:
                cosine = np.clip(along / magnitude, -1.0, 1.0)
                self.axis = max(self.axis, float(np.arccos(cosine)))
        det = out.determinants
        if det.algorithmic < self.det_algorithmic:
            self.det_algorithmic, self.det_algorithmic_time = det.algorithmic, t
        self.det_kinematic = min(self.det_kinematic, det.kinematic)
        self.det_coupling = min(self.det_coupling, det.coupling)

    def result(
        self, target: np.ndarray, state: FreeFloatingState, momentum_drift: float, steps: int
    ) -> ClosedLoopResult:
        """The :class:`ClosedLoopResult` of the run, ``state`` its end."""
        return ClosedLoopResult(
            max_base_deviation_deg=float(np.rad2deg(self.base)),
            final_orientation_error_deg=float(
                np.rad2deg(attitude_deviation(target, state.camera.rotation))
            ),
            max_axis_error_deg=float(np.rad2deg(self.axis)),
            rms_tracking_error=float(np.sqrt(self.squared_error / max(steps, 1))),
            achieved_angle_deg=float(np.rad2deg(self.angle)),
            max_wrist_drift=self.wrist,
            max_joint_speed=self.joint_speed,
            min_sigma=self.sigma,
            max_damping=self.damping,
            min_speed_scale=self.min_scale,
            max_speed_scale=self.max_scale,
            min_algorithmic_determinant=self.det_algorithmic,
            min_algorithmic_determinant_time=self.det_algorithmic_time,
            min_kinematic_determinant=self.det_kinematic,
            min_coupling_determinant=self.det_coupling,
            max_coupling_momentum=self.coupling,
            momentum_drift=momentum_drift,
            max_servo_error=self.servo_error,
            steps=steps,
        )
