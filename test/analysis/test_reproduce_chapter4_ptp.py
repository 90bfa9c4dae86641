"""Chapter 4 point-to-point and deployment reproductions (chapter4_ptp: Table 4.2, Figs.
4.10-4.12; chapter4_deployment: Figs. 4.13-4.15, partial deployment):
each id runs quick into JSON + PNG with the documented keys, and every verdict follows from the
numbers next to it (Table 4.2 and §4.5.2 as printed numbers, the fitted targets as inputs)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from rns_testing import comparison_rows, expected_verdict, quick_documents, quick_result_verdicts

from rns_ros.analysis.reproduce import chapter4_deployment, chapter4_ptp, ptp_snapshots
from rns_ros.analysis.reproduce.registry import CHAPTER_MODULES

IDS = (
    "table4.2",
    "fig4.10",
    "fig4.11",
    "fig4.12",
    "fig4.13",
    "partial_deployment",
    "fig4.14",
    "fig4.15",
)
METHODS = {"3-phase", "JS-C", "IJ-C", "TJ-C"}
#: full-resolution max base deviations [deg] of table4.2 and partial_deployment (docs/ptp.md)
FULL_TABLE = {"3-phase": 1.934631, "JS-C": 2.651097, "IJ-C": 3.062447, "TJ-C": 3.028953}
FULL_PARTIAL = {"partial_reactionless": 3.105277, "baseline": 4.064867}


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    """{id: (json document, png path)}; table4.2/fig4.10/fig4.12 share their runs (cache)."""
    return quick_documents(IDS, tmp_path_factory.mktemp("chapter4_ptp"))


def test_registered_after_the_singularity_results_in_thesis_order():
    assert (*chapter4_ptp.REPRODUCTIONS, *chapter4_deployment.REPRODUCTIONS) == IDS
    modules = list(CHAPTER_MODULES)
    first = modules.index("rns_ros.analysis.reproduce.chapter4_singularity")
    assert modules[first + 1 : first + 3] == [
        "rns_ros.analysis.reproduce.chapter4_ptp",
        "rns_ros.analysis.reproduce.chapter4_deployment",
    ]


def test_the_thesis_numbers_are_exact_and_the_trend_holds():
    table = chapter4_ptp.table_comparisons(chapter4_ptp.THESIS_TABLE, 0.0)
    partial = chapter4_deployment.partial_comparisons(chapter4_ptp.THESIS_PARTIAL, -180.0)
    # the printed ratios are the printed degrees' to within 0.014 (thesis_rest §2.5)
    assert {c.verdict.value for c in table + partial} == {"exact", "qualitative"}


def test_full_resolution_numbers_give_close_and_different_with_a_cause():
    table = {c.key: c for c in chapter4_ptp.table_comparisons(FULL_TABLE, 34.6)}
    verdicts = {key: c.verdict.value for key, c in table.items()}
    assert verdicts["max_base_deviation_3-phase_deg"] == "close"  # 1.935 vs 1.95
    assert verdicts["max_base_deviation_JS-C_deg"] == "different"  # 2.651 vs 3.61
    assert verdicts["ratio_JS-C"] == "different"  # 1.370 vs 1.84
    assert verdicts["ratio_IJ-C"] == "close"  # 1.583 vs 1.64
    assert verdicts["three_phase_least"] == "qualitative"
    assert "73%" in table["ratio_JS-C"].note  # the baseline's deviation is 73 % of the thesis'
    assert "34.6 deg" in table["max_base_deviation_3-phase_deg"].note


def test_a_gap_the_link_lengths_cover_is_not_called_open():
    printed = chapter4_ptp.THESIS_TABLE["JS-C"]
    small = {0.9: {**FULL_TABLE, "JS-C": 2.4}, 1.1: {**FULL_TABLE, "JS-C": 2.9}}
    large = {0.9: {**FULL_TABLE, "JS-C": 1.9}, 1.1: {**FULL_TABLE, "JS-C": 3.7}}
    for sensitivity, open_ in ((small, True), (large, False)):
        rows = {c.key: c for c in chapter4_ptp.table_comparisons(FULL_TABLE, 34.6, sensitivity)}
        note = rows["max_base_deviation_JS-C_deg"].note
        assert f"{abs(printed / FULL_TABLE['JS-C'] - 1):.0%} gap" in note
        assert ("do not explain it" in note) is open_


def test_partial_reduction_of_23_6_against_28_5_is_different():
    comparisons = chapter4_deployment.partial_comparisons(FULL_PARTIAL, -197.34)
    reduction = {c.key: c for c in comparisons}["reduction_percent"]
    assert reduction.ours == pytest.approx(23.61, abs=0.01)
    assert reduction.verdict.value == expected_verdict(28.5, reduction.ours, 0.05) == "different"
    # the note gives what the run shows: both deviations against the thesis' and the fold
    for shown in ("57%", "53%", "-197.3 deg", "17.3 deg", "open"):
        assert shown in reduction.note


def test_three_phase_least_fails_when_a_baseline_deviates_less():
    deviation = {**FULL_TABLE, "IJ-C": 1.5}
    least = {c.key: c for c in chapter4_ptp.table_comparisons(deviation, 0.0)}["three_phase_least"]
    assert least.verdict.value == "not reproduced"
    assert "IJ-C" in least.note
    assert "open" in least.note


@pytest.mark.slow
@pytest.mark.parametrize("identifier", IDS)
def test_each_result_writes_json_and_png(documents, identifier):
    document, png = documents[identifier]
    quick_result_verdicts(document, png, identifier)
    for c in document["comparisons"]:
        assert c["note"]
        if c["verdict"] in {"different", "not reproduced"}:
            # a cause backed by the run: a number before the stated tolerance
            assert re.search(r"\d", c["note"].split("; exact within")[0]), c


@pytest.mark.slow
def test_table_4_2(documents):
    document, _ = documents["table4.2"]
    deviation, ratio = document["max_base_deviation_deg"], document["ratio"]
    assert set(deviation) == METHODS
    assert set(ratio) == METHODS
    assert ratio["3-phase"] == pytest.approx(1.0)
    for name in METHODS - {"3-phase"}:
        assert ratio[name] == pytest.approx(deviation[name] / deviation["3-phase"], rel=1e-5)
    # the thesis' claim holds on our geometry: the 3-phase method disturbs the base least
    assert min(deviation, key=deviation.get) == "3-phase"
    assert document["final_camera_error_m"]["TJ-C"] < 0.01
    table = comparison_rows(document)
    for name in METHODS:
        row = table[f"max_base_deviation_{name}_deg"]
        assert row["ours"] == pytest.approx(deviation[name], abs=1e-4)
        assert row["verdict"] == expected_verdict(row["thesis"], row["ours"], 5e-3)
    for name in METHODS - {"3-phase"}:
        row = table[f"ratio_{name}"]
        assert row["verdict"] == expected_verdict(row["thesis"], row["ours"], 0.02)
    assert table["three_phase_least"]["verdict"] == "qualitative"
    # the target is our own 3-phase end: an input
    assert table["camera_target_m"]["verdict"] == "input"
    # the same joint-space path on a longer arm: more coupling inertia, more base deviation
    sensitivity = document["arm_length_sensitivity"]
    assert sensitivity["0.9"]["JS-C"] < deviation["JS-C"] < sensitivity["1.1"]["JS-C"]
    # the labelled runs aimed at the thesis' printed point reach it
    for name, run in document["thesis_point_target"].items():
        assert run["final_camera_error_m"] < (0.05 if name == "IJ-C" else 0.01)


def test_the_base_frame_camera_is_the_world_camera_until_the_base_moves():
    """World = base frame at t = 0: the fitted (base-frame) camera point and the run's world
    camera agree at the start and part by the base's motion at the end."""
    run = chapter4_ptp._table_runs(True)["3-phase"]
    start = chapter4_ptp._camera_in_base_frame(run.theta[0])
    np.testing.assert_allclose(start, run.camera[0], atol=1e-9)
    end = chapter4_ptp._camera_in_base_frame(run.theta[-1])
    lever = np.linalg.norm(end)
    # a base turned by the final deviation moves a point at this lever arm by about angle * lever
    assert np.linalg.norm(end - run.camera[-1]) > 0.5 * run.base_deviation[-1] * lever


