"""Chapter 6 reproductions (Figs. 6.3, 6.4, 6.7, 6.8): quick runs give finite JSON with the
documented keys and a PNG."""

from __future__ import annotations

import pytest
from rns_testing import assert_chapter_order, quick_documents, quick_result_statuses

from rns_ros.analysis.reproduce import chapter6 as ch6
from rns_ros.analysis.reproduce.registry import Status

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
    statuses = quick_result_statuses(document, png, identifier)
    for key in KEYS:
        assert set(document[key]) == CONTROLLERS
        assert all(value >= 0.0 for value in document[key].values())
    assert set(document["peak_ratio_to_rns_c"]) == {"OS-C", "OS-C-kinematic"}
    assert set(document["runs"]) == CONTROLLERS
    assert statuses
    assert Status.EXACT.value not in statuses  # nothing here is an exact reproduction
    settings = document["settings"]
    assert settings["control_period_s"] == ch6.QUICK_PERIOD
    assert settings["k_p_1_s2"] == 100.0
    assert settings["k_d_1_s"] == 10.0
    assert settings["k_f"] == 5.0
    assert settings["virtual_mass_kg"] == 1e5
    assert settings["gravity"] is False
    assert len(document["choices"]) >= 8
    assert any("Quick run" in choice for choice in document["choices"])


def test_fig6_4_reports_the_thesis_peaks_and_the_tuning(documents):
    document = documents["fig6.4"][0]
    rows = {c["key"]: c for c in document["comparisons"]}
    rns = rows["peak_joint_speed_rns_c_rad_s"]
    assert rns["thesis"] == 0.73
    assert "TUNED" in rns["note"]
    assert rns["ours"] == pytest.approx(0.73, rel=0.1)
    assert rows["peak_joint_speed_os_c_rad_s"]["thesis"] == 4.22
    assert rows["peak_ratio_osc_over_rns_c"]["thesis"] == pytest.approx(5.78)
    assert set(rows["peak_ratio_osc_over_rns_c"]["ours"]) == {"OS-C", "OS-C-kinematic"}
    # the thesis claim holds in the quick run: both OS-C variants peak > 1.5x RNS-C
    assert rows["peak_ratio_osc_over_rns_c"]["status"] == Status.QUALITATIVE.value
    assert document["scenario"]["start_point_m"] == pytest.approx([1.203, 1.91])
    assert document["scenario"]["half_cycle_s"] == document["settings"]["half_cycle_s"] == 1.6


def test_task_error_results_share_the_runs_of_the_velocity_results(documents):
    for task, velocity in (("fig6.3", "fig6.4"), ("fig6.7", "fig6.8")):
        a, b = documents[task][0], documents[velocity][0]
        for key in KEYS:
            assert a[key] == b[key]
        rows = {c["key"] for c in a["comparisons"]}
        assert {"task_position_error_spread", "task_force_error_spread"} <= rows
        final = next(c for c in a["comparisons"] if c["key"] == "final_contact_force_N")
        assert all(value == pytest.approx(10.0, abs=1e-3) for value in final["ours"].values())
    assert set(documents["fig6.7"][0]["max_orientation_error_rad"]) == CONTROLLERS
