"""Named joint commands: reordering and every rejection names the problem."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.core import InputError
from rns_ros.core.commands import match_named_command

JOINTS = ("a", "b", "c")
LIMITS = np.array([1.0, 1.0, 2.0])


def test_reorders_into_model_order():
    command = match_named_command(
        ["c", "a", "b"], JOINTS, positions=[3.0, 1.0, 2.0], velocities=[0.3, 0.1, 0.2]
    )
    assert command.positions.tolist() == [1.0, 2.0, 3.0]
    assert command.velocities.tolist() == [0.1, 0.2, 0.3]
    assert command.accelerations is None


@pytest.mark.parametrize(
    ("names", "kwargs", "message"),
    [
        (
            ["a", "b", "x"],
            {"velocities": [0, 0, 0]},
            r"unknown joints \['x'\].*missing joints \['c'\]",
        ),
        (["a", "b"], {"velocities": [0, 0]}, r"missing joints \['c'\]"),
        (["a", "a", "b", "c"], {"velocities": [0, 0, 0, 0]}, r"duplicated joints \['a'\]"),
        (["a", "b", "c"], {"velocities": [0, 0]}, "velocities has 2 values for 3 joints"),
        (["a", "b", "c"], {"positions": [0, np.nan, 0]}, "positions must be finite"),
        (["a", "b", "c"], {"velocities": [0, np.inf, 0]}, "velocities must be finite"),
        (["a", "b", "c"], {}, "neither positions nor velocities"),
        (["a", "b", "c"], {"velocities": [0, 1.5, 0]}, "1.5 rad/s on b exceeds its limit 1"),
    ],
)
def test_rejections_name_the_problem(names, kwargs, message):
    with pytest.raises(InputError, match=message):
        match_named_command(names, JOINTS, velocity_limits=LIMITS, **kwargs)


def test_speed_at_the_limit_is_accepted():
    command = match_named_command(
        ["a", "b", "c"], JOINTS, velocities=[1.0, -1.005, 2.0], velocity_limits=LIMITS
    )
    assert command.velocities[1] == -1.005
