"""Point-to-point baselines of thesis section 4.4.2: JS-C, IJ-C and TJ-C (thesis_rest section 2).

* JS-C: quintic straight line start -> goal over ``settings.duration``.
* IJ-C: theta_dot_P = J*_P^+ (p_dot_des + K_p (p_des - p_e)), with J*_P the linear rows of the
  Generalized Jacobian of the camera for the positioning joints (A-2.8) and p_des a quintic
  straight line from the start camera position to ``camera_target``.
* TJ-C: theta_dot_P = K J*_P^T (p_des - p_e), same p_des (A-2.9); K is the first of
  ``transposed_gains`` whose final error is below ``target_tolerance``.

For IJ-C and TJ-C only the positioning subchain is driven by the law; the wrist joints move
start -> goal on the JS-C quintic (held when start and goal wrists agree, as in the thesis
scenario). Both are closed-loop laws: they are integrated offline on the kinematic free-floating
model (zero momentum, RK4, ``integration_step``) and the trajectory is stored, so
:meth:`PtpPlan.sample` gives the same kind of output as for the other methods.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rns_ros.control.ptp import (
    PhaseInfo,
    PtpMethod,
    PtpPlan,
    PtpSettings,
    QuinticLine,
    StoredTrajectory,
    joint_speed_limits,
    line_duration,
    stretch_note,
)
from rns_ros.control.ptp_phases import plan_three_phase
from rns_ros.core.errors import ModelError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.momentum import generalized_jacobian
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.timing import quintic
from rns_ros.core.validation import as_vector, positive

#: theta_dot_P of a Jacobian baseline from (gain, camera linear Generalized Jacobian (3, n),
#: camera position error (3,) [m], desired camera velocity (3,) [m/s], theta_dot (n,) with the
#: wrist rates set, positioning indices, wrist indices) [rad/s], shape (p,).
PositioningLaw = Callable[..., np.ndarray]


def plan_joint_space(
    robot: FreeFloatingModel, start: np.ndarray, goal: np.ndarray, settings: PtpSettings
) -> PtpPlan:
    """JS-C: the quintic line ``start`` -> ``goal`` [rad] (n,, both checked), stretched to the
    joint velocity limits."""
    nominal = positive(settings.duration, "duration", "[s]")
    duration = line_duration(robot, goal - start, nominal)
    notes = stretch_note("JS-C", nominal, duration)
    phase = PhaseInfo("JS-C", 0.0, duration, False, None)
    segment = QuinticLine(start, goal, duration)
    return PtpPlan(
        PtpMethod.JOINT_SPACE, [phase], [segment], notes, goal, start, settings.elbow_gain
    )


def inverse_jacobian_rates(gain, jacobian, error, v_des, theta_dot, positioning, wrist):
    """IJ-C (A-2.8): J*_P^+ (p_dot_des + K_p e - J*_W theta_dot_W), least squares."""
    j_p = jacobian[:, positioning]
    rhs = v_des + gain * error - jacobian[:, wrist] @ theta_dot[wrist]
    return np.linalg.lstsq(j_p, rhs, rcond=1e-10)[0]


def transposed_jacobian_rates(gain, jacobian, error, v_des, theta_dot, positioning, wrist):
    """TJ-C (A-2.9): K J*_P^T e."""
    j_p = jacobian[:, positioning]
    return gain * (j_p.T @ error)


class BaselineRun(NamedTuple):
    """One offline integration of a Jacobian baseline.

    Attributes:
        times: node times [s], shape (k,).
        qs: configurations (k, 7 + n).
        rates: theta_dot at the nodes [rad/s], shape (k, n).
        error: final camera position error [m].
        scaled: evaluations whose command was scaled to the velocity limits.
    """

    times: np.ndarray
    qs: np.ndarray
    rates: np.ndarray
    error: float
    scaled: int


class JacobianBaseline:
    """What IJ-C and TJ-C share: the camera target and its quintic line p_des(t), the wrist's
    JS-C quintic, the offline integration and the resulting :class:`PtpPlan`."""

    def __init__(
        self, robot: FreeFloatingModel, start: np.ndarray, goal: np.ndarray, settings: PtpSettings
    ) -> None:
        if robot.subchains is None:
            raise ModelError(f"{robot.name}: IJ-C/TJ-C drive the positioning subchain; none is set")
        self.robot, self.start, self.settings = robot, start, settings
        self.duration = positive(settings.duration, "duration", "[s]")
        self.step = positive(settings.integration_step, "integration_step", "[s]")
        self.notes = []
        if settings.camera_target is None:
            reference = plan_three_phase(robot, start, goal, settings)
            self.target = final_camera_position(robot, reference, self.step)
            self.notes.append("camera target: final camera position of the 3-phase plan (A-2.5)")
        else:
            self.target = as_vector(settings.camera_target, 3, "camera_target")
            self.notes.append("camera target: settings.camera_target")
        self.q0 = robot.configuration(start)
        self.p0 = np.array(FreeFloatingState.compute(robot, self.q0).camera.position)
        wrist = robot.subchains.wrist
        self.wrist_line = QuinticLine(start[wrist], goal[wrist], self.duration)

    def run(self, law: PositioningLaw, gain: float) -> BaselineRun:
        """Integrate theta_dot_P = ``law`` (wrist on its quintic) with ``gain``."""
        robot, duration, target, p0 = self.robot, self.duration, self.target, self.p0
        positioning, wrist = robot.subchains.positioning, robot.subchains.wrist
        limits = joint_speed_limits(robot)
        scaled = [0]

        def rates(t: float, state: FreeFloatingState) -> np.ndarray:
            s, s_dot = quintic(t, duration)
            p_des, v_des = p0 + s * (target - p0), s_dot * (target - p0)
            jacobian = generalized_jacobian(state, state.camera)[:3]
            error = p_des - state.camera.position
            theta_dot = np.zeros(robot.n)
            theta_dot[wrist] = self.wrist_line(t)[1]
            theta_dot[positioning] = law(
                gain, jacobian, error, v_des, theta_dot, positioning, wrist
            )
            excess = float(np.max(np.abs(theta_dot) / limits))
            if excess > 1.0:
                scaled[0] += 1
                theta_dot /= excess
            return theta_dot

        times, qs, thetas_dot = integrate_kinematic(robot, self.q0, rates, duration, self.step)
        final = FreeFloatingState.compute(robot, qs[-1]).camera.position
        error = float(np.linalg.norm(final - target))
        return BaselineRun(times, qs, thetas_dot, error, scaled[0])

    def plan(
        self, method: PtpMethod, name: str, run: BaselineRun, gain: float, note: str
    ) -> PtpPlan:
        """The :class:`PtpPlan` of ``run`` (one stored phase ``name``)."""
        notes = [*self.notes, note]
        if run.scaled:
            notes.append(
                f"{name}: command scaled uniformly to the velocity limits at {run.scaled} "
                "evaluations"
            )
        thetas = run.qs[:, 7:]
        segment = StoredTrajectory(run.times, thetas, run.rates)
        phase = PhaseInfo(name, 0.0, self.duration, False, None)
        details = {"camera_target": self.target, "gain": gain, "final_error": run.error}
        return PtpPlan(
            method,
            [phase],
            [segment],
            notes,
            thetas[-1],
            self.start,
            self.settings.elbow_gain,
            details,
        )


def plan_inverse_jacobian(
    robot: FreeFloatingModel, start: np.ndarray, goal: np.ndarray, settings: PtpSettings
) -> PtpPlan:
    """IJ-C with K_p = ``settings.position_gain``; ``start``, ``goal`` [rad] (n,), checked."""
    baseline = JacobianBaseline(robot, start, goal, settings)
    gain = positive(settings.position_gain, "position_gain", "[1/s]")
    run = baseline.run(inverse_jacobian_rates, gain)
    note = (
        f"IJ-C: Generalized Jacobian, K_p = {gain:g} 1/s; "
        f"final camera error {run.error * 1e3:.2f} mm"
    )
    return baseline.plan(PtpMethod.INVERSE_JACOBIAN, "IJ-C", run, gain, note)


def plan_transposed_jacobian(
    robot: FreeFloatingModel, start: np.ndarray, goal: np.ndarray, settings: PtpSettings
) -> PtpPlan:
    """TJ-C with the first K of ``settings.transposed_gains`` whose final camera error is below
    ``settings.target_tolerance`` (else the last); ``start``, ``goal`` [rad] (n,), checked."""
    baseline = JacobianBaseline(robot, start, goal, settings)
    for gain in settings.transposed_gains:
        run = baseline.run(transposed_jacobian_rates, positive(gain, "transposed gain"))
        if run.error < settings.target_tolerance:
            break
    note = (
        f"TJ-C: Generalized Jacobian transpose, K = {gain:g}; final camera error "
        f"{run.error * 1e3:.2f} mm (tolerance {settings.target_tolerance * 1e3:g} mm)"
    )
    return baseline.plan(PtpMethod.TRANSPOSED_JACOBIAN, "TJ-C", run, gain, note)


# offline integration ---------------------------------------------------------------------------
def integrate_kinematic(
    robot: FreeFloatingModel,
    q0: np.ndarray,
    law: Callable[[float, FreeFloatingState], np.ndarray],
    duration: float,
    step: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kinematic free-floating RK4 (zero momentum) of theta_dot = law(t, state).

    The base twist keeps the centroidal momentum zero (eq. 2.33): A_b v_b = -A_m theta_dot with
    Pinocchio's centroidal map A_G = [A_b, A_m]; stage velocities are pulled back with
    Jlog6(exp6) as in :mod:`rns_ros.sim.free_floating`.

    Returns:
        (times [s] (k,), q (k, 7 + n), theta_dot at the nodes [rad/s] (k, n)).
    """
    model = robot.model
    data = model.createData()
    count = max(1, math.ceil(duration / step - 1e-9))
    dt = duration / count

    def rate(t: float, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        state = FreeFloatingState.compute(robot, q)
        theta_dot = np.asarray(law(t, state), dtype=float)
        centroidal = pin.computeCentroidalMap(model, data, q)
        base = np.linalg.solve(centroidal[:, :6], -centroidal[:, 6:] @ theta_dot)
        return np.concatenate((base, theta_dot)), theta_dot

    q = np.array(q0, dtype=float)
    times, qs, rates = [0.0], [q.copy()], []
    for i in range(count):
        t = i * dt

        def stage(fraction: float, velocity: np.ndarray, t=t, q=q) -> np.ndarray:
            increment = fraction * dt * velocity
            v, _ = rate(t + fraction * dt, pin.integrate(model, q, increment))
            v[:6] = pin.Jlog6(pin.exp6(increment[:6])) @ v[:6]
            return v

        k1, theta_dot = rate(t, q)
        rates.append(theta_dot)
        k2 = stage(0.5, k1)
        k3 = stage(0.5, k2)
        k4 = stage(1.0, k3)
        q = pin.integrate(model, q, dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4))
        times.append(t + dt)
        qs.append(q.copy())
    rates.append(np.zeros(robot.n))
    return np.array(times), np.array(qs), np.array(rates)


def final_camera_position(robot: FreeFloatingModel, plan: PtpPlan, step: float) -> np.ndarray:
    """Camera position in world [m] (3,) at the end of ``plan`` played on the kinematic
    free-floating model from the base at the origin with identity attitude (A-2.5)."""
    q0 = robot.configuration(plan.start)
    _, qs, _ = integrate_kinematic(
        robot, q0, lambda t, state: plan.sample(t).theta_dot, plan.duration, step
    )
    return np.array(FreeFloatingState.compute(robot, qs[-1]).camera.position)
