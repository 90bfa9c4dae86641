"""rns_ros.observer: argument errors are reported before any waiting (the DDS part is covered by
test_two_hosts.py)."""

from __future__ import annotations

import pytest

from rns_ros import observer


def test_unknown_scenario_is_reported_at_once(capsys):
    assert observer.main(["--scenario", "no_such_scenario", "--wait", "30"]) == 2
    assert "no_such_scenario" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [(["--domain-id", "200"], "--domain-id must be in [0, 101]"), (["--idle", "-1"], "--idle")],
)
def test_bad_numbers_name_the_option(argv, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        observer.parse_args(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_static_peer_environment_is_the_two_computer_recipe():
    env = observer.static_peer_environment(7, ["192.0.2.1", "robot.local"], base={})
    assert env["ROS_DOMAIN_ID"] == "7"
    assert env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert env["ROS_STATIC_PEERS"] == "192.0.2.1;robot.local"
