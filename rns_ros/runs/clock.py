"""Which clock a scripted run steps on.

By default every node of a run is on simulated time (``use_sim_time``, ``/clock`` from the
simulator) and the simulator waits for each control period's output (lockstep): a process the
machine delays stops the simulated world instead of losing motion, so the figures do not depend
on the load. The simulator still paces itself to wall time at ``--real-time-factor`` while the
machine keeps up (0: as fast as possible), and simply runs slower when it does not.
``--wall-clock`` runs the nodes on the wall clock as hardware and a human operator do; its
figures then depend on how promptly this machine schedules the processes.
"""

from __future__ import annotations

import argparse


def lockstep(args: argparse.Namespace) -> bool:
    """True: the run is on simulated time in lockstep (not ``--wall-clock``)."""
    return not getattr(args, "wall_clock", False)


def clock_text(args: argparse.Namespace) -> str:
    """How the run keeps time, for its header line."""
    if not lockstep(args):
        return "on the wall clock"
    pace = (
        "as fast as possible"
        if args.real_time_factor == 0.0
        else (f"paced to real-time factor {args.real_time_factor:g}")
    )
    return f"on simulated time in lockstep, {pace}"
