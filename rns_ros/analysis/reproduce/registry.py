"""The reproduction registry: every thesis figure and table as one :class:`Reproduction`.

A chapter module registers its results at import (``register_all(Reproduction(...), ...)``);
:func:`load_all` imports the chapter modules listed in :data:`CHAPTER_MODULES`, so a later
chapter adds itself by adding its module there. Each result has

* ``compute(quick) -> Outcome``: the numbers. ``quick`` uses coarse grids / short runs (tests);
  the default is the thesis' resolution.
* ``plot(outcome, figure)``: draws what the thesis figure shows on a matplotlib ``Figure``.

:func:`run_one` turns one result into ``<id>.json`` and ``<id>.png``; the JSON holds the thesis'
numbers under the thesis' names next to ours, the settings and the documented choices.
:mod:`~rns_ros.analysis.reproduce.report` writes docs/reproduction.md from the results.

Ids follow the thesis' numbering: ``fig<chapter>.<n>`` and ``table<chapter>.<n>`` for one thesis
figure or table, ``sec<section>`` for a claim made in the text, ``ext-...`` for our extensions.
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
    :data:`VERDICT_RULE`). *by construction* marks an identity or a result our set-up forces:
    listed, never counted as agreement. *input* marks a value we set or fitted: shown, never
    counted."""

    EXACT = "exact"
    CLOSE = "close"
    DIFFERENT = "different"
    QUALITATIVE = "qualitative"
    NOT_REPRODUCED = "not reproduced"
    BY_CONSTRUCTION = "by construction"
    INPUT = "input"


#: verdicts that are results (counted); the others are listed only
COUNTED = (
    Verdict.EXACT,
    Verdict.CLOSE,
    Verdict.DIFFERENT,
    Verdict.QUALITATIVE,
    Verdict.NOT_REPRODUCED,
)


#: relative distance to the thesis' number within which ours is *close* [-]
CLOSE_FRACTION = 0.10
#: the rule, as the report states it
VERDICT_RULE = (
    "*exact*: within the stated numerical tolerance of the thesis' number; "
    f"*close*: every element within {CLOSE_FRACTION:.0%} of the thesis' element; "
    "*different*: further than that; "
    "*qualitative*: the thesis states only a trend, and the trend holds in our run; "
    "*not reproduced*: the trend fails; *by construction*: an identity, or a result our set-up "
    "forces (exact model, a plan built from the null vector), listed and never counted as "
    "agreement (should one fail, it is *not reproduced*: a defect); *input*: a value we set or "
    "fitted, or a statement of the set-up, shown for reference and never counted. "
    'Where the thesis prints a number (a ratio, "about two times" = 2, "almost 10³" = '
    "10³), ours is compared as a number, element by element for a list; each exact band is "
    "written in the code before the run and is never wider than the close band; a quantity "
    "bounded below (C_ratio ≥ 1) is compared on its excess over the bound. "
    "*Extension* rows and results (conditions the thesis never ran) are reported apart."
)


def number_verdict(thesis, ours, tolerance: float) -> Verdict:
    """*exact* when every element of ``ours`` is within ``tolerance`` of the thesis' (same
    unit), *close* when every element is within :data:`CLOSE_FRACTION` of the thesis' element's
    magnitude, else *different*. A non-finite or non-numeric ``ours`` is *different*.

    ``tolerance`` is the exact band; it may not be wider than the close band of any non-zero
    thesis element (a zero element has no close band: only the exact band applies).

    Raises:
        ConfigError: a negative or non-finite ``tolerance``, one wider than the close band, a
            non-finite thesis number, or shapes that differ.
    """
    if not (math.isfinite(tolerance) and tolerance >= 0.0):
        raise ConfigError(f"tolerance must be finite and >= 0, got {tolerance!r}")
    expected = np.asarray(thesis, dtype=float)
    if not np.all(np.isfinite(expected)):
        raise ConfigError(f"the thesis' number must be finite, got {thesis!r}")
    band = CLOSE_FRACTION * np.abs(expected)
    if np.any((expected != 0.0) & (tolerance > band)):
        raise ConfigError(
            f"the exact band {tolerance!r} is wider than the close band "
            f"({CLOSE_FRACTION:.0%} of {thesis!r}): state a narrower tolerance"
        )
    try:
        value = np.asarray(ours, dtype=float)
    except (TypeError, ValueError):
        return Verdict.DIFFERENT
    if value.shape != expected.shape:
        raise ConfigError(f"ours {value.shape} and the thesis' {expected.shape} differ in shape")
    if not np.all(np.isfinite(value)):
        return Verdict.DIFFERENT
    distance = np.abs(value - expected)
    if float(np.max(distance, initial=0.0)) <= tolerance:
        return Verdict.EXACT
    if np.all(distance <= band):
        return Verdict.CLOSE
    return Verdict.DIFFERENT


def trend_verdict(holds: bool) -> Verdict:
    """*qualitative* when the thesis' trend holds in our run, else *not reproduced*."""
    return Verdict.QUALITATIVE if holds else Verdict.NOT_REPRODUCED


