"""Chapter 4 point-to-point and deployment reproductions (chapter4_ptp: Table 4.2, Figs.
4.10-4.12; chapter4_deployment: Figs. 4.13-4.15, §4.5.2 partial deployment):
each id runs quick into JSON + PNG with the documented keys, and every verdict follows from the
numbers next to it (Table 4.2, "about two times" and §4.5.2 as printed numbers, the fitted
targets as inputs, what the plan is built to have by construction, failing when it fails)."""

from __future__ import annotations

import math
import re
from types import SimpleNamespace

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
    "sec4.5.2",
    "fig4.14",
    "fig4.15",
)
METHODS = {"3-phase", "JS-C", "IJ-C", "TJ-C"}
#: full-resolution max base deviations [deg] of table4.2 and sec4.5.2 (docs/ptp.md)
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


def test_the_thesis_numbers_are_exact_but_its_ratios_are_not_about_two():
    table = {c.key: c for c in chapter4_ptp.table_comparisons(chapter4_ptp.THESIS_TABLE, 0.0)}
    partial = chapter4_deployment.partial_comparisons(chapter4_ptp.THESIS_PARTIAL, -180.0)
    ratio = table.pop("deviation_ratio_baselines_over_3_phase")
    assert {c.verdict.value for c in [*table.values(), *partial]} == {"exact"}
    # the thesis' own IJ-C / 3-phase = 3.21 / 1.95 = 1.65 is 18 % below "about two times"
    assert ratio.ours == pytest.approx([1.851, 1.646, 1.974], abs=1e-3)
    assert ratio.verdict.value == "different"
    assert "which this rule calls different" in ratio.note


def test_table_4_2_counts_four_deviations_and_one_ratio_row():
    keys = [c.key for c in chapter4_ptp.table_comparisons(FULL_TABLE, 34.6)]
    assert keys == [
        "max_base_deviation_3-phase_deg",
        "max_base_deviation_JS-C_deg",
        "max_base_deviation_IJ-C_deg",
        "max_base_deviation_TJ-C_deg",
        "deviation_ratio_baselines_over_3_phase",
    ]


@pytest.mark.parametrize(
    ("ratios", "verdict"),
    [
        ((2.0, 2.0, 2.0), "exact"),
        ((1.81, 2.19, 2.0), "exact"),  # within 0.2 of 2: exact and close coincide
        ((1.4, 2.0, 2.0), "different"),
        ((2.0, 2.0, 2.21), "different"),
        ((1.37, 1.583, 1.566), "different"),  # ours at full resolution
    ],
)
def test_about_two_times_is_judged_element_by_element(ratios, verdict):
    deviation = {"3-phase": 1.0, **dict(zip(("JS-C", "IJ-C", "TJ-C"), ratios, strict=True))}
    row = chapter4_ptp.about_two_row(deviation, "Phase II turns theta_4 by 0.0 deg")
    assert row.thesis == [2.0, 2.0, 2.0]
    assert row.ours == pytest.approx(list(ratios), abs=1e-3)
    assert row.verdict.value == verdict
    assert "exact within 0.2" in row.note
    assert ("open" in row.note) is (verdict == "different")


def test_full_resolution_numbers_give_close_and_different_with_a_cause():
    table = {c.key: c for c in chapter4_ptp.table_comparisons(FULL_TABLE, 34.6)}
    verdicts = {key: c.verdict.value for key, c in table.items()}
    assert verdicts["max_base_deviation_3-phase_deg"] == "close"  # 1.935 vs 1.95
    assert verdicts["max_base_deviation_JS-C_deg"] == "different"  # 2.651 vs 3.61
    assert verdicts["max_base_deviation_IJ-C_deg"] == "close"  # 3.062 vs 3.21
    ratio = table["deviation_ratio_baselines_over_3_phase"]
    assert verdicts["deviation_ratio_baselines_over_3_phase"] == "different"  # 1.37-1.58 vs 2
    assert "73% of the thesis'" in ratio.note  # JS-C's deviation is 73 % of the thesis'
    assert "34.6 deg" in ratio.note
    # the 3-phase method still disturbs the base least: said in the note, not counted again
    assert "the least max deviation of the four is 3-phase's" in ratio.note
    assert "34.6 deg" in table["max_base_deviation_3-phase_deg"].note
    assert not {"three_phase_least", "ratio_JS-C", "ratio_IJ-C", "ratio_TJ-C"} & set(table)


