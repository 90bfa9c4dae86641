"""Chapter 5 inspection-energy reproductions (Figs. 5.4-5.5): quick runs give finite JSON with the
documented keys and a PNG."""

from __future__ import annotations

import numpy as np
import pytest
from rns_testing import assert_chapter_order, quick_documents, quick_result_verdicts

from rns_ros.analysis.reproduce import chapter5_inspection_energy as ch5

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
    assert quick_result_verdicts(document, png, identifier)
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
    # the same condition on resized arms: the wheel part (5.11) grows with the arm's lengths
    sensitivity = document["arm_length_sensitivity"]
    assert set(sensitivity) == {"0.9", "1.1"}
    assert sensitivity["0.9"][1] < ratio["c_sum"] < sensitivity["1.1"][1]


def _ratio_verdict(ours: list[float]) -> str:
    """The verdict of a [C_max, C_sum] ratio against the thesis' 10^3 printed to one significant
    figure (exact within 500, close within 10 %)."""
    distance = np.abs(np.asarray(ours) - 1000.0)
    if distance.max() <= 500.0:
        return "exact"
    return "close" if np.linalg.norm(distance) <= 0.1 * np.hypot(1000.0, 1000.0) else "different"


def test_fig5_4_verdicts_follow_from_the_numbers(documents):
    document = documents["fig5.4"][0]
    rows = {c["key"]: c for c in document["comparisons"]}
    energy = rows["energy_ratio"]
    ratio = document["energy_ratio"]
    assert energy["thesis"] == [1000.0, 1000.0]
    assert energy["ours"] == [ratio["c_max"], ratio["c_sum"]]
    # our arm's wheel part makes the ratio an order above the thesis' 10^3
    assert min(energy["ours"]) > 1500.0
    assert energy["verdict"] == _ratio_verdict(energy["ours"]) == "different"
    assert "open" in energy["note"]
    wheels = rows["wheel_over_arm_peak_energy"]
    assert wheels["ours"] > ch5.ORDER_OF_MAGNITUDE
    assert wheels["verdict"] == "qualitative"
    torque = rows["peak_wheel_torque_Nm"]
    assert torque["ours"] == document["wheel_torque"]["peak_Nm"] > 0.1
    assert torque["verdict"] == "qualitative"
    residual = rows["reactionless_wheel_over_arm_energy"]
    assert residual["verdict"] == "input"  # zero by construction of eq. (4.5)
    assert 0.0 <= residual["ours"] < 1e-6


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


def test_fig5_5_verdicts_follow_from_the_numbers(documents):
    document = documents["fig5.5"][0]
    conditions = document["conditions"]
    rows = {c["key"]: c for c in document["comparisons"]}
    for condition in conditions:
        row = rows[f"energy_ratio_{condition['label'].replace(' ', '_')}"]
        ratio = condition["energy_ratio"]
        assert row["thesis"] == [1000.0, 1000.0]
        assert row["ours"] == [ratio["c_max"], ratio["c_sum"]]
        assert row["verdict"] == _ratio_verdict(row["ours"])
    mean = document["energy_ratio_geometric_mean"]
    mean_row = rows["energy_ratio_geometric_mean"]
    assert mean_row["ours"] == [mean["c_max"], mean["c_sum"]]
    assert mean_row["verdict"] == _ratio_verdict(mean_row["ours"])
    cheaper = rows["reactionless_cheaper_in_every_condition"]
    smallest = min(min(condition["energy_ratio"].values()) for condition in conditions)
    assert cheaper["ours"] == smallest > 1.0  # reactionless is cheaper in every condition
    assert cheaper["verdict"] == ("qualitative" if smallest >= 10.0 else "not reproduced")
