"""Two stacks on one domain: rns_demo names the one already running and starts nothing."""

from __future__ import annotations

import os

import pytest
import rclpy
from rosgraph_msgs.msg import Clock

from rns_ros.apps import demo
from rns_ros.apps.demo import main
from rns_ros.runs import contact, ptp

DOMAIN = os.environ.setdefault("ROS_DOMAIN_ID", "43")


def _no_run(*_args, **_kwargs):
    raise AssertionError("a run was started")


@pytest.fixture
def running_simulator():
    """A stand-in for another stack's simulator on the test's domain: a node named
    rns_simulator publishing /clock, in its own Context (its own DDS participant)."""
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(DOMAIN))
    node = rclpy.create_node("rns_simulator", context=context)
    node.create_publisher(Clock, "/clock", 10)
    yield node
    node.destroy_node()
    rclpy.try_shutdown(context=context)


@pytest.mark.parametrize("scenario", ["satellite_observation", "ptp_three_phase", "wall_contact"])
def test_a_stack_running_on_the_domain_stops_the_demo_in_one_line(
    running_simulator, scenario, monkeypatch, capsys
):
    monkeypatch.setattr(demo, "run_method", _no_run)
    monkeypatch.setattr(demo, "run_ptp_method", _no_run)
    monkeypatch.setattr(demo, "run_contact_method", _no_run)
    monkeypatch.setattr(ptp, "Harness", _no_run)
    monkeypatch.setattr(contact, "Harness", _no_run)
    argv = ["--scenario", scenario, "--no-record", "--domain-id", DOMAIN]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.err == (
        f"rns_demo: domain {DOMAIN} already has a running stack (/rns_simulator publishing "
        "/clock): stop it or pass --domain-id N\n"
    )
    assert "running" not in captured.out
    assert "Traceback" not in captured.err
