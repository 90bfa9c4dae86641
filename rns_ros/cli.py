"""Command-line pieces shared by the non-node executables (``rns_demo``, ``rns_observer``)."""

from __future__ import annotations

import argparse
import os

#: ROS 2 domain IDs accepted here (the range that maps to valid UDP ports on every platform).
DOMAIN_ID_RANGE = (0, 101)


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """(own arguments, ROS arguments): ``--ros-args ... [--]`` is cut out, as rcl reads it."""
    if "--ros-args" not in argv:
        return list(argv), []
    start = argv.index("--ros-args")
    end = argv.index("--", start) if "--" in argv[start:] else len(argv)
    return argv[:start] + argv[end + 1 :], argv[start:end]


def add_domain_id_argument(parser: argparse.ArgumentParser, fallback: int, what: str) -> None:
    """``--domain-id``: default ``ROS_DOMAIN_ID`` of the environment, else ``fallback``.

    The environment value is checked by the same rule as the option (an integer in
    :data:`DOMAIN_ID_RANGE`), so a bad ``ROS_DOMAIN_ID`` is a usage error naming it.
    """
    low, high = DOMAIN_ID_RANGE

    def domain_id(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"must be an integer in [{low}, {high}] (option or ROS_DOMAIN_ID), got {text!r}"
            )
        return value

    parser.add_argument(
        "--domain-id",
        type=domain_id,
        default=os.environ.get("ROS_DOMAIN_ID", str(fallback)),  # argparse converts it
        help=f"ROS domain {what} [{low}, {high}] (default: ROS_DOMAIN_ID, else {fallback})",
    )
