"""Chapter 7 reproductions (Figs. 7.1, 7.3, 7.4): quick runs give finite JSON with the documented
keys and a PNG."""

from __future__ import annotations

import numpy as np
import pytest
from rns_testing import assert_chapter_order, quick_documents, quick_result_verdicts

from rns_ros.analysis.reproduce import chapter7 as ch7

# whole chapter-7 reproductions (quick runs): make test, not test-quick
pytestmark = pytest.mark.slow

IDS = ("fig7.1", "fig7.3", "fig7.4")
RUN_KEYS = {
    "peak_joint_speed_rad_s",
    "peak_joint_speed_per_joint_rad_s",
    "max_null_space_rns_rad_s",
    "final_null_space_rns_rad_s",
    "max_null_space_jacobian_rad_s",
    "final_null_space_jacobian_rad_s",
    "max_radial_error_m",
    "max_tracking_error_m",
}


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    return quick_documents(IDS, tmp_path_factory.mktemp("chapter7"))


def test_the_module_comes_after_the_other_chapters_and_registers_both_results():
    earlier = (
        "chapter3",
        "chapter4",
        "chapter4_ptp",
        "chapter5",
        "chapter5_inspection_energy",
        "chapter6",
    )
    assert_chapter_order("chapter7", earlier, IDS)


@pytest.mark.parametrize("identifier", IDS)
def test_each_result_writes_finite_json_and_a_png(documents, identifier):
    document, png = documents[identifier]
    verdicts = quick_result_verdicts(document, png, identifier)
    # the thesis prints no numbers here: trends, the damper gain as an input and its RK4 limit
    # by construction
    assert verdicts <= {"qualitative", "not reproduced", "input", "by construction"}
    settings = document["settings"]
    assert settings["step_s"] == ch7.QUICK_STEP
    assert settings["half_period_s"] == ch7.QUICK_HALF_PERIOD
    assert settings["half_cycles"] == 1
    assert settings["arc_radius_m"] == 0.707
    assert len(document["choices"]) >= 7


def test_fig7_1_and_fig7_3_keys(documents):
    """One set of runs, each figure with its own rows (Fig. 7.1: velocities; Fig. 7.3: RMS)."""
    fig7_1, fig7_3 = documents["fig7.1"][0], documents["fig7.3"][0]
    masses = [f"{m:g}" for m in ch7.QUICK_SWEEP_MASSES]
    assert set(fig7_1["runs"]) == set(masses) | {f"{m:g}" for m in ch7.QUICK_FIGURE_MASSES}
    for values in fig7_1["runs"].values():
        assert set(values) >= RUN_KEYS
        assert values["rms_vs_resolved_rad"] > 0.0
        assert values["max_radial_error_m"] < 1e-6
    for document in (fig7_1, fig7_3):
        assert set(document["resolved"]) >= RUN_KEYS
    assert set(fig7_1["spec_v_table"]) == {"10", "100", "1000", "10000", "100000"}
    rms = fig7_3["rms_vs_mass"]
    assert "rms_vs_mass" not in fig7_1
    assert rms["masses_kg"] == list(ch7.QUICK_SWEEP_MASSES)
    assert len(rms["rms_rad"]) == len(masses)
    assert rms["log_slope"] == pytest.approx(-1.0, abs=0.1)
    velocity = {c["key"]: c for c in fig7_1["comparisons"]}
    keys = {c["key"]: c for c in fig7_3["comparisons"]}
    assert set(velocity) == {"max_null_space_velocity_rad_s"}
    assert set(keys) == {
        "rms_delta_theta_rad",
        "rms_log_slope",
        "rms_delta_theta_free_floating_rad",
    }
    # both fall with the mass in the quick run, and the verdicts say so
    for row in (velocity["max_null_space_velocity_rad_s"], keys["rms_delta_theta_rad"]):
        assert np.all(np.diff(row["ours"]) < 0.0)
        assert row["verdict"] == "qualitative"
    assert keys["rms_delta_theta_rad"]["ours"] == rms["rms_rad"]
    assert keys["rms_log_slope"]["ours"] == rms["log_slope"]
    assert keys["rms_log_slope"]["verdict"] == "qualitative"
    # the literal reading (b) is the same claim again: reported apart, counted once
    assert keys["rms_delta_theta_free_floating_rad"]["extension"] is True


