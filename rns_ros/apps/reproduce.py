"""``rns_reproduce``: regenerate the thesis' figures and tables next to the thesis values.

``rns_reproduce list`` prints one line per registered result (id, thesis label, title).
``rns_reproduce run ID [ID ...] [--out DIR] [--quick] [--dask-scheduler ADDRESS]`` writes
``DIR/ID.json`` and ``DIR/ID.png`` for each id; ``--dask-scheduler`` runs fig5.3's 6.25e6-point
map on a running dask.distributed scheduler instead of the local cores (checked before anything
runs). ``rns_reproduce all [--out DIR] [--report FILE] [--quick]`` runs every result with a
progress bar and regenerates the report (default ``docs/reproduction.md`` with its figures in
``docs/reproduction/``, relative to the working directory: run it from the repository root).
``--quick`` uses coarse grids and short runs (what the tests use); the default is the thesis'
resolution. Exit codes: 0 done (or Ctrl-C), 2 bad id / unwritable output, one line on stderr.
The results themselves live in :mod:`rns_ros.analysis.reproduce`.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from rns_ros.cli import OneLineParser, output_file_problem, run_main

PROGRAM = "rns_reproduce"
DEFAULT_RUN_DIR = "reproduction_out"
DEFAULT_ALL_DIR = "docs/reproduction"
BAR_WIDTH = 30


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog=PROGRAM,
        description="Regenerate every thesis figure and table next to the thesis value.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    commands.add_parser("list", help="one line per result: id, thesis figure/table, title")
    run = commands.add_parser("run", help="run the given ids; write DIR/ID.json and DIR/ID.png")
    run.add_argument("ids", nargs="+", metavar="ID")
    run.add_argument("--out", default=DEFAULT_RUN_DIR, metavar="DIR", help="output directory")
    run.add_argument("--quick", action="store_true", help="coarse grids, short runs (tests)")
    run.add_argument(
        "--dask-scheduler",
        default=None,
        metavar="ADDRESS",
        help="fig5.3 only: compute the 4-DoF map on this dask.distributed scheduler "
        "(e.g. tcp://host:8786) instead of the local cores",
    )
    everything = commands.add_parser("all", help="run every result and regenerate the report")
    everything.add_argument("--out", default=DEFAULT_ALL_DIR, metavar="DIR")
    everything.add_argument(
        "--report", default=None, metavar="FILE", help="report path (default: DIR.md)"
    )
    everything.add_argument("--quick", action="store_true", help="coarse grids, short runs")
    return parser


def _progress(done: int, total: int, label: str, seconds: float) -> None:
    filled = round(BAR_WIDTH * done / total)
    bar = "#" * filled + "." * (BAR_WIDTH - filled)
    print(f"[{bar}] {done}/{total} {label} ({seconds:.1f} s)", file=sys.stderr, flush=True)


def _run(reproductions, out: Path, quick: bool, progress: bool):
    from rns_ros.analysis.reproduce.registry import run_one

    records = []
    for k, reproduction in enumerate(reproductions, start=1):
        if progress:
            _progress(k - 1, len(reproductions), f"{reproduction.id} ...", 0.0)
        record = run_one(reproduction, out, quick=quick)
        records.append(record)
        if progress:
            _progress(k, len(reproductions), reproduction.id, record.seconds)
        else:
            print(
                f"{reproduction.id}: {record.json_path}, {record.png_path} ({record.seconds:.1f} s)"
            )
    return records


def _announce_replaced(reproductions, out: Path) -> None:
    """Say which earlier results in ``out`` the run replaces (their JSON and PNG files)."""
    replaced = [
        reproduction.id
        for reproduction in reproductions
        if any((out / f"{reproduction.id}.{suffix}").exists() for suffix in ("json", "png"))
    ]
    if replaced:
        shown = ", ".join(replaced[:5]) + (
            f" and {len(replaced) - 5} more" if len(replaced) > 5 else ""
        )
        print(
            f"{PROGRAM}: replacing {len(replaced)} earlier result(s) in {out}: {shown}",
            file=sys.stderr,
        )


def _use_dask_scheduler(address: str, ids: list[str]) -> None:
    """Check the scheduler answers, then hand its address to fig5.3 (the only result that uses
    one) through the environment variable chapter5.DASK_SCHEDULER_ENV."""
    from rns_ros.analysis.chain_energy_maps import check_dask_scheduler
    from rns_ros.analysis.reproduce.chapter5 import DASK_SCHEDULER_ENV
    from rns_ros.core.errors import ConfigError

    if "fig5.3" not in ids:
        raise ConfigError("--dask-scheduler is only used by fig5.3, which is not among the ids")
    check_dask_scheduler(address)
    os.environ[DASK_SCHEDULER_ENV] = address


def _body(argv: Sequence[str]) -> int:
    args = _parser().parse_args(list(argv))
    from rns_ros.analysis.reproduce.registry import load_all, output_dir, resolve
    from rns_ros.analysis.reproduce.report import report_markdown

    if args.command == "list":
        for reproduction in load_all().values():
            print(f"{reproduction.id:<14} {reproduction.figure:<12} {reproduction.title}")
        return 0
    if args.command == "run":
        reproductions = resolve(args.ids)
        if args.dask_scheduler is not None:
            _use_dask_scheduler(args.dask_scheduler, [r.id for r in reproductions])
        out = output_dir(args.out)
        _announce_replaced(reproductions, out)
        _run(reproductions, out, args.quick, progress=False)
        return 0
    out = output_dir(args.out)
    report = Path(args.report) if args.report else out.with_suffix(".md")
    problem = output_file_problem(report)
    if problem is not None:  # before the hour of work, not after it
        from rns_ros.core.errors import ConfigError

        raise ConfigError(f"--report {str(report)!r} {problem}")
    reproductions = list(load_all().values())
    _announce_replaced(reproductions, out)
    start = time.perf_counter()
    records = _run(reproductions, out, args.quick, progress=True)
    figures = os.path.relpath(out.resolve(), report.resolve().parent)
    try:
        report.write_text(report_markdown(records, figures))
    except OSError as exc:
        from rns_ros.core.errors import ConfigError

        raise ConfigError(f"cannot write the report {str(report)!r}: {exc.strerror}") from None
    print(
        f"{len(records)} results in {time.perf_counter() - start:.1f} s; report: {report}",
        file=sys.stderr,
    )
    return 0


def main(args: Sequence[str] | None = None) -> int:
    argv = sys.argv[1:] if args is None else list(args)
    return run_main(PROGRAM, lambda: _body(argv))


if __name__ == "__main__":
    raise SystemExit(main())
