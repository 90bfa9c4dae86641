"""Play a :class:`~rns_ros.control.ptp.PtpPlan` on the kinematic free-floating simulator.

Like the controller: every control period (``rate`` [Hz]) the reference joint velocity is sampled
at the middle of the period and held (zero-order hold) while :mod:`rns_ros.sim.free_floating`
integrates the kinematic model (RK4, ``dt``, zero momentum; thesis_rest section 0). With
``feedback`` the command is :meth:`PtpPlan.command` at the measured configuration instead (the
arc-length form of eq. 4.18, exactly reactionless in the reactionless phases).

Recorded once per period (at its start, with the command held over it): theta, theta_dot, the
coupling angular momentum M~_omega_m theta_dot (eq. 3.2) [kg m^2/s], the base attitude deviation
angle(R_b(0)^T R_b(t)) (A-0.1) [rad] and the camera position in world [m].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rns_ros.control.ptp import PtpPlan
from rns_ros.core.errors import ConfigError
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import positive
from rns_ros.sim.free_floating import FreeFloatingSimulator, SimulationMode


@dataclass(frozen=True)
class PtpRun:
    """Time series of one played plan (k samples, one per control period plus the end).

    Attributes:
        t: times [s], shape (k,).
        theta: joint angles [rad], shape (k, n).
        theta_dot: commanded (held) joint velocities [rad/s], shape (k, n); zero at the end.
        coupling: M~_omega_m theta_dot [kg m^2/s], shape (k, 3).
        base_deviation: geodesic base attitude deviation [rad], shape (k,).
        camera: camera position in world [m], shape (k, 3).
        phase: phase name per sample, length k.
        plan: the played plan.
    """

    t: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray
    coupling: np.ndarray
    base_deviation: np.ndarray
    camera: np.ndarray
    phase: tuple[str, ...]
    plan: PtpPlan

    @property
    def max_base_deviation(self) -> float:
        """Largest base attitude deviation over the run [rad]."""
        return float(self.base_deviation.max())

    @property
    def max_base_deviation_deg(self) -> float:
        """Largest base attitude deviation over the run [deg]."""
        return math.degrees(self.max_base_deviation)

    def max_coupling(self, reactionless: bool) -> float:
        """Largest |M~_omega_m theta_dot| [kg m^2/s] over the (non-)reactionless phases."""
        names = {p.name for p in self.plan.phases if p.reactionless == reactionless}
        mask = np.array([name in names for name in self.phase])
        if not mask.any():
            return 0.0
        return float(np.linalg.norm(self.coupling[mask], axis=1).max())


def run_plan(
    robot: FreeFloatingModel,
    plan: PtpPlan,
    *,
    dt: float = 1e-3,
    rate: float = 100.0,
    feedback: bool = False,
) -> PtpRun:
    """Play ``plan`` from ``plan.start`` (base at the origin, identity attitude, zero momentum).

    Args:
        robot: the model.
        plan: the plan.
        dt: simulator RK4 step [s].
        rate: control rate [Hz]; the period must be a whole number of steps.
        feedback: use :meth:`PtpPlan.command` at the measured theta instead of the reference
            velocity.

    Raises:
        ConfigError: the control period is not a whole number of simulator steps.
    """
    dt = positive(dt, "dt", "[s]")
    period = 1.0 / positive(rate, "rate", "[Hz]")
    steps = round(period / dt)
    if steps < 1 or abs(steps * dt - period) > 1e-9:
        raise ConfigError(f"control period {period} s is not a whole number of steps of {dt} s")
    sim = FreeFloatingSimulator(
        robot, mode=SimulationMode.KINEMATIC, dt=dt, initial_q=robot.configuration(plan.start)
    )
    rotation_0 = None
    periods = math.ceil(plan.duration / period - 1e-9)
    records: dict[str, list] = {key: [] for key in ("t", "theta", "rate", "h", "dev", "cam", "ph")}
    for k in range(periods + 1):
        t = k * period
        state = FreeFloatingState.compute(robot, sim.q)
        if rotation_0 is None:
            rotation_0 = state.base_rotation.copy()
        middle = min(t + 0.5 * period, plan.duration)
        if k == periods:
            command = np.zeros(robot.n)
            phase = "done"
        elif feedback:
            command = plan.command(middle, state.theta)
            phase = plan.sample(middle).phase
        else:
            reference = plan.sample(middle)
            command, phase = reference.theta_dot, reference.phase
        records["t"].append(t)
        records["theta"].append(state.theta.copy())
        records["rate"].append(command)
        records["h"].append(state.coupling_angular_momentum_matrix @ command)
        records["dev"].append(attitude_deviation(rotation_0, state.base_rotation))
        records["cam"].append(state.camera.position.copy())
        records["ph"].append(phase)
        if k == periods:
            break
        sim.set_reference(velocities=command)
        for _ in range(steps):
            sim.step()
    return PtpRun(
        t=np.array(records["t"]),
        theta=np.array(records["theta"]),
        theta_dot=np.array(records["rate"]),
        coupling=np.array(records["h"]),
        base_deviation=np.array(records["dev"]),
        camera=np.array(records["cam"]),
        phase=tuple(records["ph"]),
        plan=plan,
    )
