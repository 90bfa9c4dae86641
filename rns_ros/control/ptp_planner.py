"""Point-to-point motion planning of the free-floating arm (thesis sections 4.4-4.5).

:func:`plan_ptp` maps each :class:`~rns_ros.control.ptp.PtpMethod` (thesis names in brackets,
thesis_rest section 2) to its planner and returns a :class:`~rns_ros.control.ptp.PtpPlan`:

* ``three_phase`` (3-phase, section 4.4.1) and ``deploy`` (section 4.5.1):
  :mod:`rns_ros.control.ptp_phases`, on reactionless elbow paths
  (:mod:`rns_ros.control.reactionless_path`).
* ``joint_space`` (JS-C), ``inverse_jacobian`` (IJ-C), ``transposed_jacobian`` (TJ-C), the
  baselines of section 4.4.2: :mod:`rns_ros.control.ptp_baselines`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np

from rns_ros.control.ptp import PtpMethod, PtpPlan, PtpSettings, check_configuration
from rns_ros.control.ptp_baselines import (
    plan_inverse_jacobian,
    plan_joint_space,
    plan_transposed_jacobian,
)
from rns_ros.control.ptp_phases import plan_deployment, plan_three_phase
from rns_ros.core.model import FreeFloatingModel

#: A planner from (robot, checked start (n,) [rad], goal as given, settings).
Planner = Callable[[FreeFloatingModel, np.ndarray, object, PtpSettings], PtpPlan]


def _to_goal(plan: Callable[..., PtpPlan]) -> Planner:
    """``plan`` (robot, start, goal, settings) with the goal checked first."""

    def planner(robot, start, theta_goal, settings):
        goal = check_configuration(robot, theta_goal, "theta_goal")
        return plan(robot, start, goal, settings)

    return planner


def _deploy(robot, start, theta_goal, settings):
    """The full deployment from ``start``; it has no goal."""
    return plan_deployment(robot, start, settings)


_PLANNERS: Mapping[PtpMethod, Planner] = MappingProxyType(
    {
        PtpMethod.THREE_PHASE: _to_goal(plan_three_phase),
        PtpMethod.JOINT_SPACE: _to_goal(plan_joint_space),
        PtpMethod.INVERSE_JACOBIAN: _to_goal(plan_inverse_jacobian),
        PtpMethod.TRANSPOSED_JACOBIAN: _to_goal(plan_transposed_jacobian),
        PtpMethod.DEPLOY: _deploy,
    }
)


def plan_ptp(
    robot: FreeFloatingModel,
    theta_start,
    theta_goal,
    method: PtpMethod | str,
    settings: PtpSettings | None = None,
) -> PtpPlan:
    """Plan a point-to-point motion start -> goal with ``method`` (see the module docstring).

    ``deploy`` ignores the goal (it deploys from the start,
    :func:`~rns_ros.control.ptp_phases.plan_deployment`); IJ-C/TJ-C end where their closed loop
    brings the arm (``plan.goal``), not exactly at ``theta_goal``.

    Raises:
        InputError: non-finite or out-of-limit start/goal (the message names the joint).
        ConfigError: unknown method or a non-positive duration.
    """
    settings = settings or PtpSettings()
    planner = _PLANNERS[PtpMethod.parse(method)]
    start = check_configuration(robot, theta_start, "theta_start")
    return planner(robot, start, theta_goal, settings)
