"""rns_demo --scenario ptp_three_phase: argument checks, the table, and a short run over DDS."""

from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest

from rns_ros.analysis.ptp_runs import run_plan
from rns_ros.apps import demo
from rns_ros.apps.demo import main
from rns_ros.bag import open_bag
from rns_ros.control.ptp import PtpSettings
from rns_ros.control.ptp_planner import plan_ptp
from rns_ros.core import load_model
from rns_ros.resources import default_model_config
from rns_ros.runs import ptp
from rns_ros.runs.ptp import PTP_SCENARIOS, PtpDemoRow, PtpScenario
from rns_ros.runs.report import format_ptp_table

DOMAIN = os.environ.setdefault("ROS_DOMAIN_ID", "43")
#: A short JS-C / 3-phase task: theta_4 starts near -180 deg so the reactionless folds are short.
SHORT = PtpScenario(
    "ptp_short",
    "short point-to-point test task",
    tuple(np.radians([-20.0, -40.0, 0.0, -170.0, 180.0, 180.0, 0.0])),
    tuple(np.radians([-26.0, -34.0, 0.0, -170.0, 180.0, 180.0, 0.0])),
)


def _row(method: str, deviation: float, **changes) -> PtpDemoRow:
    values = {
        "method": method,
        "label": ptp.PTP_METHODS[method],
        "max_base_deviation_deg": deviation,
        "final_joint_error_deg": 0.01,
        "final_camera_error_m": None,
        "duration_s": 30.0,
        "fold_reached": "none",
        "max_joint_speed": 0.2,
        "wall_time_s": 1.0,
        "recording": None,
    }
    return PtpDemoRow(**{**values, **changes})


def test_ptp_scenario_is_the_thesis_task():
    scenario = PTP_SCENARIOS["ptp_three_phase"]
    assert np.degrees(scenario.start) == pytest.approx([-20, -40, 0, -60, 180, 180, 0])
    assert np.degrees(scenario.goal) == pytest.approx([-120, 50, 0, -60, 180, 180, 0])


def test_table_ratio_is_to_the_three_phase_run():
    rows = [
        _row("three_phase", 2.0),
        _row("joint_space", 3.0),
        _row("inverse_jacobian", 4.0, final_camera_error_m=0.0042),
    ]
    lines = format_ptp_table(rows).splitlines()
    assert lines[2].split()[:3] == ["3-phase", "2.0000", "1.00"]
    assert lines[3].split()[:3] == ["JS-C", "3.0000", "1.50"]
    assert lines[4].split()[:3] == ["IJ-C", "4.0000", "2.00"]
    assert "4.2 mm cam" in lines[4]
    # the thesis' Table 4.2 and its ratios: 3.61 / 1.95 = 1.85
    assert lines[3].split()[3:5] == ["3.61", "1.85"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--scenario", "ptp_three_phase", "--methods", "dls"], "subset of ['three_phase'"),
        (["--methods", "three_phase"], "subset of ('dls'"),
    ],
)
def test_methods_are_checked_against_the_scenario(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_non_finite_figures_fail_the_run(monkeypatch, capsys, tmp_path, bad):
    def fake(method, _scenario, _args):
        return _row(method, bad if method == "joint_space" else 1.0)

    monkeypatch.setattr(demo, "run_ptp_method", fake)
    summary = tmp_path / "summary.json"
    argv = ["--scenario", "ptp_three_phase", "--summary", str(summary), "--domain-id", DOMAIN]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert f"JS-C: max_base_deviation_deg = {bad}" in err
    assert not summary.exists()


def test_short_task_over_dds_matches_the_core_and_reaches_the_goal(monkeypatch, tmp_path):
    """rns_simulator + rns_ptp over DDS on sim time in lockstep, 3-phase and JS-C: both end at
    the goal, the base turns as in the core run of the same plan (within 20 %), and the 3-phase
    plan reports its folds. On this short task the 3-phase plan does not beat the joint-space
    line (its Phase II is that line); the thesis' claim is for the Table 4.2 task (README)."""
    monkeypatch.setitem(demo.PTP_SCENARIOS, SHORT.name, SHORT)
    summary = tmp_path / "summary.json"
    argv = [
        "--scenario",
        SHORT.name,
        "--methods",
        "three_phase,joint_space",
        "--real-time-factor",
        "0",
        "--summary",
        str(summary),
        "--output",
        str(tmp_path / "recordings"),
        "--domain-id",
        DOMAIN,
        "--ros-args",
        "-p",
        "duration:=4.0",
        "-p",
        "phase_durations:=[1.0, 4.0, 1.0]",
    ]
    assert main(argv) == 0
    rows = {row["method"]: row for row in json.loads(summary.read_text())}
    robot = load_model(default_model_config())
    settings = PtpSettings(duration=4.0, phase_durations=(1.0, 4.0, 1.0))
    for method, row in rows.items():
        plan = plan_ptp(robot, np.array(SHORT.start), np.array(SHORT.goal), method, settings)
        core = run_plan(robot, plan, rate=100.0).max_base_deviation_deg
        print(f"{method}: DDS {row['max_base_deviation_deg']:.4e} deg, core {core:.4e} deg")
        # open-loop playback: a lockstep "one step on" (rns_ptp's sim-time timer missing a
        # pause for 2 s, seen once in CI) left 0.17 deg; normally ~1e-4 deg
        assert row["final_joint_error_deg"] < 0.5
        assert row["max_base_deviation_deg"] == pytest.approx(core, rel=0.2)
        assert os.path.isfile(row["recording"] or "")
        # the bag beside it carries what a viewer draws the arm from
        topics = open_bag(row["mcap"]).topics
        assert topics["/robot_description"].message_count == 1
        assert topics["/tf_static"].message_count == 1
        assert topics["/tf"].message_count > 0
    # both folds of the 3-phase plan reach the thesis' -180 deg from -170 deg
    assert rows["three_phase"]["fold_reached"] == "I: -180 deg, III: -180 deg"
