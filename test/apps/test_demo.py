"""The main job end to end over DDS (short scenario), and its figures against the core's physics."""

from __future__ import annotations

import json
import math
import os
import re
import signal

import pytest
import yaml
from rns_testing import SHORT_ROLL_SCENARIO

from rns_ros.analysis.closed_loop import run_scenario
from rns_ros.analysis.recorded_run import RunFigures
from rns_ros.apps import demo
from rns_ros.apps.demo import main
from rns_ros.control.scenario import load_scenario
from rns_ros.core import load_model
from rns_ros.resources import default_model_config
from rns_ros.runs import inspection
from rns_ros.runs.inspection import DemoRow
from rns_ros.viz import paths
from rns_ros.viz.readback import recording_summary

DOMAIN = os.environ.setdefault("ROS_DOMAIN_ID", "43")


def _short_demo(folder, *options: str) -> tuple:
    """rns_demo on the short roll scenario in ``folder`` with extra ``options``; returns the
    scenario file and the summary rows by method."""
    scenario = folder / "short.yaml"
    scenario.write_text(yaml.safe_dump(SHORT_ROLL_SCENARIO))
    summary = folder / "summary.json"
    argv = ["--scenario", str(scenario), "--summary", str(summary), "--domain-id", DOMAIN]
    assert main([*argv, *options]) == 0
    return scenario, {row["method"]: row for row in json.loads(summary.read_text())}


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("demo")
    return _short_demo(folder, "--output", str(folder / "recordings"))


def test_demo_compares_reactionless_and_conventional_over_dds(demo_run):
    scenario_file, rows = demo_run
    assert set(rows) == {"dls", "sc", "conventional"}
    dls, sc, conventional = rows["dls"], rows["sc"], rows["conventional"]
    # the in-process closed loop of the same scenario: what DDS should reproduce
    core = run_scenario(load_model(default_model_config()), load_scenario(scenario_file))
    core_conventional = run_scenario(
        load_model(default_model_config()), load_scenario(scenario_file), method="conventional"
    )
    assert conventional["max_base_deviation_deg"] == pytest.approx(
        core_conventional.max_base_deviation_deg, rel=0.2
    )
    for row in (dls, sc):
        # reactionless over DDS: sample latency costs a little (1e-4 deg), the baseline 0.07 deg
        assert row["max_base_deviation_deg"] < 0.05 * conventional["max_base_deviation_deg"]
        assert row["max_base_deviation_deg"] < 5e-3
    assert core.max_base_deviation_deg < 1e-5
    assert dls["final_camera_error_deg"] < 1.0
    for row in rows.values():
        assert row["angular_momentum_drift"] < 1e-9
        assert row["samples"] > 300  # 100 Hz for > 3 s
        assert row["max_joint_speed"] < 1.0 + 1e-9
    assert dls["rms_tracking_error"] < 0.02  # rad/s, latency-limited


def test_demo_recordings_load_back_with_the_documented_entities(demo_run):
    _, rows = demo_run
    for method, row in rows.items():
        counts = recording_summary(row["recording"])
        assert row["recording"].endswith(f"{method}.rrd")
        # at most one sample per robot state the simulator published (100 Hz over the run's
        # wall time, real time); the logger is a best-effort observer, so how many it gets
        # depends on how this machine schedules it (428 of 485 in a CI run, 175 of 439 beside
        # two busy loops and a second stack): present, never more than published
        for path in (paths.BASE_ATTITUDE_TOTAL, paths.CAMERA_POINTING):
            assert 1 <= counts[path] <= 100.0 * row["wall_time_s"], path
        assert counts[paths.SIGMA_MIN] >= 1  # the controller's status
        assert any(path.startswith(paths.JOINTS) for path in counts)


