"""The core's free-floating dynamics against iDynTree, an independent multibody library.

iDynTree (KinDynComputations, its own URDF parser and algorithms; nothing shared with Pinocchio)
loads the same URDF text as each model YAML, with the same floating base, and at seeded random
states gives the free-floating mass matrix, the spatial momentum and the camera frame's Jacobian.

Coordinates. iDynTree's MIXED representation uses, for the base, the linear velocity of the base
origin and the angular velocity, both in world axes, linear first: exactly the thesis V_b of
eq. (2.1)-(2.4). So its mass matrix is M of eq. (2.7) as it stands, its momentum is L_B of
eq. (2.33) (about the base origin, world axes), and a frame's Jacobian is [J_b, J_m] with
J_m = [J_v; J_omega] of the frame origin in world axes (LOCAL_WORLD_ALIGNED in Pinocchio).
In the BODY_FIXED representation the base twist is in base axes, nu_body = T nu with
T = blkdiag(R^T, R^T, E_n), so M = T^T M_body T and L_B = blkdiag(R, R) L_body: checked too.

What the iDynTree side is given, besides the URDF text: the controlled joints (in our theta
order), the positions of the held joints (from the YAML's ``held_joints``, default 0, a <mimic>
joint by its leader's rule; iDynTree lumps them at those positions), and the satellite body when
the YAML has ``base``, or the URDF root (with its fixed links) has no mass, or the root is a
massless ``world`` link (the thesis satellite then: 2550 kg, principal moments 6200 3540 7090
kg m^2, arm root at (-0.79, -0.29, 1.0) m), added as a new root link whose frame is the base frame
{B}, carrying the URDF root link at the mount pose (a ``world`` root stays, as a massless link on
the satellite: the same bodies at the same places as replacing it).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from rns_ros.core import FreeFloatingModel, FreeFloatingState, load_model
from rns_ros.core.momentum import generalized_jacobian, spatial_momentum
from rns_ros.resources import default_model_config

idt = pytest.importorskip(
    "idyntree.bindings", reason="iDynTree (idyntree, requirements-dev.txt) is not installed"
)

ARMS = Path(__file__).resolve().parents[1] / "data" / "arms"
MODEL_YAMLS = [default_model_config(), *sorted(ARMS.glob("*/model.yaml"))]
#: Largest relative difference max|ours - iDynTree| / max|iDynTree| allowed per quantity [-].
RELATIVE_TOLERANCE = 1e-9
#: Relative change of one link's mass the comparison must detect [-].
MASS_PERTURBATION = 1e-3
STATES = 5
#: The thesis satellite used when the YAML has no ``base`` and the URDF root is massless.
DEFAULT_SATELLITE = {
    "mass": 2550.0,
    "inertia": [6200.0, 3540.0, 7090.0],
    "mount_xyz": [-0.79, -0.29, 1.0],
    "mount_rpy": [0.0, 0.0, 0.0],
}
SATELLITE_LINK = "idyntree_check_satellite"


def _yaml_id(path: Path) -> str:
    return "default" if path == default_model_config() else path.parent.name


@dataclass(frozen=True)
class Description:
    """What iDynTree is built from: URDF text, base link, controlled and held joints."""

    xml: str
    base_link: str
    controlled: tuple[str, ...]
    held: dict[str, float]
    camera_frame: str


def _mass(link: ET.Element) -> float:
    mass = link.find("inertial/mass")
    return 0.0 if mass is None else float(mass.get("value"))


def _root_link(root: ET.Element) -> str:
    children = {joint.find("child").get("link") for joint in root.findall("joint")}
    links = [link.get("name") for link in root.findall("link")]
    (name,) = [link for link in links if link not in children]
    return name


def _add_satellite(root: ET.Element, base: dict) -> None:
    """Add the satellite as the new root link, carrying the URDF root at the mount pose."""
    arm_root = _root_link(root)
    moments = [float(value) for value in base["inertia"]]
    if len(moments) == 3:
        moments = [moments[0], 0.0, 0.0, moments[1], 0.0, moments[2]]
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    satellite = ET.SubElement(root, "link", name=SATELLITE_LINK)
    inertial = ET.SubElement(satellite, "inertial")
    ET.SubElement(inertial, "mass", value=repr(float(base["mass"])))
    ET.SubElement(inertial, "inertia", {k: repr(v) for k, v in zip(keys, moments, strict=True)})
    mount = ET.SubElement(root, "joint", name=f"{SATELLITE_LINK}_mount", type="fixed")
    ET.SubElement(mount, "parent", link=SATELLITE_LINK)
    ET.SubElement(mount, "child", link=arm_root)
    xyz, rpy = base.get("mount_xyz", [0.0] * 3), base.get("mount_rpy", [0.0] * 3)
    ET.SubElement(mount, "origin", xyz=" ".join(map(repr, xyz)), rpy=" ".join(map(repr, rpy)))


def _needs_satellite(root: ET.Element) -> bool:
    """The URDF root link and every link joined to it by fixed joints carry no mass, or the root
    is a massless ``world`` link (a fixed-base description: the satellite replaces the world)."""
    links = {link.get("name"): link for link in root.findall("link")}
    children = {joint.find("child").get("link"): joint for joint in root.findall("joint")}
    cluster = [_root_link(root)]
    if cluster == ["world"] and _mass(links["world"]) == 0.0:
        return True
    for name in cluster:  # grows while iterating: the links fixed to the cluster
        cluster += [
            child
            for child, joint in children.items()
            if joint.find("parent").get("link") == name and joint.get("type") == "fixed"
        ]
    return all(_mass(links[name]) == 0.0 for name in cluster)


def _held_positions(root: ET.Element, controlled, given: dict) -> dict[str, float]:
    """Position [rad or m] of every moving joint not controlled: ``held_joints`` of the YAML,
    else a <mimic> joint's multiplier * leader + offset, else 0."""
    joints = {j.get("name"): j for j in root.findall("joint") if j.get("type") != "fixed"}
    held = {name: float(given[name]) for name in joints if name not in controlled and name in given}
    pending = [name for name in joints if name not in controlled and name not in held]
    while pending:
        name = pending.pop(0)
        mimic = joints[name].find("mimic")
        if mimic is None:
            held[name] = 0.0
            continue
        leader = mimic.get("joint")
        assert leader not in controlled, f"held joint {name} mimics controlled joint {leader}"
        if leader not in held:
            pending.append(name)
            continue
        multiplier = float(mimic.get("multiplier", 1.0))
        held[name] = multiplier * held[leader] + float(mimic.get("offset", 0.0))
    return held


