"""rns_demo --model: every node on another arm, and the start configuration a scenario gives it.

The other arm here is the default arm with joint_7 welded (6 controlled joints, no wrist frame):
the smallest change that makes a scenario written for the default arm's 7 joints unusable.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from rns_testing import SHORT_ROLL_SCENARIO, six_joint_model

from rns_ros.analysis.closed_loop import run_scenario
from rns_ros.apps import demo
from rns_ros.apps.demo import main
from rns_ros.control.scenario import load_scenario
from rns_ros.core import load_model
from rns_ros.resources import default_model_config, scenario_path
from rns_ros.runs.inspection import DemoRow, start_configuration
from rns_ros.viz.readback import recording_summary

# this file's own domain (the DDS run below), apart from the other demo tests'
DOMAIN = str(int(os.environ.get("ROS_DOMAIN_ID", "43")) + 1)
#: the thesis start without joint 7 (away from the 6-joint arm's singularities)
SIX_ANGLES_DEG = [-90.0, -30.0, 0.0, -70.0, 180.0, -30.0]


def _scenario(folder: Path, degrees: list[float], name: str = "short.yaml") -> Path:
    path = folder / name
    path.write_text(yaml.safe_dump({**SHORT_ROLL_SCENARIO, "initial_joint_positions_deg": degrees}))
    return path


def test_a_scenario_for_the_arm_gives_the_start(tmp_path):
    robot = load_model(six_joint_model(tmp_path, wrist_frame=None))
    scenario = load_scenario(_scenario(tmp_path, SIX_ANGLES_DEG))
    theta, note = start_configuration(scenario, robot)
    np.testing.assert_array_equal(theta, np.deg2rad(SIX_ANGLES_DEG))
    # the model YAML starts elsewhere (zeros): the note says which start the run takes
    assert note == (
        "starting from scenario 'short_observation''s initial_joint_positions_deg "
        "[-90, -30, 0, -70, 180, -30] deg, not the model's [0, 0, 0, 0, 0, 0] deg"
    )


def test_the_thesis_scenario_on_the_thesis_arm_starts_where_both_say_without_a_note():
    robot = load_model(default_model_config())
    theta, note = start_configuration(load_scenario(scenario_path("satellite_observation")), robot)
    np.testing.assert_allclose(theta, robot.initial_theta, atol=1e-9)
    assert note == ""


def test_a_scenario_that_writes_the_models_start_in_rounded_degrees_needs_no_note(tmp_path):
    """The model's own start written to a scenario file to 6 decimals in degrees (as a user or
    scripts/arm_table.py does) is the model's start, not another one to note; 0.01 deg off is
    another start."""
    model = six_joint_model(tmp_path, wrist_frame=None)
    start = {"joint_1": 0.17669333, "joint_2": -0.36242853, "joint_4": -1.2}  # [rad]
    model.write_text(model.read_text() + f"initial_joint_positions: {start}\n")
    robot = load_model(model)
    rounded = np.rad2deg(robot.initial_theta).round(6).tolist()
    assert not np.allclose(np.deg2rad(rounded), robot.initial_theta, rtol=0.0, atol=1e-9)
    _, note = start_configuration(load_scenario(_scenario(tmp_path, rounded)), robot)
    assert note == ""
    shifted = [rounded[0] + 0.01, *rounded[1:]]
    _, note = start_configuration(load_scenario(_scenario(tmp_path, shifted)), robot)
    assert note.startswith("starting from scenario")


def test_a_scenario_for_another_arm_starts_from_the_models_configuration(tmp_path):
    robot = load_model(six_joint_model(tmp_path, wrist_frame=None))
    scenario = load_scenario(
        _scenario(tmp_path, SHORT_ROLL_SCENARIO["initial_joint_positions_deg"])
    )
    theta, note = start_configuration(scenario, robot)
    np.testing.assert_array_equal(theta, robot.initial_theta)
    assert "gives 7 initial angles, the model has 6 controlled joints" in note


def test_angles_outside_the_joint_limits_are_another_arms(tmp_path, robot):
    degrees = [0.0] * robot.n
    joint = 1
    degrees[joint] = float(np.rad2deg(robot.upper_limits[joint])) + 1.0
    theta, note = start_configuration(load_scenario(_scenario(tmp_path, degrees)), robot)
    assert f"puts joints ['{robot.joint_names[joint]}'] outside their limits" in note
    assert np.all(theta >= robot.lower_limits)
    assert np.all(theta <= robot.upper_limits)


def test_demo_passes_the_model_and_prints_the_note(tmp_path, monkeypatch, capsys):
    model = six_joint_model(tmp_path, wrist_frame=None)
    seen = []

    def fake_run(method, args, _file):
        seen.append((args.model, args.initial_theta))
        return DemoRow(method, _figures(), 1.0, None)

    monkeypatch.setattr(demo, "run_method", fake_run)
    scenario = _scenario(tmp_path, SHORT_ROLL_SCENARIO["initial_joint_positions_deg"])
    argv = ["--no-record", "--methods", "dls", "--scenario", str(scenario), "--model", str(model)]
    assert main([*argv, "--domain-id", DOMAIN]) == 0
    out = capsys.readouterr().out
    assert "note: scenario 'short_observation' gives 7 initial angles" in out
    assert f"model: {model.resolve()}" in out
    assert seen[0][0] == model.resolve()
    assert seen[0][1].shape == (6,)


def test_demo_rejects_a_missing_model_in_one_line(capsys):
    assert main(["--no-record", "--model", "no_such_model.yaml", "--domain-id", DOMAIN]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "model config not found" in err[0]


def test_model_is_an_inspection_option(capsys):
    with pytest.raises(SystemExit) as exit_info:  # a usage error, as every other option's
        main(["--scenario", "ptp_three_phase", "--model", "x.yaml"])
    assert exit_info.value.code == 2
    assert "--model is for the inspection scenarios" in capsys.readouterr().err


def _figures():
    from rns_ros.analysis.recorded_run import RunFigures

    return RunFigures(
        max_base_deviation_deg=1e-4,
        final_camera_error_deg=0.05,
        rms_tracking_error=1e-3,
        max_wrist_drift_m=0.1,
        max_joint_speed=0.3,
        angular_momentum_drift=1e-13,
        samples=400,
        min_sigma=0.4,
        singular_time_s=0.0,
    )


def test_demo_runs_a_six_joint_arm_reactionless_over_dds(tmp_path):
    """Simulator, controller, operator and logger all on the 6-joint model: the camera turns
    30 deg while the base stays as still as the in-process closed loop keeps it."""
    model = six_joint_model(tmp_path, wrist_frame=None)
    scenario = _scenario(tmp_path, SIX_ANGLES_DEG)
    summary = tmp_path / "summary.json"
    argv = ["--scenario", str(scenario), "--model", str(model), "--methods", "dls"]
    argv += ["--summary", str(summary), "--output", str(tmp_path / "rec"), "--domain-id", DOMAIN]
    assert main(argv) == 0
    (row,) = json.loads(summary.read_text())
    core = run_scenario(load_model(model), load_scenario(scenario))
    assert core.max_base_deviation_deg < 1e-5
    assert row["max_base_deviation_deg"] < 5e-3  # DDS sample latency, as the default arm's
    assert row["final_camera_error_deg"] < 1.0
    assert row["angular_momentum_drift"] < 1e-9
    counts = recording_summary(row["recording"])
    assert any(path.endswith("joint_6") and rows > 0 for path, rows in counts.items())
    assert not any(path.endswith("joint_7") and rows > 0 for path, rows in counts.items())


def test_a_failing_method_leaves_the_others_run_and_printed(tmp_path, monkeypatch, capsys):
    """One method's run fails (here: did not finish): it is said in one line and exit 2, and
    the methods after it still run and print their figures."""
    from rns_ros.core import RnsError

    def fake_run(method, _args, _file):
        if method == "dls":
            raise RnsError("dls: the scenario did not finish within 82 s")
        return DemoRow(method, _figures(), 1.0, None)

    monkeypatch.setattr(demo, "run_method", fake_run)
    argv = ["--no-record", "--methods", "dls,sc", "--domain-id", DOMAIN]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert "\nsc " in captured.out  # its row
    assert "rns_demo: dls: the scenario did not finish within 82 s" in captured.err


def test_a_joint_driven_to_its_limit_ends_the_run_with_the_cause_and_the_figures_so_far(
    tmp_path, capfd
):
    """gripper7's default roll drives g7_joint5 into its upper limit 2.9 rad: each method's run
    ends there with its figures so far (row marked *), the cause in one line each, exit 2; the
    summary says so."""
    model = Path(__file__).parents[1] / "data" / "arms" / "gripper7" / "model.yaml"
    summary = tmp_path / "summary.json"
    argv = ["--model", str(model), "--methods", "dls,sc", "--no-record", "--real-time-factor"]
    argv += ["0", "--summary", str(summary), "--domain-id", DOMAIN]
    assert main(argv) == 2
    captured = capfd.readouterr()
    for method in ("dls", "sc"):
        assert f"\n{method} *" in captured.out
        assert re.search(
            rf"rns_demo: {method}: g7_joint5 reached its upper limit 2.9 rad at t = \d+\.\d\d s",
            captured.err,
        ), captured.err
    rows = {row["method"]: row for row in json.loads(summary.read_text())}
    assert rows["dls"]["ended"].startswith("g7_joint5 reached its upper limit 2.9 rad")
    assert rows["dls"]["max_base_deviation_deg"] < 1e-4  # reactionless up to the stop


def test_a_node_that_fails_at_start_up_is_named_with_its_one_line_at_once(capfd):
    """rns_controller refuses a parameter and exits 2: the demo does not wait out its start-up
    timeout, and its line names the process and quotes the node's own one-line error."""
    argv = ["--no-record", "--methods", "dls", "--real-time-factor", "0", "--domain-id", DOMAIN]
    assert main([*argv, "--ros-args", "-p", "state_timeout:=-1.0"]) == 2
    err = capfd.readouterr().err
    assert (
        "rns_demo: dls: a node did not start: rns_controller exited (code 2): rns_controller: "
        "parameter 'state_timeout' out of range: valid range [0.005, 10.0] [s]"
    ) in err
    assert "Traceback" not in err
