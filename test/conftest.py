"""Shared fixtures: the default 7-DoF model (session scoped)."""

from __future__ import annotations

import pytest

from rns_ros.core import FreeFloatingModel, load_model
from rns_ros.resources import default_model_config


@pytest.fixture(scope="session")
def robot() -> FreeFloatingModel:
    return load_model(default_model_config())


@pytest.fixture(scope="session")
def scenario():
    """Load a shipped scenario by name: ``scenario("satellite_observation")``."""
    from rns_ros.control.scenario import load_scenario
    from rns_ros.resources import config_dir

    return lambda name: load_scenario(config_dir() / "scenarios" / f"{name}.yaml")
