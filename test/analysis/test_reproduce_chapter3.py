"""The four chapter-3 reproductions run (quick) into JSON + PNG with the thesis/ours keys.

The chapter module is imported directly (not through registry.load_all) so that these tests do
not depend on the other chapters' modules."""

from __future__ import annotations

import json

import pytest

from rns_ros.analysis.reproduce import chapter3
from rns_ros.analysis.reproduce.registry import Status, run_one

IDS = ("fig3.1", "fig3.2", "fig3.3", "bifurcation")


def test_the_four_results_are_registered():
    assert tuple(chapter3.REPRODUCTIONS) == IDS
    figures = [r.figure for r in chapter3.REPRODUCTIONS.values()]
    assert figures == ["Fig. 3.1", "Fig. 3.2", "Fig. 3.3", "§3.2.2"]


@pytest.mark.parametrize("identifier", IDS)
def test_quick_run_writes_json_and_png(identifier, tmp_path):
    record = run_one(chapter3.REPRODUCTIONS[identifier], tmp_path, quick=True)
    assert record.seconds < 5.0
    assert record.png_path.stat().st_size > 10_000
    assert record.png_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    document = json.loads(record.json_path.read_text())
    assert document["id"] == identifier
    assert document["quick"] is True
    assert document["thesis"].keys() == document["ours"].keys()
    assert document["thesis"]
    assert document["settings"]["base_mass_kg"] == 1000.0
    assert document["choices"]
    statuses = {c["status"] for c in document["comparisons"]}
    assert statuses <= {s.value for s in Status}
    assert Status.NOT_REPRODUCIBLE.value not in statuses  # the planar model is fully specified


def test_bifurcation_json(tmp_path):
    document = json.loads(
        run_one(chapter3.REPRODUCTIONS["bifurcation"], tmp_path, quick=True).json_path.read_text()
    )
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


def test_figure_numbers(tmp_path):
    fig3_2 = json.loads(run_one(chapter3.REPRODUCTIONS["fig3.2"], tmp_path).json_path.read_text())
    assert fig3_2["fixed_point_counts"] == {"0.5": 0, "0.945": 4, "1.5": 4}
    fig3_3 = json.loads(run_one(chapter3.REPRODUCTIONS["fig3.3"], tmp_path).json_path.read_text())
    assert fig3_3["det_argmax_theta_rad"] == [0.0, 0.0]
    assert fig3_3["det_max_kg2_m4"] == pytest.approx(2.5251e5, rel=1e-3)
    fig3_1 = json.loads(run_one(chapter3.REPRODUCTIONS["fig3.1"], tmp_path).json_path.read_text())
    assert fig3_1["ours"]["fixed_point_count"] == 0
    assert fig3_1["min_abs_n2"] >= 0.95
