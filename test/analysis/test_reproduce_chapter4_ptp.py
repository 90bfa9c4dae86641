"""Chapter 4 point-to-point reproductions (Table 4.2, Figs. 4.10/4.12/4.13, partial deployment):
each id runs quick into JSON + PNG with the documented keys."""

from __future__ import annotations

import pytest
from rns_testing import quick_documents

from rns_ros.analysis.reproduce import chapter4_ptp
from rns_ros.analysis.reproduce.registry import CHAPTER_MODULES, Status

# whole point-to-point reproductions (quick grids): make test, not test-quick
pytestmark = pytest.mark.slow

IDS = ("table4.2", "fig4.10", "fig4.12", "fig4.13", "partial_deployment")
METHODS = {"3-phase", "JS-C", "IJ-C", "TJ-C"}


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    """{id: (json document, png path)}; table4.2/fig4.10/fig4.12 share their runs (cache)."""
    return quick_documents(IDS, tmp_path_factory.mktemp("chapter4_ptp"))


def test_registered_after_chapter4():
    assert tuple(chapter4_ptp.REPRODUCTIONS) == IDS
    modules = list(CHAPTER_MODULES)
    assert modules.index("rns_ros.analysis.reproduce.chapter4_ptp") == (
        modules.index("rns_ros.analysis.reproduce.chapter4") + 1
    )


@pytest.mark.parametrize("identifier", IDS)
def test_each_result_writes_json_and_png(documents, identifier):
    document, png = documents[identifier]
    assert document["id"] == identifier
    assert document["quick"] is True
    assert png.stat().st_size > 10_000
    statuses = {c["status"] for c in document["comparisons"]}
    assert statuses <= {status.value for status in Status}
    assert all(c["note"] for c in document["comparisons"] if c["status"] != Status.EXACT.value)


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


def test_fig_4_10_coupling_only_in_phase_two(documents):
    document, _ = documents["fig4.10"]
    per_phase = document["max_coupling_per_phase"]
    assert per_phase["II"] > 1.0
    assert per_phase["I"] < 1e-10 * per_phase["II"]
    assert per_phase["III"] < 1e-10 * per_phase["II"]


def test_deployments(documents):
    full, _ = documents["fig4.13"]
    assert full["max_base_deviation_deg"] < 1e-3
    partial, _ = documents["partial_deployment"]
    deviation = partial["max_base_deviation_deg"]
    assert set(deviation) == {"partial_reactionless", "baseline"}
    assert partial["reduction_percent"] == pytest.approx(
        100.0 * (1.0 - deviation["partial_reactionless"] / deviation["baseline"]), rel=1e-4
    )
    assert partial["reduction_percent"] > 0.0
    assert partial["final_error_deg"] < 0.1