def _expanded(path: Path, config: dict) -> str:
    """The URDF text of the model YAML's ``urdf``: a xacro expanded by the xacro package
    itself, its ``$(find pkg)`` through an ament index made for the test (as ROS finds them)."""
    urdf = path.parent / config["urdf"]
    if not urdf.name.endswith(".xacro"):
        return urdf.read_text()
    import os
    import tempfile

    import xacro

    with tempfile.TemporaryDirectory() as prefix:
        for package, folder in (config.get("packages") or {}).items():
            marker = Path(prefix, "share", "ament_index", "resource_index", "packages", package)
            marker.parent.mkdir(parents=True, exist_ok=True)
            marker.write_text("")
            Path(prefix, "share", package).symlink_to((path.parent / folder).resolve())
        old = os.environ.get("AMENT_PREFIX_PATH")
        os.environ["AMENT_PREFIX_PATH"] = prefix
        try:
            args = {k: str(v) for k, v in (config.get("xacro_args") or {}).items()}
            return xacro.process_file(str(urdf), mappings=args).toxml()
        finally:
            if old is None:
                del os.environ["AMENT_PREFIX_PATH"]
            else:
                os.environ["AMENT_PREFIX_PATH"] = old


def _description(path: Path, robot: FreeFloatingModel) -> Description:
    config = yaml.safe_load(path.read_text())
    root = ET.fromstring(_expanded(path, config))  # the text we loaded
    controlled = tuple(robot.joint_names)
    held = _held_positions(root, controlled, config.get("held_joints") or {})
    if "base" in config or _needs_satellite(root):
        _add_satellite(root, config.get("base") or DEFAULT_SATELLITE)
    return Description(
        xml=ET.tostring(root, encoding="unicode"),
        base_link=_root_link(root),
        controlled=controlled,
        held=held,
        camera_frame=config.get("camera_frame", "camera"),
    )