def test_fig7_4_keys(documents):
    document = documents["fig7.4"][0]
    labels = {ch7.VELOCITY, ch7.DAMPER, ch7.MOMENTUM}
    assert set(document["runs"]) == labels
    for values in document["runs"].values():
        assert set(values) >= RUN_KEYS
    assert set(document["peak_null_space_rns_rad_s"]) == labels
    assert set(document["final_null_space_rns_rad_s"]) == labels
    assert document["damper_gain_1_s"] == pytest.approx(2.77 / ch7.QUICK_STEP)
    ratio = document["damper_over_velocity_level"]
    assert ratio["peak"] > ch7.ORDER_RATIO
    assert document["unstable_damper_check"]["diverged"] is True
    rows = {c["key"]: c for c in document["comparisons"]}
    assert rows["peak_null_space_velocity_damper_over_velocity_level"]["ours"] == ratio["peak"]
    assert rows["peak_null_space_velocity_damper_over_velocity_level"]["verdict"] == "qualitative"
    # the integrator was inferred from the thesis' 2770: its limit agrees by construction
    assert rows["damper_rk4_limit"]["verdict"] == "by construction"
    peaks = document["peak_null_space_rns_rad_s"]
    momentum = rows["peak_null_space_velocity_damper_over_momentum_form"]
    assert momentum["ours"] == pytest.approx(peaks[ch7.DAMPER] / peaks[ch7.MOMENTUM])
    holds = momentum["ours"] >= ch7.ORDER_RATIO
    assert momentum["verdict"] == ("qualitative" if holds else "not reproduced")
    assert holds or "zero momentum (7.9)" in momentum["note"]
    gain = rows["damper_gain_1_s"]
    assert gain["thesis"] == 2770.0
    assert gain["verdict"] == "input"
    assert gain["ours"] == pytest.approx(2.77 / ch7.QUICK_STEP)


def test_fig7_3_free_floating_variant_tends_to_the_closed_form(documents):
    """A-4.15 variant (b), (7.4) without F_B: it leaves the arc (the closed form does not), by
    less as m_hat grows, and its verdict follows from its own series."""
    document = documents["fig7.3"][0]
    free = document["rms_vs_mass_free_floating"]
    closed = document["rms_vs_mass"]
    assert free["masses_kg"] == closed["masses_kg"]
    assert free["over_closed_form"] == pytest.approx(
        np.array(free["rms_rad"]) / np.array(closed["rms_rad"])
    )
    tracking = np.array(free["max_tracking_error_m"])
    assert np.all(tracking > 1e3 * free["closed_form_tracking_error_m"])
    assert np.all(np.diff(tracking) < 0.0)
    assert np.all(np.diff(free["rms_vs_closed_form_rad"]) < 0.0)
    row = {c["key"]: c for c in document["comparisons"]}["rms_delta_theta_free_floating_rad"]
    assert row["ours"] == free["rms_rad"]
    falling = bool(np.all(np.diff(free["rms_rad"]) < 0.0))
    assert row["verdict"] == ("qualitative" if falling else "not reproduced")


def test_free_floating_row_fails_on_a_series_that_does_not_fall():
    free = {
        "rms_rad": [1e-2, 2e-2, 1e-3],
        "log_slope": 0.0,
        "over_closed_form": [1.0, 1.0, 1.0],
        "rms_vs_closed_form_rad": [0.0, 0.0, 0.0],
        "max_tracking_error_m": [0.0, 0.0, 0.0],
        "closed_form_tracking_error_m": 0.0,
    }
    row = ch7._free_floating_row([1e1, 1e3, 1e5], [1.0, 1e-2, 1e-4], free)
    assert row.verdict.value == "not reproduced"


def test_the_rk4_limit_fails_loudly_when_the_unstable_run_stays_finite():
    divergence = {"k_d_step": ch7.UNSTABLE_DAMPER_STEP, "diverged": False, "message": ""}
    assert ch7._rk4_limit_row(divergence).verdict.value == "not reproduced"
    divergence = {"k_d_step": ch7.UNSTABLE_DAMPER_STEP, "diverged": True, "message": "nan"}
    assert ch7._rk4_limit_row(divergence).verdict.value == "by construction"
