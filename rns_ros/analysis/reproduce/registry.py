"""The reproduction registry: every thesis figure and table as one :class:`Reproduction`.

A chapter module registers its results at import (``register_all(Reproduction(...), ...)``);
:func:`load_all` imports the chapter modules listed in :data:`CHAPTER_MODULES`, so a later
chapter adds itself by adding its module there. Each result has

* ``compute(quick) -> Outcome``: the numbers. ``quick`` uses coarse grids / short runs (tests);
  the default is the thesis' resolution.
* ``plot(outcome, figure)``: draws what the thesis figure shows on a matplotlib ``Figure``.

:func:`run_one` turns one result into ``<id>.json`` and ``<id>.png``; the JSON holds the thesis'
numbers under the thesis' names next to ours, the settings and the documented choices.
"""

from __future__ import annotations

import importlib
import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from rns_ros.analysis.reproduce.plotting import save_figure
from rns_ros.core.errors import ConfigError

#: Modules that register results when imported, in report order (a new chapter appends its own).
CHAPTER_MODULES = (
    "rns_ros.analysis.reproduce.chapter3",
    "rns_ros.analysis.reproduce.chapter3_bifurcation",
    "rns_ros.analysis.reproduce.chapter4_model",
    "rns_ros.analysis.reproduce.chapter4",
    "rns_ros.analysis.reproduce.chapter4_singularity",
    "rns_ros.analysis.reproduce.chapter4_ptp",
    "rns_ros.analysis.reproduce.chapter4_deployment",
    "rns_ros.analysis.reproduce.chapter5",
    "rns_ros.analysis.reproduce.chapter5_inspection_energy",
    "rns_ros.analysis.reproduce.chapter6",
    "rns_ros.analysis.reproduce.chapter6_remarks",
    "rns_ros.analysis.reproduce.chapter7",
    "rns_ros.analysis.reproduce.chapter7_wall",
)


class Verdict(StrEnum):
    """How a thesis number or claim is reproduced: one rule for every comparison (see
    :data:`VERDICT_RULE`). *input* marks a value we set or fitted: shown, never counted."""

    EXACT = "exact"
    CLOSE = "close"
    DIFFERENT = "different"
    QUALITATIVE = "qualitative"
    NOT_REPRODUCED = "not reproduced"
    INPUT = "input"


#: relative distance to the thesis' number within which ours is *close* [-]
CLOSE_FRACTION = 0.10
#: the rule, as the report states it
VERDICT_RULE = (
    "*exact*: within the stated numerical tolerance of the thesis' number; "
    f"*close*: within {CLOSE_FRACTION:.0%} of it; *different*: further than that; "
    "*qualitative*: the thesis states only a trend, and the trend holds in our run; "
    "*not reproduced*: the trend fails; *input*: a value we set or fitted, shown for reference "
    "and never counted as a result."
)


def number_verdict(thesis, ours, tolerance: float) -> Verdict:
    """*exact* when ``ours`` is within ``tolerance`` of ``thesis`` (largest element-wise
    distance, same unit), *close* within :data:`CLOSE_FRACTION` of the thesis' magnitude (norms
    for arrays), else *different*. A non-finite or non-numeric ``ours`` is *different*.

    Raises:
        ConfigError: a negative or non-finite ``tolerance``, a non-finite thesis number, or
            shapes that differ.
    """
    if not (math.isfinite(tolerance) and tolerance >= 0.0):
        raise ConfigError(f"tolerance must be finite and >= 0, got {tolerance!r}")
    expected = np.asarray(thesis, dtype=float)
    if not np.all(np.isfinite(expected)):
        raise ConfigError(f"the thesis' number must be finite, got {thesis!r}")
    try:
        value = np.asarray(ours, dtype=float)
    except (TypeError, ValueError):
        return Verdict.DIFFERENT
    if value.shape != expected.shape:
        raise ConfigError(f"ours {value.shape} and the thesis' {expected.shape} differ in shape")
    if not np.all(np.isfinite(value)):
        return Verdict.DIFFERENT
    if float(np.max(np.abs(value - expected), initial=0.0)) <= tolerance:
        return Verdict.EXACT
    if float(np.linalg.norm(value - expected)) <= CLOSE_FRACTION * float(np.linalg.norm(expected)):
        return Verdict.CLOSE
    return Verdict.DIFFERENT


def trend_verdict(holds: bool) -> Verdict:
    """*qualitative* when the thesis' trend holds in our run, else *not reproduced*."""
    return Verdict.QUALITATIVE if holds else Verdict.NOT_REPRODUCED


