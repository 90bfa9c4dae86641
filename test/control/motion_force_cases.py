"""Shared arms, tasks and states of the motion/force controller tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.task_space import FULL_ROWS, PLANAR_ROWS, TaskSpace
from rns_ros.core.fixed_base import FixedBaseState, load_fixed_base_model

CONFIG = Path(__file__).resolve().parents[2] / "config"


PLANAR_START = np.deg2rad([106.4, -45.7, -56.2])


LWR_START = np.deg2rad([20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0])


PLANAR = load_fixed_base_model(CONFIG / "planar_3dof.yaml")


LWR = load_fixed_base_model(CONFIG / "lwr_7dof.yaml", gravity=True)  # gravity on: G_e, g_l used


PLANAR_TASK = TaskSpace.from_contact(PLANAR_ROWS, [1.0, 0.0, 0.0])  # normal +x, tangent +y


WALL_TASK = TaskSpace.from_contact(FULL_ROWS, [0.0, 0.0, 1.0])  # wall: force along z


PLANAR_RNS = ReversedModel(PLANAR, PLANAR_ROWS)


LWR_RNS = ReversedModel(LWR, FULL_ROWS)


CASES = {
    "planar": (PLANAR, PLANAR_TASK, PLANAR_RNS, PLANAR_START),
    "lwr": (LWR, WALL_TASK, LWR_RNS, LWR_START),
}


def state_case(name: str, seed: int = 0, speed: float = 0.5):
    robot, task, rns, q0 = CASES[name]
    rng = np.random.default_rng(seed)
    state = FixedBaseState.compute(robot, q0, speed * rng.standard_normal(robot.n))
    return state, task, rns, rng.standard_normal(task.m), np.array([7.0])


def free_arm_acceleration(state, torque):
    """theta_ddot of the free arm (no contact force) under ``torque``, from M directly."""
    return np.linalg.solve(state.mass_matrix, torque - state.coriolis - state.gravity)
