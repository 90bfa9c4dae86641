"""Shared fixtures: the default 7-DoF model (session scoped)."""

from __future__ import annotations

import pytest

from rns_ros.core import FreeFloatingModel, load_model
from rns_ros.resources import default_model_config


@pytest.fixture(scope="session")
def robot() -> FreeFloatingModel:
    return load_model(default_model_config())