def test_demo_mcap_recordings_hold_the_recorded_topics(demo_run):
    """Next to each .rrd, a bag of the topics the figures come from; every robot state of the
    figures' window is in its MCAP file, which decodes with the ROS 2 decoder."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    _, rows = demo_run
    for method, row in rows.items():
        assert row["mcap"].endswith(f"/{method}")  # the bag folder
        with open(f"{row['mcap']}/{method}_0.mcap", "rb") as stream:
            reader = make_reader(stream, decoder_factories=[DecoderFactory()])
            summary = reader.get_summary()
            topics = {c.id: c.topic for c in summary.channels.values()}
            counts = {topics[i]: n for i, n in summary.statistics.channel_message_counts.items()}
            assert {"/joint_states", "/base_odom", "/momentum", "/cmd_twist"} <= set(counts)
            assert counts["/joint_states"] >= row["samples"]
            _, _, _, odom = next(reader.iter_decoded_messages(topics=["/base_odom"]))
            quaternion = odom.pose.pose.orientation
            norm = quaternion.x**2 + quaternion.y**2 + quaternion.z**2 + quaternion.w**2
            assert norm == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("clock", [["--wall-clock"], ["--real-time-factor", "5"]])
def test_demo_in_dynamic_mode_reaches_the_target(tmp_path, clock):
    """The joint servo tracks the reference positions, so they must follow what the plant was
    actually commanded: ticks are not exactly one period apart (a changed command is served at
    once, a busy timer fires late), and under /clock the hold lasts simulated time. Advancing
    the reference by the nominal period left the camera 0.6-0.9 deg short of a 30 deg roll;
    with the actual hold times it is within 0.01 deg."""
    # state_timeout 0.5 s: this test is about tracking, not the watchdog; the whole VM stalls
    # for 0.1-0.33 s now and then (seen with the code of the previous stop too), and the 0.1 s
    # default then stopped the arm mid-roll (camera 6.1 deg short in a fresh-clone CI run)
    _, rows = _short_demo(
        tmp_path, "--no-record", "--mode", "dynamic", "--methods", "dls",
        *clock, "--ros-args", "-p", "state_timeout:=0.5",
    )  # fmt: skip
    row = rows["dls"]
    # the camera ends where the operator's recorded twists take it; on the wall clock the
    # scripted operator's own samples can come late (a process that waited for a core), which
    # changes what was commanded, not how it is followed
    assert row["commanded_camera_error_deg"] < 0.1
    if "--wall-clock" not in clock:
        assert row["final_camera_error_deg"] < 0.1
    assert row["max_base_deviation_deg"] < 5e-3
    assert row["angular_momentum_drift"] < 1e-9


def test_the_default_demo_paced_to_real_time_gives_the_as_fast_as_possible_figures(tmp_path):
    """By default the nodes run on /clock in lockstep, paced to real time: the figures are
    those of the run as fast as possible, to rounding, however the processes were scheduled
    (a run that lost motion to a late process, as on the wall clock, would differ by orders of
    magnitude: 1e-5 to 1e-3 deg of base deviation instead of 1e-7)."""
    _, paced = _short_demo(tmp_path, "--no-record", "--methods", "dls")
    _, fast = _short_demo(tmp_path, "--no-record", "--methods", "dls", "--real-time-factor", "0")
    for figure in ("max_base_deviation_deg", "final_camera_error_deg", "max_joint_speed"):
        assert paced["dls"][figure] == pytest.approx(fast["dls"][figure], rel=1e-3, abs=1e-9)
    assert paced["dls"]["max_base_deviation_deg"] < 2e-5


@pytest.mark.parametrize("turns", ["--output-lead", "--no-output-lead"])
def test_demo_as_fast_as_possible_runs_in_lockstep(tmp_path, turns):
    """--real-time-factor 0: the simulator waits for each control period's output and the
    controller keeps its ticks on the period grid, so sampling is synchronous and the base
    stays within 2e-5 deg (1.6-1.9e-6 measured with /clock every 1 ms step; the 20 s scenario
    now matches the in-process loop). Free-running it turned 1.7e-2 deg; with commands served
    between ticks, 4e-4 deg. Side by side (the default) and in turn alike."""
    _, rows = _short_demo(
        tmp_path, "--no-record", "--real-time-factor", "0", "--methods", "dls", turns
    )
    row = rows["dls"]
    assert row["max_base_deviation_deg"] < 2e-5
    if turns == "--output-lead":
        # the controller serves each tick with the operator's sample in force then (published
        # ahead, await_commands): the camera ends where the in-process loop puts it (4.6e-6
        # against 4.4e-6 deg, the same in every run). Twists acting on receipt ended 0.057 and
        # 0.078 deg off, and on the 180 deg roll 1-19 deg off in about one run in thirty,
        # when the operator's process waited for a core at the start of its profile
        assert row["final_camera_error_deg"] < 1e-4
    else:
        # in turn the twist and the tick fall on the same simulated instant, and the twist may
        # land before or after the tick, which moves when a command is served by a period
        # (measured 0.057 and 0.078 deg of a 30 deg roll, 0.86 deg beside two busy loops and a
        # second stack, where the operator's process waits for a core). That depends on
        # scheduling, so only the base is held to a bound (every output is reactionless
        # whatever command it serves); the camera still turns most of the 30 deg roll
        assert row["final_camera_error_deg"] < 15.0


def test_conventional_with_wheels_costs_orders_of_magnitude_more_energy(tmp_path):
    """Thesis chapter 5 over DDS: the conventional controller with rns_attitude_control and
    reaction wheels against reactionless DLS. The Lambda cost (5.12) of the conventional motion
    is dominated by the wheel term; the reactionless motion's is the arm's alone. The wheels
    really spin (their kinetic energy is measured by the simulator), and the saturation time
    of the 0.1 N m wheels is reported."""
    _, rows = _short_demo(tmp_path, "--no-record", "--methods", "dls,conventional+wheels")
    dls, wheels = rows["dls"]["energy"], rows["conventional+wheels"]["energy"]
    print(f"dls {dls}\nconventional+wheels {wheels}")
    assert dls["peak_wheel_energy"] == 0.0
    assert dls["wheel_saturation_s"] is None
    assert wheels["peak_wheel_energy"] > 0.0
    assert 0.0 <= wheels["wheel_saturation_s"] <= 3.5
    assert wheels["c_max"] > 100.0 * dls["c_max"]
    assert wheels["c_sum"] > 100.0 * dls["c_sum"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--methods", "magic"], "--methods for satellite_observation must be"),
        (["--rate", "0"], "--rate must be in"),
        (["--real-time-factor", "-1"], "--real-time-factor must be in"),
        (["--wall-clock", "--real-time-factor", "0"], "--wall-clock runs at real-time factor 1"),
        (["--wall-clock", "--scenario", "wall_contact"], "--wall-clock is for the inspection"),
        (["--sim-step", "0.003"], "--sim-step must divide the control period 1/rate = 0.01 s"),
        (["--sim-step", "0.2", "--rate", "1"], "and lie in [1e-05, 0.1] s, got 0.2"),
    ],
)
def test_demo_rejects_bad_arguments(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_demo_checks_its_output_paths_before_the_runs(tmp_path, capsys):
    """A summary or a recording folder that cannot be written is a usage error at start-up
    (exit 2, naming the path), not a traceback after the task."""
    missing = tmp_path / "no" / "such" / "s.json"
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    cases = [
        (
            ["--summary", str(missing), "--no-record"],
            f"its folder {str(missing.parent)!r} does not",
        ),
        (["--summary", str(tmp_path), "--no-record"], "is a folder, not a file"),
        (["--output", str(blocker / "rec")], f"{str(blocker)!r} is a file"),
    ]
    for argv, message in cases:
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert exit_info.value.code == 2
        err = capsys.readouterr().err
        assert message in err, err
        assert "running" not in err


def test_demo_reports_an_unknown_scenario(capsys):
    assert main(["--scenario", "nowhere", "--no-record"]) == 2
    assert "neither a file nor one of" in capsys.readouterr().err


def _no_dds(*_args, **_kwargs):
    raise AssertionError("a DDS stack was started")


def test_demo_refuses_a_scenario_faster_than_the_controller_before_any_run(
    tmp_path, monkeypatch, capsys
):
    """Such a scenario used to run: the controller rejected every command and the table came
    out with NaN / inf figures, exit code 0."""
    monkeypatch.setattr(inspection, "Harness", _no_dds)
    fast = {**SHORT_ROLL_SCENARIO, "name": "quick_roll", "angle_deg": 180.0, "duration": 2.0}
    scenario = tmp_path / "fast.yaml"
    scenario.write_text(yaml.safe_dump(fast))
    assert main(["--scenario", str(scenario), "--no-record", "--domain-id", DOMAIN]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    # 180 deg in 2 s, quintic: 15/8 * pi / 2 s = 2.945 rad/s against the default 1 rad/s
    assert "'quick_roll'" in lines[0]
    assert "2.945 rad/s" in lines[0]
    assert "max_angular_speed 1 rad/s" in lines[0]
    assert "running" not in captured.out


def _figures(**changes) -> RunFigures:
    values = {
        "max_base_deviation_deg": 1e-3,
        "final_camera_error_deg": 0.05,
        "rms_tracking_error": 1e-3,
        "max_wrist_drift_m": 0.5,
        "max_joint_speed": 0.3,
        "angular_momentum_drift": 1e-13,
        "samples": 400,
        "min_sigma": 0.4,
        "singular_time_s": 0.0,
    }
    return RunFigures(**{**values, **changes})


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_demo_fails_on_non_finite_figures(tmp_path, monkeypatch, capsys, bad):
    def fake_run(method, _args, _file):
        changes = {"final_camera_error_deg": bad} if method == "sc" else {}
        return DemoRow(method, _figures(**changes), 1.0, None)

    monkeypatch.setattr(demo, "run_method", fake_run)
    summary = tmp_path / "summary.json"
    argv = ["--no-record", "--summary", str(summary), "--domain-id", DOMAIN]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert f"sc: final_camera_error_deg = {bad}" in err
    assert "dls" not in err
    assert not summary.exists()  # NaN is not JSON: no summary that looks like a result


def test_demo_with_finite_figures_exits_0(tmp_path, monkeypatch):
    monkeypatch.setattr(demo, "run_method", lambda m, _a, _f: DemoRow(m, _figures(), 1.0, None))
    summary = tmp_path / "summary.json"
    assert main(["--no-record", "--summary", str(summary), "--domain-id", DOMAIN]) == 0
    assert [row["method"] for row in json.loads(summary.read_text())] == [
        "dls",
        "sc",
        "conventional",
    ]


def test_runs_report_the_spread_of_the_base_deviation(tmp_path, monkeypatch, capsys):
    """--runs 3: every method three times; the min / median / max of each method's max base
    deviation come from its own runs (printed and in --summary)."""
    deviations = iter([1e-5, 3e-5, 4e-5, 9e-5, 2e-5, 6e-5])  # dls, sc per run

    def fake_run(method, _args, _file):
        return DemoRow(method, _figures(max_base_deviation_deg=next(deviations)), 1.0, None)

    monkeypatch.setattr(demo, "run_method", fake_run)
    summary = tmp_path / "summary.json"
    argv = ["--no-record", "--methods", "dls,sc", "--runs", "3", "--summary", str(summary)]
    assert main([*argv, "--domain-id", DOMAIN]) == 0
    rows = {row["method"]: row["runs"] for row in json.loads(summary.read_text())}
    assert rows["dls"]["values"] == [1e-5, 4e-5, 2e-5]
    assert (rows["dls"]["min"], rows["dls"]["median"], rows["dls"]["max"]) == (1e-5, 2e-5, 4e-5)
    assert (rows["sc"]["min"], rows["sc"]["median"], rows["sc"]["max"]) == (3e-5, 6e-5, 9e-5)
    assert "over 3 runs" in capsys.readouterr().out


def test_runs_report_the_task_wall_time_and_its_real_time_factor(tmp_path, monkeypatch, capsys):
    """The task's own wall time (start-up excluded) and simulated s per wall s, per run and
    over the runs; a run that did not measure it shows dashes."""
    walls = iter([2.0, 4.0, 3.0])

    def fake_run(method, _args, _file):
        return DemoRow(method, _figures(), 9.0, None, task_wall_s=next(walls), task_sim_s=21.3)

    monkeypatch.setattr(demo, "run_method", fake_run)
    summary = tmp_path / "summary.json"
    argv = ["--no-record", "--methods", "dls", "--runs", "3", "--summary", str(summary)]
    assert main([*argv, "--domain-id", DOMAIN]) == 0
    (row,) = json.loads(summary.read_text())
    assert (row["task_wall_s"], row["task_sim_s"]) == (3.0, 21.3)  # the last run
    assert row["task_wall_runs"]["median"] == 3.0
    assert DemoRow(
        "dls", _figures(), 9.0, None, task_wall_s=3.0, task_sim_s=21.3
    ).real_time_factor == pytest.approx(7.1)
    assert DemoRow("dls", _figures(), 9.0, None).real_time_factor is None
    out = capsys.readouterr().out
    assert "7.10" in out  # x real time of the last run in the table
    assert "over 3 runs" in out


@pytest.mark.parametrize("argv", [["--runs", "0"], ["--runs", "2", "--scenario", "wall_contact"]])
def test_bad_runs_are_rejected(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--no-record", "--domain-id", DOMAIN])
    assert exit_info.value.code == 2
    assert "--runs" in capsys.readouterr().err


def test_a_method_whose_recording_came_out_partial_is_run_again(capsys):
    """In lockstep a run is repeatable: a partial recording (this process stalled) runs that
    method again, up to PARTIAL_RETRIES times, then fails with the reason."""
    from rns_ros.apps import demo
    from rns_ros.runs.recorded import PartialRecordingError

    calls = []

    def flaky(method, fails):
        calls.append(method)
        if len(calls) <= fails:
            raise PartialRecordingError(f"{method}: this process missed 2 robot states")
        return method

    assert demo._run_complete(lambda m: flaky(m, 1), "dls") == "dls"
    assert calls == ["dls", "dls"]
    assert "missed 2 robot states: running dls again" in capsys.readouterr().out
    calls.clear()
    with pytest.raises(PartialRecordingError):
        demo._run_complete(lambda m: flaky(m, demo.PARTIAL_RETRIES + 1), "sc")
    assert len(calls) == demo.PARTIAL_RETRIES + 1


def test_a_constant_rate_scenario_runs_and_its_singular_region_is_said(tmp_path, capfd):
    """Fig. 4.6's scenario turns at a constant rate from its first sample (no quintic ramp at
    zero), so a recorder that missed the start would see it move at once; and it crosses the
    algorithmic singularity, where DLS lets the camera fall behind: the table's line says so."""
    summary = tmp_path / "summary.json"
    argv = ["--scenario", "algorithmic_singularity", "--methods", "dls", "--no-record"]
    argv += ["--real-time-factor", "0", "--summary", str(summary), "--domain-id", DOMAIN]
    assert main(argv) == 0
    out = capfd.readouterr().out
    (row,) = json.loads(summary.read_text())
    assert row["min_sigma"] < 0.2  # epsilon: it went through the singular region
    assert row["singular_time_s"] > 0.5
    assert row["max_base_deviation_deg"] < 1e-4
    said = r"note: dls: the camera ends [\d.]+ deg off its target: [\d.]+ s in the singular region"
    assert re.search(said, out), out


