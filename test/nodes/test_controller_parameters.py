"""rns_controller's parameter table: mirrored in config/controller.yaml, one-line descriptions,
choices from the control layer's enums, and the control objects the values make."""

from __future__ import annotations

from pathlib import Path

import pytest

from rns_ros.control.camera_law import Method
from rns_ros.control.controller import HoldCorrection, TwistFrame
from rns_ros.core import ConfigError
from rns_ros.nodes.controller_parameters import (
    PARAMETERS,
    SPECS,
    command_gate,
    controller_settings,
)

REPO = Path(__file__).resolve().parents[2]
DEFAULTS = {spec.name: spec.default for spec in PARAMETERS}
FRAMES = {"world": TwistFrame.WORLD, "": TwistFrame.CAMERA}


def test_string_choices_are_the_values_of_the_control_enums_default_first():
    assert set(SPECS["method"].choices) == {method.value for method in Method}
    assert set(SPECS["hold_correction"].choices) == {hold.value for hold in HoldCorrection}
    for name in ("method", "hold_correction"):
        assert SPECS[name].choices[0] == SPECS[name].default
        assert type(SPECS[name].default) is str


def test_the_defaults_make_the_thesis_settings_and_a_valid_gate():
    settings = controller_settings(DEFAULTS)
    assert settings.method is Method.DLS
    assert settings.period == pytest.approx(1.0 / DEFAULTS["rate"])
    assert settings.gains.wrist_gain == DEFAULTS["wrist_gain"]
    gate = command_gate(DEFAULTS, FRAMES)
    assert (gate.timeout, gate.deceleration, gate.acceleration) == (0.5, 1.0, 1.0)
    with pytest.raises(ConfigError, match="default_twist_frame"):
        command_gate({**DEFAULTS, "default_twist_frame": "odom"}, FRAMES)


def test_command_bounds_default_to_what_the_simulator_accepts_and_clock_jumps_to_a_second():
    """max_reference_error is rns_simulator's parameter of the same name: a command the
    controller's bounds let through is one the simulator does not reject for its distance."""
    from rns_ros.nodes.simulator_parameters import PARAMETERS as SIMULATOR

    simulator = {spec.name: spec.default for spec in SIMULATOR}
    assert DEFAULTS["max_reference_error"] == simulator["max_reference_error"]
    assert DEFAULTS["max_clock_jump"] == 1.0
    for name in ("max_reference_error", "max_clock_jump"):
        assert SPECS[name].low > 0.0