def test_a_gap_the_link_lengths_cover_is_not_called_open():
    printed = chapter4_ptp.THESIS_TABLE["JS-C"]
    small = {0.9: {**FULL_TABLE, "JS-C": 2.4}, 1.1: {**FULL_TABLE, "JS-C": 2.9}}
    large = {0.9: {**FULL_TABLE, "JS-C": 1.9}, 1.1: {**FULL_TABLE, "JS-C": 3.7}}
    for sensitivity, open_ in ((small, True), (large, False)):
        rows = {c.key: c for c in chapter4_ptp.table_comparisons(FULL_TABLE, 34.6, sensitivity)}
        note = rows["max_base_deviation_JS-C_deg"].note
        assert f"{abs(printed / FULL_TABLE['JS-C'] - 1):.0%} gap" in note
        assert ("do not explain it" in note) is open_
    ratio = rows["deviation_ratio_baselines_over_3_phase"].note
    assert "1.91, 1.58, 1.57 at 1.1x" in ratio  # 3.7 / 1.935


def test_partial_reduction_of_23_6_against_28_5_is_different():
    comparisons = chapter4_deployment.partial_comparisons(FULL_PARTIAL, -197.34)
    rows = {c.key: c for c in comparisons}
    assert list(rows) == [
        "max_base_deviation_partial_reactionless_deg",
        "max_base_deviation_baseline_deg",
        "reduction_percent",
    ]
    reduction = rows["reduction_percent"]
    assert reduction.ours == pytest.approx(23.61, abs=0.01)
    assert reduction.verdict.value == expected_verdict(28.5, reduction.ours, 0.05) == "different"
    # the note gives what the run shows: both deviations against the thesis' and the fold
    for shown in ("57%", "53%", "-197.3 deg", "17.3 deg", "open"):
        assert shown in reduction.note
    # a reduction within 0.05 % of the printed 28.5 % is exact, within 2.85 % close
    for partial, verdict in ((5.477, "exact"), (5.6, "close"), (5.8, "different")):
        deviation = {"partial_reactionless": partial, "baseline": 7.66}
        rows = {c.key: c for c in chapter4_deployment.partial_comparisons(deviation, -180.0)}
        assert rows["reduction_percent"].verdict.value == verdict


def _plan_run(deviation: np.ndarray) -> SimpleNamespace:
    """A 3-phase run (phases 0-5, 5-25, 25-30 s) with the base deviation ``deviation`` [rad]
    sampled every second: the parts phase_two_only reads."""
    phases = tuple(
        SimpleNamespace(name=name, start=start, end=end)
        for name, start, end in (("I", 0.0, 5.0), ("II", 5.0, 25.0), ("III", 25.0, 30.0))
    )
    return SimpleNamespace(
        t=np.arange(31.0),
        base_deviation=deviation,
        max_base_deviation_deg=math.degrees(float(deviation.max())),
        plan=SimpleNamespace(phases=phases),
    )


def test_base_still_outside_phase_two_is_by_construction_and_fails_when_it_moves():
    t = np.arange(31.0)
    deviation = np.deg2rad(np.clip((t - 5.0) / 20.0, 0.0, 1.0) * 1.95)
    row = chapter4_ptp.phase_two_only(_plan_run(deviation))
    assert row.verdict.value == "by construction"
    assert "null vector" in row.note
    moved = deviation.copy()
    moved[2] = math.radians(0.1)  # the base turns in Phase I: the reactionless phase is broken
    row = chapter4_ptp.phase_two_only(_plan_run(moved))
    assert row.verdict.value == "not reproduced"
    assert "FAILS" in row.note


def test_deployment_base_row_fails_when_the_base_turns(monkeypatch):
    monkeypatch.setattr(chapter4_deployment, "relative_reactionless_coupling", lambda *_: 1e-15)
    run = SimpleNamespace(max_base_deviation_deg=1.0e-6, plan=None)
    row = chapter4_deployment._deployment_row(run, quick=True)
    assert row.verdict.value == "by construction"
    run = SimpleNamespace(max_base_deviation_deg=0.05, plan=None)
    row = chapter4_deployment._deployment_row(run, quick=True)
    assert row.verdict.value == "not reproduced"
    assert "FAILS" in row.note


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
    # "about two times smaller": one row, each baseline's ratio against 2 within 0.2
    row = table["deviation_ratio_baselines_over_3_phase"]
    assert row["thesis"] == [2.0, 2.0, 2.0]
    assert row["ours"] == pytest.approx(
        [ratio[name] for name in ("JS-C", "IJ-C", "TJ-C")], abs=1e-3
    )
    element = [expected_verdict(2.0, value, 0.2) for value in row["ours"]]
    assert row["verdict"] == ("exact" if set(element) == {"exact"} else "different")
    assert document["thesis_ratio"] == chapter4_ptp.THESIS_RATIO
    assert document["least_method"] == "3-phase"
    assert len(table) == len(METHODS) + 2  # the deviations, the ratio row, the target
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
    # the plan is built from the null vector: by construction, checked on the plan
    assert table["coupling_only_in_phase_II"]["verdict"] == "by construction"
    assert "null vector" in table["coupling_only_in_phase_II"]["note"]
    assert table["phase_durations_s"]["verdict"] == "input"


