"""``rns_reproduce``: regenerate the thesis' figures and tables next to the thesis values.

``rns_reproduce list`` prints one line per registered result (id, thesis label, title).
``rns_reproduce run ID [ID ...] [--out DIR] [--quick]`` writes ``DIR/ID.json`` and ``DIR/ID.png``
for each id. ``rns_reproduce all [--out DIR] [--report FILE] [--quick]`` runs every result with a
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

from rns_ros.cli import run_main

PROGRAM = "rns_reproduce"
DEFAULT_RUN_DIR = "reproduction_out"
DEFAULT_ALL_DIR = "docs/reproduction"
BAR_WIDTH = 30


class _Parser(argparse.ArgumentParser):
    """argparse that raises ConfigError (one line, exit 2) instead of printing usage."""

    def error(self, message: str):
        from rns_ros.core.errors import ConfigError

        raise ConfigError(f"{message} (see {PROGRAM} --help)")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog=PROGRAM,
        description="Regenerate every thesis figure and table next to the thesis value.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    commands.add_parser("list", help="one line per result: id, thesis figure/table, title")
    run = commands.add_parser("run", help="run the given ids; write DIR/ID.json and DIR/ID.png")
    run.add_argument("ids", nargs="+", metavar="ID")
    run.add_argument("--out", default=DEFAULT_RUN_DIR, metavar="DIR", help="output directory")
    run.add_argument("--quick", action="store_true", help="coarse grids, short runs (tests)")
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


def _body(argv: Sequence[str]) -> int:
    args = _parser().parse_args(list(argv))
    from rns_ros.analysis.reproduce.registry import (
        load_all,
        output_dir,
        report_markdown,
        resolve,
    )

    if args.command == "list":
        for reproduction in load_all().values():
            print(f"{reproduction.id:<14} {reproduction.figure:<12} {reproduction.title}")
        return 0
    if args.command == "run":
        reproductions = resolve(args.ids)
        _run(reproductions, output_dir(args.out), args.quick, progress=False)
        return 0
    out = output_dir(args.out)
    report = Path(args.report) if args.report else out.with_suffix(".md")
    start = time.perf_counter()
    records = _run(list(load_all().values()), out, args.quick, progress=True)
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
