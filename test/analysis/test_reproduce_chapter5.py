"""Chapter 5 C_ratio maps (Figs. 5.1-5.3): quick runs give finite JSON with the documented keys,
physically sensible numbers, a PNG, and fig5.3 runs on a dask scheduler given on the command
line."""

from __future__ import annotations

import json
import math

import pytest
from rns_testing import json_finite

from rns_ros.analysis.reproduce import chapter5, registry
from rns_ros.analysis.reproduce.registry import Status, run_one
from rns_ros.apps import reproduce

IDS = ("fig5.1", "fig5.2", "fig5.3")
KEYS = {
    "fig5.1": ("c_ratio_mean", "c_ratio_median", "c_ratio_max"),
    "fig5.2": ("c_ratio_mean_range", "decreasing_with_alpha"),
    "fig5.3": ("c_ratio_mean", "c_ratio_median", "c_ratio_p99", "points"),
}


@pytest.fixture(scope="module")
def documents(tmp_path_factory):
    out = tmp_path_factory.mktemp("chapter5")
    written = {}
    for identifier in IDS:
        record = run_one(chapter5.REPRODUCTIONS[identifier], out, quick=True)
        assert record.seconds < 10.0
        written[identifier] = (json.loads(record.json_path.read_text()), record.png_path)
    return written


def test_registered_in_order_before_the_inspection_results():
    assert tuple(chapter5.REPRODUCTIONS) == IDS
    modules = list(registry.CHAPTER_MODULES)
    assert "rns_ros.analysis.reproduce.chapter5" in modules
    assert set(IDS) <= set(registry.load_all())


@pytest.mark.parametrize("identifier", IDS)
def test_quick_run_writes_finite_json_with_the_documented_keys(documents, identifier):
    document, png = documents[identifier]
    assert document["quick"] is True
    assert tuple(document["ours"]) == KEYS[identifier]
    assert json_finite(document)
    statuses = {c["status"] for c in document["comparisons"]}
    assert statuses <= {s.value for s in Status}
    assert document["choices"]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_fig5_1_ratio_is_one_almost_everywhere(documents):
    document, _ = documents["fig5.1"]
    ours = document["ours"]
    assert 1.0 <= ours["c_ratio_median"] < 1.001
    assert ours["c_ratio_median"] <= ours["c_ratio_mean"] <= ours["c_ratio_max"]
    assert document["thesis"]["c_ratio_mean"] == 1.002
    assert document["share_above_1_01"] < 0.05


def test_fig5_2_means_are_near_one_and_fall_with_alpha(documents):
    document, _ = documents["fig5.2"]
    table = document["c_ratio_mean_table"]
    assert len(table) == len(document["alphas"])
    assert all(1.0 <= value < 1.01 for row in table for value in row)
    middle = len(table[0]) // 2  # beta = 1
    assert table[0][middle] > table[-1][middle]  # alpha 0.5 above alpha 1.5


def test_fig5_3_statistics_and_slices(documents):
    document, _ = documents["fig5.3"]
    ours = document["ours"]
    assert ours["points"] == 8**4
    assert 1.0 - 1e-9 <= ours["c_ratio_median"] <= ours["c_ratio_p99"] <= document["c_ratio_max"]
    assert document["wall_s"] > 0.0
    assert document["thesis"]["c_ratio_mean"] == 1.14
    assert [s["theta1_rad"] for s in document["slices"]] == [-3.05, -math.pi]
    assert all(s["c_ratio_mean"] >= 1.0 - 1e-9 for s in document["slices"])


def test_cli_runs_fig5_3_on_a_dask_scheduler(tmp_path, monkeypatch, capsys):
    distributed = pytest.importorskip("distributed")
    monkeypatch.setenv(chapter5.DASK_SCHEDULER_ENV, "")  # restored after the test
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        argv = ["run", "fig5.3", "--quick", "--out", str(tmp_path)]
        assert reproduce.main([*argv, "--dask-scheduler", cluster.scheduler_address]) == 0
    document = json.loads((tmp_path / "fig5.3.json").read_text())
    assert document["settings"]["computed_on"] == f"dask scheduler {cluster.scheduler_address}"
    assert document["ours"]["points"] == 8**4


@pytest.mark.parametrize(
    ("ids", "address", "message"),
    [
        (["fig5.3"], "not an address", "cannot connect to the dask scheduler"),
        (["fig5.1"], "tcp://127.0.0.1:8786", "only used by fig5.3"),
    ],
)
def test_bad_dask_scheduler_is_one_line_and_exit_2(tmp_path, capsys, ids, address, message):
    argv = ["run", *ids, "--quick", "--out", str(tmp_path), "--dask-scheduler", address]
    assert reproduce.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert message in err[0]
    assert not (tmp_path / f"{ids[0]}.json").exists()
