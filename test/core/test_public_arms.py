"""Arm descriptions as published load as they come (test/data/arms: three arms written for these
tests with the traits of public descriptions), and the reduced model keeps the physics.

The dynamics are checked against an independent build: Pinocchio reads the arm's URDF unchanged
(continuous joints as unit-complex joints, every joint free, no satellite), the thesis satellite
is added by hand, and the spatial momentum and kinetic energy summed link by link must equal the
ones of our reduced model's mass matrix (eq. 2.7, 2.33).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from rns_ros.core import ConfigError, FreeFloatingModel, FreeFloatingState, ModelError
from rns_ros.core.config import load_model, load_model_config
from rns_ros.core.momentum import spatial_momentum
from rns_ros.resources import default_model_config

ARMS = Path(__file__).resolve().parents[1] / "data" / "arms"
# The thesis satellite (section 4.1.1), written out here rather than imported.
SATELLITE_MASS = 2550.0  # kg
SATELLITE_INERTIA = np.diag([6200.0, 3540.0, 7090.0])  # kg m^2
MOUNT = np.array([-0.79, -0.29, 1.0])  # m
EXPECTED = {
    "gripper7": {
        "joints": tuple(f"g7_joint{i}" for i in range(1, 8)),
        "held": {"g7_finger_joint1": 0.02, "g7_finger_joint2": 0.02},  # the second by <mimic>
        "subchains": ([0, 1, 2, 3], [4, 5, 6]),
    },
    "cont6": {
        "joints": tuple(f"c6_joint_{i}" for i in range(1, 7)),
        "held": {},
        "subchains": ([0, 1, 2], [3, 4, 5]),
    },
    "world7": {
        "joints": tuple(f"w7_joint_{i}" for i in range(1, 8)),
        "held": {},
        "subchains": ([0, 1, 2, 3], [4, 5, 6]),
    },
}


def _config(arm: str) -> Path:
    return ARMS / arm / "model.yaml"


@pytest.fixture(scope="module", params=sorted(EXPECTED))
def arm(request) -> tuple[str, FreeFloatingModel]:
    return request.param, load_model(_config(request.param))


def _urdf(arm: str) -> str:
    return (ARMS / arm / "robot.urdf").read_text()


def _links(xml: str) -> dict[str, ET.Element]:
    return {link.get("name"): link for link in ET.fromstring(xml).findall("link")}


def test_the_arms_have_the_published_traits():
    """What makes them worth testing: zero-mass inertials on frame links, package:// meshes,
    continuous joints, a <mimic> finger, a fixed world root."""
    gripper, cont, world = _urdf("gripper7"), _urdf("cont6"), _urdf("world7")
    for xml in (gripper, cont):
        assert 'mass value="0"' in xml
        assert "package://" in xml
    assert gripper.count('type="prismatic"') == 2
    assert "<mimic" in gripper
    assert cont.count('type="continuous"') == 6
    assert "<limit effort=" in cont
    root = ET.fromstring(world)
    assert root.find("joint[@name='world_joint']").get("type") == "fixed"
    assert root.find("joint/parent[@link='world']") is not None
    # blocks that are not kinematic, with <joint> entries of their own
    assert gripper.count("<ros2_control name=") == 1
    assert world.count("<transmission name=") == 7
    # a joint and a link named alike
    cont_root = ET.fromstring(cont)
    assert cont_root.find("joint[@name='c6_hand']") is not None
    assert cont_root.find("link[@name='c6_hand']") is not None


def test_a_frame_name_shared_by_a_joint_and_a_link_means_the_link():
    """cont6's camera_frame c6_hand names a fixed joint and its child link; the camera is the
    link, 2 cm past c6_end_effector along its z axis."""
    robot = load_model(_config("cont6"))
    frame = robot.model.frames[robot.camera_frame_id]
    assert frame.name == "c6_hand"
    assert frame.type == pin.FrameType.BODY
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.configuration(robot.initial_theta))
    end = data.oMf[robot.model.getFrameId("c6_end_effector", pin.FrameType.BODY)]
    np.testing.assert_allclose(
        data.oMf[robot.camera_frame_id].translation,
        end.act(np.array([0.0, 0.0, 0.02])),
        atol=1e-12,
    )


def test_each_arm_loads_with_its_controlled_and_held_joints(arm):
    name, robot = arm
    expected = EXPECTED[name]
    assert robot.joint_names == expected["joints"]
    assert robot.n == len(expected["joints"]) == robot.model.nv - 6
    assert robot.held_joints == pytest.approx(expected["held"], abs=1e-15)
    positioning, wrist = expected["subchains"]
    assert robot.subchains.positioning.tolist() == positioning
    assert robot.subchains.wrist.tolist() == wrist
    assert robot.base_link == "satellite"
    assert robot.source_path == (ARMS / name / "robot.urdf").resolve()
    assert robot.urdf_xml == _urdf(name)
    lines = robot.describe()
    assert all("\n" not in line for line in lines)
    assert any("thesis satellite" in line for line in lines)


def test_total_mass_is_the_urdf_masses_plus_the_satellite(arm):
    name, robot = arm
    masses = [
        float(link.find("inertial/mass").get("value"))
        for link in _links(_urdf(name)).values()
        if link.find("inertial") is not None
    ]
    assert robot.total_mass == pytest.approx(SATELLITE_MASS + sum(masses), rel=1e-14)
    # the links fixed to the root merge into the base body
    assert robot.base_mass >= SATELLITE_MASS


def test_initial_joint_positions_are_read_in_theta_order(arm):
    name, robot = arm
    given = yaml.safe_load(_config(name).read_text())["initial_joint_positions"]
    for joint, value in given.items():
        assert robot.initial_theta[robot.joint_names.index(joint)] == value
    assert np.count_nonzero(robot.initial_theta) == np.count_nonzero(list(given.values()))


def test_continuous_joints_are_unbounded_with_their_velocity_tags():
    robot = load_model(_config("cont6"))
    assert np.all(robot.lower_limits == -np.inf)
    assert np.all(robot.upper_limits == np.inf)
    assert robot.velocity_limits.tolist() == [0.63, 0.63, 0.63, 0.84, 0.84, 0.84]
    # any angle, however large, is a configuration
    state = FreeFloatingState.compute(robot, robot.configuration(np.full(6, 40.0)))
    assert np.all(np.isfinite(state.inertia))


def test_the_world_root_is_replaced_by_the_satellite_at_the_mount():
    robot = load_model(_config("world7"))
    assert not robot.model.existFrame("world")
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.neutral())
    link_0 = data.oMf[robot.model.getFrameId("w7_link_0")]
    np.testing.assert_allclose(link_0.translation, MOUNT, atol=1e-15)
    np.testing.assert_allclose(link_0.rotation, np.eye(3), atol=1e-15)


# --- the dynamics of the reduced model, against the unchanged URDF ----------------------------
def _independent_full_model(name: str, robot: FreeFloatingModel, q, base_twist, theta_dot):
    """(linear momentum [kg m/s], angular momentum about the base origin [kg m^2/s], kinetic
    energy [J], camera position [m]) summed over the links of the URDF as published, every joint
    free (held ones at their positions, at rest), plus the satellite body."""
    full = pin.buildModelFromXML(_urdf(name), pin.JointModelFreeFlyer())
    data = full.createData()
    base = pin.XYZQUATToSE3(q[:7])
    root = base * pin.SE3(np.eye(3), MOUNT)  # the arm's root frame
    v_b, omega_b = base_twist[:3], base_twist[3:]
    v_root = v_b + np.cross(omega_b, root.translation - base.translation)
    q_full, v_full = pin.neutral(full), np.zeros(full.nv)
    q_full[:7] = pin.SE3ToXYZQUAT(root)
    v_full[:6] = np.concatenate((root.rotation.T @ v_root, root.rotation.T @ omega_b))
    theta = robot.joint_angles(q)
    for index in range(2, full.njoints):
        joint, joint_name = full.joints[index], full.names[index]
        if joint_name in robot.joint_names:
            k = robot.joint_names.index(joint_name)
            angle, rate = theta[k], theta_dot[k]
        else:
            angle, rate = robot.held_joints[joint_name], 0.0
        if joint.nq == 2:  # a continuous joint: q = (cos, sin)
            q_full[joint.idx_q : joint.idx_q + 2] = np.cos(angle), np.sin(angle)
        else:
            q_full[joint.idx_q] = angle
        v_full[joint.idx_v] = rate
    pin.forwardKinematics(full, data, q_full, v_full)
    pin.updateFramePlacements(full, data)
    satellite = pin.Inertia(SATELLITE_MASS, np.zeros(3), SATELLITE_INERTIA)
    base_velocity = pin.Motion(base.rotation.T @ v_b, base.rotation.T @ omega_b)
    bodies = [(base, satellite, base_velocity)] + [
        (data.oMi[i], full.inertias[i], data.v[i]) for i in range(1, full.njoints)
    ]
    linear, angular, energy = np.zeros(3), np.zeros(3), 0.0
    for placement, inertia, velocity in bodies:
        local = inertia.matrix() @ velocity.vector
        force = placement.act(pin.Force(local))  # world axes, about the world origin
        linear += force.linear
        angular += force.angular
        energy += 0.5 * velocity.vector @ local
    angular_about_base = angular - np.cross(base.translation, linear)
    camera = data.oMf[full.getFrameId(robot.spec.camera_frame, pin.FrameType.BODY)].translation
    return linear, angular_about_base, energy, camera


def test_momentum_and_energy_match_the_unchanged_urdf(arm):
    name, robot = arm
    rng = np.random.default_rng(31)
    for _ in range(3):
        theta = robot.initial_theta + rng.uniform(-0.3, 0.3, robot.n)
        q = robot.configuration(theta, rng.normal(size=3), rng.normal(size=4))
        base_twist = rng.normal(size=6) * 0.1
        theta_dot = rng.normal(size=robot.n)
        state = FreeFloatingState.compute(robot, q)
        momentum = spatial_momentum(state, base_twist, theta_dot)
        rate = np.concatenate((base_twist, theta_dot))
        energy = 0.5 * rate @ state.inertia @ rate
        linear, angular, full_energy, camera = _independent_full_model(
            name, robot, q, base_twist, theta_dot
        )
        scale = np.abs(np.concatenate((linear, angular))).max()
        np.testing.assert_allclose(momentum[:3], linear, rtol=0, atol=1e-11 * scale)
        np.testing.assert_allclose(momentum[3:], angular, rtol=0, atol=1e-11 * scale)
        assert energy == pytest.approx(full_energy, rel=1e-11)
        np.testing.assert_allclose(state.camera.position, camera, atol=1e-12)


def test_the_held_finger_mass_moves_with_its_position():
    """The locked fingers merge into the hand's body: opening them shifts that body's inertia
    (and the mimic finger follows the leader), it does not drop their mass."""
    urdf, spec = load_model_config(_config("gripper7"))
    closed = FreeFloatingModel.from_urdf(urdf, _with(spec, held_joints={}))
    opened = FreeFloatingModel.from_urdf(urdf, _with(spec, held_joints={"g7_finger_joint1": 0.04}))
    assert closed.held_joints == {"g7_finger_joint1": 0.0, "g7_finger_joint2": 0.0}
    assert opened.held_joints["g7_finger_joint2"] == 0.04
    hand_closed, hand_open = (m.model.inertias[m.model.njoints - 1] for m in (closed, opened))
    assert hand_closed.mass == pytest.approx(hand_open.mass, rel=1e-15)
    # two 0.015 kg fingers 0.01 m off the hand's axis move 0.04 m out, symmetrically (the
    # body's CoM stays): the moment about z grows by 2 m ((0.01 + s)^2 - 0.01^2)
    finger_mass, stroke = 0.015, 0.04
    grown = hand_open.inertia - hand_closed.inertia
    assert grown[0, 0] > 0.0
    assert grown[2, 2] > 0.0
    assert grown[2, 2] == pytest.approx(
        2 * finger_mass * ((0.01 + stroke) ** 2 - 0.01**2), rel=1e-6
    )


def _with(spec, **changes):
    import dataclasses

    return dataclasses.replace(spec, **changes)


# --- what is still refused --------------------------------------------------------------------
def _edited(arm: str, link: str, **attributes: str) -> str:
    root = ET.fromstring(_urdf(arm))
    inertial = root.find(f"link[@name='{link}']/inertial")
    for key, value in attributes.items():
        inertial.find("mass" if key == "value" else "inertia").set(key, value)
    return ET.tostring(root, encoding="unicode")


@pytest.mark.parametrize(
    ("arm_name", "link", "attributes", "message"),
    [
        ("gripper7", "g7_link3", {"ixx": "-0.01"}, r"link 'g7_link3': inertia must be positive"),
        ("gripper7", "g7_link8", {"value": "abc"}, r"link 'g7_link8' <mass>: value='abc' is not"),
        ("gripper7", "g7_link8", {"izz": "nan"}, r"link 'g7_link8' <inertia>: izz='nan' must be"),
        ("cont6", "c6_link_2", {"izz": "1.0"}, r"link 'c6_link_2': principal moments .* triangle"),
        ("cont6", "c6_link_mount", {"value": "-1"}, r"link 'c6_link_mount': mass must be finite"),
        # a mass of 0 with a non-zero inertia is no rigid body
        ("world7", "w7_link_3", {"value": "0"}, r"link 'w7_link_3': mass must be finite and > 0"),
    ],
)
def test_a_bad_inertial_is_a_one_line_error_naming_the_link(arm_name, link, attributes, message):
    _, spec = load_model_config(_config(arm_name))
    with pytest.raises(ModelError, match=message) as caught:
        FreeFloatingModel.from_urdf_string(_edited(arm_name, link, **attributes), spec)
    assert "\n" not in str(caught.value)


def test_a_moving_link_with_an_empty_inertial_is_refused():
    zero = {key: "0" for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    _, spec = load_model_config(_config("cont6"))
    xml = _edited("cont6", "c6_link_6", value="0", **zero)
    with pytest.raises(ModelError, match=r"body of joint 'c6_joint_6' .*mass 0\.0 kg") as caught:
        FreeFloatingModel.from_urdf_string(xml, spec)
    assert "\n" not in str(caught.value)


def test_mimic_joints_cannot_be_controlled():
    urdf, spec = load_model_config(_config("gripper7"))
    leader = (*EXPECTED["gripper7"]["joints"], "g7_finger_joint1")
    with pytest.raises(ModelError, match=r"controlled joint 'g7_finger_joint1' leads <mimic>"):
        FreeFloatingModel.from_urdf(urdf, _with(spec, controlled_joints=leader, held_joints={}))
    follower = (*EXPECTED["gripper7"]["joints"], "g7_finger_joint2")
    with pytest.raises(ModelError, match=r"'g7_finger_joint2' is a <mimic> of 'g7_finger_joint1'"):
        FreeFloatingModel.from_urdf(urdf, _with(spec, controlled_joints=follower))
    conflicting = {"g7_finger_joint1": 0.02, "g7_finger_joint2": 0.03}
    with pytest.raises(ModelError, match=r"'g7_finger_joint2' 0.03, but its <mimic> rule"):
        FreeFloatingModel.from_urdf(urdf, _with(spec, held_joints=conflicting))


def test_a_controlled_joint_left_at_0_outside_its_limits_is_refused_naming_it():
    """The model YAML gives no angle for g7_joint4, whose range [-3.07, -0.07] rad excludes the
    default 0: one line naming the joint and its range, not a start every command is refused
    from."""
    urdf, spec = load_model_config(_config("gripper7"))
    given = {k: v for k, v in spec.initial_joint_positions.items() if k != "g7_joint4"}
    with pytest.raises(ModelError, match=r"defaults to 0 rad, outside the limits of g7_joint4 \["):
        FreeFloatingModel.from_urdf(urdf, _with(spec, initial_joint_positions=given))


def test_joints_past_the_camera_are_held_and_must_sit_within_their_limits():
    """Camera on link 3: joints 4-7 are off the chain and held; joint 4's range excludes 0."""
    urdf, spec = load_model_config(_config("gripper7"))
    short = _with(
        spec,
        camera_frame="g7_link3",
        wrist_frame=None,
        positioning_joints=None,
        wrist_joints=None,
        initial_joint_positions={},
    )
    with pytest.raises(ModelError, match=r"held joint 'g7_joint4' at 0 is outside its limits"):
        FreeFloatingModel.from_urdf(urdf, short)
    held = {"g7_joint4": -1.5, "g7_finger_joint1": 0.01}
    robot = FreeFloatingModel.from_urdf(urdf, _with(short, held_joints=held))
    assert robot.joint_names == ("g7_joint1", "g7_joint2", "g7_joint3")
    assert set(robot.held_joints) == {f"g7_joint{i}" for i in range(4, 8)} | {
        "g7_finger_joint1",
        "g7_finger_joint2",
    }
    assert robot.subchains is None  # 3 joints: no positioning / wrist split by default
    with pytest.raises(ModelError, match=r"initial_joint_positions names 'g7_joint5'.*held"):
        FreeFloatingModel.from_urdf(
            urdf, _with(short, held_joints=held, initial_joint_positions={"g7_joint5": 0.1})
        )