@pytest.mark.slow
def test_fig_4_10_coupling_only_in_phase_two(documents):
    document, _ = documents["fig4.10"]
    per_phase = document["max_coupling_per_phase"]
    assert per_phase["II"] > 1.0
    assert per_phase["I"] < 1e-10 * per_phase["II"]
    assert per_phase["III"] < 1e-10 * per_phase["II"]
    table = comparison_rows(document)
    assert table["coupling_only_in_phase_II"]["verdict"] == "qualitative"
    assert table["phase_durations_s"]["verdict"] == "input"


@pytest.mark.slow
def test_fig_4_12_deviation_only_in_phase_two(documents):
    document, _ = documents["fig4.12"]
    table = comparison_rows(document)
    row = table["deviation_only_in_phase_II_deg"]
    outside = max(row["ours"].values())
    assert outside < 1e-3 * document["max_base_deviation_deg"]["3-phase"]
    assert row["verdict"] == "qualitative"
    peaks = table["max_base_deviation_deg"]
    assert len(peaks["ours"]) == len(peaks["thesis"]) == len(METHODS)


@pytest.mark.slow
def test_deployments(documents):
    full, _ = documents["fig4.13"]
    assert full["max_base_deviation_deg"] < 1e-3
    table = comparison_rows(full)
    assert table["max_base_deviation_deg"]["verdict"] == "qualitative"
    # theta_4 = 134.55 deg is where the plan ends the fold: an input
    assert table["theta4_final_deg"]["verdict"] == "input"
    assert table["theta4_final_deg"]["ours"] == pytest.approx(134.55, abs=0.01)
    partial, _ = documents["partial_deployment"]
    deviation = partial["max_base_deviation_deg"]
    assert set(deviation) == {"partial_reactionless", "baseline"}
    assert partial["reduction_percent"] == pytest.approx(
        100.0 * (1.0 - deviation["partial_reactionless"] / deviation["baseline"]), rel=1e-4
    )
    assert partial["reduction_percent"] > 0.0
    assert partial["final_error_deg"] < 0.1
    reduction = comparison_rows(partial)["reduction_percent"]
    assert reduction["verdict"] == expected_verdict(28.5, reduction["ours"], 0.05)
    # the same joint-space baseline path on a longer arm disturbs the base more
    sensitivity = partial["arm_length_sensitivity"]
    assert sensitivity["0.9"]["baseline"] < deviation["baseline"] < sensitivity["1.1"]["baseline"]


