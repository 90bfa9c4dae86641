"""Chapter-6 remarks (sec6.1.2 exact C_A, sec6.2.1 gravity): quick runs, verdicts follow from the
computed numbers."""

from __future__ import annotations

import pytest
from rns_testing import assert_chapter_order, quick_documents, quick_result_verdicts

from rns_ros.analysis.reproduce import chapter6_remarks as remarks

pytestmark = pytest.mark.slow

IDS = ("sec6.1.2", "sec6.2.1")


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    return quick_documents(IDS, tmp_path_factory.mktemp("chapter6_remarks"))


def test_the_module_comes_after_chapter6():
    assert_chapter_order("chapter6_remarks", ("chapter6",), IDS)


def test_exact_c_a_row_follows_from_the_literal_runs(documents):
    document, png = documents["sec6.1.2"]
    quick_result_verdicts(document, png, "sec6.1.2")
    (row,) = document["comparisons"]
    errors = document["max_position_error_m"]
    ratio = errors["RNS-C-literal-momentum"] / errors["RNS-C-literal"]
    assert row["ours"] == pytest.approx(ratio)
    assert row["verdict"] == (
        "qualitative" if ratio > remarks.C_A_ERROR_FACTOR else "not reproduced"
    )
    # with the exact C_hat_A the literal loop tracks like the closed form
    assert errors["RNS-C-literal"] == pytest.approx(errors["RNS-C"], rel=0.05)


def test_gravity_rows_follow_from_the_runs(documents):
    document, png = documents["sec6.2.1"]
    quick_result_verdicts(document, png, "sec6.2.1")
    rows = {c["key"]: c for c in document["comparisons"]}
    assert rows["gravity_m_s2"]["verdict"] == "input"
    factor = document["osc_peak_gravity_over_no_gravity"]
    large = rows["osc_gravity_peak_factor"]
    assert large["verdict"] == (
        "qualitative" if factor > remarks.GRAVITY_PEAK_FACTOR else "not reproduced"
    )
    turns = document["osc_self_motion_reversals"]["gravity"]
    cyclic = rows["osc_gravity_self_motion_reversals"]
    assert cyclic["verdict"] == (
        "qualitative" if turns >= remarks.MIN_REVERSALS else "not reproduced"
    )
    assert cyclic["verdict"] == "qualitative" or "open" in cyclic["note"]
    # RNS-C compensates all of g_l: gravity leaves its peak
    on, off = (
        document["peak_joint_speed_gravity_rad_s"],
        document["peak_joint_speed_no_gravity_rad_s"],
    )
    assert on["RNS-C"] == pytest.approx(off["RNS-C"], rel=0.05)
