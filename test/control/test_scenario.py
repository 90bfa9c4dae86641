"""Scenario files: validation names the bad key; the profiles integrate to the commanded angle."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import yaml

from rns_ros.control.scenario import TimeScaling, check_speed_limit, load_scenario
from rns_ros.core import ConfigError
from rns_ros.resources import config_dir, scenario_path

#: The shipped Part I scenario files (Part II files say ``kind: motion_force``: their own loader,
#: rns_ros.control.contact_scenarios).
CAMERA_ROTATION_FILES = [
    path
    for path in sorted((config_dir() / "scenarios").glob("*.yaml"))
    if yaml.safe_load(path.read_text()).get("kind", "camera_rotation") == "camera_rotation"
]

BASE = {
    "initial_joint_positions_deg": [0, 10, 0, 20, 0, 30, 0],
    "axis": [0, 0, 2],
    "angle_deg": 90.0,
    "duration": 4.0,
}


def _write(tmp_path, **changes):
    content = {**BASE, **changes}
    content = {key: value for key, value in content.items() if value is not None}
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(content))
    return path


@pytest.mark.parametrize("path", CAMERA_ROTATION_FILES)
def test_shipped_scenarios_load(path):
    scenario = load_scenario(path)
    assert scenario.name == path.stem
    assert scenario.initial_theta.shape == (7,)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"speed": 1.0}, r"unknown key\(s\) \['speed'\]"),
        ({"axis": [0, 0, 0]}, "'axis' must be non-zero"),
        ({"axis": [1, 0]}, "axis must have shape"),
        ({"duration": 0.0}, "'duration' must be > 0"),
        ({"duration": None}, r"missing key\(s\) \['duration'\]"),
        ({"frame": "map"}, "twist frame must be one of"),
        ({"time_scaling": "cubic"}, "time_scaling must be one of"),
        ({"controller": {"gain": 1.0}}, r"controller: unknown key\(s\) \['gain'\]"),
        ({"controller": {"method": "magic"}}, "method must be one of"),
        ({"controller": {"wrist_gain": -1.0}}, "wrist_gain"),
        ({"time_scaling": "piecewise"}, "'segments' is required"),
        ({"time_scaling": "piecewise", "segments": [[1, 0.5], [2, 0.5]]}, "sum to 3.0 s"),
        ({"time_scaling": "piecewise", "segments": [[2, 0.5], [2, 0.6]]}, "fractions sum"),
        ({"time_scaling": "piecewise", "segments": [[4, "x"]]}, "pairs"),
        (
            {"controller": {"max_angular_speed": 0.0}},
            "max_angular_speed must be a finite number > 0",
        ),
    ],
)
def test_bad_scenarios_name_the_key(tmp_path, changes, message):
    with pytest.raises(ConfigError, match=message):
        load_scenario(_write(tmp_path, **changes))


@pytest.mark.parametrize(
    ("scaling", "segments"),
    [("quintic", None), ("constant", None), ("piecewise", [[1.0, 0.25], [1.5, 0.0], [1.5, 0.75]])],
)
def test_profiles_integrate_to_the_angle_about_the_unit_axis(tmp_path, scaling, segments):
    scenario = load_scenario(_write(tmp_path, time_scaling=scaling, segments=segments))
    assert scenario.time_scaling is TimeScaling(scaling)
    assert np.allclose(scenario.axis, [0, 0, 1])
    dt = 1e-4
    times = np.arange(0.0, 5.0, dt) + dt / 2  # midpoint rule, past the end too
    rates = np.array([scenario.angular_velocity(t) for t in times])
    assert np.allclose(rates.sum(axis=0) * dt, [0, 0, np.pi / 2], atol=1e-6)
    # s(t) is the integral of s_dot(t)
    s_values = np.array([scenario.progress(t)[0] for t in times])
    s_dots = np.array([scenario.progress(t)[1] for t in times])
    assert np.allclose(np.cumsum(s_dots) * dt, s_values, atol=2e-3)


def test_target_rotation_per_frame():
    scenario = load_scenario(scenario_path("own_device_inspection"))
    camera_0 = pin.exp3(np.array([0.3, -0.2, 0.1]))
    base_0 = pin.exp3(np.array([0.0, 0.4, 0.0]))
    turn = pin.exp3(scenario.angle * scenario.axis)
    assert np.allclose(scenario.target_rotation(camera_0, base_0, 99.0), turn @ camera_0)
    assert np.allclose(scenario.target_rotation(camera_0, base_0, 0.0), camera_0)


def test_scenario_path_resolves_names_and_lists_the_shipped_ones(tmp_path):
    assert scenario_path("satellite_observation").name == "satellite_observation.yaml"
    path = _write(tmp_path)
    assert scenario_path(path) == path
    with pytest.raises(ConfigError, match="algorithmic_singularity"):
        scenario_path("nowhere")


@pytest.mark.parametrize(
    ("scaling", "segments", "expected"),
    [
        ("quintic", None, 15 / 8 * np.pi / 2 / 4.0),  # 90 deg in 4 s: 0.589 rad/s at t = 2 s
        ("constant", None, np.pi / 2 / 4.0),
        ("piecewise", [[1.0, 0.25], [1.5, 0.0], [1.5, 0.75]], 0.75 * np.pi / 2 / 1.5),
    ],
)
def test_peak_angular_speed_is_the_largest_commanded_speed(tmp_path, scaling, segments, expected):
    scenario = load_scenario(_write(tmp_path, time_scaling=scaling, segments=segments))
    assert scenario.peak_angular_speed() == pytest.approx(expected, rel=1e-12)
    sampled = max(np.linalg.norm(scenario.angular_velocity(t)) for t in np.linspace(0.0, 4.0, 4001))
    assert sampled == pytest.approx(expected, rel=1e-6)  # reached (t = 2 s is on the grid) ...
    assert sampled <= expected * (1 + 1e-12)  # ... and never exceeded


def test_negative_angles_peak_at_their_magnitude(tmp_path):
    scenario = load_scenario(_write(tmp_path, angle_deg=-90.0))
    assert scenario.peak_angular_speed() == pytest.approx(15 / 8 * np.pi / 2 / 4.0)


@pytest.mark.parametrize("path", CAMERA_ROTATION_FILES)
def test_shipped_scenarios_stay_within_the_default_controller_limit(path):
    scenario = load_scenario(path)
    assert check_speed_limit(scenario, 1.0) == 1.0
    assert scenario.peak_angular_speed() < 1.0


def test_a_scenario_faster_than_the_controller_is_a_config_error(tmp_path):
    # 180 deg in 2 s, quintic: 15/8 * pi / 2 = 2.945 rad/s
    scenario = load_scenario(_write(tmp_path, name="quick_flip", angle_deg=180.0, duration=2.0))
    with pytest.raises(ConfigError) as error:
        check_speed_limit(scenario, 1.0)
    message = str(error.value)
    assert "'quick_flip'" in message
    assert "peak angular speed 2.945 rad/s" in message
    assert "max_angular_speed 1 rad/s" in message
    assert "at least 5.89 s" in message  # 2 s * 2.945 / 1.0: exactly at the limit
    slow = load_scenario(_write(tmp_path, angle_deg=180.0, duration=5.9))
    assert check_speed_limit(slow, 1.0) == 1.0


def test_the_scenario_override_of_max_angular_speed_is_the_limit(tmp_path):
    fast = _write(tmp_path, angle_deg=180.0, duration=2.0, controller={"max_angular_speed": 3.0})
    scenario = load_scenario(fast)
    assert check_speed_limit(scenario, 1.0) == 3.0
    assert scenario.gains().wrist_gain == 100.0  # not a gain: gains() ignores it
    strict = load_scenario(_write(tmp_path, controller={"max_angular_speed": 0.5}))
    with pytest.raises(ConfigError, match=r"max_angular_speed 0\.5 rad/s"):
        check_speed_limit(strict, 1.0)  # 0.589 rad/s > 0.5
