#!/usr/bin/env python3
"""Parameter tables of the node pages, generated from each node's parameters module.

Usage:  .venv/bin/python scripts/node_docs.py --write | --check

Each page docs/nodes/<NODE_NAME>.md holds its table between the lines :data:`BEGIN` and
:data:`END`; a page with two tables (one node, two parameter sets) names the parameters module
after the word in each marker (``<!-- parameters: begin contact_simulator_parameters -->``).
``--write`` replaces the text between them with
:func:`rns_ros.nodes.parameters.markdown_table`, ``--check`` exits with code 1 naming every page
whose table differs. A parameters module that does not import, or a page that does not exist or
lacks the markers, is reported and skipped.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path
from types import ModuleType

from rns_ros.nodes.parameters import markdown_table

#: Parameters modules of the nodes (each defines NODE_NAME and PARAMETERS).
PARAMETER_MODULES = (
    "rns_ros.nodes.simulator_parameters",
    "rns_ros.nodes.contact_simulator_parameters",
    "rns_ros.nodes.controller_parameters",
    "rns_ros.nodes.ptp_parameters",
    "rns_ros.nodes.force_controller_parameters",
    "rns_ros.nodes.attitude_control_parameters",
    "rns_ros.nodes.link_parameters",
    "rns_ros.nodes.predictor_parameters",
    "rns_ros.nodes.operator_parameters",
    "rns_ros.nodes.rerun_logger_parameters",
    "rns_ros.nodes.teleop_keyboard_parameters",
    "rns_ros.nodes.teleop_spacemouse_parameters",
)
BEGIN = "<!-- parameters: begin -->"
END = "<!-- parameters: end -->"
#: Folder of the node pages.
PAGES = Path(__file__).resolve().parents[1] / "docs" / "nodes"


def load(name: str) -> ModuleType | None:
    """The parameters module ``name``, or None after a message when it does not import."""
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        print(f"skipped {name}: it does not import ({exc})", file=sys.stderr)
        return None


def page(module: ModuleType) -> Path:
    """The page of the node whose parameters module is ``module`` (in :data:`PAGES`)."""
    return PAGES / f"{module.NODE_NAME}.md"


def markers(module: ModuleType, text: str) -> tuple[str, str]:
    """The (begin, end) marker lines of ``module``'s table in a page ``text``: the ones that name
    the module when the page has them, else :data:`BEGIN` and :data:`END`."""
    short = module.__name__.rpartition(".")[2]
    named = (f"{BEGIN[:-4]} {short} -->", f"{END[:-4]} {short} -->")
    return named if named[0] in text else (BEGIN, END)


def with_table(text: str, table: str, begin_line: str = BEGIN, end_line: str = END) -> str | None:
    """``text`` with ``table`` between its ``begin_line`` and ``end_line``; None when the
    markers are missing or out of order."""
    lines = text.splitlines(keepends=True)
    stripped = [line.strip() for line in lines]
    if stripped.count(begin_line) != 1 or stripped.count(end_line) != 1:
        return None
    begin, end = stripped.index(begin_line), stripped.index(end_line)
    if end < begin:
        return None
    return "".join(lines[: begin + 1]) + table + "\n" + "".join(lines[end:])


def current_text(module: ModuleType) -> tuple[str, str] | None:
    """(page text, text with the generated table) of ``module``'s node; None after a message
    when the page does not exist or lacks the markers."""
    path = page(module)
    if not path.is_file():
        print(f"skipped {module.NODE_NAME}: no page {path}", file=sys.stderr)
        return None
    text = path.read_text(encoding="utf-8")
    begin, end = markers(module, text)
    updated = with_table(text, markdown_table(module.PARAMETERS), begin, end)
    if updated is None:
        print(f"skipped {path}: it needs one line {begin} before one line {end}", file=sys.stderr)
        return None
    return text, updated


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    action = parser.add_mutually_exclusive_group(required=True)
    action.add_argument("--write", action="store_true", help="rewrite the tables")
    action.add_argument("--check", action="store_true", help="exit 1 when a table is stale")
    args = parser.parse_args(argv)
    stale = []
    for name in PARAMETER_MODULES:
        module = load(name)
        texts = None if module is None else current_text(module)
        if texts is None or texts[0] == texts[1]:
            continue
        if args.write:
            page(module).write_text(texts[1], encoding="utf-8")
            print(f"wrote {page(module)}")
        else:
            stale.append(page(module))
    for path in stale:
        print(f"stale parameter table: {path} (run scripts/node_docs.py --write)", file=sys.stderr)
    return 1 if stale else 0


if __name__ == "__main__":
    raise SystemExit(main())
