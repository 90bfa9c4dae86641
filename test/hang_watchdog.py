"""pytest plugin: a test still running after :data:`HANG_LIMIT_S` ends its process.

pytest-timeout's limit (the ini's ``timeout``, 300 s, signal method) raises in the main thread,
which happens only once a C call returns to Python. A call that never returns (a DDS deadlock
inside Fast DDS) would stall the whole run instead. faulthandler's watchdog is a C thread: it
prints every Python thread's stack to the terminal's stderr and ends the process. Under
`make test` that process is a pytest-xdist worker: xdist starts a new one, the run goes on, and
the test runs once more (Makefile ``SUITE_FLAGS``).
"""

from __future__ import annotations

import faulthandler
import os
import sys

import pytest

#: [s] longer than pytest-timeout's 300 s, so a hang Python can see is reported by pytest-timeout.
#: RNS_TEST_HANG_LIMIT_S overrides it (the watchdog's own test).
HANG_LIMIT_S = float(os.environ.get("RNS_TEST_HANG_LIMIT_S", "420"))

_real_stderr: int | None = None


def pytest_configure(config: pytest.Config) -> None:
    global _real_stderr
    # stderr before pytest captures a test's output: a dump into the capture file would die with
    # the process
    _real_stderr = os.dup(sys.__stderr__.fileno())


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None):
    """Arm the watchdog over the test's set-up, call and tear-down."""
    stream = _real_stderr if _real_stderr is not None else sys.__stderr__
    faulthandler.dump_traceback_later(HANG_LIMIT_S, exit=True, file=stream)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
