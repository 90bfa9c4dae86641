"""Node tests: the public launch-free harness, private Context, DDS on loopback only."""

from __future__ import annotations

import os

import pytest

# DDS must never leave this machine, whatever the caller's environment says.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", "43")

from rns_ros.harness import Harness


@pytest.fixture
def ros():
    """A :class:`rns_ros.harness.Harness`; every node added is destroyed at teardown."""
    with Harness() as harness:
        yield harness
