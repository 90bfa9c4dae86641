"""rns_reproduce: the command line, the report, and that the committed report is complete."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from rns_ros.analysis.reproduce import registry
from rns_ros.analysis.reproduce.registry import (
    CLOSE_FRACTION,
    Comparison,
    Outcome,
    Reproduction,
    Verdict,
    number_verdict,
    trend_verdict,
)
from rns_ros.apps import reproduce
from rns_ros.core.errors import ConfigError

REPO = Path(__file__).resolve().parents[2]
EXECUTABLE = REPO / ".venv" / "bin" / "rns_reproduce"


def _line(value: float) -> Outcome:
    return Outcome(
        comparisons=(
            Comparison.number("slope_m", 2.0, value, "m", tolerance=1e-9, note="a line"),
            Comparison.trend("shape", "straight", "straight", "", holds=value > 0),
            Comparison.input("points", 2, 2, "", "set by the test"),
        ),
        values={"samples": [0.0, value], "ratio": float("inf")},
        settings={"points": 2},
        choices=("A-0.0: a straight line",),
        figure_data=value,
    )


def _plot(outcome: Outcome, figure) -> None:
    axes = figure.subplots()
    axes.plot([0.0, 1.0], [0.0, outcome.figure_data])
    axes.set_xlabel("x [m]")


FAKES = {
    "fake1": Reproduction("fake1", "Fig. 0.1", "a line", lambda quick: _line(2.0), _plot),
    "fake.2": Reproduction("fake.2", "Table 0.2", "another line", lambda quick: _line(1.5), _plot),
}


@pytest.fixture
def fakes(monkeypatch):
    monkeypatch.setattr(registry, "load_all", lambda: dict(FAKES))
    monkeypatch.setattr(reproduce, "PROGRAM", "rns_reproduce")


def test_list_prints_one_line_per_result(fakes, capsys):
    assert reproduce.main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == ["fake1", "fake.2"]
    assert "Table 0.2" in lines[1]


def test_run_writes_json_and_png(fakes, tmp_path):
    assert reproduce.main(["run", "fake.2", "--out", str(tmp_path), "--quick"]) == 0
    document = json.loads((tmp_path / "fake.2.json").read_text())
    assert document["thesis"] == {"slope_m": 2.0, "shape": "straight", "points": 2}
    assert document["ours"]["slope_m"] == 1.5
    assert document["ratio"] == "inf"  # valid JSON: no Infinity literal
    assert document["settings"] == {"points": 2}
    assert document["quick"] is True
    assert (tmp_path / "fake.2.png").read_bytes().startswith(b"\x89PNG")
    assert not (tmp_path / "fake1.json").exists()


def test_all_regenerates_the_report_with_every_result(fakes, tmp_path, capsys):
    out = tmp_path / "docs" / "reproduction"
    assert reproduce.main(["all", "--out", str(out)]) == 0
    report = (tmp_path / "docs" / "reproduction.md").read_text()
    for identifier in FAKES:
        assert f"## {identifier}" in report
        assert f"(reproduction/{identifier}.png)" in report
    # fake.2's 1.5 is 25 % off the thesis' 2: different, whatever the figure says
    assert "| `slope_m` [m] | 2 | 1.5 | different | a line; exact within 1e-09 m |" in report
    assert "| `slope_m` [m] | 2 | 2 | exact |" in report
    assert (
        "**Thesis claims judged: 4**: 1 exact, 0 close, 1 different, 2 qualitative, "
        "0 not reproduced (3 agree)."
    ) in report
    assert "0 by construction (identities" in report
    assert "2 input (values we set" in report
    assert "One verdict rule for every comparison: *exact*" in report
    progress = capsys.readouterr().err
    assert "[" + "#" * reproduce.BAR_WIDTH + "] 2/2" in progress


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["run", "fig9.9"], "unknown id(s) ['fig9.9']; known: fake1, fake.2"),
        (["run"], "the following arguments are required: ID"),
        (["frobnicate"], "invalid choice: 'frobnicate'"),
    ],
)
def test_bad_ids_and_usage_are_one_line_and_exit_2(fakes, capsys, argv, message):
    assert reproduce.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith("rns_reproduce: ")
    assert message in err[0]


def test_a_report_that_cannot_be_written_stops_before_the_work(
    fakes, monkeypatch, tmp_path, capsys
):
    """The report is written after every result: a path that cannot take it is an error at
    start-up (one line, exit 2), before any result is computed."""
    computed = []
    slow = Reproduction(
        "fake1", "Fig. 0.1", "a line", lambda q: computed.append(q) or _line(2.0), _plot
    )
    monkeypatch.setattr(registry, "load_all", lambda: {"fake1": slow})
    report = tmp_path / "no" / "such" / "report.md"
    assert reproduce.main(["all", "--out", str(tmp_path / "out"), "--report", str(report)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"rns_reproduce: --report {str(report)!r} cannot be written: its folder "
        f"{str(report.parent)!r} does not exist"
    ]
    assert computed == []


def test_earlier_results_that_a_run_replaces_are_named(fakes, tmp_path, capsys):
    assert reproduce.main(["run", "fake1", "--out", str(tmp_path), "--quick"]) == 0
    assert "replacing" not in capsys.readouterr().err  # nothing there yet
    assert reproduce.main(["run", "fake1", "fake.2", "--out", str(tmp_path), "--quick"]) == 0
    assert f"rns_reproduce: replacing 1 earlier result(s) in {tmp_path}: fake1" in (
        capsys.readouterr().err
    )


def test_an_unwritable_output_is_one_line_and_exit_2(fakes, tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    assert reproduce.main(["run", "fake1", "--out", str(blocker / "sub")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "is not a writable directory" in err[0]


def test_the_installed_executable_reports_a_bad_id_in_one_line():
    result = subprocess.run(
        [str(EXECUTABLE), "run", "no_such_result"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1
    assert "unknown id(s) ['no_such_result']" in result.stderr


def test_the_committed_report_lists_every_registered_result():
    """docs/reproduction.md is regenerated by `rns_reproduce all`; a result registered since
    then is missing from it until someone runs that again."""
    report = (REPO / "docs" / "reproduction.md").read_text()
    for identifier in registry.load_all():
        assert f"## {identifier}\n" in report, f"{identifier} is not in docs/reproduction.md"
        assert (REPO / "docs" / "reproduction" / f"{identifier}.png").is_file()
        assert (REPO / "docs" / "reproduction" / f"{identifier}.json").is_file()


def test_register_all_keeps_the_order_and_refuses_a_second_id(monkeypatch):
    monkeypatch.setattr(registry, "_REGISTRY", {})
    registered = registry.register_all(FAKES["fake.2"], FAKES["fake1"])
    assert list(registered) == ["fake.2", "fake1"]
    assert list(registry._REGISTRY) == ["fake.2", "fake1"]
    with pytest.raises(ConfigError, match="registered twice"):
        registry.register_all(FAKES["fake1"])


def test_a_trend_is_qualitative_when_it_holds_and_not_reproduced_when_it_fails():
    assert trend_verdict(True) is Verdict.QUALITATIVE
    assert trend_verdict(False) is Verdict.NOT_REPRODUCED
    assert Comparison.trend("k", "grows", "shrinks", "", holds=False).verdict is (
        Verdict.NOT_REPRODUCED
    )


@pytest.mark.parametrize(
    ("thesis", "ours", "tolerance", "verdict"),
    [
        (0.944885, 0.944885, 5e-7, Verdict.EXACT),
        (0.944885, 0.9449, 5e-7, Verdict.CLOSE),
        (1000.0, 1085.0, 100.0, Verdict.EXACT),
        (1000.0, 1100.0 + 1e-9, 100.0, Verdict.DIFFERENT),
        (28.5, 23.6, 0.05, Verdict.DIFFERENT),  # a deliberately wrong value is different
        (4.22, 1.365, 0.005, Verdict.DIFFERENT),
        (1000.0, 11.0, 0.5, Verdict.DIFFERENT),
        (5.0, 5.0 * (1 + CLOSE_FRACTION) + 1e-9, 0.0, Verdict.DIFFERENT),
        (5.0, 5.0 * (1 + CLOSE_FRACTION) - 1e-9, 0.0, Verdict.CLOSE),
        (-2.0, -2.0, 0.0, Verdict.EXACT),
        (0.0, 1e-3, 1e-6, Verdict.DIFFERENT),  # nothing is within 10 % of zero
        ([1.0, 2.0, 3.0], [1.0, 2.0, 3.0 + 1e-12], 1e-9, Verdict.EXACT),
        ([1.0, 2.0, 3.0], [1.0, 2.0, 3.2], 1e-9, Verdict.CLOSE),
        ([1.0, 2.0, 3.0], [1.0, 2.0, 4.0], 1e-9, Verdict.DIFFERENT),
        # element by element: one element 15 % off is different, however close the norm
        ([1000.0, 1000.0], [1085.0, 850.0], 1e-9, Verdict.DIFFERENT),
        ([1.0, 100.0], [1.15, 100.0], 1e-9, Verdict.DIFFERENT),
        ([0.0, 0.0], [0.004, 0.0], 0.00873, Verdict.EXACT),  # a zero has only the exact band
        (1.0, float("nan"), 0.1, Verdict.DIFFERENT),
        (1.0, "n/a", 0.1, Verdict.DIFFERENT),
    ],
)
def test_one_rule_judges_every_number(thesis, ours, tolerance, verdict):
    assert number_verdict(thesis, ours, tolerance) is verdict
    assert Comparison.number("k", thesis, ours, "", tolerance=tolerance).verdict is verdict


@pytest.mark.parametrize(
    ("thesis", "ours", "tolerance", "message"),
    [
        (1.0, 1.0, -1.0, "tolerance must be finite and >= 0"),
        (1.0, 1.0, float("nan"), "tolerance must be finite and >= 0"),
        (float("inf"), 1.0, 0.0, "the thesis' number must be finite"),
        ([1.0, 2.0], [1.0], 0.0, "differ in shape"),
        (1000.0, 1000.0, 500.0, "wider than the close band"),
        ([1000.0, 1.0], [1000.0, 1.0], 0.2, "wider than the close band"),
    ],
)
def test_a_comparison_that_cannot_be_judged_is_an_error(thesis, ours, tolerance, message):
    with pytest.raises(ConfigError, match=message):
        number_verdict(thesis, ours, tolerance)


def test_an_excess_is_judged_over_its_bound():
    """C_ratio >= 1: 1.047 against 1.14 is 4.6 % off as printed, but its excess 0.047 is a
    third of the thesis' 0.14."""
    row = Comparison.excess("c", 1.14, 1.047, "", bound=1.0, tolerance=0.005)
    assert row.verdict is Verdict.DIFFERENT
    assert (row.thesis, row.ours) == (1.14, 1.047)
    assert "excess over 1" in row.note
    assert Comparison.excess("c", 1.14, 1.135, "", bound=1.0, tolerance=0.005).verdict is (
        Verdict.EXACT
    )
    assert Comparison.excess("c", 1.14, 1.13, "", bound=1.0, tolerance=0.005).verdict is (
        Verdict.CLOSE
    )
    with pytest.raises(ConfigError, match="not above the bound"):
        Comparison.excess("c", 0.9, 1.0, "", bound=1.0, tolerance=0.0)


def test_a_result_by_construction_is_listed_and_fails_loudly():
    holds = Comparison.by_construction("d", "no drift", 0.0, "deg", holds=True, note="exact model")
    assert holds.verdict is Verdict.BY_CONSTRUCTION
    fails = Comparison.by_construction("d", "no drift", 1.0, "deg", holds=False, note="exact")
    assert fails.verdict is Verdict.NOT_REPRODUCED
    assert "defect" in fails.note
    assert Verdict.BY_CONSTRUCTION not in registry.COUNTED
    assert Verdict.INPUT not in registry.COUNTED


def test_an_input_is_shown_and_never_a_result():
    row = Comparison.input("epsilon", 0.2, 0.2, "", "the threshold we set (eq. 4.10)")
    assert row.verdict is Verdict.INPUT


def test_the_resolution_choice_names_quick_or_full_runs():
    assert registry.resolution_choice(True, "coarse.", "fine.") == "Quick run (tests): coarse."
    assert registry.resolution_choice(False, "coarse.", "fine.") == "Full run: fine."
