"""Chapter 4 reproductions (Figs. 4.4-4.8): each id runs quick into JSON + PNG, the physics holds,
and every verdict follows from the numbers next to it."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from rns_testing import quick_documents, quick_result_verdicts

from rns_ros.analysis.reproduce import (
    chapter4,
    chapter4_singularity,  # noqa: F401  (registers figs. 4.6-4.8)
    scenario_runs,
    trace_windows,
)
from rns_ros.analysis.reproduce.registry import Verdict, number_verdict, trend_verdict

# whole closed-loop reproductions (quick grids): make test, not test-quick
slow = pytest.mark.slow

IDS = ("fig4.4", "fig4.5", "fig4.6", "fig4.7", "fig4.8")
METHODS = {
    "fig4.4": {"dls", "dls_kg0", "conventional"},
    "fig4.5": {"dls", "dls_kg0", "conventional"},
    "fig4.6": {"pinv", "pinv_urdf_limits"},
    "fig4.7": {"dls", "pinv"},
    "fig4.8": {"sc", "dls", "pinv"},
}


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    """{id: (json document, png path)}; the singularity runs are shared through the cache."""
    return quick_documents(IDS, tmp_path_factory.mktemp("chapter4"))


def rows_of(documents, identifier: str) -> dict[str, dict]:
    return {c["key"]: c for c in documents[identifier][0]["comparisons"]}


# --------------------------------------------------------------------------- helpers


def test_runs_of_and_first_pass_find_the_first_interval_below_epsilon():
    sigma = np.array([0.5, 0.1, 0.05, 0.3, 0.1, 0.4])
    assert trace_windows.runs_of(sigma < 0.2) == [(1, 3), (4, 5)]
    trace = SimpleNamespace(sigma_min=sigma, t_mid=np.arange(6.0))
    assert trace_windows.first_pass(trace, 0.2) == slice(1, 3)
    # never inside: the whole run
    assert trace_windows.first_pass(trace, 0.01) == slice(0, 6)
    assert trace_windows.intervals(trace.t_mid, sigma < 0.2) == [[1.0, 2.0], [4.0, 4.0]]


def test_peak_names_the_two_fastest_joints_of_the_peak_period():
    theta_dot = np.zeros((4, 7))
    theta_dot[1, [4, 6]] = [2.0, -1.5]
    theta_dot[3, 0] = 5.0  # outside the window
    trace = SimpleNamespace(
        theta_dot=theta_dot, t_mid=np.arange(4.0), sigma_min=np.array([0.5, 0.1, 0.2, 0.9])
    )
    peak = trace_windows.peak(trace, slice(0, 3))
    assert peak["peak_rad_s"] == 2.0
    assert peak["fastest_joints"] == [5, 7]
    assert peak["their_rates_rad_s"] == [2.0, -1.5]
    assert peak["window_s"] == [0.0, 2.0]
    assert trace_windows.peak(trace, slice(0, 4))["peak_rad_s"] == 5.0


def test_task_bound_is_the_inverse_norm_bound():
    # |omega| s / sigma_min: 0.2 rad/s through an inverse of norm 2 / 0.5
    trace = SimpleNamespace(
        omega_ref=np.array([[0.0, -0.2, 0.0]]),
        speed_scale=np.array([2.0]),
        sigma_min=np.array([0.5]),
    )
    assert trace_windows.task_bound(trace, 0) == pytest.approx(0.8)


# --------------------------------------------------------------------------- quick runs


@slow
@pytest.mark.parametrize("identifier", IDS)
def test_each_result_writes_json_and_png(documents, identifier):
    document, png = documents[identifier]
    verdicts = quick_result_verdicts(document, png, identifier)
    assert verdicts - {Verdict.INPUT.value}
    assert set(document["max_base_deviation_deg"]) == METHODS[identifier]
    assert all(value >= 0.0 for value in document["max_base_deviation_deg"].values())
    assert all(0.0 < s <= 1.0 for s in document["min_joint_limit_scale"].values())
    settings = document["settings"]
    assert settings["controller_rate_hz"] == scenario_runs.QUICK_RATE
    assert settings["simulation_step_s"] == scenario_runs.QUICK_STEP
    assert settings["simulation_mode"] == "kinematic"
    assert settings["hold_correction"] == "midpoint"
    assert len(document["choices"]) >= 5


@slow
@pytest.mark.parametrize("identifier", ["fig4.4", "fig4.5"])
def test_reactionless_leaves_the_base_where_conventional_turns_it(documents, identifier):
    deviation = documents[identifier][0]["max_base_deviation_deg"]
    for method, value in deviation.items():
        if method.startswith("dls"):
            assert value < 1e-3
            assert deviation["conventional"] > 1e3 * value
    assert deviation["conventional"] > chapter4.ETS_VII_ALLOWANCE_DEG


@slow
@pytest.mark.parametrize("identifier", ["fig4.4", "fig4.5"])
def test_inspection_verdicts_follow_the_numbers(documents, identifier):
    rows = rows_of(documents, identifier)
    for key in ("max_base_deviation_dls_deg", "max_base_deviation_dls_kg0_deg"):
        holds = rows[key]["ours"] < chapter4.UNDISTURBED_DEG
        assert rows[key]["verdict"] == trend_verdict(holds).value
    conventional = rows["max_base_deviation_conventional_deg"]
    holds = conventional["ours"] > chapter4.ETS_VII_ALLOWANCE_DEG
    assert conventional["verdict"] == trend_verdict(holds).value
    for method in ("dls", "conventional"):
        row = rows[f"final_camera_error_{method}_deg"]
        assert row["verdict"] == trend_verdict(row["ours"] < chapter4.REACHED_DEG).value
    document = documents[identifier][0]
    drift = document["max_wrist_drift_m"]
    holds = drift["dls"] < chapter4.WRIST_HELD_SHARE * drift["dls_kg0"]
    assert rows["max_wrist_drift_m"]["verdict"] == trend_verdict(holds).value
    assert f"{drift['dls_kg0']:.3f} m" in rows["max_wrist_drift_m"]["note"]
    if identifier == "fig4.5" and not holds:
        # the cause comes from the labelled lower-gain run: saturated only if it barely moves
        change = abs(drift["dls"] / drift["dls_kg10"] - 1.0)
        assert ("saturated" in rows["max_wrist_drift_m"]["note"]) == (
            change < chapter4.SATURATED_CHANGE
        )
    # one row per claim: the allowance ratio is a value, not a second verdict
    assert "conventional_over_ets_vii_allowance" not in rows
    assert document["conventional_over_ets_vii_allowance"] == pytest.approx(
        conventional["ours"] / chapter4.ETS_VII_ALLOWANCE_DEG
    )


@slow
@pytest.mark.parametrize("identifier", IDS)
def test_reproductions_run_without_joint_limits(documents, identifier):
    """The thesis scales nothing down: only the labelled URDF series is ever scaled."""
    document = documents[identifier][0]
    methods = document["settings"]["methods"]
    for label, scale in document["min_joint_limit_scale"].items():
        if label.endswith("_urdf_limits"):
            assert methods[label]["joint_limits"].startswith("URDF")
        else:
            assert scale == 1.0
            assert methods[label]["joint_limits"].startswith("none")
    assert any(c.startswith("Joint limits: none") for c in document["choices"])


@slow
def test_singularity_is_algorithmic_at_its_first_pass(documents):
    document = documents["fig4.6"][0]
    rows = rows_of(documents, "fig4.6")
    t = rows["singularity_time_s"]["ours"]
    low, high = chapter4.THESIS_SINGULAR_REGION_S
    assert rows["singularity_time_s"]["verdict"] == trend_verdict(low <= t <= high).value
    determinants = document["determinants_at_singularity"]
    assert determinants["algorithmic"] == rows["min_det_algorithmic"]["ours"]
    # the first pass is the one inside the thesis' region; the deepest one comes later
    assert low <= t <= high < document["deepest_pass_time_s"]
    assert rows["min_det_algorithmic"]["verdict"] == Verdict.QUALITATIVE.value
    assert rows["det_kinematic_at_singularity"]["verdict"] == Verdict.QUALITATIVE.value
    assert rows["fastest_joints_near_singularity"]["ours"].startswith("joints 5 and 7")


@slow
def test_fig4_6_peaks_and_suppression_follow_the_runs(documents):
    document = documents["fig4.6"][0]
    rows = rows_of(documents, "fig4.6")
    pinv = scenario_runs.recorded_run(chapter4.SINGULARITY, "pinv", True)
    dls = scenario_runs.recorded_run(chapter4.SINGULARITY, "dls", True)
    peak = float(np.abs(pinv.trace.theta_dot).max())
    assert document["pinv_peak_joint_speed_rad_s"] == pytest.approx(peak)
    assert document["pinv_peak_window"].startswith("whole run")
    assert len(document["pinv_peak_joints"]) == 2
    factor = peak / float(np.abs(dls.trace.theta_dot).max())
    assert document["dls_suppression_factor"] == pytest.approx(factor)
    # the verdicts of the two claims follow from these numbers
    fastest = rows["fastest_joints_near_singularity"]
    first = document["pinv_peaks"]["first_pass"]
    median = float(np.median(np.abs(pinv.trace.theta_dot).max(axis=1)))
    a, b = first["their_rates_rad_s"]
    holds = (
        first["fastest_joints"] == [5, 7]
        and a * b < 0.0
        and first["peak_rad_s"] >= chapter4.HIGH_RATE_FACTOR * median
    )
    assert fastest["verdict"] == trend_verdict(holds).value
    suppression = rows_of(documents, "fig4.7")["peak_joint_speed_rad_s"]
    assert suppression["ours"]["pinv"] == pytest.approx(peak)
    holds = suppression["ours"]["dls"] < chapter4.SUPPRESSED_SHARE * suppression["ours"]["pinv"]
    assert suppression["verdict"] == trend_verdict(holds).value
    assert f"{factor:.1f}" in suppression["note"]
    # the unlimited pinv outruns the URDF speed limits; the labelled series is capped by them
    series = document["urdf_limits_series"]
    limits = scenario_runs.default_robot().velocity_limits
    assert peak > limits.max()
    assert series["peak_joint_speed_rad_s"] <= limits.max() + 1e-9
    assert series["min_joint_limit_scale"] < 1.0
    assert rows["peak_joint_speed_urdf_limits_rad_s"]["verdict"] == Verdict.INPUT.value


@slow
def test_singular_region_end_is_a_number_and_its_start_an_input(documents):
    dls = documents["fig4.7"][0]
    rows = rows_of(documents, "fig4.7")
    assert rows["epsilon_lambda2_max"]["verdict"] == Verdict.INPUT.value
    assert rows["singular_region_start_s"]["verdict"] == Verdict.INPUT.value
    assert rows["singular_region_start_s"]["ours"] == dls["singular_region_s"][0][0]
    end = rows["singular_region_end_s"]
    assert end["thesis"] == chapter4.THESIS_SINGULAR_REGION_S[1]
    assert end["ours"] == dls["singular_region_s"][0][1]
    expected = number_verdict(end["thesis"], end["ours"], chapter4.THESIS_TIME_TOLERANCE_S)
    assert end["verdict"] == expected.value
    # today's geometry leaves the region about 0.8 s early: more than 10 % off, so different
    assert end["ours"] < 0.9 * end["thesis"]
    assert end["verdict"] == Verdict.DIFFERENT.value
    start, stop = dls["singular_region_s"][0]
    assert f"the first lasts {stop - start:.2f} s" in end["note"]
    assert "singular_region_duration_s" not in rows


@slow
def test_dls_verdicts_follow_the_numbers(documents):
    dls = documents["fig4.7"][0]
    rows = rows_of(documents, "fig4.7")
    speed = rows["peak_joint_speed_rad_s"]["ours"]
    holds = speed["dls"] < chapter4.SUPPRESSED_SHARE * speed["pinv"]
    assert rows["peak_joint_speed_rad_s"]["verdict"] == trend_verdict(holds).value
    error = rows["max_angular_velocity_error_in_singular_region_rad_s"]
    assert error["ours"] > 0.01  # [rad/s]: DLS trades tracking for bounded rates in the region
    if error["verdict"] == Verdict.NOT_REPRODUCED.value:
        assert "cause open" in error["note"]
    # no verdict names the clipping any more: the runs have no joint limits
    assert not any("clipping" in row["note"] for row in rows.values())
    base = rows["max_base_deviation_in_singular_region_deg"]
    assert base["verdict"] == trend_verdict(base["ours"] < chapter4.UNDISTURBED_DEG).value
    assert dls["max_base_deviation_deg"]["dls"] < 1e-3


@slow
def test_sc_verdicts_follow_the_numbers(documents):
    document = documents["fig4.8"][0]
    rows = rows_of(documents, "fig4.8")
    assert rows["sc_gain_b"]["verdict"] == Verdict.INPUT.value
    axis = rows["max_axis_error_deg"]["ours"]
    holds = axis["sc"] < 1.0 and axis["dls"] > 10.0 * axis["sc"]
    assert rows["max_axis_error_deg"]["verdict"] == trend_verdict(holds).value
    # the thesis compares SC with the untreated singularity (pinv, Fig. 4.6), not with DLS
    accel = rows["max_joint_acceleration_rad_s2"]["ours"]
    assert set(accel) == {"sc", "pinv"}
    assert accel == pytest.approx(
        {m: document["max_joint_acceleration_rad_s2"][m] for m in ("sc", "pinv")}
    )
    holds = accel["sc"] < accel["pinv"]
    assert rows["max_joint_acceleration_rad_s2"]["verdict"] == trend_verdict(holds).value
    # a failed trend names its cause only when the lower-gain runs meet the same criterion
    lower = document["lower_wrist_gain"]
    lower_holds = {
        "max_axis_error_deg": lower["sc"]["max_axis_error_deg"] < 1.0
        and lower["dls"]["max_axis_error_deg"] > 10.0 * lower["sc"]["max_axis_error_deg"],
        "max_joint_acceleration_rad_s2": lower["sc"]["max_joint_acceleration_rad_s2"]
        < lower["pinv"]["max_joint_acceleration_rad_s2"],
    }
    for key, held in lower_holds.items():
        if rows[key]["verdict"] == Verdict.NOT_REPRODUCED.value:
            assert ("the cause is the wrist term" in rows[key]["note"]) == held
            assert ("open" in rows[key]["note"]) != held


@slow
def test_singularity_choices_come_from_the_run(documents):
    pinv = scenario_runs.recorded_run(chapter4.SINGULARITY, "pinv", True)
    regions = trace_windows.intervals(pinv.trace.t_mid, pinv.trace.sigma_min < 0.2)
    duration = scenario_runs.shipped_scenario(chapter4.SINGULARITY).duration
    for identifier in ("fig4.6", "fig4.7", "fig4.8"):
        (choice,) = [c for c in documents[identifier][0]["choices"] if c.startswith("Duration")]
        assert f"runs {duration:g} s" in choice
        assert str(regions) in choice
