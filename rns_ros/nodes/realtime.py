"""Real-time scheduling of a node's threads (``SCHED_FIFO``), the way ros2_control's
controller_manager (priority 50) and moveit_servo (``thread_priority``, 40) run their loops.

On a machine shared with other work, a loop under normal scheduling waits for a core: a tick
comes tens of milliseconds late, a joint state or a command waits in a queue, and a plant that
applies a reactionless command late applies it where the arm no longer is, so the base turns.
A SCHED_FIFO thread runs as soon as it is ready, ahead of every normally scheduled process.
The kernel keeps 5 % of each second for the others (``sched_rt_runtime_us``), so a loop gone
wrong cannot freeze the machine.

Only nodes that pace themselves on the wall clock ask for it: on simulated time the lockstep
waits for the slowest node, and a simulation that runs as fast as it can would take a core from
everything else. Setting the policy needs ``CAP_SYS_NICE`` or an ``rtprio`` limit
(docs/realtime.md); without it the node says so in one line and runs with normal scheduling.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from typing import NamedTuple

from rclpy.node import Node

from rns_ros.nodes.parameters import ParameterSpec

#: Highest SCHED_FIFO priority Linux accepts.
MAX_THREAD_PRIORITY = 99
#: Where Linux lists the threads of this process (one folder per thread id).
TASK_DIR = "/proc/self/task"


def thread_priority_spec(default: int, when: str) -> ParameterSpec:
    """The ``thread_priority`` parameter of a node: SCHED_FIFO priority ``default`` (0-99; 0:
    normal scheduling), applied at start-up ``when`` (e.g. "on the wall clock")."""
    return ParameterSpec(
        "thread_priority",
        default,
        f"SCHED_FIFO priority of the node's threads {when}; 0: normal scheduling",
        "[-]",
        0,
        MAX_THREAD_PRIORITY,
    )


class Scheduling(NamedTuple):
    """What :func:`set_thread_priority` did: ``applied`` (every thread now SCHED_FIFO) and one
    line for the log."""

    applied: bool
    text: str


def process_threads(task_dir: str = TASK_DIR) -> list[int]:
    """Thread ids of this process (Linux); [] where the system does not list them."""
    try:
        return sorted(int(name) for name in os.listdir(task_dir) if name.isdigit())
    except OSError:
        return []


def set_thread_priority(
    priority: int,
    *,
    threads: Callable[[], Iterable[int]] = process_threads,
    set_scheduler: Callable[[int, int, object], None] | None = None,
) -> Scheduling:
    """SCHED_FIFO at ``priority`` (1-99) for every thread of this process; threads started
    later inherit it from the thread that starts them. ``priority`` 0: normal scheduling
    (SCHED_OTHER) for every thread, also in a process that inherited a real-time policy from
    the one that started it (lowering a policy needs no permission).

    Args:
        priority: SCHED_FIFO priority; 0 for normal scheduling.
        threads: the thread ids to set (default: all of this process).
        set_scheduler: ``os.sched_setscheduler`` (injected in tests).

    Returns:
        Whether it was applied, and one line for the log naming the priority and, when it was
        not applied, why (not permitted, not supported), with the threads left as they were.
    """
    if not 0 <= priority <= MAX_THREAD_PRIORITY:
        raise ValueError(f"thread_priority {priority} outside [0, {MAX_THREAD_PRIORITY}]")
    setter = set_scheduler or getattr(os, "sched_setscheduler", None)
    policy = getattr(os, "SCHED_FIFO", None)
    ids = list(threads())
    if priority == 0:
        if setter is not None:
            _restore(ids, setter)
        return Scheduling(False, "thread_priority 0: normal scheduling")
    if setter is None or policy is None or not ids:
        return Scheduling(
            False,
            f"thread_priority {priority} not applied: this system has no SCHED_FIFO for "
            "threads; normal scheduling",
        )
    param = os.sched_param(priority)
    done: list[int] = []
    for tid in ids:
        try:
            setter(tid, policy, param)
        except ProcessLookupError:
            continue  # the thread ended meanwhile
        except OSError as exc:
            _restore(done, setter)
            reason = "not permitted" if isinstance(exc, PermissionError) else exc.strerror
            return Scheduling(
                False,
                f"thread_priority {priority} not applied: SCHED_FIFO {reason} (needs "
                "CAP_SYS_NICE or an rtprio limit, docs/realtime.md); normal scheduling: on a "
                "busy machine its ticks come late",
            )
        done.append(tid)
    return Scheduling(True, f"SCHED_FIFO priority {priority} for its {len(done)} threads")


def _restore(tids: Iterable[int], setter: Callable[[int, int, object], None]) -> None:
    """Normal scheduling (SCHED_OTHER) for the threads ``tids``."""
    other = getattr(os, "SCHED_OTHER", 0)
    for tid in tids:
        try:
            setter(tid, other, os.sched_param(0))
        except OSError:
            continue


def schedule_node(node: Node, priority: int, wall_paced: bool) -> Scheduling:
    """Apply ``thread_priority`` = ``priority`` to ``node``'s process when it paces itself on
    the wall clock (``wall_paced``), and log the outcome in one line: a warning when it was
    asked for and refused, info otherwise. Call once every thread of the node's own is
    started."""
    if not wall_paced and priority > 0:
        set_thread_priority(0)  # not a real-time policy inherited from a parent either
        outcome = Scheduling(
            False,
            f"thread_priority {priority} not used: off the wall clock the run waits for its "
            "slowest node (normal scheduling)",
        )
    else:
        outcome = set_thread_priority(priority)
    if outcome.applied or not wall_paced or priority == 0:
        node.get_logger().info(outcome.text)
    else:
        node.get_logger().warn(outcome.text)
    return outcome
