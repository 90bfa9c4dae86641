"""The four chapter-3 reproductions run (quick) into JSON + PNG with the thesis/ours keys, and
their verdicts follow from the numbers.

The chapter module is imported directly (not through registry.load_all) so that these tests do
not depend on the other chapters' modules."""

from __future__ import annotations

import json

import numpy as np
import pytest
from rns_testing import quick_result_verdicts

from rns_ros.analysis.planar_field import PlanarArm, critical_distance, fixed_points
from rns_ros.analysis.reproduce import chapter3, chapter3_bifurcation
from rns_ros.analysis.reproduce.registry import CLOSE_FRACTION, Verdict, run_one

IDS = ("fig3.1", "fig3.2", "fig3.3", "sec3.2.2")


def _rows(document) -> dict[str, dict]:
    return {row["key"]: row for row in document["comparisons"]}


#: chapter 3's results in report order: chapter3's three, then the bifurcation module's
REPRODUCTIONS = {**chapter3.REPRODUCTIONS, **chapter3_bifurcation.REPRODUCTIONS}


def _run(identifier, tmp_path, *, quick=True) -> dict:
    record = run_one(REPRODUCTIONS[identifier], tmp_path, quick=quick)
    return json.loads(record.json_path.read_text())


def test_the_four_results_are_registered():
    assert tuple(REPRODUCTIONS) == IDS
    figures = [r.figure for r in REPRODUCTIONS.values()]
    assert figures == ["Fig. 3.1", "Fig. 3.2", "Fig. 3.3", "§3.2.2"]


@pytest.mark.parametrize("identifier", IDS)
def test_quick_run_writes_json_and_png(identifier, tmp_path):
    record = run_one(REPRODUCTIONS[identifier], tmp_path, quick=True)
    document = json.loads(record.json_path.read_text())
    verdicts = quick_result_verdicts(document, record.png_path, identifier)
    assert document["thesis"].keys() == document["ours"].keys()
    assert document["thesis"]
    assert document["settings"]["base_mass_kg"] == 1000.0
    assert document["choices"]
    # the planar model is fully specified: every number the thesis prints is met exactly
    assert verdicts <= {
        Verdict.EXACT,
        Verdict.QUALITATIVE,
        Verdict.NOT_REPRODUCED,
        Verdict.BY_CONSTRUCTION,
    }


def test_bifurcation_json(tmp_path):
    document = _run("sec3.2.2", tmp_path)
    assert 0.9448 <= document["r_star_m"] <= 0.9450
    assert document["thesis"]["r_star_m"] == 0.945
    assert document["ours"]["r_star_m"] == pytest.approx(0.944885, abs=1e-6)
    points = document["fixed_points"]
    assert {p["r_m"] for p in points} == {0.946, 0.95, 1.0, 1.5, 3.0, 10.0, 100.0}
    for point in points:
        assert point.keys() >= {"r_m", "theta_rad"}
        assert len(point["theta_rad"]) == 2
    at_1_5 = sorted(tuple(round(v, 3) for v in p["theta_rad"]) for p in points if p["r_m"] == 1.5)
    assert at_1_5 == [(-2.459, -0.786), (-1.964, -2.935), (1.964, 2.935), (2.459, 0.786)]


def test_bifurcation_verdicts_follow_the_numbers(tmp_path):
    rows = _rows(_run("sec3.2.2", tmp_path))
    # 0.944885 is 1.2e-4 m from the printed 0.945, within half its last digit (5e-4 m)
    assert abs(rows["r_star_m"]["ours"] - 0.945) <= chapter3.R_STAR_TOLERANCE
    assert rows["r_star_m"]["verdict"] == Verdict.EXACT
    # a mirror pair of saddle-nodes at r*: the thesis' "two fixed points are created"
    assert rows["fixed_points_created"]["ours"] == 2
    assert rows["fixed_points_created"]["verdict"] == Verdict.EXACT
    assert "4 at 0.946 m" in rows["fixed_points_created"]["note"]
    assert rows["limit_theta2_rad"]["verdict"] == Verdict.QUALITATIVE


def test_another_arm_makes_the_printed_numbers_different(monkeypatch, tmp_path):
    """The verdicts can fail: 0.4 m links (uniform 100 kg rods) move r* far below 0.945 m and
    bring fixed points to r = 0.5 m, against the thesis' 'no fixed point'."""
    short = PlanarArm(
        link_lengths=(0.4, 0.4), com_distances=(0.2, 0.2), link_inertias=(4 / 3, 4 / 3)
    )
    r_star = critical_distance(short).r_star
    assert abs(r_star - 0.945) > CLOSE_FRACTION * 0.945
    at_half = len(fixed_points(short.at(0.5)))
    assert at_half > 0
    monkeypatch.setattr(chapter3, "ARM", short)
    monkeypatch.setattr(chapter3_bifurcation, "ARM", short)
    rows = _rows(_run("sec3.2.2", tmp_path))
    assert rows["r_star_m"]["ours"] == pytest.approx(r_star)
    assert rows["r_star_m"]["verdict"] == Verdict.DIFFERENT
    rows = _rows(_run("fig3.2", tmp_path))
    assert "r_star_m" not in rows  # one claim, judged once (sec3.2.2)
    assert rows["fixed_points_r0_5"]["ours"] == at_half
    assert rows["fixed_points_r0_5"]["verdict"] == Verdict.DIFFERENT