def test_unknown_joint_names_are_listed():
    urdf, spec = load_model_config(_config("world7"))
    with pytest.raises(ModelError, match=r"held_joints \['elbow'\] are not moving joints"):
        FreeFloatingModel.from_urdf(urdf, _with(spec, held_joints={"elbow": 0.0}))
    with pytest.raises(ModelError, match=r"both in controlled_joints and held_joints"):
        FreeFloatingModel.from_urdf(
            urdf,
            _with(spec, controlled_joints=("w7_joint_1",), held_joints={"w7_joint_1": 0.0}),
        )


# --- the model YAML's base ---------------------------------------------------------------------
def _yaml(tmp_path: Path, arm: str, text: str) -> Path:
    path = tmp_path / "model.yaml"
    head = f"urdf: {ARMS / arm / 'robot.urdf'}\ncamera_frame: c6_end_effector\nwrist_frame: null\n"
    path.write_text(head + text)
    return path


def test_the_base_of_the_model_yaml_is_the_root_body(tmp_path):
    path = _yaml(
        tmp_path,
        "cont6",
        "base:\n  mass: 150.0\n  inertia: [20, 1, 0, 25, 0, 30]\n"
        "  mount_xyz: [0.1, 0.2, 0.3]\n  mount_rpy: [0, 0, 1.5707963267948966]\n",
    )
    robot = load_model(path)
    base = robot.model.inertias[1]
    assert base.mass == 150.0  # the mount link has no mass
    np.testing.assert_allclose(base.inertia, [[20, 1, 0], [1, 25, 0], [0, 0, 30]], atol=1e-12)
    np.testing.assert_allclose(base.lever, 0.0, atol=1e-15)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, robot.neutral())
    mount = data.oMf[robot.model.getFrameId("c6_root")]
    np.testing.assert_allclose(mount.translation, [0.1, 0.2, 0.3], atol=1e-15)
    np.testing.assert_allclose(mount.rotation @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    assert not any("thesis satellite" in line for line in robot.describe())


@pytest.mark.parametrize(
    ("text", "error", "message"),
    [
        ("base: {mass: 10}\n", ConfigError, r"'base': 'inertia' is required"),
        ("base: {mass: 10, inertia: [1, 1]}\n", ConfigError, r"'inertia' must be a list of 3 or 6"),
        ("base: {mass: 10, inertia: [1, 1, 1], spin: 1}\n", ConfigError, r"unknown key\(s\)"),
        ("base: {mass: .nan, inertia: [1, 1, 1]}\n", ConfigError, r"'mass' must be a finite"),
        ("base: {mass: -10, inertia: [1, 1, 1]}\n", ModelError, r"base: mass must be finite"),
        ("base: {mass: 10, inertia: [1, 1, 3]}\n", ModelError, r"base: principal moments"),
        ("held_joints: [c6_joint_1]\n", ConfigError, r"'held_joints' must be a mapping"),
        ("controlled_joints: c6_joint_1\n", ConfigError, r"'controlled_joints' must be a list"),
    ],
)
def test_a_bad_model_yaml_is_a_one_line_error(tmp_path, text, error, message):
    with pytest.raises(error, match=message) as caught:
        load_model(_yaml(tmp_path, "cont6", text))
    assert "\n" not in str(caught.value)


# --- the default arm is untouched -------------------------------------------------------------
def test_the_default_arm_is_built_exactly_as_pinocchio_reads_its_urdf():
    urdf, _ = load_model_config(default_model_config())
    robot = load_model(default_model_config())
    reference = pin.buildModelFromXML(urdf.read_text(), pin.JointModelFreeFlyer())
    model = robot.model
    assert list(model.names) == list(reference.names)
    assert (model.nq, model.nv) == (reference.nq, reference.nv)
    for mine, theirs in zip(model.inertias, reference.inertias, strict=True):
        assert mine.mass == theirs.mass
        assert np.array_equal(mine.lever, theirs.lever)
        assert np.array_equal(mine.inertia, theirs.inertia)
    for mine, theirs in zip(model.jointPlacements, reference.jointPlacements, strict=True):
        assert np.array_equal(mine.homogeneous, theirs.homogeneous)
    assert [f.name for f in model.frames] == [f.name for f in reference.frames]
    for limits in ("lowerPositionLimit", "upperPositionLimit", "velocityLimit", "effortLimit"):
        assert np.array_equal(getattr(model, limits), getattr(reference, limits))
    assert robot.held_joints == {}
    assert robot.base_link == "base_link"
    assert robot.urdf_xml == urdf.read_text()
