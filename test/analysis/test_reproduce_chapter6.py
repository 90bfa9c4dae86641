"""Chapter 6 reproductions (Figs. 6.3, 6.4, 6.7, 6.8): quick runs give finite JSON with the
documented keys and a PNG."""

from __future__ import annotations

import pytest
from rns_testing import assert_chapter_order, quick_documents, quick_result_verdicts

from rns_ros.analysis.reproduce import chapter6 as ch6

# whole motion/force reproductions (quick runs): make test, not test-quick
pytestmark = pytest.mark.slow

IDS = ("fig6.3", "fig6.4", "fig6.7", "fig6.8")
CONTROLLERS = {"RNS-C", "OS-C", "OS-C-kinematic"}
KEYS = ("peak_joint_speed_rad_s", "max_position_error_m", "max_force_error_N")


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    """{id: (json document, png path)}; fig6.3/6.4 and fig6.7/6.8 share their cached runs."""
    return quick_documents(IDS, tmp_path_factory.mktemp("chapter6"))


def test_the_module_comes_after_chapter5_and_registers_four_results():
    earlier = ("chapter3", "chapter4", "chapter4_ptp", "chapter5", "chapter5_inspection_energy")
    assert_chapter_order("chapter6", earlier, IDS)


@pytest.mark.parametrize("identifier", IDS)
def test_each_result_writes_finite_json_with_the_documented_keys(documents, identifier):
    document, png = documents[identifier]
    verdicts = quick_result_verdicts(document, png, identifier)
    for key in KEYS:
        assert set(document[key]) == CONTROLLERS
        assert all(value >= 0.0 for value in document[key].values())
    assert set(document["peak_ratio_to_rns_c"]) == {"OS-C", "OS-C-kinematic"}
    assert set(document["runs"]) == CONTROLLERS
    assert verdicts
    settings = document["settings"]
    assert settings["control_period_s"] == ch6.QUICK_PERIOD
    assert settings["k_p_1_s2"] == 100.0
    assert settings["k_d_1_s"] == 10.0
    assert settings["k_f"] == 5.0
    assert settings["virtual_mass_kg"] == 1e5
    assert settings["gravity"] is False
    assert len(document["choices"]) >= 8
    assert any("Quick run" in choice for choice in document["choices"])


def _trend(holds: bool) -> str:
    return "qualitative" if holds else "not reproduced"


def test_fig6_4_reports_the_thesis_peaks_and_the_tuning(documents):
    document = documents["fig6.4"][0]
    rows = {c["key"]: c for c in document["comparisons"]}
    rns = rows["peak_joint_speed_rns_c_rad_s"]
    assert rns["thesis"] == 0.73
    assert "TUNED" in rns["note"]
    assert rns["verdict"] == "input"  # T_half was fitted to it
    assert rns["ours"] == pytest.approx(0.73, rel=0.1)
    peaks = document["peak_joint_speed_rad_s"]
    # the OS-C peak alone is the same claim as the ratio (RNS-C's is fitted): values, not rows
    assert "peak_joint_speed_os_c_rad_s" not in rows
    for controller in ("OS-C", "OS-C-kinematic"):
        text = document["osc_peak_causes"][controller]
        assert f"{peaks[controller]:.3g} rad/s against the thesis' 4.22" in text
        # both OS-C readings peak more than 10 % below the thesis' 4.22 rad/s on our arc, and
        # the cause comes from the ratio sweep: every factor's ratio is named
        assert peaks[controller] < 0.9 * 4.22
        assert "ratio sweep" in text
        for label, entry in document["ratio_sweep"].items():
            assert label == "baseline" or f"{label}: {entry['ratio'][controller]:.3g}" in text
    sweep = document["ratio_sweep"]
    assert sweep["baseline"]["peak_rad_s"] == peaks
    # the gravity-free closed loops are time-scale invariant: T_half leaves the ratio
    timing = sweep["T_half = 1 s"]["ratio"]
    for variant, ratio in sweep["baseline"]["ratio"].items():
        assert timing[variant] == pytest.approx(ratio, rel=0.01)
    # the printed 4.22 vs 0.73 rad/s is judged as the number 5.78, the literal OS-C's ratio
    ratio = rows["peak_ratio_osc_over_rns_c"]
    assert ratio["thesis"] == pytest.approx(5.78, abs=0.005)
    assert ratio["ours"] == document["peak_ratio_to_rns_c"]["OS-C"]
    assert ratio["verdict"] == "different"
    assert "exact within 0.05" in ratio["note"]
    assert document["scenario"]["start_point_m"] == pytest.approx([1.203, 1.91])
    assert document["scenario"]["half_cycle_s"] == document["settings"]["half_cycle_s"] == 1.6


