"""Parameters of rns_operator (:mod:`rns_ros.nodes.operator`); mirrored in config/operator.yaml."""

from __future__ import annotations

from rns_ros.nodes.parameters import (
    BASE_FRAME,
    CAMERA_FRAME,
    MODEL_CONFIG,
    WORLD_FRAME,
    ParameterSpec,
    specs_by_name,
)
from rns_ros.nodes.realtime import thread_priority_spec

NODE_NAME = "rns_operator"
SUMMARY = (
    "Scripted operator: plays a scenario file as twists on cmd_twist (motion_force: and force "
    "setpoints on force_setpoint)."
)
#: Rate suggested for motion/force scenarios [Hz] (the force controller runs at 1 kHz).
MOTION_FORCE_RATE = 500.0

PARAMETERS = (
    thread_priority_spec(40, "on the wall clock (use_sim_time false)"),
    ParameterSpec(
        "scenario",
        "satellite_observation",
        "Scenario file path, or the name of a shipped one in config/scenarios/",
    ),
    ParameterSpec(
        "rate",
        50.0,
        f"Command publishing rate (motion_force scenarios: {MOTION_FORCE_RATE:g} Hz suggested)",
        "[Hz]",
        1.0,
        1000.0,
    ),
    ParameterSpec(
        "start_delay",
        0.5,
        "Wait after the start condition before the profile begins",
        "[s]",
        0.0,
        3600.0,
    ),
    ParameterSpec(
        "wait_for_subscriber",
        True,
        "Start only once cmd_twist (motion_force: and force_setpoint) has a subscriber",
    ),
    ParameterSpec(
        "min_subscribers",
        1,
        "With wait_for_subscriber: start once cmd_twist (motion_force: and force_setpoint) has "
        "this many subscribers",
        "[-]",
        1,
        100,
    ),
    ParameterSpec(
        "subscriber_nodes",
        "",
        "With wait_for_subscriber: also wait until these nodes (base names, comma-separated) "
        "subscribe to cmd_twist",
    ),
    ParameterSpec(
        "zero_duration",
        1.0,
        "Publish zero twists (motion_force: and the held force setpoint) this long after the "
        "profile",
        "[s]",
        0.0,
        3600.0,
    ),
    ParameterSpec(
        "lead",
        0.0,
        "use_sim_time: publish each sample (twist, force setpoint) this long before its "
        "instant, stamped with the instant",
        "[s]",
        0.0,
        1.0,
    ),
    ParameterSpec(
        "start_grid",
        0.0,
        "use_sim_time: the profile starts on a multiple of this in simulated time (the "
        "controller's period); 0: off",
        "[s]",
        0.0,
        1.0,
    ),
    MODEL_CONFIG,
    WORLD_FRAME,
    BASE_FRAME,
    CAMERA_FRAME,
)
SPECS = specs_by_name(PARAMETERS)
