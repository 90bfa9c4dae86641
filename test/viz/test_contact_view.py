"""ContactRecorder (Part II, fixed-base arm in contact) into .rrd files, read back (no DDS)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from rerun.chunk import RrdReader

from rns_ros.control.contact_topics import CONTACT_LABELS, ERROR_LABELS
from rns_ros.core import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState, load_fixed_base_model
from rns_ros.core.model import FreeFloatingModel
from rns_ros.resources import default_model_config
from rns_ros.viz import RecorderSettings, SinkSettings, paths
from rns_ros.viz.contact import (
    CONTACT_STATE_COLORS,
    WALL_HALF_SIZE,
    ContactRecorder,
    ContactSample,
    ContactSettings,
    ForceErrorSample,
    labelled_values,
    load_arm_model,
    parse_environment,
)
from rns_ros.viz.readback import read_components, read_scalars, read_static, recording_summary

CONFIG = Path(__file__).resolve().parents[2] / "config"
LWR = CONFIG / "lwr_7dof.yaml"
PLANAR = CONFIG / "planar_3dof.yaml"
#: thesis_rest A-4.12's LWR start: the flange at (0.515, 0.187, 0.464) m.
THETA = np.radians([20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0])
MS = 1_000_000  # [ns]


def contact_values(k: int, state: int = 1, **overrides) -> dict[str, float]:
    """Sample k of a 1 kHz contact stream (labels of the contract)."""
    values = dict.fromkeys(CONTACT_LABELS, 0.0)
    values |= {"time": k * 1e-3, "contact_state": state, "normal_force": 10.0 + k}
    values |= {"gap": 1e-6 * k, "point_x": 0.5, "point_y": 0.2 + 1e-3 * k, "point_z": 0.4}
    values |= {"normal_z": -1.0}
    return values | overrides


def error_values(k: int, **overrides) -> dict[str, float]:
    values = dict(zip(ERROR_LABELS, np.arange(len(ERROR_LABELS)) * 0.1 + k, strict=True))
    values |= {"time": k * 1e-3, "normal_x": 0.0, "normal_y": 0.6, "normal_z": -0.8}
    values |= {"force_desired": 10.0 + k, "force_active": 1.0}
    return values | overrides


@pytest.fixture
def open_contact(tmp_path):
    """Factory: a ContactRecorder saving to tmp_path/<name>.rrd; all closed at teardown."""
    recorders = []

    def factory(name="contact", model=LWR, **contact):
        robot, urdf = load_arm_model(model)
        sink = SinkSettings(kind="save", rrd_path=tmp_path / f"{name}.rrd")
        recorder = ContactRecorder(
            robot, urdf, sink, RecorderSettings(), contact=ContactSettings(**contact)
        )
        recorders.append(recorder)
        return recorder

    yield factory
    for recorder in recorders:
        recorder.close()


def _static(path, entity) -> dict:
    return read_static(path, entity)


def test_load_arm_model_tells_fixed_base_from_free_floating():
    robot, urdf = load_arm_model(LWR)
    assert isinstance(robot, FixedBaseModel)
    assert robot.n == 7
    assert urdf == (CONFIG / "urdf" / "lwr_7dof.urdf").resolve()
    robot, urdf = load_arm_model(default_model_config())
    assert isinstance(robot, FreeFloatingModel)
    with pytest.raises(ConfigError, match="not found"):
        load_arm_model(CONFIG / "no_such_model.yaml")


def test_wall_is_a_thin_box_at_its_point_across_its_normal(open_contact):
    recorder = open_contact()
    normal = np.array([0.0, 1.0, -1.0])
    text = json.dumps(
        {"type": "wall", "frame": "world", "point": [0.5, 0.2, 0.4], "normal": normal.tolist()}
    )
    environment = recorder.environment(text)
    assert environment.kind == "wall"
    recorder.close()
    rrd = recorder.sink.rrd_path
    box = _static(rrd, paths.ENVIRONMENT_WALL)
    np.testing.assert_allclose(box["Boxes3D:centers"][0], [0.5, 0.2, 0.4], atol=1e-6)
    np.testing.assert_allclose(box["Boxes3D:half_sizes"][0], WALL_HALF_SIZE, atol=1e-6)
    x, y, z, w = box["Boxes3D:quaternions"][0]
    thin_axis = pin.Quaternion(w, x, y, z).toRotationMatrix()[:, 2]  # the 2 mm side
    np.testing.assert_allclose(thin_axis, normal / np.linalg.norm(normal), atol=1e-6)
    arrow = _static(rrd, paths.ENVIRONMENT_NORMAL)
    np.testing.assert_allclose(arrow["Arrows3D:origins"][0], [0.5, 0.2, 0.4], atol=1e-6)
    direction = np.array(arrow["Arrows3D:vectors"][0])
    np.testing.assert_allclose(direction / np.linalg.norm(direction), normal / np.sqrt(2), 1e-6)
    assert _static(rrd, paths.ENVIRONMENT_ARC).get("Cylinders3D:radii", []) == []


def test_arc_is_a_cylinder_about_its_axis_and_a_new_environment_replaces_the_old(open_contact):
    recorder = open_contact(model=PLANAR)
    wall = {"type": "wall", "frame": "world", "point": [1, 0, 0], "normal": [1, 0, 0]}
    recorder.environment(json.dumps(wall))
    arc = {"type": "arc", "frame": "world", "center": [1.91, 1.91, 0.0], "radius": 0.707}
    recorder.environment(json.dumps(arc | {"axis": [0, 0, 2]}))
    recorder.close()
    rrd = recorder.sink.rrd_path
    cylinder = _static(rrd, paths.ENVIRONMENT_ARC)
    np.testing.assert_allclose(cylinder["Cylinders3D:centers"][0], [1.91, 1.91, 0.0], atol=1e-6)
    assert cylinder["Cylinders3D:radii"][0] == pytest.approx(0.707)
    x, y, z, w = cylinder["Cylinders3D:quaternions"][0]
    np.testing.assert_allclose(pin.Quaternion(w, x, y, z).toRotationMatrix()[:, 2], [0, 0, 1])
    # the wall of the first message is gone: its static box was overwritten by an empty one
    assert _static(rrd, paths.ENVIRONMENT_WALL).get("Boxes3D:centers", []) == []
    assert recorder.counts["environment"] == 2


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{not json", "not JSON"),
        ("[1, 2]", "JSON object"),
        ('{"type": "sphere", "frame": "world"}', "type must be one of"),
        ('{"type": "wall", "frame": "world", "point": [0, 0, 0]}', "missing \\['normal'\\]"),
        ('{"type": "wall", "frame": "w", "point": [0, 0, 0], "normal": [0, 0, 0]}', "non-zero"),
        ('{"type": "arc", "frame": "w", "center": [0, 0, 0], "radius": -1, "axis": [0, 0, 1]}',
         "radius"),
    ],
)  # fmt: skip
def test_bad_environment_is_an_input_error(text, message):
    with pytest.raises(InputError, match=message):
        parse_environment(text)


def test_none_environment_draws_nothing(open_contact):
    recorder = open_contact()
    assert parse_environment('{"type": "none", "frame": "world"}').constraint is None
    recorder.environment('{"type": "none", "frame": "world"}')
    recorder.close()
    rrd = recorder.sink.rrd_path
    assert _static(rrd, paths.ENVIRONMENT_WALL).get("Boxes3D:centers", []) == []


def test_arm_and_force_arrows_follow_the_forward_kinematics(open_contact):
    recorder = open_contact(force_arrow_scale=0.02)
    assert not recorder.wrist_wrench(0, [0.0, 0.0, 10.0])  # no joint state: no EE pose yet
    recorder.joint_state(0, THETA, np.full(7, 0.1))
    force_ee = np.array([1.0, -2.0, 10.0])
    assert recorder.wrist_wrench(0, force_ee, [0.0, 0.0, 0.0])
    assert recorder.force_errors(0, error_values(0))
    recorder.close()
    rrd = recorder.sink.rrd_path

    core = FixedBaseState.compute(load_fixed_base_model(LWR), THETA, np.zeros(7))
    np.testing.assert_allclose(core.ee_position, [0.515, 0.187, 0.464], atol=1e-3)
    (measured,) = [
        r for r in read_components(rrd, paths.FORCE_MEASURED_ARROW) if r.get("Arrows3D:vectors")
    ]
    np.testing.assert_allclose(measured["Arrows3D:origins"][0], core.ee_position, atol=1e-6)
    expected = core.ee_rotation @ force_ee * 0.02
    np.testing.assert_allclose(measured["Arrows3D:vectors"][0], expected, atol=1e-6)
    (desired,) = [
        r for r in read_components(rrd, paths.FORCE_DESIRED_ARROW) if r.get("Arrows3D:vectors")
    ]
    np.testing.assert_allclose(desired["Arrows3D:origins"][0], core.ee_position, atol=1e-6)
    np.testing.assert_allclose(desired["Arrows3D:vectors"][0], [0.0, 0.12, -0.16], atol=1e-6)

    summary = recording_summary(rrd)
    for joint in recorder.robot.joint_names:
        assert summary[paths.joint_transform(joint)] == 1
        assert summary[paths.joint_velocity(joint)] == 1
    assert summary[paths.BASE_POSE] == 0  # static: the base at the world origin
    assert paths.CAMERA_POINTING not in summary  # no camera on a Part II arm
    for link in ("base_link", "link_7"):
        for visual in recorder.view.visual_paths()[link]:
            assert visual in summary
    assert len(RrdReader(rrd).blueprints()) == 1


def test_series_and_contact_points_are_the_samples(open_contact):
    recorder = open_contact(contact_log_rate=0.0)
    for k, state in enumerate((1, 0, -1)):
        recorder.joint_state(k * MS, THETA)
        recorder.contact(k * MS, contact_values(k, state))
        recorder.force_errors(k * MS, error_values(k))
    recorder.close()
    rrd = recorder.sink.rrd_path
    times, force = read_scalars(rrd, paths.CONTACT_NORMAL_FORCE)
    np.testing.assert_allclose(times, [0.0, 1e-3, 2e-3])
    np.testing.assert_allclose(force, [10.0, 11.0, 12.0])
    np.testing.assert_allclose(read_scalars(rrd, paths.CONTACT_GAP)[1], [0.0, 1e-6, 2e-6])
    rows = [r for r in read_components(rrd, paths.CONTACT_POINT) if "Points3D:positions" in r]
    points = [r["Points3D:positions"][0] for r in rows]
    np.testing.assert_allclose(points, [[0.5, 0.2 + 1e-3 * k, 0.4] for k in range(3)], atol=1e-6)
    colors = [r["Points3D:colors"][0] for r in rows]
    packed = [(r << 24) | (g << 16) | (b << 8) | 255 for r, g, b in CONTACT_STATE_COLORS.values()]
    assert colors == packed  # pushing, no load, pulling: the dict's order +1, 0, -1
    for label, path in (
        ("force_desired", paths.FORCE_DESIRED),
        ("force_measured", paths.FORCE_MEASURED),
        ("force_error", paths.FORCE_ERROR),
        ("force_reference", paths.FORCE_REFERENCE),
        ("position_error_x", paths.POSITION_ERROR_AXES[0]),
        ("position_error_z", paths.POSITION_ERROR_AXES[2]),
        ("orientation_error", paths.POSITION_ERROR_ORIENTATION),
    ):
        expected = [error_values(k)[label] for k in range(3)]
        np.testing.assert_allclose(read_scalars(rrd, path)[1], expected, err_msg=label)


def test_contact_streams_are_rate_limited_by_their_own_clock(open_contact):
    recorder = open_contact(contact_log_rate=50.0)
    recorder.joint_state(0, THETA)
    logged = []
    for k in range(101):  # 0.1 s at 1 kHz, all placed at the one joint state's stamp
        logged.append(recorder.contact(0, contact_values(k)))
        recorder.force_errors(0, error_values(k))
        recorder.wrist_wrench(k * MS, [0.0, 0.0, 1.0])
    recorder.close()
    assert [k for k, kept in enumerate(logged) if kept] == [0, 20, 40, 60, 80, 100]
    assert recorder.counts["contact"] == recorder.counts["errors"] == 6
    assert recorder.counts["wrench"] == 6
    rrd = recorder.sink.rrd_path
    np.testing.assert_allclose(
        read_scalars(rrd, paths.CONTACT_NORMAL_FORCE)[1], [10.0, 30.0, 50.0, 70.0, 90.0, 110.0]
    )
    assert recording_summary(rrd)[paths.FORCE_MEASURED_ARROW] == 6


def test_malformed_samples_are_input_errors_and_leave_the_limiter_alone(open_contact):
    with pytest.raises(InputError, match="11 values for the 12 labels"):
        labelled_values("", [0.0] * 11, CONTACT_LABELS, "contact")
    labels = "time contact_state normal_force"
    assert labelled_values(labels, [1.0, 1.0, 5.0], CONTACT_LABELS, "contact") == {
        "time": 1.0,
        "contact_state": 1.0,
        "normal_force": 5.0,
    }
    with pytest.raises(InputError, match="no \\['gap'"):
        ContactSample.from_values({"time": 1.0, "contact_state": 1.0, "normal_force": 5.0})
    with pytest.raises(InputError, match="finite"):
        ContactSample.from_values(contact_values(0, normal_force=float("nan")))
    with pytest.raises(InputError, match="contact_state must be -1, 0 or 1"):
        ContactSample.from_values(contact_values(0, contact_state=2.0))
    with pytest.raises(InputError, match="finite"):
        ForceErrorSample.from_values(error_values(0, force_error=float("inf")))
    recorder = open_contact()
    recorder.joint_state(0, THETA)
    with pytest.raises(InputError):
        recorder.contact(0, contact_values(0, gap=float("nan")))
    with pytest.raises(InputError):
        recorder.wrist_wrench(0, [0.0, float("nan"), 0.0])
    assert recorder.contact(0, contact_values(0))  # the bad one did not use the slot
    assert recorder.counts["contact"] == 1


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"contact_log_rate": -1.0}, "contact_log_rate"),
        ({"force_arrow_scale": 0.0}, "force_arrow_scale"),
        ({"force_arrow_scale": float("nan")}, "force_arrow_scale"),
    ],
)
def test_bad_contact_settings(settings, message):
    with pytest.raises(ConfigError, match=message):
        ContactSettings(**settings)
