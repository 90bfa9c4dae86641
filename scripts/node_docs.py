#!/usr/bin/env python3
"""Parameter tables of the node pages, generated from each node's parameters module.

Usage:  .venv/bin/python scripts/node_docs.py --write | --check

Each page docs/nodes/<NODE_NAME>.md holds its table between the lines :data:`BEGIN` and
:data:`END`; ``--write`` replaces the text between them with
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
    "rns_ros.nodes.operator_parameters",
    "rns_ros.nodes.rerun_logger_parameters",
    "rns_ros.nodes.teleop_keyboard_parameters",
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


def with_table(text: str, table: str) -> str | None:
    """``text`` with ``table`` between its :data:`BEGIN` and :data:`END` lines; None when the
    markers are missing or out of order."""
    lines = text.splitlines(keepends=True)
    stripped = [line.strip() for line in lines]
    if stripped.count(BEGIN) != 1 or stripped.count(END) != 1:
        return None
    begin, end = stripped.index(BEGIN), stripped.index(END)
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
    updated = with_table(text, markdown_table(module.PARAMETERS))
    if updated is None:
        print(f"skipped {path}: it needs one line {BEGIN} before one line {END}", file=sys.stderr)
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
