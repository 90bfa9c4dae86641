"""``rns_reproduce``: every thesis figure and table regenerated next to the thesis value.

See :mod:`rns_ros.analysis.reproduce.registry` for the record types and how a chapter registers
its results; the chapter modules (``chapter3``, ``chapter4``, ...) hold the results themselves.
"""

from rns_ros.analysis.reproduce.registry import (
    Comparison,
    Outcome,
    Reproduction,
    RunRecord,
    Status,
    load_all,
    register,
    report_markdown,
    resolve,
    run_one,
)

__all__ = [
    "Comparison",
    "Outcome",
    "Reproduction",
    "RunRecord",
    "Status",
    "load_all",
    "register",
    "report_markdown",
    "resolve",
    "run_one",
]
