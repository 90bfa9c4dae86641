"""``rns_reproduce``: every thesis figure and table regenerated next to the thesis value.

See :mod:`rns_ros.analysis.reproduce.registry` for the record types and how a chapter registers
its results; the chapter modules (``chapter3``, ``chapter4``, ...) hold the results themselves.
"""

from rns_ros.analysis.reproduce.registry import (
    Comparison,
    Outcome,
    Reproduction,
    RunRecord,
    Verdict,
    load_all,
    number_verdict,
    register,
    resolve,
    run_one,
    trend_verdict,
)
from rns_ros.analysis.reproduce.report import report_markdown

__all__ = [
    "Comparison",
    "Outcome",
    "Reproduction",
    "RunRecord",
    "Verdict",
    "load_all",
    "number_verdict",
    "register",
    "report_markdown",
    "resolve",
    "run_one",
    "trend_verdict",
]
