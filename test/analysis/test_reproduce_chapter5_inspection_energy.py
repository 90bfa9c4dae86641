"""Chapter 5 inspection-energy reproductions (Figs. 5.4-5.5): quick runs give finite JSON with the
documented keys and a PNG."""

from __future__ import annotations

import pytest
from rns_testing import assert_chapter_order, quick_documents, quick_result_statuses

from rns_ros.analysis.reproduce import chapter5_inspection_energy as ch5
from rns_ros.analysis.reproduce.registry import Status

# whole energy reproductions (quick grids): make test, not test-quick
pytestmark = pytest.mark.slow

IDS = ("fig5.4", "fig5.5")
RUNS = {ch5.REACTIONLESS, ch5.CONVENTIONAL}


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    """{id: (json document, png path)}; condition 1 is shared through the cache."""
    return quick_documents(IDS, tmp_path_factory.mktemp("chapter5_inspection_energy"))


def test_the_module_comes_after_the_other_chapters_and_registers_both_results():
    earlier = ("chapter3", "chapter4", "chapter4_ptp", "chapter5")
    assert_chapter_order("chapter5_inspection_energy", earlier, IDS)


@pytest.mark.parametrize("identifier", IDS)
def test_each_result_writes_finite_json_and_a_png(documents, identifier):
    document, png = documents[identifier]
    assert quick_result_statuses(document, png, identifier)
    settings = document["settings"]
    assert settings["controller_rate_hz"] == ch5.QUICK_RATE
    assert settings["simulation_step_s"] == ch5.QUICK_STEP
    assert settings["condition_seed"] == 5
    assert len(document["choices"]) >= 8


def test_fig5_4_keys(documents):
    document = documents["fig5.4"][0]
    assert set(document["peak_energy_J"]) == RUNS
    for parts in document["peak_energy_J"].values():
        assert set(parts) == {"arm", "wheels", "total"}
    assert set(document["c_max_J"]) == RUNS
    assert set(document["c_sum_Js"]) == RUNS
    ratio = document["energy_ratio"]
    assert set(ratio) == {"c_max", "c_sum"}
    assert ratio["c_max"] == pytest.approx(
        document["c_max_J"][ch5.CONVENTIONAL] / document["c_max_J"][ch5.REACTIONLESS]
    )
    torque = document["wheel_torque"]
    assert torque["limit_Nm"] == 0.1
    assert torque["peak_Nm"] > 0.0
    assert torque["time_above_limit_s"] >= 0.0
    keys = {c["key"] for c in document["comparisons"]}
    assert {"energy_ratio", "peak_wheel_torque_Nm", "wheel_over_arm_peak_energy"} <= keys
    energy_row = next(c for c in document["comparisons"] if c["key"] == "energy_ratio")
    assert energy_row["thesis"] == 1000.0
    assert energy_row["status"] != Status.EXACT.value  # never asserted as the thesis value


def test_fig5_5_keys(documents):
    document = documents["fig5.5"][0]
    rows = document["conditions"]
    assert len(rows) == ch5.QUICK_CONDITIONS
    assert rows[0]["label"] == "condition 1"
    assert rows[0]["initial_joint_positions_deg"] == pytest.approx([-90, -30, 0, -70, 180, -30, 0])
    for row in rows:
        assert set(row["c_max_J"]) == RUNS
        assert set(row["c_sum_Js"]) == RUNS
        assert set(row["energy_ratio"]) == {"c_max", "c_sum"}
        assert row["sigma_min_start"] >= 0.1
        assert document["energy_ratio"][row["label"]] == row["energy_ratio"]
    mean = document["energy_ratio_geometric_mean"]
    assert set(mean) == {"c_max", "c_sum"}
    assert all(v > 0.0 for v in mean.values())
    assert "conditions" in document["energy_ratio_geometric_mean_completed"]
    # condition 1 is the same run in both results
    fig5_4 = documents["fig5.4"][0]
    assert rows[0]["energy_ratio"] == pytest.approx(fig5_4["energy_ratio"])
    assert all(c["status"] != Status.EXACT.value for c in document["comparisons"])
