"""The default model matches thesis section 4.1.1 / Table 4.1, and bad descriptions fail clearly."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.analysis.arm_geometry import IDENTIFIED_GEOMETRY
from rns_ros.core import ConfigError, FreeFloatingModel, InputError, ModelError, ModelSpec
from rns_ros.core.config import load_model, load_model_config
from rns_ros.core.urdf_prep import INERTIA_KEYS
from rns_ros.resources import default_model_config

# Thesis Table 4.1: mass [kg] and principal moments [kg m^2] of links 1-7.
TABLE_4_1 = {
    "link_1": (30.0, (0.0671, 0.0671, 0.0851)),
    "link_2": (30.0, (0.0843, 0.267, 0.267)),
    "link_3": (45.0, (3.81, 3.81, 0.127)),
    "link_4": (40.0, (0.113, 2.19, 2.19)),
    "link_5": (20.0, (0.213, 0.213, 0.0250)),
    "link_6": (20.0, (0.0250, 0.0292, 0.0292)),
    "link_7": (25.0, (0.0990, 0.0990, 0.0313)),
}
# The identified geometry (docs/arm_identification.md): link lengths [m] and lateral offsets.
LINK_LENGTHS = IDENTIFIED_GEOMETRY.lengths
MOUNT = (-0.79, -0.29, 1.0)  # m, thesis section 4.1.1


def _body_inertia(robot: FreeFloatingModel, joint: str) -> pin.Inertia:
    return robot.model.inertias[robot.model.getJointId(joint)]


def test_joint_names_and_counts(robot):
    assert robot.joint_names == tuple(f"joint_{i}" for i in range(1, 8))
    assert robot.n == 7
    assert robot.model.nq == 14
    assert robot.model.nv == 13


def test_gravity_is_zero(robot):
    assert np.allclose(robot.model.gravity.vector, 0.0)


def test_base_mass_and_inertia(robot):
    base = robot.model.inertias[1]
    assert base.mass == pytest.approx(2550.0)
    assert np.allclose(base.lever, 0.0)  # base CoM frame = base link frame
    assert np.allclose(base.inertia, np.diag([6200.0, 3540.0, 7090.0]))


@pytest.mark.parametrize(("index", "link"), list(enumerate(TABLE_4_1, start=1)))
def test_link_mass_and_principal_moments_match_table_4_1(robot, index, link):
    mass, moments = TABLE_4_1[link]
    inertia = _body_inertia(robot, f"joint_{index}")
    assert inertia.mass == pytest.approx(mass)
    assert np.allclose(np.sort(np.linalg.eigvalsh(inertia.inertia)), np.sort(moments), atol=1e-12)
    # The distinct (axial) moment lies along the link, which points along the joint-frame z axis.
    axial = min(set(moments), key=lambda value: moments.count(value))
    assert inertia.inertia[2, 2] == pytest.approx(axial)
    # CoM at mid-length on the link axis.
    assert np.allclose(inertia.lever, [0.0, 0.0, LINK_LENGTHS[index - 1] / 2])


def test_total_mass(robot):
    assert robot.total_mass == pytest.approx(2550.0 + sum(m for m, _ in TABLE_4_1.values()))


def test_mount_position_and_straight_arm_at_zero(robot):
    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, robot.neutral())
    joint_1 = data.oMi[model.getJointId("joint_1")].translation
    assert np.allclose(joint_1, MOUNT)
    # theta = 0: straight arm along base +z, plus the shoulder, elbow and wrist offsets (x, y)
    camera = data.oMf[robot.camera_frame_id].translation
    lateral = np.add.reduce(
        [IDENTIFIED_GEOMETRY.shoulder, IDENTIFIED_GEOMETRY.elbow, IDENTIFIED_GEOMETRY.wrist]
    )
    assert np.allclose(camera - joint_1, [*lateral, sum(LINK_LENGTHS)])
    wrist = data.oMf[robot.wrist_frame_id].translation
    joint_6 = data.oMi[model.getJointId("joint_6")].translation
    assert np.allclose(wrist, joint_6)


def test_folded_elbow_puts_forearm_beside_upper_arm(robot):
    """theta_4 = pi (the elbow axis is base x at theta = 0) turns the forearm back along the
    upper arm: the elbow-to-wrist vector is the straight one rotated by pi about x, and the
    forearm's line passes beside the upper arm's, not through it."""
    model, data = robot.model, robot.data

    def points(theta4):
        theta = np.zeros(7)
        theta[3] = theta4
        pin.framesForwardKinematics(model, data, robot.configuration(theta))
        shoulder = data.oMi[model.getJointId("joint_3")].translation.copy()
        elbow = data.oMi[model.getJointId("joint_4")].translation.copy()
        return shoulder, elbow, data.oMf[robot.wrist_frame_id].translation.copy()

    _, elbow_0, wrist_0 = points(0.0)
    shoulder, elbow, wrist = points(np.pi)
    np.testing.assert_allclose(wrist - elbow, np.diag([1.0, -1.0, -1.0]) @ (wrist_0 - elbow_0))
    assert (wrist - elbow)[2] < -0.9  # [m] runs back down along the upper arm (+z)
    lateral = np.linalg.norm((wrist - shoulder)[:2])
    # [m] beside it, not through it. The identified offsets leave only 0.070 m between the
    # folded wrist and the upper-arm axis (docs/arm_identification.md: thin links)
    assert lateral > 0.05


def test_limits(robot):
    assert np.allclose(robot.lower_limits, -2 * np.pi)
    assert np.allclose(robot.upper_limits, 2 * np.pi)
    assert np.allclose(robot.velocity_limits, [0.5, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0])


def test_subchains_from_config(robot):
    assert robot.subchains is not None
    assert robot.subchains.positioning.tolist() == [0, 1, 2, 3]
    assert robot.subchains.wrist.tolist() == [4, 5, 6]


def test_missing_urdf_names_the_path(tmp_path):
    with pytest.raises(ModelError, match="not found"):
        FreeFloatingModel.from_urdf(tmp_path / "nope.urdf")


def test_unparsable_urdf():
    with pytest.raises(ModelError, match="could not be parsed"):
        FreeFloatingModel.from_urdf_string("<robot name='x'><link></robot>")


def test_unknown_frame_lists_the_valid_ones():
    urdf, _ = load_model_config(default_model_config())
    with pytest.raises(ModelError, match=r"camera_frame 'eye' .*'camera'"):
        FreeFloatingModel.from_urdf(urdf, ModelSpec(camera_frame="eye"))


def test_unknown_subchain_joint_names_the_valid_ones():
    urdf, _ = load_model_config(default_model_config())
    spec = ModelSpec(positioning_joints=("joint_1", "shoulder"), wrist_joints=("joint_5",))
    with pytest.raises(ModelError, match=r"\['shoulder'\].*joint_7"):
        FreeFloatingModel.from_urdf(urdf, spec)


def test_subchains_must_partition_the_arm():
    urdf, _ = load_model_config(default_model_config())
    spec = ModelSpec(positioning_joints=("joint_1", "joint_2"), wrist_joints=("joint_7",))
    with pytest.raises(ModelError, match="cover all 7 joints"):
        FreeFloatingModel.from_urdf(urdf, spec)


def _one_joint_urdf(kind: str) -> str:
    return (
        "<robot name='c'><link name='base'><inertial><mass value='10'/><inertia ixx='1' iyy='1'"
        " izz='1' ixy='0' ixz='0' iyz='0'/></inertial></link><link name='l'><inertial><mass"
        " value='1'/><inertia ixx='1' iyy='1' izz='1' ixy='0' ixz='0' iyz='0'/></inertial></link>"
        f"<joint name='spin' type='{kind}'><parent link='base'/><child link='l'/>"
        "<axis xyz='0 0 1'/><limit effort='5' velocity='2'/></joint><link name='camera'/>"
        "<joint name='cam' type='fixed'><parent link='l'/><child link='camera'/></joint></robot>"
    )


def test_continuous_joint_is_an_unbounded_revolute_joint():
    """One position coordinate (not Pinocchio's (cos, sin) pair), no position limits whatever the
    <limit> tag says, its velocity limit kept; the root link has mass: no satellite added."""
    robot = FreeFloatingModel.from_urdf_string(
        _one_joint_urdf("continuous"), ModelSpec(wrist_frame=None)
    )
    assert robot.n == 1
    assert robot.model.nq == 8
    assert robot.joint_names == ("spin",)
    assert robot.lower_limits.tolist() == [-np.inf]
    assert robot.upper_limits.tolist() == [np.inf]
    assert robot.velocity_limits.tolist() == [2.0]
    assert robot.base_link == "base"
    # the angle is an angle: 2 pi further is the same placement of the camera
    poses = []
    for angle in (0.3, 0.3 + 2 * np.pi):
        pin.framesForwardKinematics(robot.model, robot.data, robot.configuration([angle]))
        poses.append(robot.data.oMf[robot.camera_frame_id].homogeneous.copy())
    np.testing.assert_allclose(poses[0], poses[1], atol=1e-12)


def test_floating_arm_joint_is_rejected():
    with pytest.raises(ModelError, match=r"joint 'spin' is .*; rns_ros supports revolute"):
        FreeFloatingModel.from_urdf_string(_one_joint_urdf("floating"), ModelSpec(wrist_frame=None))


def test_configuration_validates_inputs(robot):
    with pytest.raises(InputError, match=r"joint_angles must have shape \(7,\)"):
        robot.configuration(np.zeros(6))
    with pytest.raises(InputError, match="finite"):
        robot.configuration([0, 0, 0, np.nan, 0, 0, 0])
    with pytest.raises(InputError, match="non-zero"):
        robot.configuration(np.zeros(7), base_quaternion=(0, 0, 0, 0))
    q = robot.configuration(np.zeros(7), base_quaternion=(0, 0, 0, 2.0))
    assert np.allclose(q[3:7], [0, 0, 0, 1])


def test_model_config_rejects_unknown_key(tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text("urdf: arm.urdf\ncamera: tip\n")
    with pytest.raises(ConfigError, match=r"unknown key\(s\) \['camera'\]"):
        load_model_config(path)


def test_model_config_rejects_bad_types(tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text("urdf: arm.urdf\nwrist_joints: joint_5\n")
    with pytest.raises(ConfigError, match="'wrist_joints' must be a list"):
        load_model_config(path)
    path.write_text("- just a list\n")
    with pytest.raises(ConfigError, match="expected a mapping"):
        load_model_config(path)


def test_base_link_is_the_urdf_root(robot):
    assert robot.base_link == "base_link"


# --- inertial validation: what the URDF writes, and what Pinocchio builds from it ----
def _default_urdf() -> str:
    urdf, _ = load_model_config(default_model_config())
    return urdf.read_text()


def _with_inertial(link: str, **attributes: str) -> str:
    """The default URDF with attributes of ``link``'s <mass> (``value``) or <inertia> replaced."""
    root = ET.fromstring(_default_urdf())
    inertial = root.find(f"link[@name='{link}']/inertial")
    for key, value in attributes.items():
        inertial.find("mass" if key == "value" else "inertia").set(key, value)
    return ET.tostring(root, encoding="unicode")


@pytest.mark.parametrize(
    ("link", "attributes", "message"),
    [
        # Pinocchio would build a base of zero inertia from this one (urdfdom drops the element)
        ("base_link", {"ixx": "nan"}, r"link 'base_link' <inertia>: ixx='nan' must be finite"),
        ("link_2", {"iyy": "inf"}, r"link 'link_2' <inertia>: iyy='inf' must be finite"),
        ("link_1", {"izz": "abc"}, r"link 'link_1' <inertia>: izz='abc' is not a number"),
        ("link_3", {"ixx": "-3.81"}, r"link 'link_3': inertia must be positive definite"),
        # diagonal fine, off-diagonal too large: one principal moment < 0
        ("link_1", {"ixy": "0.1"}, r"link 'link_1': inertia must be positive definite"),
        ("link_5", {"izz": "1.0"}, r"link 'link_5': principal moments .* triangle inequality"),
        ("link_7", {"value": "0"}, r"link 'link_7': mass must be finite and > 0 kg, got 0.0"),
        ("link_7", {"value": "-25"}, r"link 'link_7': mass must be finite and > 0 kg, got -25"),
        ("link_4", {"value": "nan"}, r"link 'link_4' <mass>: value='nan' must be finite"),
    ],
)
def test_bad_link_inertial_is_a_one_line_model_error_naming_the_link(link, attributes, message):
    with pytest.raises(ModelError, match=message) as caught:
        FreeFloatingModel.from_urdf_string(_with_inertial(link, **attributes))
    assert "\n" not in str(caught.value)


def test_missing_inertia_attribute_is_named():
    root = ET.fromstring(_default_urdf())
    del root.find("link[@name='link_6']/inertial/inertia").attrib["iyz"]
    with pytest.raises(ModelError, match=r"link 'link_6' <inertia>: attribute iyz is missing"):
        FreeFloatingModel.from_urdf_string(ET.tostring(root, encoding="unicode"))


def test_thin_disk_on_the_triangle_bound_is_accepted():
    # I1 + I2 = I3 exactly, and a rounding residue (7e-5 relative) past it: accepted
    for izz in ("0.426", "0.42603"):
        FreeFloatingModel.from_urdf_string(_with_inertial("link_5", izz=izz))


def test_every_loader_path_validates_inertials(tmp_path):
    broken = tmp_path / "broken.urdf"
    broken.write_text(_with_inertial("base_link", ixx="nan"))
    with pytest.raises(ModelError, match="link 'base_link'"):
        FreeFloatingModel.from_urdf(broken)
    config = tmp_path / "model.yaml"
    config.write_text(f"urdf: {broken.name}\n")
    with pytest.raises(ModelError, match="link 'base_link'"):
        load_model(config)


def test_moving_link_without_inertial_is_a_massless_body():
    # link_7 carries the camera: without its <inertial> Pinocchio builds a body of mass 0
    root = ET.fromstring(_default_urdf())
    link = root.find("link[@name='link_7']")
    link.remove(link.find("inertial"))
    with pytest.raises(ModelError, match=r"body of joint 'joint_7' \(links \['link_7'.*mass 0"):
        FreeFloatingModel.from_urdf_string(ET.tostring(root, encoding="unicode"))


def _with_camera_inertial(mass: str, moment: str) -> str:
    """The default URDF with an <inertial> of ``mass`` and all six moments ``moment`` on the
    camera frame link (fixed to link_7), as Sawyer's description writes its frame links."""
    root = ET.fromstring(_default_urdf())
    inertial = ET.SubElement(root.find("link[@name='camera']"), "inertial")
    ET.SubElement(inertial, "origin", xyz=f"{mass} {mass} {mass}", rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=mass)
    ET.SubElement(inertial, "inertia", {key: moment for key in INERTIA_KEYS})
    return ET.tostring(root, encoding="unicode")


def test_placeholder_inertial_is_read_as_a_frame_link(robot):
    # 1e-8 everywhere: a rank-1 inertia, not a rigid body, but below any arm body's rounding
    loaded = FreeFloatingModel.from_urdf_string(_with_camera_inertial("1.0E-08", "1.0E-08"))
    body = robot.model.frames[robot.model.getFrameId("camera")].parentJoint
    ours, theirs = loaded.model.inertias[body], robot.model.inertias[body]
    assert ours.mass == theirs.mass
    assert np.array_equal(ours.lever, theirs.lever)
    assert np.array_equal(ours.inertia, theirs.inertia)
    assert any("['camera']: placeholder inertials" in note for note in loaded.loading_notes)
    assert not any("placeholder" in note for note in robot.loading_notes)


@pytest.mark.parametrize(
    ("mass", "moment"),
    [("1.0E-08", "1.0E-03"), ("1.0E-03", "1.0E-08")],  # one of the two is not negligible
)
def test_a_light_but_not_negligible_bad_inertial_is_still_refused(mass, moment):
    with pytest.raises(ModelError, match=r"link 'camera': inertia must be positive definite"):
        FreeFloatingModel.from_urdf_string(_with_camera_inertial(mass, moment))


def test_pinocchio_bodies_are_checked_too(robot):
    model = robot.model.copy()
    model.inertias[1] = pin.Inertia(2550.0, np.zeros(3), np.zeros((3, 3)))
    with pytest.raises(ModelError, match=r"joint 'root_joint'.*positive definite"):
        FreeFloatingModel(model, robot.spec)


def test_skeleton_is_rigid_and_ends_at_the_camera(robot):
    """Stick figure: consecutive joint origins keep the URDF offsets at any angles and base pose
    (rigid links), the first point is the base origin and the last the camera of the state."""
    from rns_ros.core.state import FreeFloatingState

    rng = np.random.default_rng(3)
    zero = robot.skeleton(robot.configuration(np.zeros(robot.n)))
    assert zero.shape == (robot.n + 2, 3)
    offsets = [
        np.linalg.norm(robot.model.jointPlacements[j].translation)
        for j in range(2, robot.model.njoints)
    ]
    for _ in range(5):
        theta = rng.uniform(-np.pi, np.pi, robot.n)
        position = rng.normal(size=3)
        quaternion = rng.normal(size=4)
        q = robot.configuration(theta, position, quaternion)
        points = robot.skeleton(q)
        np.testing.assert_allclose(points[0], position, atol=1e-12)
        lengths = np.linalg.norm(np.diff(points[:-1], axis=0), axis=1)
        np.testing.assert_allclose(lengths, offsets, atol=1e-12)
        camera = FreeFloatingState.compute(robot, q).camera.position
        np.testing.assert_allclose(points[-1], camera, atol=1e-12)