@pytest.mark.slow
def test_fig_4_11_snapshots_per_phase(documents):
    document, _ = documents["fig4.11"]
    assert document["snapshot_phases"] == ["I", "I", "II", "II", "III", "III", "III"]
    table = comparison_rows(document)
    share = table["elbow_share_of_joint_travel"]["ours"]
    travel = document["joint_travel_deg"]
    for name in ("I", "II", "III"):
        assert share[name] == pytest.approx(travel[name][3] / sum(travel[name]), abs=1e-3)
    holds = share["I"] > share["II"] and share["III"] > share["II"]
    assert table["elbow_share_of_joint_travel"]["verdict"] == _trend(holds)
    folded = table["folded_in_phase_II_m"]["ours"]
    holds = folded["phase_II_max"] < min(folded["initial"], folded["final"])
    assert table["folded_in_phase_II_m"]["verdict"] == _trend(holds)
    # the base-in-Phase-II check is fig4.12's alone (one thesis claim, counted once)
    assert "base_moves_only_in_phase_II_deg" not in table


@pytest.mark.slow
def test_fig_4_14_and_4_15_snapshots(documents):
    partial, _ = documents["fig4.14"]
    assert partial["snapshot_phases"] == ["II", "II", "III", "III", "III"]
    table = comparison_rows(partial)
    share = table["elbow_share_of_joint_travel"]["ours"]
    assert share["III"] > share["II"]
    assert table["elbow_share_of_joint_travel"]["verdict"] == "qualitative"
    folded = table["folded_in_phase_II_m"]["ours"]
    assert folded["phase_II_max"] < folded["goal"]
    assert table["folded_in_phase_II_m"]["verdict"] == "qualitative"
    # no number row repeats partial_deployment's deviations
    assert not any(key.startswith("max_base_deviation") for key in table)
    baseline, _ = documents["fig4.15"]
    rows = comparison_rows(baseline)
    late, peak = baseline["late_deviation_change_deg"], baseline["max_base_deviation_deg"]
    assert peak == pytest.approx(documents["partial_deployment"][0]["max_base_deviation_deg"])
    moving = late["baseline"] > 1e-3 * peak["baseline"]
    assert rows["base_moves_throughout_deg"]["verdict"] == _trend(moving)
    reach = baseline["mean_reach_phase_II_m"]
    extended = reach["baseline"] > reach["partial_reactionless"]
    assert rows["extended_while_turning_m"]["verdict"] == _trend(extended)


