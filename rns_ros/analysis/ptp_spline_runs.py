"""What a joint_trajectory_controller's interpolation between plan samples costs in base
attitude: the plan and its sampled cubic (:mod:`rns_ros.control.ptp_sampling`) replayed on the
kinematic free-floating simulator (RK4, ``dt``, zero momentum; thesis_rest section 0) as
continuous-time joint velocity laws, from the same start.

The deviation compared is the geodesic angle between the two base attitudes at each step,
angle(R_plan(t)^T R_spline(t)) (A-0.1) [rad]: zero when the interpolation keeps the plan's base
motion (none in a reactionless phase).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rns_ros.control.ptp import PtpPlan
from rns_ros.control.ptp_sampling import hermite, sample_plan
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import positive
from rns_ros.sim.free_floating import FreeFloatingSimulator, SimulationMode


@dataclass(frozen=True)
class SplineCost:
    """One plan replayed exactly and through its samples.

    Attributes:
        spacing: longest sample interval [s].
        samples: number of samples (JointTrajectory points).
        base_gap: largest angle between the two replays' base attitudes [rad].
        plan_deviation: the exact replay's largest base deviation from the start [rad].
        spline_deviation: the spline replay's largest base deviation from the start [rad].
        joint_gap: largest |theta_spline - theta_plan| over joints and time [rad].
    """

    spacing: float
    samples: int
    base_gap: float
    plan_deviation: float
    spline_deviation: float
    joint_gap: float

    @property
    def base_gap_deg(self) -> float:
        return math.degrees(self.base_gap)


def spline_cost(
    robot: FreeFloatingModel, plan: PtpPlan, spacing: float, *, dt: float = 2e-3
) -> SplineCost:
    """Replay ``plan`` (theta_dot = plan rate at t) and its samples at ``spacing`` [s]
    (theta_dot = the Hermite cubic's rate at t) for plan.duration, RK4 step ``dt`` [s]."""
    dt = positive(dt, "dt", "[s]")
    samples = sample_plan(plan, spacing)
    laws = (
        lambda t, _q: plan.sample(t).theta_dot if t < plan.duration else np.zeros(robot.n),
        lambda t, _q: hermite(samples, t)[1],
    )
    sims = [
        FreeFloatingSimulator(
            robot, mode=SimulationMode.KINEMATIC, dt=dt, initial_q=robot.configuration(plan.start)
        )
        for _ in laws
    ]
    rotation_0 = FreeFloatingState.compute(robot, sims[0].q).base_rotation.copy()
    gap = deviation_plan = deviation_spline = joint_gap = 0.0
    for _ in range(math.ceil(plan.duration / dt - 1e-9)):
        for sim, law in zip(sims, laws, strict=True):
            sim.step(law)
        rotations = [FreeFloatingState.compute(robot, sim.q).base_rotation for sim in sims]
        gap = max(gap, attitude_deviation(rotations[0], rotations[1]))
        deviation_plan = max(deviation_plan, attitude_deviation(rotation_0, rotations[0]))
        deviation_spline = max(deviation_spline, attitude_deviation(rotation_0, rotations[1]))
        joint_gap = max(joint_gap, float(np.abs(sims[0].q[7:] - sims[1].q[7:]).max()))
    return SplineCost(
        spacing=float(spacing),
        samples=int(samples.t.size),
        base_gap=gap,
        plan_deviation=deviation_plan,
        spline_deviation=deviation_spline,
        joint_gap=joint_gap,
    )