@dataclass(frozen=True)
class Comparison:
    """One quantity the thesis reports, next to ours, with its verdict. Build it with
    :meth:`number`, :meth:`excess`, :meth:`trend`, :meth:`by_construction` or :meth:`input`:
    the verdict follows from the values.

    Attributes:
        key: name in the JSON (the thesis' quantity, with its unit as suffix, e.g. ``r_star_m``).
        thesis: the thesis' value (number or short text); None when it only says it in words.
        ours: our value (number, text or list).
        unit: unit of both, e.g. "m", "deg"; "" for counts and text.
        verdict: :class:`Verdict`.
        note: why, the tolerance, or the cause of a *different* / *not reproduced*.
        extension: a condition the thesis never ran (ours only): reported apart from the
            thesis' claims.
    """

    key: str
    thesis: Any
    ours: Any
    unit: str
    verdict: Verdict
    note: str = ""
    extension: bool = False

    @classmethod
    def number(
        cls,
        key: str,
        thesis,
        ours,
        unit: str,
        *,
        tolerance: float,
        note: str = "",
        extension: bool = False,
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
            extension,
        )

    @classmethod
    def excess(
        cls,
        key: str,
        thesis,
        ours,
        unit: str,
        *,
        bound: float,
        tolerance: float,
        note: str = "",
    ) -> Comparison:
        """A printed number of a quantity bounded below by ``bound`` (C_ratio >= 1), judged by
        :func:`number_verdict` on the excess over the bound (``ours - bound`` against
        ``thesis - bound``), which is what carries the information; the row shows both values
        as printed.

        Raises:
            ConfigError: the thesis' number is not above the bound.
        """
        expected = np.asarray(thesis, dtype=float)
        if not np.all(expected > bound):
            raise ConfigError(f"the thesis' {thesis!r} is not above the bound {bound!r}")
        try:
            value = np.asarray(ours, dtype=float) - bound
        except (TypeError, ValueError):
            value = ours
        stated = (
            f"compared on the excess over {bound:g}: ours {cell_text(_plain(value))} against "
            f"{cell_text(_plain(expected - bound))}; exact within {tolerance:.3g}"
            f"{f' {unit}' if unit else ''}"
        )
        return cls(
            key,
            thesis,
            ours,
            unit,
            number_verdict(expected - bound, value, tolerance),
            f"{note}; {stated}" if note else stated,
        )

    @classmethod
    def trend(
        cls,
        key: str,
        thesis,
        ours,
        unit: str,
        *,
        holds: bool,
        note: str = "",
        extension: bool = False,
    ) -> Comparison:
        """A trend the thesis states in words (``thesis`` quotes it), judged by
        :func:`trend_verdict` on ``holds``, computed from our run."""
        return cls(key, thesis, ours, unit, trend_verdict(bool(holds)), note, extension)

    @classmethod
    def by_construction(
        cls, key: str, thesis, ours, unit: str, *, holds: bool, note: str
    ) -> Comparison:
        """A claim our set-up makes true whatever the physics (an identity, an exact model, a
        plan built to have it): *by construction*, never counted as agreement. ``holds`` is
        still checked: an identity that fails is a defect, shown as *not reproduced*. ``note``
        says why it holds by construction."""
        verdict = Verdict.BY_CONSTRUCTION if holds else Verdict.NOT_REPRODUCED
        if not holds:
            note = f"{note}; the identity FAILS in our run: a defect in the model or the code"
        return cls(key, thesis, ours, unit, verdict, note)

    @classmethod
    def input(cls, key: str, thesis, ours, unit: str, note: str) -> Comparison:
        """A value we set or fitted, or a statement of the set-up (``note`` says how): shown,
        never counted as a result."""
        return cls(key, thesis, ours, unit, Verdict.INPUT, note)


def _plain(value):
    """A numpy value as a float or a list of floats (for notes)."""
    array = np.asarray(value, dtype=float) if not isinstance(value, str) else value
    if isinstance(array, np.ndarray):
        return float(array) if array.ndim == 0 else [float(v) for v in array.ravel()]
    return array


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
        id: short id for the command line, e.g. ``fig3.1``, ``sec3.2.2``.
        figure: the thesis' label, e.g. "Fig. 3.1", "§3.2.2".
        title: one line saying what it shows.
        compute: ``quick -> Outcome``.
        plot: ``(outcome, figure) -> None`` draws on a matplotlib Figure.
        size: figure size [in] (width, height).
        extension: ours only (a condition or method the thesis never ran): every row is
            reported apart from the thesis' claims.
    """

    id: str
    figure: str
    title: str
    compute: Callable[[bool], Outcome]
    plot: Callable[[Outcome, Any], None]
    size: tuple[float, float] = field(default=(8.0, 6.0))
    extension: bool = False


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
        "extension": reproduction.extension,
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
                "extension": c.extension or reproduction.extension,
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


def cell_text(value) -> str:
    """``value`` as one markdown table cell (floats to 6 digits, long lists counted)."""
    if value is None:
        return "—"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list | tuple):
        if len(value) <= 6 and not any(isinstance(v, list | tuple) for v in value):
            return ", ".join(cell_text(v) for v in value)
        try:
            flat = np.asarray(value, dtype=float).ravel()
        except (TypeError, ValueError):
            return f"{len(value)} values"
        if not flat.size:
            return "—"
        if flat.min() == flat.max():
            return f"{flat.size} values, all {flat.min():.4g}"
        return f"{flat.size} values, {flat.min():.4g} to {flat.max():.4g}"
    if isinstance(value, Mapping) and len(value) <= 6:
        return ", ".join(f"{k}: {cell_text(v)}" for k, v in value.items())
    return str(value).replace("|", "\\|")
