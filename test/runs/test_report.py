"""rns_ros.runs.report: the demo's table marks a run that ended early, and a camera that ends off
its target gets one line saying whether the singular region is why."""

from __future__ import annotations

from rns_ros.analysis.recorded_run import RunFigures
from rns_ros.runs.inspection import DemoRow
from rns_ros.runs.report import CAMERA_OFF_DEG, camera_notes, format_table


def _row(
    method,
    camera_deg,
    singular_s=0.0,
    min_sigma=0.5,
    ended=None,
    products=(None, None),
    commanded_deg=None,
):
    figures = RunFigures(
        max_base_deviation_deg=1e-6,
        final_camera_error_deg=camera_deg,
        rms_tracking_error=1e-3,
        max_wrist_drift_m=0.01,
        max_joint_speed=0.3,
        angular_momentum_drift=1e-15,
        samples=100,
        min_sigma=min_sigma,
        singular_time_s=singular_s,
        min_singular_product=products[0],
        max_singular_product=products[1],
        commanded_camera_error_deg=commanded_deg,
    )
    return DemoRow(method, figures, 1.0, None, ended=ended)


def test_a_camera_off_its_target_is_explained_once():
    rows = [
        _row("dls", 25.0, singular_s=6.2, min_sigma=1.7e-4),
        _row("sc", 3.0),
        _row("pinv", CAMERA_OFF_DEG / 2),  # on target: nothing to say
        _row("conventional", 30.0, ended="joint_2 reached its upper limit 1 rad at t = 2.00 s"),
    ]
    notes = camera_notes(rows, 0.2)
    assert len(notes) == 2
    assert notes[0].startswith("dls: the camera ends 25 deg off its target: 6.20 s in the singular")
    assert "sigma_min of J-bar down to 0.00017 < 0.2" in notes[0]
    assert notes[1].startswith("sc: the camera ends 3 deg off its target with sigma_min")
    assert "not a singular region" in notes[1]
    # the same run with the joints at their 0.3 rad/s speed limit
    (speed,) = camera_notes([rows[1]], 0.2, speed_limit=0.3)
    assert speed.startswith("sc: the camera ends 3 deg off its target: the joint rates reached")


def test_an_sc_camera_off_because_of_its_speed_scale_says_so():
    # xArm7's roll: sigma_min >= 0.63, prod(sigma) 0.69 to 1.02, b = 1.7: SC turns the camera
    # 1.17 to 1.74 times as fast as commanded and ends 61 deg off the 180 deg roll
    row = _row("sc", 61.2, min_sigma=0.63, products=(0.6866, 1.0231))
    (note,) = camera_notes([row], 0.2, sc_gain=1.7)
    assert note.startswith("sc: the camera ends 61.2 deg off its target: SC scales the")
    assert "1.2 to 1.7 here (1: as commanded), so the camera turns faster than commanded" in note
    (slow,) = camera_notes([_row("sc", 9.0, products=(0.2, 0.5))], 0.2, sc_gain=1.7)
    assert "so the camera turns slower than commanded" in slow
    # a scale within 10 % of 1 explains nothing: the generic line
    (other,) = camera_notes([_row("sc", 9.0, products=(0.56, 0.62))], 0.2, sc_gain=1.7)
    assert "not a singular region; see the RMS" in other


def test_a_camera_on_what_the_operator_sent_puts_the_error_on_the_operators_stream():
    """1.14 deg off the scenario's target, 0.003 deg off what the recorded twists add up to
    (an operator that waited for a core on the wall clock): the stream fell short, not the
    control; a camera off both gets the generic line."""
    (note,) = camera_notes([_row("dls", 1.14, commanded_deg=0.003)], 0.2)
    assert note.startswith("dls: the camera ends 1.14 deg off its target but 0.003 deg off")
    assert "the operator's stream fell short of the scenario" in note
    (other,) = camera_notes([_row("dls", 1.14, commanded_deg=1.1)], 0.2)
    assert "not a singular region; see the RMS" in other


def test_the_table_marks_a_run_that_ended_early_and_shows_the_singular_figures():
    table = format_table(
        [_row("dls", 0.1, singular_s=1.25, min_sigma=0.031), _row("sc", 9.0, ended="x")]
    )
    lines = table.splitlines()
    assert "min σ(J̄)" in lines[0]
    assert "sing. [s]" in lines[0]
    dls = next(line for line in lines if line.startswith("dls "))
    assert "0.031" in dls
    assert "1.25" in dls
    assert any(line.startswith("sc *") for line in lines)
    assert lines[-1] == "* ended before the task's end: the figures up to then"