def test_snapshot_trends_fail_on_wrong_numbers():
    travel = {
        "I": np.radians([45.0, 17.0, 81.0, 120.0, 0, 0, 0]),
        "II": np.radians([130.0, 111.0, 182.0, 35.0, 0, 0, 0]),
        "III": np.radians([30.0, 12.0, 110.0, 85.0, 0, 0, 0]),
    }
    assert ptp_snapshots.elbow_share_row(travel, ("I", "III")).verdict.value == "qualitative"
    # an elbow that turns most in Phase II: the folds are not where the elbow moves
    travel["II"][3] = math.radians(400.0)
    row = ptp_snapshots.elbow_share_row(travel, ("I", "III"))
    assert row.verdict.value == "not reproduced"
    assert "open" in row.note

    times = np.linspace(0.0, 30.0, 31)
    reach = np.where((times >= 5.0) & (times <= 25.0), 0.7, 1.4)

    class Phase:  # the only attributes folded_row reads
        start, end = 5.0, 25.0

    ends = {"initial": 0.0, "final": 30.0}
    assert ptp_snapshots.folded_row(times, reach, Phase, ends).verdict.value == "qualitative"
    reach[15] = 1.5  # an extended arm in the middle of Phase II
    assert ptp_snapshots.folded_row(times, reach, Phase, ends).verdict.value == "not reproduced"

    partial, baseline = "partial_reactionless", "baseline"
    late = {partial: 2e-6, baseline: 0.441}
    peak = {partial: 3.105, baseline: 4.065}
    reach = {partial: 0.609, baseline: 1.282}
    share = chapter4_ptp.REACTIONLESS_SHARE
    rows = ptp_snapshots.baseline_rows(late, peak, reach, share)
    assert [row.verdict.value for row in rows] == ["qualitative", "qualitative"]
    late, reach = {**late, baseline: 1e-6}, {**reach, baseline: 0.5}
    rows = ptp_snapshots.baseline_rows(late, peak, reach, share)
    assert [row.verdict.value for row in rows] == ["not reproduced", "not reproduced"]


def _trend(holds: bool) -> str:
    """The verdict of a trend, written out independently of the registry."""
    return "qualitative" if holds else "not reproduced"