def _kindyn(description: Description, representation):
    loader = idt.ModelLoader()
    assert loader.loadReducedModelFromString(
        description.xml, list(description.controlled), description.held
    ), "iDynTree could not load the URDF"
    model = loader.model()
    names = tuple(model.getJointName(i) for i in range(model.getNrOfDOFs()))
    assert names == description.controlled, f"iDynTree joint order {names}"
    kindyn = idt.KinDynComputations()
    assert kindyn.loadRobotModel(model)
    assert kindyn.setFloatingBase(description.base_link)
    assert kindyn.getFloatingBase() == description.base_link
    assert kindyn.setFrameVelocityRepresentation(representation)
    return kindyn


def _perturbed(description: Description) -> Description:
    """The description with one arm link's mass scaled by 1 + MASS_PERTURBATION: the child link
    of the last controlled joint that carries mass (a flange link may carry none)."""
    root = ET.fromstring(description.xml)
    links = {link.get("name"): link for link in root.findall("link")}
    joints = root.findall("joint")  # under <robot>: not those of a <ros2_control> block
    children = {joint.get("name"): joint.find("child").get("link") for joint in joints}
    link = next(
        links[children[joint]]
        for joint in reversed(description.controlled)
        if _mass(links[children[joint]]) > 0.0
    )
    mass = link.find("inertial/mass")
    mass.set("value", repr(float(mass.get("value")) * (1.0 + MASS_PERTURBATION)))
    return replace(description, xml=ET.tostring(root, encoding="unicode"))


def _states(robot: FreeFloatingModel, seed: int = 31):
    """Seeded random (theta [rad] (n,), r_b [m] (3,), quaternion xyzw (4,), V_b (6,), theta_dot)."""
    rng = np.random.default_rng(seed)
    lower = np.maximum(robot.lower_limits, -np.pi)
    upper = np.minimum(robot.upper_limits, np.pi)
    for _ in range(STATES):
        quaternion = rng.normal(size=4)
        yield (
            rng.uniform(lower, upper),
            rng.uniform(-5.0, 5.0, 3),
            quaternion / np.linalg.norm(quaternion),
            rng.normal(size=6),
            rng.normal(size=robot.n),
        )


def _ours(robot: FreeFloatingModel, sample) -> dict[str, np.ndarray]:
    """Our quantities at a sampled state (thesis coordinates, world axes)."""
    theta, position, quaternion, base_twist, theta_dot = sample
    state = FreeFloatingState.compute(robot, robot.configuration(theta, position, quaternion))
    return {
        "total mass": np.array(robot.total_mass),
        "CoM": state.center_of_mass,
        "camera position": state.camera.position,
        "camera rotation": state.camera.rotation,
        "M": state.inertia,
        "M_b": state.inertia_base,
        "M_bm": state.coupling_inertia,
        "M_m": state.manipulator_inertia,
        "M~_omega": state.base_rotational_inertia,
        "M~_omega_m": state.coupling_angular_momentum_matrix,
        "L_B": spatial_momentum(state, base_twist, theta_dot),
        "J_b": state.camera.base_jacobian,
        "J_m": state.camera.jacobian,
        "J*": generalized_jacobian(state, state.camera),
    }


def _set_state(kindyn, sample, body_fixed: bool) -> np.ndarray:
    """Give iDynTree the sampled state; returns R (world <- base) from iDynTree's quaternion."""
    theta, position, quaternion, base_twist, theta_dot = sample
    x, y, z, w = quaternion
    rotation = idt.Rotation.RotationFromQuaternion(idt.Vector4([w, x, y, z])).toNumPy()
    world_h_base = np.eye(4)
    world_h_base[:3, :3], world_h_base[:3, 3] = rotation, position
    if body_fixed:  # the base twist in base axes
        base_twist = np.concatenate((rotation.T @ base_twist[:3], rotation.T @ base_twist[3:]))
    assert kindyn.setRobotState(world_h_base, theta, base_twist, theta_dot, np.zeros(3))
    return rotation


def _mass_matrix(kindyn, n: int) -> np.ndarray:
    matrix = idt.MatrixDynSize(6 + n, 6 + n)
    assert kindyn.getFreeFloatingMassMatrix(matrix)
    return matrix.toNumPy()


