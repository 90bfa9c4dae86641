"""Fixtures of the control tests."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.core.state import FreeFloatingState


@pytest.fixture
def relative_coupling(robot):
    """|M~_omega_m theta_dot| / |theta_dot| [kg m^2] at ``theta``: 0 for reactionless motion."""

    def ratio(theta, theta_dot) -> float:
        state = FreeFloatingState.compute(robot, robot.configuration(theta))
        speed = float(np.linalg.norm(theta_dot))
        coupling = state.coupling_angular_momentum_matrix @ theta_dot
        return float(np.linalg.norm(coupling)) / speed

    return ratio