@pytest.mark.slow
def test_fig_4_12_deviation_only_in_phase_two(documents):
    document, _ = documents["fig4.12"]
    table = comparison_rows(document)
    row = table["deviation_only_in_phase_II_deg"]
    outside = max(row["ours"].values())
    assert outside < 1e-3 * document["max_base_deviation_deg"]["3-phase"]
    assert row["verdict"] == "by construction"
    # the peaks are Table 4.2's numbers: values here, compared in table4.2 only
    assert list(table) == ["deviation_only_in_phase_II_deg"]
    assert set(document["max_base_deviation_deg"]) == METHODS
    assert any("table4.2 compares them" in choice for choice in document["choices"])


@pytest.mark.slow
def test_deployments(documents):
    full, _ = documents["fig4.13"]
    assert full["max_base_deviation_deg"] < 1e-3
    table = comparison_rows(full)
    assert table["max_base_deviation_deg"]["verdict"] == "by construction"
    # theta_4 = 134.55 deg is where the plan ends the fold: an input
    assert table["theta4_final_deg"]["verdict"] == "input"
    assert table["theta4_final_deg"]["ours"] == pytest.approx(134.55, abs=0.01)
    partial, _ = documents["sec4.5.2"]
    deviation = partial["max_base_deviation_deg"]
    assert set(deviation) == {"partial_reactionless", "baseline"}
    assert partial["reduction_percent"] == pytest.approx(
        100.0 * (1.0 - deviation["partial_reactionless"] / deviation["baseline"]), rel=1e-4
    )
    assert partial["reduction_percent"] > 0.0
    assert partial["final_error_deg"] < 0.1
    rows = comparison_rows(partial)
    reduction = rows["reduction_percent"]
    assert reduction["verdict"] == expected_verdict(28.5, reduction["ours"], 0.05)
    for name, printed in chapter4_ptp.THESIS_PARTIAL.items():
        row = rows[f"max_base_deviation_{name}_deg"]
        assert row["verdict"] == expected_verdict(printed, row["ours"], 5e-3)
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
    # the plan joins two folds in Phase II: by construction, still checked on the run
    assert table["folded_in_phase_II_m"]["verdict"] == _by_construction(holds)
    assert "-180.0 -> -145.4 deg" in table["folded_in_phase_II_m"]["note"]
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
    assert table["folded_in_phase_II_m"]["verdict"] == "by construction"
    assert table["base_moves_only_in_phase_II_deg"]["verdict"] == "by construction"
    # no number row repeats sec4.5.2's deviations
    assert not any(key.startswith("max_base_deviation") for key in table)
    baseline, _ = documents["fig4.15"]
    rows = comparison_rows(baseline)
    late, peak = baseline["late_deviation_change_deg"], baseline["max_base_deviation_deg"]
    assert peak == pytest.approx(documents["sec4.5.2"][0]["max_base_deviation_deg"])
    moving = late["baseline"] > 1e-3 * peak["baseline"]
    assert rows["base_moves_throughout_deg"]["verdict"] == _trend(moving)
    reach = baseline["mean_reach_phase_II_m"]
    extended = reach["baseline"] > reach["partial_reactionless"]
    assert rows["extended_while_turning_m"]["verdict"] == _by_construction(extended)


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
    folds = (-180.0, -145.4)
    row = ptp_snapshots.folded_row(times, reach, Phase, ends, folds)
    assert row.verdict.value == "by construction"
    reach[15] = 1.5  # an extended arm in the middle of Phase II: the plan is not what it claims
    row = ptp_snapshots.folded_row(times, reach, Phase, ends, folds)
    assert row.verdict.value == "not reproduced"
    assert "FAILS" in row.note

    partial, baseline = "partial_reactionless", "baseline"
    late = {partial: 2e-6, baseline: 0.441}
    peak = {partial: 3.105, baseline: 4.065}
    reach = {partial: 0.609, baseline: 1.282}
    share = chapter4_ptp.REACTIONLESS_SHARE
    rows = ptp_snapshots.baseline_rows(late, peak, reach, share)
    assert [row.verdict.value for row in rows] == ["qualitative", "by construction"]
    late, reach = {**late, baseline: 1e-6}, {**reach, baseline: 0.5}
    rows = ptp_snapshots.baseline_rows(late, peak, reach, share)
    assert [row.verdict.value for row in rows] == ["not reproduced", "not reproduced"]


def _trend(holds: bool) -> str:
    """The verdict of a trend, written out independently of the registry."""
    return "qualitative" if holds else "not reproduced"


def _by_construction(holds: bool) -> str:
    """The verdict of an identity, written out independently of the registry."""
    return "by construction" if holds else "not reproduced"
