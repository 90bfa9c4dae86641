"""Shared arms and a single step of the force controller tests."""

from __future__ import annotations

import numpy as np

from rns_ros.control.force.commands import JointMeasurement, WrenchSample
from rns_ros.core.fixed_base import load_fixed_base_model
from rns_ros.resources import config_dir

LWR = load_fixed_base_model(config_dir() / "lwr_7dof.yaml")


PLANAR = load_fixed_base_model(config_dir() / "planar_3dof.yaml")


START = np.radians([20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0])


ZERO = np.zeros(3)


def ns(t: float) -> int:
    return round(t * 1e9)


def one_step(controller, *, t=0.0, wrench=ZERO):
    controller.add_wrench(WrenchSample(ns(t), np.asarray(wrench, float), ZERO))
    return controller.step(JointMeasurement(ns(t), START, np.zeros(7)), t)