@dataclass(frozen=True)
class Comparison:
    """One quantity the thesis reports, next to ours, with its verdict. Build it with
    :meth:`number`, :meth:`trend` or :meth:`input`: the verdict follows from the values.

    Attributes:
        key: name in the JSON (the thesis' quantity, with its unit as suffix, e.g. ``r_star_m``).
        thesis: the thesis' value (number or short text); None when it only says it in words.
        ours: our value (number, text or list).
        unit: unit of both, e.g. "m", "deg"; "" for counts and text.
        verdict: :class:`Verdict`.
        note: why, the tolerance, or the cause of a *different* / *not reproduced*.
    """

    key: str
    thesis: Any
    ours: Any
    unit: str
    verdict: Verdict
    note: str = ""

    @classmethod
    def number(
        cls, key: str, thesis, ours, unit: str, *, tolerance: float, note: str = ""
    ) -> Comparison:
        """A number the thesis prints, judged by :func:`number_verdict` (the tolerance is
        stated in the note)."""
        stated = f"exact within {tolerance:.3g}{f' {unit}' if unit else ''}"
        return cls(
            key,
            thesis,
            ours,
            unit,
            number_verdict(thesis, ours, tolerance),
            f"{note}; {stated}" if note else stated,
        )

    @classmethod
    def trend(cls, key: str, thesis, ours, unit: str, *, holds: bool, note: str = "") -> Comparison:
        """A trend the thesis states in words (``thesis`` quotes it), judged by
        :func:`trend_verdict` on ``holds``, computed from our run."""
        return cls(key, thesis, ours, unit, trend_verdict(bool(holds)), note)

    @classmethod
    def input(cls, key: str, thesis, ours, unit: str, note: str) -> Comparison:
        """A value we set or fitted (``note`` says how): shown, never counted as a result."""
        return cls(key, thesis, ours, unit, Verdict.INPUT, note)


@dataclass(frozen=True)
class Outcome:
    """What ``compute`` returns.

    Attributes:
        comparisons: the thesis' numbers next to ours.
        values: our numbers under their JSON names (e.g. ``max_base_deviation_deg``), JSON-able.
        settings: grid, step, gains, model... everything needed to rerun it.
        choices: the documented choices this result depends on (ids of thesis_rest ambiguities
            and our own), one sentence each.
        figure_data: whatever ``plot`` needs (arrays); not written to the JSON.
    """

    comparisons: tuple[Comparison, ...]
    values: Mapping[str, Any]
    settings: Mapping[str, Any]
    choices: tuple[str, ...] = ()
    figure_data: Any = None


@dataclass(frozen=True)
class Reproduction:
    """One thesis figure or table.

    Attributes:
        id: short id for the command line, e.g. ``fig3.1``, ``bifurcation``.
        figure: the thesis' label, e.g. "Fig. 3.1", "§3.2.2".
        title: one line saying what it shows.
        compute: ``quick -> Outcome``.
        plot: ``(outcome, figure) -> None`` draws on a matplotlib Figure.
        size: figure size [in] (width, height).
    """

    id: str
    figure: str
    title: str
    compute: Callable[[bool], Outcome]
    plot: Callable[[Outcome, Any], None]
    size: tuple[float, float] = field(default=(8.0, 6.0))


_REGISTRY: dict[str, Reproduction] = {}


def register(reproduction: Reproduction) -> Reproduction:
    """Add ``reproduction`` (its id must be new)."""
    if reproduction.id in _REGISTRY:
        raise ConfigError(f"reproduction id {reproduction.id!r} is registered twice")
    _REGISTRY[reproduction.id] = reproduction
    return reproduction


def resolution_choice(quick: bool, quick_run: str, full_run: str) -> str:
    """The choice that states a result's resolution: ``Quick run (tests): <quick_run>`` or
    ``Full run: <full_run>``."""
    return f"Quick run (tests): {quick_run}" if quick else f"Full run: {full_run}"


def register_all(*reproductions: Reproduction) -> dict[str, Reproduction]:
    """Register ``reproductions`` in the given order; {id: reproduction} of them."""
    return {reproduction.id: register(reproduction) for reproduction in reproductions}


def load_all() -> dict[str, Reproduction]:
    """Import every chapter module and return {id: reproduction} in registration order."""
    for module in CHAPTER_MODULES:
        importlib.import_module(module)
    return dict(_REGISTRY)


def resolve(ids) -> list[Reproduction]:
    """The reproductions named by ``ids``, in the given order.

    Raises:
        ConfigError: an unknown id (the message lists the known ones).
    """
    known = load_all()
    unknown = [name for name in ids if name not in known]
    if unknown:
        raise ConfigError(f"unknown id(s) {unknown}; known: {', '.join(known)}")
    return [known[name] for name in ids]


@dataclass(frozen=True)
class RunRecord:
    """One result written to disk: its outcome, files and wall time [s]."""

    reproduction: Reproduction
    outcome: Outcome
    json_path: Path
    png_path: Path
    seconds: float