def _records(distances, theta2_of_r) -> list[dict]:
    return [
        {"r_m": r, "theta_rad": [sign * 1.6, sign * theta2]}
        for r in distances
        for theta2 in theta2_of_r(r)
        for sign in (1.0, -1.0)
    ]


def test_the_limit_trend_fails_when_the_branches_stop_short():
    converging = _records((1.0, 10.0, 100.0), lambda r: (0.5 / r, np.pi - 0.3 / r))
    assert chapter3_bifurcation._limit_row(converging).verdict is Verdict.QUALITATIVE
    stalled = _records((1.0, 10.0, 100.0), lambda r: (0.5 - 0.1 * np.log10(r), 2.9))
    assert chapter3_bifurcation._limit_row(stalled).verdict is Verdict.NOT_REPRODUCED


#: a det map with no zero and no fixed point: "the dark area is singular" cannot hold
_FLAT_MAP = (np.linspace(-np.pi, np.pi, 5), np.linspace(-np.pi, np.pi, 5), np.ones((5, 5)))


@pytest.mark.parametrize(
    ("row", "verdict"),
    [
        # an identity is listed, never agreement; should it fail, it is a defect
        (lambda: chapter3._symmetry_row(1e-15, 11), Verdict.BY_CONSTRUCTION),
        (lambda: chapter3._symmetry_row(1e-3, 11), Verdict.NOT_REPRODUCED),
        (lambda: chapter3._com_distance_row([0.0, 0.0], 2.5, 0.01), Verdict.BY_CONSTRUCTION),
        (lambda: chapter3._com_distance_row([0.0, 0.5], 2.4, 0.01), Verdict.NOT_REPRODUCED),
        (lambda: chapter3._dark_area_row(chapter3.ARM, _FLAT_MAP, []), Verdict.NOT_REPRODUCED),
        (lambda: chapter3._joint_2_row(0.95, 0.31, 11), Verdict.QUALITATIVE),
        (lambda: chapter3._joint_2_row(0.4, 0.9, 11), Verdict.NOT_REPRODUCED),
        (lambda: chapter3._separation_row([], 0.05, 1.2), Verdict.QUALITATIVE),
        (lambda: chapter3._separation_row([], 1.2, 0.05), Verdict.NOT_REPRODUCED),
        (lambda: chapter3._separation_row([], None, 1.2), Verdict.NOT_REPRODUCED),
    ],
)
def test_a_trend_is_judged_on_its_numbers(row, verdict):
    assert row().verdict is verdict


def test_det_follows_distance_only_when_it_does():
    distance = np.linspace(0.0, 2.5, 100).reshape(10, 10)
    along = chapter3._large_distance_row(distance**2, distance, 1.0)
    against = chapter3._large_distance_row((2.5 - distance) ** 2, distance, -1.0)
    assert along.verdict is Verdict.QUALITATIVE
    assert against.verdict is Verdict.NOT_REPRODUCED


def test_figure_numbers(tmp_path):
    fig3_2 = _run("fig3.2", tmp_path, quick=False)
    assert fig3_2["fixed_point_counts"] == {"0.5": 0, "0.945": 4, "1.5": 4}
    rows = _rows(fig3_2)
    assert rows["fixed_points_r0_5"]["verdict"] == Verdict.EXACT
    assert "fixed_points_created_at_r_star" not in rows  # counted in sec3.2.2
    assert "4 fixed points at r = 0.945 m" in fig3_2["near_r_star"]
    assert rows["separation_r1_5"]["verdict"] == Verdict.QUALITATIVE
    fig3_3 = _run("fig3.3", tmp_path, quick=False)
    assert fig3_3["det_argmax_theta_rad"] == [0.0, 0.0]
    assert fig3_3["det_max_kg2_m4"] == pytest.approx(2.5251e5, rel=1e-3)
    rows = _rows(fig3_3)
    assert rows["det_argmax_theta_rad"]["verdict"] == Verdict.EXACT
    assert rows["dark_area_is_singular"]["verdict"] == Verdict.BY_CONSTRUCTION
    assert rows["com_distance_argmax_theta_rad"]["verdict"] == Verdict.BY_CONSTRUCTION
    assert rows["fixed_points_in_small_distance_area"]["verdict"] == Verdict.QUALITATIVE
    # 'det large whenever the distance is large' fails at the edge of the large-distance half
    assert fig3_3["det_min_where_distance_above_median_kg2_m4"] < fig3_3["det_median_kg2_m4"]
    assert rows["det_large_where_distance_large"]["verdict"] == Verdict.NOT_REPRODUCED
    assert "fails at the area's edge" in rows["det_large_where_distance_large"]["note"]
    fig3_1 = _run("fig3.1", tmp_path, quick=False)
    assert fig3_1["ours"]["fixed_point_count"] == 0
    assert fig3_1["min_abs_n2"] >= 0.95
    assert fig3_1["max_abs_n1"] <= 0.31
    assert _rows(fig3_1)["joint_2_dominant"]["verdict"] == Verdict.QUALITATIVE
