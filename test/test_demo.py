"""The interim main job runs end to end and its figures agree with the core's physics."""

from __future__ import annotations

import json

import pytest

from rns_ros.demo import main


def test_demo_compares_conventional_and_reactionless(tmp_path, capsys):
    summary = tmp_path / "summary.json"
    assert main(["--duration", "4", "--dt", "0.02", "--summary", str(summary)]) == 0
    rows = {row["method"]: row for row in json.loads(summary.read_text())}
    conventional, reactionless = rows["conventional"], rows["reactionless"]
    assert conventional["max_base_attitude_deviation_deg"] > 1e-2
    assert reactionless["max_base_attitude_deviation_deg"] < 1e-9
    assert reactionless["max_coupling_angular_momentum_kgm2_s"] < 1e-9
    assert conventional["max_positioning_joint_speed_rad_s"] == 0.0  # eq. (4.8)
    # both sweep the wrist by the same joint angles, so the camera turns by a similar amount
    assert reactionless["camera_rotation_deg"] == pytest.approx(
        conventional["camera_rotation_deg"], rel=0.1
    )
    assert "reactionless" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [(["--duration", "0"], "--duration must be in"), (["--dt", "1"], "--dt must be in")],
)
def test_demo_rejects_bad_arguments(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_demo_reports_bad_model_file(tmp_path, capsys):
    bad = tmp_path / "model.yaml"
    bad.write_text("urdf: missing.urdf\n")
    assert main(["--model", str(bad), "--duration", "1"]) == 2
    assert "URDF file not found" in capsys.readouterr().err