def output_dir(path: str | Path) -> Path:
    """Create ``path`` if needed and check it is a writable directory.

    Raises:
        ConfigError: it is a file, or it cannot be created or written.
    """
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".rns_reproduce_write_test"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        reason = exc.strerror or str(exc)
        raise ConfigError(f"--out {str(out)!r} is not a writable directory: {reason}") from None
    return out


def run_one(reproduction: Reproduction, out: Path, *, quick: bool = False) -> RunRecord:
    """Compute ``reproduction``, write ``out/<id>.json`` and ``out/<id>.png``."""
    start = time.perf_counter()
    outcome = reproduction.compute(quick)
    png = out / f"{reproduction.id}.png"
    save_figure(
        png,
        reproduction.size,
        f"{reproduction.figure}: {reproduction.title}",
        lambda figure: reproduction.plot(outcome, figure),
    )
    seconds = time.perf_counter() - start
    document = {
        "id": reproduction.id,
        "figure": reproduction.figure,
        "title": reproduction.title,
        "quick": quick,
        "thesis": {c.key: c.thesis for c in outcome.comparisons},
        "ours": {c.key: c.ours for c in outcome.comparisons},
        "comparisons": [
            {
                "key": c.key,
                "thesis": c.thesis,
                "ours": c.ours,
                "unit": c.unit,
                "verdict": c.verdict.value,
                "note": c.note,
            }
            for c in outcome.comparisons
        ],
        **{key: value for key, value in outcome.values.items()},
        "settings": dict(outcome.settings),
        "choices": list(outcome.choices),
        "wall_time_s": round(seconds, 3),
    }
    path = out / f"{reproduction.id}.json"
    path.write_text(json.dumps(_jsonable(document), indent=2, allow_nan=False) + "\n")
    return RunRecord(reproduction, outcome, path, png, seconds)


def _jsonable(value):
    """Plain JSON types; non-finite floats become strings ("inf", "nan") so the file stays valid."""
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, StrEnum):
        return value.value
    return value


def report_markdown(records: list[RunRecord], figure_dir: str) -> str:
    """docs/reproduction.md: the verdict rule and counts, then per result a table thesis | ours |
    verdict and its figure.

    Args:
        figure_dir: path of the PNGs relative to the report (e.g. "reproduction").
    """
    counts = {verdict: 0 for verdict in Verdict}
    for record in records:
        for comparison in record.outcome.comparisons:
            counts[comparison.verdict] += 1
    compared = [verdict for verdict in Verdict if verdict is not Verdict.INPUT]
    lines = [
        "# Reproduction of the thesis",
        "",
        "Generated by `rns_reproduce all` (do not edit by hand). Each section is one registered",
        "result: the numbers the thesis reports next to ours, the settings and our choices.",
        "The JSON of each result, with every value, is written next to its figure.",
        "",
        f"One verdict rule for every comparison: {VERDICT_RULE}",
        "",
        f"Totals: {sum(counts[v] for v in compared)} compared: "
        + ", ".join(f"{counts[v]} {v.value}" for v in compared)
        + f"; {counts[Verdict.INPUT]} input (not counted); {len(records)} results, "
        f"{sum(r.seconds for r in records):.0f} s of computing.",
        "",
        "| id | thesis | title |",
        "|---|---|---|",
    ]
    lines += [
        f"| [`{r.reproduction.id}`](#{_anchor(r.reproduction.id)}) | {r.reproduction.figure} | "
        f"{r.reproduction.title} |"
        for r in records
    ]
    for record in records:
        rep, outcome = record.reproduction, record.outcome
        lines += [
            "",
            f"## {rep.id}",
            "",
            f"{rep.figure}: {rep.title}. Computed in {record.seconds:.1f} s.",
            "",
            "| quantity | thesis | ours | verdict | note |",
            "|---|---|---|---|---|",
        ]
        for c in outcome.comparisons:
            unit = f" [{c.unit}]" if c.unit else ""
            lines.append(
                f"| `{c.key}`{unit} | {_cell(c.thesis)} | {_cell(c.ours)} | {c.verdict.value} | "
                f"{_cell(c.note)} |"
            )
        if outcome.settings:
            settings = "; ".join(f"{k} = {_cell(v)}" for k, v in outcome.settings.items())
            lines += ["", f"Settings: {settings}."]
        if outcome.choices:
            lines += ["", "Choices:", ""] + [f"* {choice}" for choice in outcome.choices]
        lines += ["", f"![{rep.figure}]({figure_dir}/{rep.id}.png)"]
    return "\n".join(lines) + "\n"


def _anchor(identifier: str) -> str:
    return identifier.replace(".", "").lower()


def _cell(value) -> str:
    if value is None:
        return "—"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list | tuple):
        return ", ".join(_cell(v) for v in value) if len(value) <= 6 else f"{len(value)} values"
    return str(value).replace("|", "\\|")