def test_an_interrupted_run_keeps_its_figures_so_far_and_exits_130(monkeypatch, capsys):
    """Ctrl-C during sc: dls's figures and sc's so far (marked), no conventional run, one
    line, exit code 128 + SIGINT."""
    from rns_ros.runs.recorded import InterruptedRun

    ran = []

    def fake_run(method, _args, _file):
        ran.append(method)
        if method == "sc":
            row = DemoRow(method, _figures(), 1.0, None, ended="interrupted 3.0 s into the task")
            raise InterruptedRun(KeyboardInterrupt(), row, [])
        return DemoRow(method, _figures(), 1.0, None)

    monkeypatch.setattr(demo, "run_method", fake_run)
    assert main(["--no-record", "--domain-id", DOMAIN]) == 130
    assert ran == ["dls", "sc"]
    out, err = capsys.readouterr()
    rows = [line.split()[:2] for line in out.splitlines() if line.startswith(("dls", "sc"))]
    assert rows[-2:] == [["dls", "1.000e-03"], ["sc", "*"]]
    assert err.splitlines()[-2:] == [
        "rns_demo: sc: interrupted 3.0 s into the task",
        "rns_demo: interrupted (Ctrl-C)",
    ]


def test_sigterm_before_a_task_started_exits_143(monkeypatch, capsys):
    from rns_ros.cli import Interrupted
    from rns_ros.runs.recorded import InterruptedRun

    def fake_run(method, _args, _file):
        if method == "sc":
            raise InterruptedRun(Interrupted(signal.SIGTERM), None, [])
        return DemoRow(method, _figures(), 1.0, None)

    monkeypatch.setattr(demo, "run_method", fake_run)
    assert main(["--no-record", "--domain-id", DOMAIN]) == 128 + signal.SIGTERM
    out, err = capsys.readouterr()
    assert any(line.startswith("dls ") for line in out.splitlines())
    assert err.splitlines()[-2:] == [
        "rns_demo: sc: stopped by SIGTERM; no figures of this run",
        "rns_demo: stopped by SIGTERM",
    ]


def test_a_recording_that_could_not_be_written_is_said_and_exits_1(monkeypatch, capsys):
    lost = "cannot write /x/dls: No space left on device; the bag is removed"

    def fake_run(method, _args, _file):
        return DemoRow(method, _figures(), 1.0, None, unwritten=(lost,) if method == "dls" else ())

    monkeypatch.setattr(demo, "run_method", fake_run)
    assert main(["--no-record", "--domain-id", DOMAIN]) == 1
    out, err = capsys.readouterr()
    assert [line.split()[0] for line in out.splitlines() if line.startswith(("dls", "sc", "conv"))][
        -3:
    ] == ["dls", "sc", "conventional"]
    assert err.splitlines() == [f"rns_demo: {lost}"]
