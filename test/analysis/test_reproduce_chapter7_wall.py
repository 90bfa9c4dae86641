"""Chapter 7 on the wall task (ext-fig6.8-ch7): the quick run's rows follow from its numbers, and
the trend rows fail on deliberately wrong series."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from rns_testing import (
    assert_chapter_order,
    comparison_rows,
    quick_documents,
    quick_result_verdicts,
)

from rns_ros.analysis.motion_force_runs import NullSpaceTerm
from rns_ros.analysis.reproduce import chapter6 as ch6
from rns_ros.analysis.reproduce import chapter7_wall as wall

# whole reproductions (quick runs): make test, not test-quick
pytestmark = pytest.mark.slow

ID = "ext-fig6.8-ch7"


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    return quick_documents(("fig6.8", ID), tmp_path_factory.mktemp("chapter7_wall"))


def test_the_module_registers_after_chapter7():
    assert_chapter_order("chapter7_wall", ("chapter6", "chapter7"), (ID,))


def test_rows_follow_from_the_runs(documents):
    document, png = documents[ID]
    assert quick_result_verdicts(document, png, ID) <= {"qualitative", "not reproduced"}
    # the thesis never ran chapter 7 on the wall: every row is reported apart from its claims
    assert document["extension"] is True
    assert all(row["extension"] for row in document["comparisons"])
    rows = comparison_rows(document)
    masses = [f"{m:g}" for m in wall.QUICK_MASSES]
    runs = document["runs"]
    osc = min(v["peak_joint_speed_rad_s"] for v in document["osc"].values())
    velocity = runs[NullSpaceTerm.VELOCITY_LEVEL.value]
    plain = runs[NullSpaceTerm.NONE.value]
    # the main row: OS-C peaks over RNS-C + (7.13) at fig6.8's m_hat
    row = rows["peak_ratio_osc_over_rns_c_velocity_level"]
    peak = velocity["100000"]["peak_joint_speed_rad_s"]
    for name, ratio in row["ours"].items():
        assert ratio == pytest.approx(document["osc"][name]["peak_joint_speed_rad_s"] / peak)
    holds = min(row["ours"].values()) > ch6.RATIO_THRESHOLD
    assert row["verdict"] == ("qualitative" if holds else "not reproduced")
    assert holds or "Cause, from these runs" in row["note"]
    # per-mass ratio rows: some m_hat above the threshold or not
    for term, key in ((plain, "no_term"), (velocity, "velocity_level")):
        row = rows[f"peak_ratio_osc_over_rns_c_per_mass_{key}"]
        finished = [m for m in masses if "stopped" not in term[m]]
        assert list(row["ours"]) == finished
        for m in finished:
            assert row["ours"][m] == pytest.approx(osc / term[m]["peak_joint_speed_rad_s"])
        holds = max(row["ours"].values()) > ch6.RATIO_THRESHOLD
        assert row["verdict"] == ("qualitative" if holds else "not reproduced")
    # the velocity-level term removes the null-space velocity by orders at every mass
    for m in masses:
        assert velocity[m]["max_null_space_rns_rad_s"] < 0.1 * plain[m]["max_null_space_rns_rad_s"]
        # and leaves the task as it was (it enters through the null space only)
        assert velocity[m]["max_position_error_m"] < 1e-4
    final = rows["final_null_space_velocity_no_term_over_velocity_level"]
    ratio = (
        plain["100000"]["final_null_space_rns_rad_s"]
        / velocity["100000"]["final_null_space_rns_rad_s"]
    )
    assert final["ours"] == pytest.approx(ratio)
    assert final["verdict"] == ("qualitative" if ratio >= wall.ORDER_RATIO else "not reproduced")


def test_fig6_8_note_quotes_the_chapter7_run(documents):
    (row,) = documents["fig6.8"][0]["comparisons"]
    if row["verdict"] == "not reproduced":
        assert "ext-fig6.8-ch7" in row["note"]
        peaks = documents[ID][0]["runs"]["velocity-level"]["100000"]
        peak = round(peaks["peak_joint_speed_per_stroke_rad_s"][0], 3)
        assert str(peak) in row["note"]


def _fake(series):
    """Stand-ins for runs with the given max ||P theta_dot|| (the rows read only these)."""
    return {
        m: SimpleNamespace(
            null_space_velocity=np.array([0.0, v]),
            null_space_velocity_jacobian=np.array([0.0, v]),
        )
        for m, v in series.items()
    }


def test_the_null_space_trend_fails_when_the_velocity_does_not_fall():
    falling = wall._null_space_row(NullSpaceTerm.VELOCITY_LEVEL, _fake({1e2: 3.0, 1e3: 2.0}))
    assert falling.verdict.value == "qualitative"
    flat = _fake({1e2: 2.0, 1e3: 2.0, 1e4: 1.0})
    rising = wall._null_space_row(NullSpaceTerm.NONE, flat, _fake({1e2: 3.0, 1e3: 2.0}))
    assert rising.verdict.value == "not reproduced"
    assert "not damped" in rising.note
    assert "open" in wall._null_space_row(NullSpaceTerm.NONE, flat, flat).note
    stopped = wall._null_space_row(NullSpaceTerm.NONE, {1e1: "diverged at t = 1 s"})
    assert stopped.verdict.value == "not reproduced"
    assert "10 kg: diverged at t = 1 s" in stopped.note


def test_the_final_row_fails_when_the_term_leaves_the_velocity():
    run = SimpleNamespace(null_space_velocity=np.array([0.0, 1.0]))
    row = wall._final_row(run, run)
    assert row.ours == 1.0
    assert row.verdict.value == "not reproduced"
    small = SimpleNamespace(null_space_velocity=np.array([0.0, 1e-3]))
    assert wall._final_row(run, small).verdict.value == "qualitative"
