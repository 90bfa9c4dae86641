"""Parameters of rns_teleop_spacemouse (:mod:`rns_ros.nodes.teleop_spacemouse`); mirrored in
config/teleop_spacemouse.yaml."""

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

NODE_NAME = "rns_teleop_spacemouse"
SUMMARY = (
    "3D mouse teleop: a SpaceMouse (pyspacemouse, raw HID) -> TwistStamped on cmd_twist; buttons "
    "cycle the frame and pause."
)

PARAMETERS = (
    ParameterSpec("rate", 50.0, "Publishing rate while the cap is deflected", "[Hz]", 1.0, 500.0),
    ParameterSpec(
        "angular_scale",
        0.2,
        "|angular| at full twist of the cap (axes combined are scaled to it as a vector)",
        "[rad/s]",
        0.0,
        1.0,
    ),
    ParameterSpec(
        "linear_scale",
        0.0,
        "|linear| at full push of the cap; 0 ignores the push (a camera-pointing controller "
        "cannot achieve it)",
        "[m/s]",
        0.0,
        1.0,
    ),
    ParameterSpec(
        "dead_zone",
        0.1,
        "Per-axis dead zone, a fraction of full deflection; the output rises from 0 at its edge",
        "[-]",
        0.0,
        0.9,
    ),
    ParameterSpec(
        "device_timeout",
        0.5,
        "A deflected cap without a report for this long counts as silent: zero twist",
        "[s]",
        0.01,
        10.0,
    ),
    ParameterSpec(
        "zero_duration",
        0.5,
        "Zero twists are published at rate this long after the motion stops, then nothing",
        "[s]",
        0.0,
        60.0,
    ),
    ParameterSpec(
        "frame_button", 0, "Button that cycles the frame camera -> world -> base", "[-]", -1, 31
    ),
    ParameterSpec("pause_button", 1, "Button that pauses / resumes (-1: none)", "[-]", -1, 31),
    ParameterSpec(
        "device_path", "", "hidraw device (/dev/hidrawN); empty: the first SpaceMouse found"
    ),
    MODEL_CONFIG,
    WORLD_FRAME,
    BASE_FRAME,
    CAMERA_FRAME,
    ParameterSpec(
        "initial_frame",
        TwistFrame.CAMERA.value,
        "Command frame at start (the frame button cycles camera -> world -> base)",
        choices=choices_of(TwistFrame),
    ),
)
SPECS = specs_by_name(PARAMETERS)
