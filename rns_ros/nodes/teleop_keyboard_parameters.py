"""Parameters of rns_teleop_keyboard (:mod:`rns_ros.nodes.teleop_keyboard`); mirrored in
config/teleop_keyboard.yaml."""

from __future__ import annotations

from rns_ros.control.controller import TwistFrame
from rns_ros.nodes.parameters import (
    BASE_FRAME,
    CAMERA_FRAME,
    MODEL_CONFIG,
    WORLD_FRAME,
    ParameterSpec,
    choices_of,
    specs_by_name,
)

NODE_NAME = "rns_teleop_keyboard"
SUMMARY = (
    "Keyboard teleop: held keys -> TwistStamped on cmd_twist (m: force mode with force_setpoint); "
    "needs a terminal."
)

PARAMETERS = (
    ParameterSpec("rate", 20.0, "Publishing rate while a key is held", "[Hz]", 1.0, 200.0),
    ParameterSpec(
        "angular_speed", 0.1, "Initial angular speed of a held key", "[rad/s]", 0.001, 1.0
    ),
    ParameterSpec(
        "max_angular_speed",
        1.0,
        "Bound of the angular speed keys and of combined keys; keep it <= the controller's "
        "max_angular_speed",
        "[rad/s]",
        0.001,
        10.0,
    ),
    ParameterSpec(
        "linear_speed",
        0.05,
        "Initial linear speed of a held key (force mode: the EE speed along EE x / y)",
        "[m/s]",
        0.001,
        1.0,
    ),
    ParameterSpec(
        "max_linear_speed",
        0.5,
        "Upper bound of the linear speed keys and of |linear| when keys combine",
        "[m/s]",
        0.001,
        10.0,
    ),
    ParameterSpec(
        "speed_step", 1.25, "Factor of one speed-up (+) or slow-down (-) key", "[-]", 1.01, 10.0
    ),
    ParameterSpec(
        "key_hold",
        0.7,
        "A key counts as held this long after its last auto-repeat; above the terminal's "
        "auto-repeat delay (X11: 660 ms)",
        "[s]",
        0.05,
        5.0,
    ),
    ParameterSpec(
        "zero_duration",
        0.5,
        "Zero twists are published at rate this long after release or stop, then nothing",
        "[s]",
        0.0,
        60.0,
    ),
    MODEL_CONFIG,
    WORLD_FRAME,
    BASE_FRAME,
    CAMERA_FRAME,
    ParameterSpec(
        "initial_frame",
        TwistFrame.CAMERA.value,
        "Command frame at start (key f cycles camera -> world -> base)",
        choices=choices_of(TwistFrame),
    ),
    ParameterSpec(
        "controller_status_topic",
        "rns_controller/status",
        "DiagnosticArray status of the controller, shown in the panel",
    ),
    ParameterSpec(
        "ee_frame", "ee", "frame_id of force-mode twists and force setpoints (the EE frame)"
    ),
    ParameterSpec(
        "force_step",
        1.0,
        "Force setpoint change per push key (+/-) in force mode",
        "[N]",
        0.01,
        100.0,
    ),
    ParameterSpec(
        "max_force", 20.0, "Upper bound of the force setpoint (lower bound 0)", "[N]", 0.1, 1000.0
    ),
    ParameterSpec(
        "force_status_topic",
        "/rns_force_controller/status",
        "DiagnosticArray status of the force controller, shown in the panel (force mode)",
    ),
)
SPECS = specs_by_name(PARAMETERS)
