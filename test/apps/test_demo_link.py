"""rns_demo --link-delay: the scripted operator on the ground behind a delayed link (rns_link),
the controller acting each twist at its stamp + the execution delay, the predictive display
(rns_predictor) measured against what the spacecraft did."""

from __future__ import annotations

import json
import os
import re

import pytest

from rns_ros.apps.demo import main
from rns_ros.viz import paths
from rns_ros.viz.readback import read_components

# this file's own domain (the DDS run below), apart from the other demo tests'
DOMAIN = str(int(os.environ.get("ROS_DOMAIN_ID", "43")) + 5)


def test_behind_a_one_second_link_the_turn_is_reactionless_and_the_prediction_exact(
    tmp_path, capfd
):
    summary = tmp_path / "summary.json"
    argv = ["--link-delay", "1", "--methods", "dls", "--real-time-factor", "0"]
    argv += ["--output", str(tmp_path), "--summary", str(summary), "--domain-id", DOMAIN]
    assert main(argv) == 0, capfd.readouterr()
    (row,) = json.loads(summary.read_text())
    assert row["link_delay_s"] == 1.0
    # the thesis' roll: the satellite held, the camera on target, as without the link
    assert row["max_base_deviation_deg"] < 1e-4
    assert row["final_camera_error_deg"] < 0.5
    # the same model and law on the ground: the prediction is the spacecraft's motion
    assert row["prediction_error_deg"] < 1e-6
    assert "pred. err [deg]" in capfd.readouterr().out
    # the recording shows the predicted and the received telemetry arms beside the real one
    for path in (paths.PREDICTED_ARM, paths.TELEMETRY_ARM):
        strips = [r for r in read_components(row["recording"], path) if "LineStrips3D:strips" in r]
        assert len(strips) > 100, path


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--link-delay", "-1"], r"--link-delay must be in \[0, 600\] s, got -1"),
        (["--link-delay", "1", "--link-loss", "0.9"], r"--link-loss must be in \[0, 0\.5\]"),
        (["--link-jitter", "0.1"], "--link-jitter and --link-loss need --link-delay"),
        (["--link-delay", "1", "--scenario", "wall_contact"], "for the inspection scenarios"),
    ],
)
def test_bad_link_options_are_usage_errors(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert re.search(message, capsys.readouterr().err)