def _theirs(kindyn, description: Description, sample) -> dict[str, np.ndarray]:
    """iDynTree's quantities (MIXED representation = thesis coordinates), the thesis blocks
    taken from its mass matrix and Jacobian."""
    n = len(description.controlled)
    _set_state(kindyn, sample, body_fixed=False)
    inertia = _mass_matrix(kindyn, n)
    jacobian = idt.MatrixDynSize(6, 6 + n)
    assert kindyn.getFrameFreeFloatingJacobian(description.camera_frame, jacobian)
    jacobian = jacobian.toNumPy()
    camera = kindyn.getWorldTransform(description.camera_frame)
    m_b, m_bm = inertia[:6, :6], inertia[:6, 6:]
    m_v, m_vw = m_b[:3, :3], m_b[:3, 3:]  # eq. (3.2): linear momentum eliminated
    j_b, j_m = jacobian[:, :6], jacobian[:, 6:]
    return {
        "total mass": np.array(kindyn.model().getTotalMass()),
        "CoM": kindyn.getCenterOfMassPosition().toNumPy(),
        "camera position": camera.getPosition().toNumPy(),
        "camera rotation": camera.getRotation().toNumPy(),
        "M": inertia,
        "M_b": m_b,
        "M_bm": m_bm,
        "M_m": inertia[6:, 6:],
        "M~_omega": m_b[3:, 3:] - m_vw.T @ np.linalg.solve(m_v, m_vw),
        "M~_omega_m": m_bm[3:] - m_vw.T @ np.linalg.solve(m_v, m_bm[:3]),
        "L_B": kindyn.getLinearAngularMomentum().toNumPy(),
        "J_b": j_b,
        "J_m": j_m,
        "J*": j_m - j_b @ np.linalg.solve(m_b, m_bm),
    }


def _relative_differences(ours: dict, theirs: dict) -> dict[str, float]:
    """max|ours - theirs| / max|theirs| per quantity."""
    return {
        key: float(np.abs(ours[key] - theirs[key]).max() / max(np.abs(theirs[key]).max(), 1e-300))
        for key in theirs
    }


def max_relative_differences(robot, description: Description) -> dict[str, float]:
    """The largest relative difference per quantity over the seeded states (MIXED)."""
    kindyn = _kindyn(description, idt.MIXED_REPRESENTATION)
    worst: dict[str, float] = {}
    for sample in _states(robot):
        differences = _relative_differences(
            _ours(robot, sample), _theirs(kindyn, description, sample)
        )
        worst = {key: max(value, worst.get(key, 0.0)) for key, value in differences.items()}
    return worst


@pytest.fixture(scope="module", params=MODEL_YAMLS, ids=_yaml_id)
def arm(request) -> tuple[FreeFloatingModel, Description]:
    robot = load_model(request.param)
    return robot, _description(request.param, robot)


def test_free_floating_quantities_match_idyntree(arm):
    robot, description = arm
    worst = max_relative_differences(robot, description)
    failed = {key: value for key, value in worst.items() if not value <= RELATIVE_TOLERANCE}
    assert not failed, f"relative differences above {RELATIVE_TOLERANCE:g}: {failed}"


def test_body_fixed_representation_gives_the_same_thesis_quantities(arm):
    """M = T^T M_body T and L_B = blkdiag(R, R) L_body with T = blkdiag(R^T, R^T, E_n)."""
    robot, description = arm
    kindyn = _kindyn(description, idt.BODY_FIXED_REPRESENTATION)
    n = robot.n
    for sample in _states(robot):
        rotation = _set_state(kindyn, sample, body_fixed=True)
        transform = np.eye(6 + n)
        transform[:3, :3] = transform[3:6, 3:6] = rotation.T
        momentum = kindyn.getLinearAngularMomentum().toNumPy()
        theirs = {
            "M": transform.T @ _mass_matrix(kindyn, n) @ transform,
            "L_B": np.concatenate((rotation @ momentum[:3], rotation @ momentum[3:])),
        }
        ours = _ours(robot, sample)
        differences = _relative_differences({key: ours[key] for key in theirs}, theirs)
        assert max(differences.values()) <= RELATIVE_TOLERANCE, differences


def test_a_changed_link_mass_is_detected(arm):
    """One link's mass 1e-3 (relative) larger on the iDynTree side: every dynamic quantity
    differs by far more than the tolerance, the kinematic ones still agree (so the comparison
    can fail, and fails for the right reason)."""
    robot, description = arm
    worst = max_relative_differences(robot, _perturbed(description))
    kinematic = ("camera position", "camera rotation", "J_b", "J_m")
    for key, value in worst.items():
        if key in kinematic:
            assert value <= RELATIVE_TOLERANCE, (key, value)
        else:
            assert value > 10.0 * RELATIVE_TOLERANCE, (key, value)
