"""rns_ros.nodes.realtime: SCHED_FIFO for every thread of a node's own process, only when it
paces itself on the wall clock, and one clear line when it cannot be had.

Scheduling is read back from the kernel (``os.sched_getscheduler`` per thread, or
/proc/PID/task/TID/stat for another process). What changes a process's scheduling runs in a
child process: the test runner itself stays normally scheduled."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from rns_ros.nodes.realtime import MAX_THREAD_PRIORITY, set_thread_priority

BIN = Path(sys.executable).parent
SCHED_OTHER, SCHED_FIFO = os.SCHED_OTHER, os.SCHED_FIFO
START_TIMEOUT_S = 60.0  # a node's start-up takes ~1 s; far longer on a loaded machine


def _may_set_fifo() -> bool:
    """Whether this user may set SCHED_FIFO priority 50 (root, or an rtprio limit)."""
    if os.geteuid() == 0:
        return True
    soft, _hard = resource.getrlimit(resource.RLIMIT_RTPRIO)
    return soft == resource.RLIM_INFINITY or soft >= 50


needs_rt = pytest.mark.skipif(not _may_set_fifo(), reason="SCHED_FIFO not permitted here")


@needs_rt
def test_every_thread_of_the_process_runs_fifo_at_the_priority_and_new_threads_inherit_it():
    script = textwrap.dedent(
        """
        import os, threading
        from rns_ros.nodes.realtime import set_thread_priority
        stop = threading.Event()
        before = threading.Thread(target=stop.wait)
        before.start()
        outcome = set_thread_priority(30)
        after = threading.Thread(target=stop.wait)
        after.start()
        tids = [int(t) for t in os.listdir("/proc/self/task")]
        seen = {(os.sched_getscheduler(t), os.sched_getparam(t).sched_priority) for t in tids}
        stop.set()
        print(outcome.applied, len(tids), sorted(seen))
        """
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60, check=True
    ).stdout.split(maxsplit=2)
    assert out[0] == "True"
    assert int(out[1]) >= 3  # main, the thread started before and the one started after
    assert out[2].strip() == f"[({SCHED_FIFO}, 30)]"
    assert os.sched_getscheduler(0) == SCHED_OTHER  # the runner itself untouched


def test_a_refused_priority_is_one_line_and_leaves_every_thread_as_it_was():
    calls: list[tuple[int, int, int]] = []

    def setter(tid, policy, param):
        calls.append((tid, policy, param.sched_priority))
        if tid == 12 and policy == SCHED_FIFO:
            raise PermissionError(1, "Operation not permitted")

    outcome = set_thread_priority(50, threads=lambda: [11, 12, 13], set_scheduler=setter)
    assert not outcome.applied
    assert "thread_priority 50 not applied" in outcome.text
    assert "not permitted" in outcome.text
    assert "\n" not in outcome.text
    # thread 11 was set, then put back; thread 13 never touched
    assert calls == [(11, SCHED_FIFO, 50), (12, SCHED_FIFO, 50), (11, SCHED_OTHER, 0)]


def test_a_thread_that_ended_meanwhile_is_skipped():
    def setter(tid, policy, param):
        if tid == 12:
            raise ProcessLookupError(3, "No such process")

    outcome = set_thread_priority(40, threads=lambda: [11, 12, 13], set_scheduler=setter)
    assert outcome.applied
    assert outcome.text == "SCHED_FIFO priority 40 for its 2 threads"


def test_priority_0_is_normal_scheduling_and_an_out_of_range_one_is_refused():
    """0 puts every thread on SCHED_OTHER: a process started by a real-time one inherits its
    policy, and a node off the wall clock must not keep it."""
    calls = []

    def setter(tid, policy, param):
        calls.append((tid, policy, param.sched_priority))

    outcome = set_thread_priority(0, threads=lambda: [1, 2], set_scheduler=setter)
    assert not outcome.applied
    assert calls == [(1, SCHED_OTHER, 0), (2, SCHED_OTHER, 0)]
    for bad in (-1, MAX_THREAD_PRIORITY + 1):
        with pytest.raises(ValueError, match=rf"thread_priority {bad} outside \[0, 99\]"):
            set_thread_priority(bad, threads=lambda: [1], set_scheduler=setter)


# --- the executables ----------------------------------------------------------------------------
def _policies(pid: int) -> set[tuple[int, int]]:
    """(policy, rt_priority) of each thread of process ``pid``, from /proc."""
    seen = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            fields = task.joinpath("stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue  # the thread ended
        # fields from 3 (state) on: rt_priority is field 40, policy field 41 (proc(5))
        seen.add((int(fields[38]), int(fields[37])))
    return seen


def _scheduling_of(executable: str, expected_line: str, *ros_args: str) -> set[tuple[int, int]]:
    """Start ``executable`` with ``ros_args``; once it logs ``expected_line``, its threads'
    (policy, priority); then Ctrl-C."""
    env = {
        **os.environ,
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "AMENT_PREFIX_PATH": str(BIN.parent),
    }
    args = [str(BIN / executable), *(["--ros-args", *ros_args] if ros_args else [])]
    with subprocess.Popen(
        args,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        start_new_session=True,
    ) as proc:
        lines = []
        try:
            deadline = time.monotonic() + START_TIMEOUT_S
            os.set_blocking(proc.stdout.fileno(), False)
            while time.monotonic() < deadline and proc.poll() is None:
                lines += proc.stdout.readlines()
                if any(expected_line in line for line in lines):
                    return _policies(proc.pid)
                time.sleep(0.05)
            pytest.fail(f"{executable} never logged {expected_line!r}:\n{''.join(lines)[-3000:]}")
        finally:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
                try:
                    proc.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    os.killpg(proc.pid, signal.SIGKILL)


@needs_rt
def test_the_simulator_on_the_real_time_pace_runs_fifo_50_and_as_fast_as_possible_normally(ros):
    fifo = _scheduling_of("rns_simulator", "SCHED_FIFO priority 50 for its")
    assert fifo == {(SCHED_FIFO, 50)}
    as_fast = _scheduling_of(
        "rns_simulator", "thread_priority 50 not used", "-p", "real_time_factor:=0.0"
    )
    assert as_fast == {(SCHED_OTHER, 0)}


@needs_rt
def test_the_controller_runs_fifo_40_on_the_wall_clock_only(ros):
    """Started from this test process, which runs under SCHED_FIFO 30 while its nodes do
    (test/nodes/conftest.py): a node off the wall clock does not keep that inherited policy."""
    assert os.sched_getscheduler(0) == SCHED_FIFO
    assert _scheduling_of("rns_controller", "SCHED_FIFO priority 40 for its") == {(SCHED_FIFO, 40)}
    on_sim_time = _scheduling_of(
        "rns_controller", "thread_priority 40 not used", "-p", "use_sim_time:=true"
    )
    assert on_sim_time == {(SCHED_OTHER, 0)}
    normal = _scheduling_of(
        "rns_ptp", "thread_priority 0: normal scheduling", "-p", "thread_priority:=0"
    )
    assert normal == {(SCHED_OTHER, 0)}
