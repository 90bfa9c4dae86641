"""Node tests: the public launch-free harness, private Context, DDS on loopback only."""

from __future__ import annotations

import contextlib
import itertools
import os

import pytest

# DDS must never leave this machine, whatever the caller's environment says.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", "43")

from rns_ros.cli import DOMAIN_ID_RANGE
from rns_ros.harness import Harness
from rns_ros.nodes.realtime import set_thread_priority

#: Consecutive tests run on DOMAINS different domains from ROS_DOMAIN_ID on: whatever a test
#: leaves behind a while (a process still exiting, a message still in flight) is not on the
#: next tests' domain.
DOMAINS = 8
_tests = itertools.count()


def _test_domain(base: int, k: int) -> int:
    """The domain of the ``k``-th test: ``base`` + k mod DOMAINS, below the range's top."""
    offset = k % DOMAINS
    return base + offset if base + DOMAINS - 1 <= DOMAIN_ID_RANGE[1] else base - offset


#: SCHED_FIFO priority of this process while a test's in-process nodes run: as their
#: executables run on the wall clock (docs/realtime.md), below theirs (40, 50).
IN_PROCESS_PRIORITY = 30


@contextlib.contextmanager
def _scheduled_like_the_executables():
    """The nodes a test creates in this process run under SCHED_FIFO, as their executables do
    on the wall clock (rns_ros.nodes.realtime), so that other work on the machine delays them
    no more than it delays a deployed node; normal scheduling again afterwards. Where SCHED_FIFO
    is not permitted, the test runs as before."""
    applied = set_thread_priority(IN_PROCESS_PRIORITY).applied
    try:
        yield
    finally:
        if applied:
            set_thread_priority(0)  # every thread back to SCHED_OTHER


@pytest.fixture
def ros(monkeypatch):
    """A :class:`rns_ros.harness.Harness` on this test's domain (also ROS_DOMAIN_ID of the
    processes the test starts); every node added is destroyed at teardown. The test runs
    under the scheduling the nodes' executables take (:func:`_scheduled_like_the_executables`)."""
    domain = _test_domain(int(os.environ["ROS_DOMAIN_ID"]), next(_tests))
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    with _scheduled_like_the_executables(), Harness(domain) as harness:
        yield harness
