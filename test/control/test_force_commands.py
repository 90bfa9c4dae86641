"""Operator command validation (rns_ros.control.force.commands)."""

from __future__ import annotations

import math

import pytest
from force_cases import ZERO

from rns_ros.control.force.commands import (
    command_frames,
    validate_force_setpoint,
    validate_twist,
)
from rns_ros.control.force.settings import CommandFrame
from rns_ros.core.errors import InputError

FRAMES = command_frames("map", "ee")


def test_bad_commands_are_rejected_with_the_value_named():
    with pytest.raises(InputError, match=r"linear velocity must be 3 finite numbers.*nan"):
        validate_twist([math.nan, 0, 0], ZERO, "", FRAMES, CommandFrame.EE, 0, 0.0)
    with pytest.raises(InputError, match="'camera' is not one of"):
        validate_twist(ZERO, ZERO, "camera", FRAMES, CommandFrame.EE, 0, 0.0)
    with pytest.raises(InputError, match="force must be 3 finite"):
        validate_force_setpoint([0, 0, math.inf], ZERO, "", FRAMES, 0.0)
    assert validate_twist(ZERO, ZERO, "", FRAMES, CommandFrame.WORLD, 0, 0.0).frame == "world"
    assert validate_twist(ZERO, ZERO, "map", FRAMES, CommandFrame.EE, 0, 0.0).frame == "world"
    assert validate_force_setpoint(ZERO, ZERO, "", FRAMES, 0.0).frame == "ee"