def test_fig6_8_verdict_follows_from_the_peaks(documents):
    document = documents["fig6.8"][0]
    (row,) = document["comparisons"]
    ratios = document["peak_ratio_to_rns_c"]
    assert row["key"] == "peak_ratio_osc_over_rns_c"
    assert row["ours"] == ratios
    assert all(ratio > 1.0 for ratio in ratios.values())  # OS-C still peaks higher
    holds = min(ratios.values()) > ch6.RATIO_THRESHOLD
    assert row["verdict"] == _trend(holds)
    assert holds or "open" in row["note"]


def test_task_error_results_share_the_runs_of_the_velocity_results(documents):
    for task, velocity in (("fig6.3", "fig6.4"), ("fig6.7", "fig6.8")):
        a, b = documents[task][0], documents[velocity][0]
        for key in KEYS:
            assert a[key] == b[key]
        rows = {c["key"]: c for c in a["comparisons"]}
        position = a["max_position_error_m"]
        spread = max(position.values()) / min(position.values())
        assert rows["task_position_error_spread"]["ours"] == pytest.approx(spread)
        assert rows["task_position_error_spread"]["verdict"] == _trend(spread <= 2.0)
        # the same-instant force loop makes the force error round-off for every controller
        force = rows["task_force_error_N"]
        assert force["verdict"] == "by construction"
        assert force["ours"] == max(a["max_force_error_N"].values()) < 1e-3
        if task == "fig6.3":  # under the payload the force errors are no longer round-off
            payload = a["payload"]["max_force_error_N"]
            spread = rows["task_force_error_spread_payload"]
            assert min(payload.values()) > 0.1
            assert spread["ours"] == pytest.approx(max(payload.values()) / min(payload.values()))
            assert spread["verdict"] == _trend(spread["ours"] <= 2.0)
            assert spread["extension"] is True  # the thesis never ran a payload
        final = rows["final_contact_force_N"]
        assert final["verdict"] == "input"
        assert all(value == pytest.approx(10.0, abs=1e-3) for value in final["ours"].values())
    orientation = {c["key"]: c for c in documents["fig6.7"][0]["comparisons"]}[
        "max_orientation_error_rad"
    ]
    assert set(orientation["ours"]) == CONTROLLERS
    assert max(orientation["ours"].values()) < ch6.ORIENTATION_HELD
    assert orientation["verdict"] == "input"  # the commanded task, not a result
    assert set(documents["fig6.7"][0]["max_orientation_error_rad"]) == CONTROLLERS


@pytest.mark.parametrize(
    ("ratio", "verdict"),
    [(5.78, "exact"), (5.3, "close"), (1.84, "different")],
)
def test_the_planar_contrast_is_judged_as_the_number_5_78(ratio, verdict):
    row = ch6._planar_ratio_row({"OS-C": ratio, "OS-C-kinematic": 4.6}, {"OS-C": "cause"})
    assert row.verdict.value == verdict
    assert "4.6" in row.note


@pytest.mark.parametrize(("worst", "verdict"), [(3e-6, "by construction"), (0.2, "not reproduced")])
def test_the_same_instant_force_loop_is_exact_by_construction(worst, verdict):
    assert ch6._force_error_row({"RNS-C": worst, "OS-C": 1e-9}).verdict.value == verdict
