"""docs/reproduction.md: the headline table and counts that keep identities, inputs and
extensions apart from the thesis' claims."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rns_ros.analysis.reproduce import report
from rns_ros.analysis.reproduce.registry import (
    Comparison,
    Outcome,
    Reproduction,
    RunRecord,
    Verdict,
    load_all,
)
from rns_ros.core.errors import ConfigError

REPO = Path(__file__).resolve().parents[2]


def _record(identifier: str, *rows: Comparison, extension: bool = False) -> RunRecord:
    reproduction = Reproduction(
        identifier, "Fig. 0.1", "a test", lambda quick: None, lambda o, f: None, extension=extension
    )
    outcome = Outcome(comparisons=rows, values={}, settings={})
    return RunRecord(reproduction, outcome, Path("x.json"), Path("x.png"), 1.0)


def _records() -> list[RunRecord]:
    return [
        _record(
            "fig0.1",
            Comparison.number("r_m", 0.945, 0.9449, "m", tolerance=5e-4),
            Comparison.by_construction("drift", "none", 0.0, "deg", holds=True, note="exact"),
            Comparison.trend("payload", "same", "same", "", holds=True, extension=True),
            Comparison.input("mass", 30.0, 30.0, "kg", "Table 0.1"),
        ),
        _record(
            "ext-fig0.1",
            Comparison.trend("more", "grows", "grows", "", holds=False),
            extension=True,
        ),
    ]


def test_only_the_thesis_claims_are_counted():
    text = "\n".join(report.counts_text(_records()))
    assert "**Thesis claims judged: 1**: 1 exact, 0 close, 0 different" in text
    assert "1 by construction" in text
    assert "1 input" in text
    assert "2 extension rows" in text
    assert "1 qualitative, 1 not reproduced" in text


def test_the_report_marks_extensions():
    markdown = report.report_markdown(_records(), "reproduction")
    assert "| `payload` | same | same | qualitative (extension) |" in markdown
    assert "An extension: ours only, reported apart." in markdown
    assert markdown.index("## Headline") < markdown.index("## Counts") < markdown.index("## fig0.1")


def test_a_headline_row_its_result_lacks_is_an_error(monkeypatch):
    monkeypatch.setattr(report, "HEADLINES", (report.Headline("r*", (("fig0.1", "r_star"),)),))
    with pytest.raises(ConfigError, match=r"'r_star' is not in the result 'fig0\.1'"):
        report.headline_table(_records())
    monkeypatch.setattr(report, "HEADLINES", (report.Headline("r*", (("fig0.1", "r_m"),)),))
    table = report.headline_table(_records())
    assert table[2] == "| r* | 0.945 | 0.9449 m | exact | [`fig0.1`](#fig01) `r_m` |"
    assert "not run" in report.headline_table([])[2]


def test_every_headline_names_a_registered_row_of_the_committed_report():
    """The headline rows exist in the JSON `rns_reproduce all` wrote for docs/."""
    known = load_all()
    for headline in report.HEADLINES:
        for identifier, key in headline.rows:
            assert identifier in known, identifier
            document = json.loads(
                (REPO / "docs" / "reproduction" / f"{identifier}.json").read_text()
            )
            assert key in {row["key"] for row in document["comparisons"]}, (identifier, key)


def _committed_rows():
    for identifier in load_all():
        document = json.loads((REPO / "docs" / "reproduction" / f"{identifier}.json").read_text())
        for row in document["comparisons"]:
            yield identifier, row


def test_each_claim_is_counted_once():
    """No counted row (a thesis claim, not an extension) appears in two results with the same
    thesis value and the same value of ours (counts aside: two claims may both count zero)."""
    seen: dict[str, str] = {}
    counted = {v.value for v in report.COUNTED}
    for identifier, row in _committed_rows():
        if row["verdict"] not in counted or row.get("extension") or isinstance(row["ours"], int):
            continue
        signature = json.dumps([row["thesis"], row["ours"]], sort_keys=True)
        assert signature not in seen, f"{identifier}.{row['key']} repeats {seen.get(signature)}"
        seen[signature] = f"{identifier}.{row['key']}"


def test_no_list_is_exact_or_close_with_an_element_more_than_ten_percent_off():
    for identifier, row in _committed_rows():
        if row["verdict"] not in (Verdict.EXACT.value, Verdict.CLOSE.value):
            continue
        thesis, ours = row["thesis"], row["ours"]
        if not isinstance(thesis, list) or not isinstance(ours, list):
            continue
        for expected, value in zip(thesis, ours, strict=True):
            if expected:
                assert abs(value - expected) <= 0.1 * abs(expected) + 1e-12, (identifier, row)


def test_the_committed_report_has_enough_rows_by_construction():
    labelled = [r for _, r in _committed_rows() if r["verdict"] == Verdict.BY_CONSTRUCTION.value]
    assert len(labelled) >= 10


def test_ids_follow_the_thesis_numbering():
    """One id per thesis figure or table (its own number), §-ids for claims in the text, and
    extensions named as such."""
    for identifier, reproduction in load_all().items():
        figure = re.fullmatch(r"(fig|table)(\d+\.\d+)", identifier)
        if figure:
            kind = "Fig." if figure[1] == "fig" else "Table"
            assert reproduction.figure == f"{kind} {figure[2]}", identifier
            assert not reproduction.extension
        elif identifier.startswith("sec"):
            assert reproduction.figure == f"§{identifier[3:]}", identifier
        else:
            assert identifier.startswith("ext-"), identifier
            assert reproduction.extension, identifier
