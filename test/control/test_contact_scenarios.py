"""Part II scenario files: the shipped ones are the reproduced thesis tasks; loading validates;
the operator's samples are the scenario's references."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from rns_ros.control.contact_scenarios import (
    MotionForceScenario,
    ScenarioKind,
    Task,
    load_contact_scenario,
    load_motion_force_scenario,
    load_operator_scenario,
    operator_sample,
    scenario_kind,
)
from rns_ros.control.contact_tasks import ArcScenario, WallScenario
from rns_ros.control.scenario import Scenario
from rns_ros.core.errors import ConfigError
from rns_ros.resources import config_dir

SCENARIOS = config_dir() / "scenarios"


def _write(tmp_path, content, name="part2.yaml"):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(content))
    return path


def test_shipped_wall_is_the_fig6_7_task():
    scenario = load_motion_force_scenario(SCENARIOS / "wall_contact.yaml")
    assert isinstance(scenario, MotionForceScenario)
    assert scenario.task is Task.WALL
    assert scenario.name == "wall_contact"
    # rns_reproduce's fig6.7/fig6.8 run WallScenario() (reproduce/chapter6.py)
    assert scenario.spec == WallScenario()
    assert (scenario.spec.strokes, scenario.spec.stroke) == (4, 2.5)
    assert (scenario.spec.force, scenario.spec.force_ramp) == (10.0, 1.0)
    assert scenario.duration == 10.0
    assert scenario.setup.name == "lwr_wall"
    assert scenario.setup.description == WallScenario().setup().description


def test_shipped_arc_is_the_fig6_3_task():
    scenario = load_motion_force_scenario(SCENARIOS / "planar_arc.yaml")
    assert scenario.task is Task.ARC
    assert scenario.spec == ArcScenario()
    assert scenario.duration == pytest.approx(3.2)
    assert scenario.setup.description == ArcScenario().setup().description
    np.testing.assert_array_equal(scenario.setup.initial_q, ArcScenario().setup().initial_q)


def test_contact_scenario_is_the_dataclass():
    assert load_contact_scenario(SCENARIOS / "wall_contact.yaml") == WallScenario()
    assert load_contact_scenario(SCENARIOS / "planar_arc.yaml") == ArcScenario()


def test_kind_dispatch_keeps_part1_files_part1():
    part1 = SCENARIOS / "satellite_observation.yaml"
    assert scenario_kind(part1) is ScenarioKind.CAMERA_ROTATION
    assert isinstance(load_operator_scenario(part1), Scenario)
    wall = SCENARIOS / "wall_contact.yaml"
    assert scenario_kind(wall) is ScenarioKind.MOTION_FORCE
    assert isinstance(load_operator_scenario(wall), MotionForceScenario)


def test_fields_override_the_defaults(tmp_path):
    path = _write(tmp_path, {"kind": "motion_force", "task": "wall", "strokes": 1,
                             "stroke": 1.0, "length": 0.1, "name": "short"})  # fmt: skip
    scenario = load_motion_force_scenario(path)
    assert scenario.name == "short"
    assert scenario.spec == WallScenario(strokes=1, stroke=1.0, length=0.1)
    end = scenario.setup.reference(1.0).position - scenario.setup.reference(0.0).position
    assert np.linalg.norm(end) == pytest.approx(0.1, abs=1e-12)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ({"task": "wall", "speed": 1.0}, r"unknown key\(s\) \['speed'\]"),
        # an arc field is unknown to the wall task, and the other way round
        ({"task": "wall", "half_cycle": 1.0}, r"unknown key\(s\) \['half_cycle'\]"),
        ({"task": "arc", "strokes": 2}, r"unknown key\(s\) \['strokes'\]"),
        ({"task": "plane"}, r"motion_force task must be one of \['wall', 'arc'\], got 'plane'"),
        ({}, "missing key 'task'"),
        ({"task": "wall", "stroke": -2.5}, r"stroke must be a finite number > 0 \[s\], got -2.5"),
        ({"task": "wall", "strokes": 0}, "strokes must be an integer >= 1, got 0"),
        ({"task": "wall", "strokes": 2.5}, "strokes must be an integer >= 1, got 2.5"),
        ({"task": "wall", "force": -1.0}, r"force must be finite and >= 0 \[N\], got -1.0"),
        ({"task": "arc", "force_ramp": 0.0}, r"force_ramp must be a finite number > 0 \[s\]"),
        (
            {"task": "arc", "radius": "big"},
            "radius must be a number or a list of numbers, got 'big'",
        ),
        ({"task": "arc", "half_cycles": True}, "half_cycles must be a number, got True"),
        ({"task": "arc", "centripetal": 1}, "centripetal must be true or false, got 1"),
        ({"task": "arc", "start_angle_deg": 270.0}, "must differ, both are 270.0 deg"),
        ({"task": "wall", "initial_deg": [0, 0]}, r"initial_deg must be 7 finite numbers"),
        ({"task": "wall", "normal": [0, 0, 0]}, r"wall normal must be non-zero, got \[0, 0, 0\]"),
        (
            {"task": "wall", "normal": [1, 0, 0], "direction": [2, 0, 0]},
            "wall stroke direction",
        ),
        ({"task": "wall", "model": "nope.yaml"}, "nope.yaml"),
    ],
)
def test_bad_files_are_config_errors_naming_the_key_or_value(tmp_path, content, message):
    path = _write(tmp_path, {"kind": "motion_force", **content})
    with pytest.raises(ConfigError, match=message) as error:
        load_motion_force_scenario(path)
    assert str(path) in str(error.value)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ({"kind": "teleport"}, r"scenario kind must be one of .*got 'teleport'"),
        ("just text", "expected a mapping"),
    ],
)
def test_bad_kind_is_a_config_error(tmp_path, content, message):
    with pytest.raises(ConfigError, match=message):
        load_operator_scenario(_write(tmp_path, content))


def test_missing_kind_is_named_by_the_motion_force_loader(tmp_path):
    with pytest.raises(ConfigError, match="missing key 'kind'"):
        load_motion_force_scenario(_write(tmp_path, {"task": "wall"}))
    with pytest.raises(ConfigError, match="scenario file not found"):
        load_motion_force_scenario(tmp_path / "absent.yaml")


@pytest.mark.parametrize("name", ["wall_contact", "planar_arc"])
def test_operator_samples_are_the_reference_and_integrate_to_it(name):
    scenario = load_motion_force_scenario(SCENARIOS / f"{name}.yaml")
    setup = scenario.setup
    t = np.linspace(0.0, scenario.duration, 20001)
    samples = [operator_sample(setup, ti) for ti in t]
    v = np.array([s.linear for s in samples])
    # the velocity integrates to the reference path (Simpson-exact to the quintic's smoothness)
    path = np.array([setup.reference(ti).position for ti in t])
    integral = np.concatenate(
        [np.zeros((1, 3)), np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t)[:, None], axis=0)]
    )
    np.testing.assert_allclose(integral, path - path[0], atol=1e-6)
    for ti, sample in zip(t[::500], samples[::500], strict=True):
        assert np.all(sample.angular == 0.0)
        assert sample.force == setup.force(ti)
        normal = setup.constraint.gradient(setup.reference(ti).position)
        np.testing.assert_array_equal(sample.normal, normal)
        np.testing.assert_allclose(np.linalg.norm(sample.force_vector), sample.force, atol=1e-12)
    # the force ramps 0 -> 10 N over 1 s, then holds; the arc normal points to the axis
    assert samples[0].force == 0.0
    assert samples[-1].force == pytest.approx(10.0, abs=1e-12)
    if name == "planar_arc":
        p = setup.reference(0.8).position
        to_axis = np.array([1.91, 1.91, 0.0]) - p
        np.testing.assert_allclose(
            operator_sample(setup, 0.8).normal, to_axis / np.linalg.norm(to_axis), atol=1e-12
        )
    # after the profile: at rest, force held
    late = operator_sample(setup, scenario.duration + 5.0)
    assert np.all(late.linear == 0.0)
    assert late.force == samples[-1].force


def test_operator_sample_rejects_a_non_finite_time():
    setup = load_motion_force_scenario(SCENARIOS / "wall_contact.yaml").setup
    with pytest.raises(Exception, match="profile time must be finite"):
        operator_sample(setup, float("nan"))
