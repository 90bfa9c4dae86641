"""The hang watchdog (test/hang_watchdog.py) with `make test`'s flags: a test stuck where
pytest-timeout's SIGALRM cannot reach it ends its worker with a stack dump, the run goes on and
the test runs once more; an ordinary failure is never rerun."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

TEST_DIR = Path(__file__).parent
MAKEFILE = TEST_DIR.parent / "Makefile"

# The stuck test blocks SIGALRM, as a thread inside C code keeps pytest-timeout's handler from
# running; its second run finds the marker file and passes.
SAMPLE = """
import signal, time
from pathlib import Path

def test_stuck_once(tmp_path_factory):
    marker = Path({marker!r})
    if not marker.exists():
        marker.write_text("ran")
        signal.pthread_sigmask(signal.SIG_BLOCK, {{signal.SIGALRM}})
        time.sleep(60)

def test_after():
    pass

def test_fails():
    assert {fails}
"""


def _suite_flags() -> list[str]:
    match = re.search(r"^SUITE_FLAGS := (.*)$", MAKEFILE.read_text(), re.MULTILINE)
    assert match, "Makefile defines SUITE_FLAGS"
    return match.group(1).split()


def _run(tmp_path: Path, fails: bool) -> subprocess.CompletedProcess:
    (tmp_path / "conftest.py").write_text(
        "from hang_watchdog import pytest_configure, pytest_runtest_protocol  # noqa: F401\n"
    )
    (tmp_path / "test_sample.py").write_text(
        SAMPLE.format(marker=str(tmp_path / "ran_once"), fails="False" if fails else "True")
    )
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join([str(TEST_DIR), os.environ.get("PYTHONPATH", "")]),
        RNS_TEST_HANG_LIMIT_S="3",
    )
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *_suite_flags()]
    command += ["-o", "timeout=1", "-o", "timeout_method=signal", "--rootdir", str(tmp_path)]
    command += ["-c", os.devnull, str(tmp_path / "test_sample.py")]
    return subprocess.run(
        command,
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_a_test_stuck_in_c_code_ends_its_worker_and_runs_once_more(tmp_path):
    result = _run(tmp_path, fails=False)
    out = result.stdout + result.stderr
    assert result.returncode == 0, out
    assert "Timeout (0:00:03)!" in out  # faulthandler's dump, with the stuck test's frame
    assert "test_stuck_once" in out
    assert re.search(r"\b3 passed\b", out), out
    assert re.search(r"\b1 rerun\b", out), out


def test_an_ordinary_failure_is_never_rerun(tmp_path):
    result = _run(tmp_path, fails=True)
    out = result.stdout + result.stderr
    assert result.returncode == 1, out
    assert re.search(r"\b1 failed\b", out), out
    assert re.search(r"\b1 rerun\b", out), out  # the stuck test only


@pytest.mark.parametrize("flag", ["-n", "--reruns", "--rerun-except"])
def test_make_test_runs_the_suite_with_the_watchdog_flags(flag):
    assert flag in _suite_flags()
