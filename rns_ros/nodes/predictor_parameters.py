"""Parameters of rns_predictor (:mod:`rns_ros.nodes.predictor`); mirrored in
config/predictor.yaml. The law's and the command gate's parameters are rns_controller's own
(same names, defaults and ranges), read once at start-up: the prediction is exact only when they
are the on-board controller's values."""

from __future__ import annotations

import dataclasses

from rns_ros.nodes import controller_parameters
from rns_ros.nodes.parameters import ParameterSpec, specs_by_name

NODE_NAME = "rns_predictor"
SUMMARY = (
    "Predictive display on the ground: the arm as the operator's commands will move it, "
    "computed at once and re-anchored on the delayed telemetry."
)
#: rns_controller's parameters the prediction depends on.
SHARED = (
    "model_config",
    "method",
    "epsilon",
    "lambda2_max",
    "sc_gain",
    "wrist_gain",
    "rate",
    "hold_correction",
    "hold_iterations",
    "max_angular_speed",
    "command_timeout",
    "stop_deceleration",
    "start_acceleration",
    "goal_gain",
    "goal_max_speed",
    "goal_tolerance",
    "default_twist_frame",
    "execution_delay",
    "world_frame",
)

PARAMETERS = (
    *(dataclasses.replace(controller_parameters.SPECS[name], read_only=True) for name in SHARED),
    ParameterSpec(
        "resync_deg",
        0.01,
        "Re-anchor on the telemetry when a predicted camera or base attitude is off by more",
        "[deg]",
        1e-6,
        90.0,
    ),
    ParameterSpec(
        "resync_rad",
        1e-3,
        "Re-anchor on the telemetry when a predicted joint angle is off by more",
        "[rad]",
        1e-6,
        3.2,
    ),
    ParameterSpec(
        "history",
        120.0,
        "Predicted states kept for comparison with the telemetry (at least the round trip)",
        "[s]",
        1.0,
        3600.0,
    ),
    ParameterSpec("status_period", 1.0, "Period of ~/status", "[s]", 0.01, 60.0),
)
SPECS = specs_by_name(PARAMETERS)
