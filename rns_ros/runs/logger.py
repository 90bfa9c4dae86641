"""The rerun logger of a run: ``rns_rerun_logger`` writing ``<output>/<name>.rrd`` or a live
viewer (``--viewer``), as its own process or in the run's own process."""

from __future__ import annotations

import argparse
import subprocess
from pathlib import Path

from rns_ros.core import RnsError
from rns_ros.harness import Harness, ProcessStack
from rns_ros.runs.link import GROUND, link_options
from rns_ros.viz.readback import rrd_problem, storage_limit


def _recording(args: argparse.Namespace, name: str) -> tuple[Path, str]:
    """``<output>/<name>.rrd`` (its folder made) and the logger's sink: ``spawn`` (a live viewer)
    with ``--viewer``, else ``save``."""
    output_folder(args)
    return args.output / f"{name}.rrd", "spawn" if args.viewer else "save"


#: How long a stopping run waits for rns_rerun_logger [s]: it sends what it still holds (a
#: flush of up to 10 s), writes the file's footer and reads the file back as it closes; killed
#: sooner, the file lacks its footer.
LOGGER_CLOSE_TIMEOUT = 60.0


def output_folder(args: argparse.Namespace) -> Path:
    """``--output``, made if it went away since the start-up check (one line if it cannot be).

    Raises:
        RnsError: the folder cannot be made.
    """
    try:
        args.output.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RnsError(f"cannot make the --output folder {args.output}: {exc.strerror}") from None
    return args.output


def start_logger(
    processes: ProcessStack,
    name: str,
    args: argparse.Namespace,
    model_config: str | None = None,
    *,
    sim_time: bool = True,
    ros_args: list[str] | None = None,
) -> tuple[str | None, subprocess.Popen | None]:
    """``rns_rerun_logger`` as a process writing ``<output>/<name>.rrd``, or a live viewer:
    (the .rrd path or None for the viewer, the process); (None, None) with ``--no-record``.
    ``model_config``: None for the default model; ``ros_args``: the run's ROS arguments
    (remaps of the whole stack)."""
    if args.no_record:
        return None, None
    path, sink = _recording(args, name)
    path = path.resolve()
    process = processes.start(
        "rns_rerun_logger",
        {
            "sink": sink,
            "rrd_path": str(path),
            "recording_name": name,
            **({"model_config": model_config} if model_config else {}),
            "use_sim_time": sim_time,
            # behind a link: the predicted and the received telemetry arms beside the real one
            **({"ground_namespace": GROUND} if link_options(args) is not None else {}),
        },
        ros_args=ros_args or [],
        stop_timeout=LOGGER_CLOSE_TIMEOUT,
    )
    return (str(path) if sink == "save" else None), process


def add_logger(stack: Harness, name: str, args: argparse.Namespace, timing: dict) -> str | None:
    """``rns_rerun_logger`` as a node of ``stack`` (``timing``: its ``use_sim_time``) writing
    ``<output>/<name>.rrd``, or a live viewer; returns the .rrd path, None for the viewer."""
    from rns_ros.nodes.rerun_logger import RerunLoggerNode

    path, sink = _recording(args, name)
    stack.add(
        RerunLoggerNode,
        {"sink": sink, "rrd_path": str(path), "recording_name": name, **timing},
    )
    return str(path) if sink == "save" else None


def rrd_lost(path: str | None) -> str | None:
    """Why the saved recording ``path`` is not one a reader can open whole (a full disk, a
    file-size limit, a logger killed: :func:`rns_ros.viz.readback.rrd_problem`), else None
    (also for no file: ``--no-record`` or a live viewer)."""
    if path is None:
        return None
    if not Path(path).exists():  # the logger removed what it could not write whole
        why = storage_limit(path) or "rns_rerun_logger could not write it whole (its log says why)"
        return f"cannot write {path}: {why}; the file is removed"
    problem = rrd_problem(path)
    if problem is None:
        return None
    return f"cannot write {path} whole: {problem} (what was written is kept, not listed)"
