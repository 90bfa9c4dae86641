"""Any arm in the 3D view: meshes that resolve, simple shapes for the links left bare, the
equivalent-inertia ellipsoid against its defining moments; drawn into a saved .rrd (no viewer)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import rerun as rr

from rns_ros.core import FreeFloatingModel, ModelSpec, load_model
from rns_ros.viz import paths
from rns_ros.viz.readback import recording_summary
from rns_ros.viz.robot import RobotView
from rns_ros.viz.robot_shapes import (
    MIN_SEMI_AXIS,
    equivalent_ellipsoid,
    resolve_description,
    resolve_mesh,
)

MISSING_MESH = "package://no_such_package_rns/meshes/upper.stl"
SHIPPED = "package://rns_ros/package.xml"  # any file of a package the ament index knows

URDF = f"""<?xml version="1.0"?>
<robot name="bare_arm">
  <link name="base">
    <inertial><mass value="500"/><inertia ixx="80" ixy="0" ixz="0" iyy="90" iyz="0" izz="100"/>
    </inertial>
    <visual><geometry><box size="1 1 1"/></geometry></visual>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="upper"/><origin xyz="0 0 0.5"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <link name="upper">
    <inertial><origin xyz="0 0 0.2" rpy="0.3 0 0"/><mass value="4"/>
      <inertia ixx="0.06" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.02"/></inertial>
    <visual><geometry><mesh filename="{MISSING_MESH}"/></geometry></visual>
  </link>
  <joint name="j2" type="revolute">
    <parent link="upper"/><child link="fore"/><origin xyz="0 0 0.4"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <link name="fore">
    <inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"/>
    </inertial>
    <visual><geometry><mesh filename="fore.stl"/></geometry></visual>
  </link>
  <joint name="j3" type="revolute">
    <parent link="fore"/><child link="hand"/><origin xyz="0 0 0.3"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <link name="hand">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>
    </inertial>
    <visual><geometry><mesh filename="{SHIPPED}"/></geometry></visual>
  </link>
  <joint name="camera_joint" type="fixed">
    <parent link="hand"/><child link="camera"/><origin xyz="0 0 0.1"/>
  </joint>
  <link name="camera"/>
</robot>
"""


@pytest.fixture
def arm(tmp_path):
    (tmp_path / "fore.stl").write_text("solid fore\nendsolid fore\n")
    path = tmp_path / "bare_arm.urdf"
    path.write_text(URDF)
    return path


def _random_rigid_body(rng):
    """(mass [kg], inertia (3, 3) [kg m^2], semi-axes [m]) of a random solid ellipsoid."""
    mass = rng.uniform(0.5, 50.0)
    semi_axes = rng.uniform(0.02, 0.8, size=3)
    a2 = semi_axes**2
    principal = mass / 5.0 * np.array([a2[1] + a2[2], a2[0] + a2[2], a2[0] + a2[1]])
    rotation = pin.Quaternion(*rng.normal(size=4)).normalized().matrix()
    return mass, rotation @ np.diag(principal) @ rotation.T, semi_axes


def test_the_equivalent_ellipsoid_has_the_links_inertia():
    rng = np.random.default_rng(31)
    for _ in range(50):
        mass, inertia, semi_axes = _random_rigid_body(rng)
        half_sizes, axes = equivalent_ellipsoid(mass, inertia)
        np.testing.assert_allclose(np.sort(half_sizes), np.sort(semi_axes), rtol=1e-9)
        # the solid ellipsoid's inertia, I_i = m (a_j^2 + a_k^2) / 5, turned to the link axes
        a2 = half_sizes**2
        moments = mass / 5.0 * np.array([a2[1] + a2[2], a2[0] + a2[2], a2[0] + a2[1]])
        np.testing.assert_allclose(axes @ np.diag(moments) @ axes.T, inertia, atol=1e-12)
        assert np.linalg.det(axes) == pytest.approx(1.0)


def test_a_flat_inertia_still_has_a_visible_thickness():
    half_sizes, _ = equivalent_ellipsoid(1.0, np.diag([0.1, 0.1, 0.2]))  # a thin disk: I3 = I1+I2
    assert half_sizes.min() == pytest.approx(MIN_SEMI_AXIS)


def test_meshes_resolve_through_the_ament_index_or_the_urdf_folder(arm):
    assert resolve_mesh(MISSING_MESH, arm.parent) is None
    assert resolve_mesh("fore.stl", arm.parent) == arm.parent / "fore.stl"
    shipped = resolve_mesh(SHIPPED, arm.parent)
    assert shipped is not None
    assert shipped.name == "package.xml"


def test_links_without_a_resolved_visual_get_their_ellipsoid_and_skeleton(arm):
    description = resolve_description(arm.read_text(), arm.parent)
    assert description.unresolved == (MISSING_MESH,)
    assert MISSING_MESH not in description.xml
    assert f'filename="{arm.parent / "fore.stl"}"' in description.xml
    shapes = {shape.link: shape for shape in description.shapes}
    assert set(shapes) == {"upper"}  # camera: a frame without inertial or child
    upper = shapes["upper"]
    np.testing.assert_allclose(upper.center, [0.0, 0.0, 0.2])
    np.testing.assert_allclose(upper.segments, [[[0.0, 0.0, 0.0], [0.0, 0.0, 0.4]]])
    # the ellipsoid turned by the inertial's rpy: its inertia in the link frame is R I R^T
    rotation = pin.Quaternion(*np.roll(upper.quaternion_xyzw, 1)).matrix()
    a2 = upper.half_sizes**2
    moments = 4.0 / 5.0 * np.array([a2[1] + a2[2], a2[0] + a2[2], a2[0] + a2[1]])
    expected = pin.rpy.rpyToMatrix(0.3, 0.0, 0.0) @ np.diag([0.06, 0.05, 0.02])
    expected = expected @ pin.rpy.rpyToMatrix(0.3, 0.0, 0.0).T
    np.testing.assert_allclose(rotation @ np.diag(moments) @ rotation.T, expected, atol=1e-12)


def test_the_view_draws_the_bare_links_into_a_recording(arm, tmp_path):
    robot = FreeFloatingModel.from_urdf(arm, ModelSpec(camera_frame="camera", wrist_frame=None))
    view = RobotView(robot, arm)
    assert view.source_path == arm
    assert view.urdf_path != arm  # the loader reads the resolved copy
    recording = tmp_path / "bare.rrd"
    rec = rr.RecordingStream("rns_ros_test_shapes")
    rec.save(recording)
    view.log_static(rec)
    rec.flush()
    rec.disconnect()
    counts = recording_summary(recording, include_static=True)
    assert counts.get(f"{paths.ROBOT_SHAPES}/upper", 0) > 0
    assert counts.get(f"{paths.ROBOT_SHAPES}/upper/skeleton", 0) > 0
    assert not any(entity.startswith(f"{paths.ROBOT_SHAPES}/fore") for entity in counts)
    # the mesh that resolved is the loader's: its visual is in the model
    assert any("fore" in entity and "visual" in entity for entity in counts)


def test_a_xacro_description_is_shown_expanded():
    """The viewer reads the model's description as the loader does: a xacro expanded with the
    model YAML's arguments and packages."""
    model = Path(__file__).resolve().parents[1] / "data" / "arms" / "xacro7" / "model.yaml"
    robot = load_model(model)
    view = RobotView(robot, robot.source_path)
    assert 'name="x7_joint_7"' in view.description.xml
    assert "xacro:" not in view.description.xml
