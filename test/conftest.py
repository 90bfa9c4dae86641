"""Shared fixtures: the default 7-DoF model (session scoped); the interpreter's thread switch
interval for in-process stacks."""

from __future__ import annotations

import signal
import sys

import pytest

# A test stuck inside C code (a DDS call that never returns) ends its process with a stack dump
# instead of stalling the run.
from hang_watchdog import pytest_configure, pytest_runtest_protocol  # noqa: F401

from rns_ros.core import FreeFloatingModel, load_model
from rns_ros.resources import default_model_config

# In-process stacks (rns_ros.harness.Harness) run a simulation thread beside the executor in one
# interpreter. A thread back from a system call (rclpy's logging stats source files; DDS waits)
# waits for the GIL until the switch interval ends: 5 ms by default, so a free-running
# simulation thread could delay each log call by seconds. 1 ms keeps the executor responsive,
# as separate processes (ros2 run) are.
sys.setswitchinterval(0.001)

# The tests press Ctrl-C (SIGINT) on the processes they start, as a terminal would. A test run
# started in the background by a non-interactive shell (`make test &`, nohup) inherits SIGINT
# ignored, and so would every executable it starts: the default disposition is restored here,
# so what the tests see does not depend on how the run was started.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture(scope="session")
def robot() -> FreeFloatingModel:
    return load_model(default_model_config())


@pytest.fixture(scope="session")
def inferred_robot() -> FreeFloatingModel:
    """The first, inferred 7-DoF geometry (config/urdf/rns_7dof_arm_inferred.urdf): straight and
    coaxial at theta = 0, kept for the properties that only it has and for comparisons."""
    from rns_ros.core import ModelSpec
    from rns_ros.resources import config_dir

    spec = ModelSpec(
        camera_frame="camera",
        wrist_frame="wrist",
        positioning_joints=("joint_1", "joint_2", "joint_3", "joint_4"),
        wrist_joints=("joint_5", "joint_6", "joint_7"),
    )
    return FreeFloatingModel.from_urdf(config_dir() / "urdf" / "rns_7dof_arm_inferred.urdf", spec)


@pytest.fixture(scope="session")
def scenario():
    """Load a shipped scenario by name: ``scenario("satellite_observation")``."""
    from rns_ros.control.scenario import load_scenario
    from rns_ros.resources import config_dir

    return lambda name: load_scenario(config_dir() / "scenarios" / f"{name}.yaml")
