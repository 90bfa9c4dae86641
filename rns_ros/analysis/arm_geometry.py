"""Candidate geometries of the thesis' 7-DoF arm, their URDF and forward kinematics.

The thesis prints the masses, principal moments (Table 4.1) and mount (section 4.1.1) of its arm,
never the joint axes, the theta = 0 pose, the link lengths or the offsets. A :class:`Geometry`
names those; :func:`geometry_urdf` writes the URDF of a candidate, reusing the base, the mount and
every link's mass and moments from ``config/urdf/rns_7dof_arm_inferred.urdf`` (docs/model.md,
docs/arm_identification.md).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import InputError, ModelError
from rns_ros.core.model import FreeFloatingModel, ModelSpec
from rns_ros.core.urdf_prep import INERTIA_KEYS, inertia_matrix
from rns_ros.core.urdf_tree import UrdfTree

_ROOT = Path(__file__).resolve().parents[2]
#: The first, inferred arm: every candidate reuses its base, mount, masses and moments (Table 4.1).
REFERENCE_URDF = _ROOT / "config" / "urdf" / "rns_7dof_arm_inferred.urdf"

_JOINTS = tuple(f"joint_{i}" for i in range(1, 8))
_UNIT = {
    "+x": (1, 0, 0),
    "-x": (-1, 0, 0),
    "+y": (0, 1, 0),
    "-y": (0, -1, 0),
    "+z": (0, 0, 1),
    "-z": (0, 0, -1),
}


def axis_vector(label: str) -> np.ndarray:
    """Unit vector (3,) of an axis label '+x', '-y', ... (base frame at theta = 0)."""
    if label not in _UNIT:
        raise InputError(f"axis label {label!r} must be one of {sorted(_UNIT)}")
    return np.array(_UNIT[label], dtype=float)


def perpendicular_basis(direction: str) -> tuple[np.ndarray, np.ndarray]:
    """(e1, e2), unit vectors spanning the plane normal to ``direction``: e1 is the first base
    axis (x, y, z order) not parallel to it, e2 = u x e1."""
    u = axis_vector(direction)
    e1 = next(np.eye(3)[i] for i in range(3) if abs(u[i]) < 0.5)
    return e1, np.cross(u, e1)


def axis_label(vector: np.ndarray) -> str:
    """Inverse of :func:`axis_vector`."""
    for label, unit in _UNIT.items():
        if np.allclose(vector, unit):
            return label
    raise InputError(f"{vector} is not a signed base axis")


@dataclass(frozen=True)
class Geometry:
    """A candidate 7-DoF geometry; at theta = 0 every link frame is parallel to the base frame.

    Attributes:
        direction: the straight arm's direction u at theta = 0 ('+z': along the base z axis).
        axes: joint axes at theta = 0, base-frame labels ('+z', '-y', ...), length 7.
        lengths: link lengths along u [m], length 7: joint i origin to joint i+1 origin (link 7:
            joint 7 to the camera); each link's CoM sits at mid-length on that segment.
        shoulder, elbow, wrist: lateral offsets [m] (e1, e2 components, :func:`perpendicular_basis`)
            added to the origins of joints 3, 4 and 6 (the wrist point p_w is the joint-6 origin).
    """

    direction: str = "+z"
    axes: tuple[str, ...] = ("+z", "+y", "+z", "+y", "+z", "+y", "+z")
    lengths: tuple[float, ...] = (0.10, 0.33, 1.00, 0.81, 0.35, 0.10, 0.20)
    shoulder: tuple[float, float] = (0.0, 0.0)
    elbow: tuple[float, float] = (0.0, 0.15)
    wrist: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        axis_vector(self.direction)
        if len(self.axes) != 7 or len(self.lengths) != 7:
            raise InputError("a Geometry needs 7 axes and 7 lengths")
        for label in self.axes:
            axis_vector(label)
        for value in self.lengths:
            if not (math.isfinite(value) and value > 0.0):
                raise InputError(f"link lengths must be finite and > 0 m, got {self.lengths}")
        for name in ("shoulder", "elbow", "wrist"):
            offset = getattr(self, name)
            if len(offset) != 2 or not all(math.isfinite(v) for v in offset):
                raise InputError(f"{name} offset must be 2 finite numbers [m], got {offset}")

    def label(self) -> str:
        """Short name: direction and axis sequence, e.g. 'u+z z+y+z+y+z+y+z+'."""
        return f"u{self.direction} " + " ".join(self.axes)

    def joint_origins(self) -> list[np.ndarray]:
        """Origins (3,) [m]: entry i (1..6) is joint i+1's origin in link i's frame, entry 7 the
        camera's in link 7's frame; entry 0 is a placeholder (joint 1 sits on the mount)."""
        u = axis_vector(self.direction)
        e1, e2 = perpendicular_basis(self.direction)
        lateral = {1: self.shoulder, 2: self.elbow, 4: self.wrist}  # added to joint i+2
        origins = [np.zeros(3)]
        for i in range(7):
            offset = lateral.get(i, (0.0, 0.0))
            origins.append(self.lengths[i] * u + offset[0] * e1 + offset[1] * e2)
        return origins


# ---- reference data (Table 4.1, mount, base) read from the default URDF -------------------------
@dataclass(frozen=True)
class LinkData:
    """Mass [kg], axial and perpendicular principal moments [kg m^2] of one link (Table 4.1)."""

    mass: float
    axial: float
    perpendicular: float

    def uniform_length(self) -> float:
        """Length [m] of a uniform prism with these moments: L^2 = (12 I_perp - 6 I_axial) / m
        (solid cylinder, tube and square bar all give it)."""
        return math.sqrt((12.0 * self.perpendicular - 6.0 * self.axial) / self.mass)


@dataclass(frozen=True)
class ReferenceData:
    """What candidates reuse from the default URDF."""

    base_xml: str
    mount: np.ndarray
    links: tuple[LinkData, ...]
    velocity: tuple[float, ...]
    effort: tuple[float, ...]


def _rpy_matrix(text: str | None) -> np.ndarray:
    roll, pitch, yaw = (float(v) for v in (text or "0 0 0").split())
    return pin.rpy.rpyToMatrix(roll, pitch, yaw)


def load_reference(path: str | Path = REFERENCE_URDF) -> ReferenceData:
    """Read the base link, mount, Table 4.1 data and joint limits from a 7-DoF URDF.

    Raises:
        ModelError: the file lacks base_link, joint_1..7 or link_1..7 inertials.
    """
    tree = UrdfTree.parse(Path(path).read_text(), str(path))
    links = {link.get("name"): link for link in tree.links}
    joints = {joint.name: joint.element for joint in tree.joints}
    if "base_link" not in links or any(name not in joints for name in _JOINTS):
        raise ModelError(f"{path}: needs base_link and joints {_JOINTS}")
    base_xml = ET.tostring(links["base_link"], encoding="unicode").strip()
    mount = np.array([float(v) for v in joints["joint_1"].find("origin").get("xyz").split()])
    data, velocity, effort = [], [], []
    for i in range(1, 8):
        inertial = links[f"link_{i}"].find("inertial")
        if inertial is None:
            raise ModelError(f"{path}: link_{i} has no <inertial>")
        element = inertial.find("inertia")
        matrix = inertia_matrix({k: float(element.get(k)) for k in INERTIA_KEYS})
        rotation = _rpy_matrix(inertial.find("origin").get("rpy"))
        matrix = rotation @ matrix @ rotation.T
        com = np.array([float(x) for x in inertial.find("origin").get("xyz").split()])
        direction = com / np.linalg.norm(com)
        axial = float(direction @ matrix @ direction)
        perpendicular = float((np.trace(matrix) - axial) / 2.0)
        data.append(LinkData(float(inertial.find("mass").get("value")), axial, perpendicular))
        limit = joints[f"joint_{i}"].find("limit")
        velocity.append(float(limit.get("velocity")))
        effort.append(float(limit.get("effort")))
    return ReferenceData(base_xml, mount, tuple(data), tuple(velocity), tuple(effort))


_REFERENCE: ReferenceData | None = None


def reference() -> ReferenceData:
    """:func:`load_reference` of the default URDF, cached."""
    global _REFERENCE
    if _REFERENCE is None:
        _REFERENCE = load_reference()
    return _REFERENCE


def uniform_lengths() -> np.ndarray:
    """Uniform-prism lengths of the seven links [m] (docs/model.md), shape (7,)."""
    return np.array([link.uniform_length() for link in reference().links])


#: The first, inferred geometry (config/urdf/rns_7dof_arm_inferred.urdf, docs/model.md).
INFERRED_GEOMETRY = Geometry()
#: The identified geometry, best of ``scripts/identify_arm.py`` (seed 13): the default model
#: (config/urdf/rns_7dof_arm.urdf is ``geometry_urdf(IDENTIFIED_GEOMETRY, "rns_7dof_arm")``).
IDENTIFIED_GEOMETRY = Geometry(
    direction="+z",
    axes=("-z", "+y", "+z", "+x", "+z", "+y", "+z"),
    lengths=(
        0.096670756074952,
        0.275744184308886,
        0.7900283433989511,
        0.6669808732095246,
        0.3188089328092297,
        0.10292696340152957,
        0.21135911297988247,
    ),
    shoulder=(0.08132620800953681, -0.13457462833088496),
    elbow=(0.08211197702113737, -0.12999504594620406),
    wrist=(-0.08242411425807081, -0.20009132118076906),
)


# ---- URDF generator ---------------------------------------------------------------------------
def _xyz(vector) -> str:
    return " ".join(f"{float(v):.9g}" for v in vector)


def geometry_urdf(geometry: Geometry, name: str = "rns_7dof_arm_candidate") -> str:
    """URDF text of ``geometry`` with the reference base, mount, masses and moments.

    Each link's inertia is I_perp (E - u u^T) + I_axial u u^T about its CoM at mid-length (the
    distinct Table 4.1 moment along the link), written in the link frame (rpy 0).
    """
    ref = reference()
    u = axis_vector(geometry.direction)
    origins = geometry.joint_origins()
    parts = [
        '<?xml version="1.0"?>',
        f"<!-- generated by rns_ros.analysis.arm_identification: {geometry!r} -->",
        f'<robot name="{name}">',
        *(f'  <material name="{n}"><color rgba="{rgba}"/></material>' for n, rgba in MATERIALS),
        "  " + ref.base_xml,
    ]
    parent = "base_link"
    for i in range(7):
        origin = ref.mount if i == 0 else origins[i]
        link = ref.links[i]
        inertia = link.perpendicular * (np.eye(3) - np.outer(u, u)) + link.axial * np.outer(u, u)
        com = 0.5 * geometry.lengths[i] * u
        parts += [
            f'  <joint name="joint_{i + 1}" type="revolute">',
            f'    <parent link="{parent}"/>',
            f'    <child link="link_{i + 1}"/>',
            f'    <origin xyz="{_xyz(origin)}" rpy="0 0 0"/>',
            f'    <axis xyz="{_xyz(axis_vector(geometry.axes[i]))}"/>',
            f'    <limit lower="{-2 * math.pi!r}" upper="{2 * math.pi!r}" '
            f'velocity="{ref.velocity[i]}" effort="{ref.effort[i]}"/>',
            "  </joint>",
            f'  <link name="link_{i + 1}">',
            "    <inertial>",
            f'      <origin xyz="{_xyz(com)}" rpy="0 0 0"/>',
            f'      <mass value="{link.mass}"/>',
            f'      <inertia ixx="{inertia[0, 0]:.9g}" ixy="{inertia[0, 1]:.9g}" '
            f'ixz="{inertia[0, 2]:.9g}" iyy="{inertia[1, 1]:.9g}" iyz="{inertia[1, 2]:.9g}" '
            f'izz="{inertia[2, 2]:.9g}"/>',
            "    </inertial>",
            *_segment_visual(origins[i + 1], "white" if i % 2 == 0 else "grey"),
            "  </link>",
        ]
        parent = f"link_{i + 1}"
    parts += [
        '  <joint name="wrist_joint" type="fixed">',
        '    <parent link="link_5"/>',
        '    <child link="wrist"/>',
        f'    <origin xyz="{_xyz(origins[5])}" rpy="0 0 0"/>',
        "  </joint>",
        '  <link name="wrist">',
        "    <visual>",
        '      <geometry><sphere radius="0.06"/></geometry>',
        '      <material name="grey"/>',
        "    </visual>",
        "  </link>",
        '  <joint name="camera_joint" type="fixed">',
        '    <parent link="link_7"/>',
        '    <child link="camera"/>',
        f'    <origin xyz="{_xyz(origins[7])}" rpy="0 0 0"/>',
        "  </joint>",
        '  <link name="camera">',
        "    <visual>",
        '      <geometry><box size="0.08 0.08 0.08"/></geometry>',
        '      <material name="black"/>',
        "    </visual>",
        "  </link>",
        "</robot>",
        "",
    ]
    return "\n".join(parts)


#: Visual colours (the first geometry's): name, rgba.
MATERIALS = (
    ("gold", "0.85 0.7 0.2 1.0"),
    ("white", "0.9 0.9 0.9 1.0"),
    ("grey", "0.5 0.5 0.55 1.0"),
    ("black", "0.1 0.1 0.1 1.0"),
)


def _segment_visual(segment: np.ndarray, material: str, radius: float = 0.075) -> list[str]:
    """A cylinder from the link frame's origin to ``segment`` (the next joint origin) [m]: what
    the rerun and rviz views draw (visuals only; the physics is the inertial)."""
    length = float(np.linalg.norm(segment))
    z = segment / length
    # rotation taking the cylinder's z axis onto the segment (Rodrigues about z x d)
    axis = np.cross([0.0, 0.0, 1.0], z)
    angle = math.atan2(float(np.linalg.norm(axis)), float(z[2]))
    rotation = (
        pin.AngleAxis(angle, axis / np.linalg.norm(axis)).matrix() if angle > 1e-12 else np.eye(3)
    )
    rpy = pin.rpy.matrixToRpy(rotation)
    return [
        "    <visual>",
        f'      <origin xyz="{_xyz(0.5 * segment)}" rpy="{_xyz(rpy)}"/>',
        f'      <geometry><cylinder radius="{radius}" length="{length:.9g}"/></geometry>',
        f'      <material name="{material}"/>',
        "    </visual>",
    ]


SPEC = ModelSpec(
    camera_frame="camera",
    wrist_frame="wrist",
    positioning_joints=_JOINTS[:4],
    wrist_joints=_JOINTS[4:],
)


def build_model(geometry: Geometry) -> FreeFloatingModel:
    """The :class:`FreeFloatingModel` of ``geometry`` (inertials validated on the way)."""
    return FreeFloatingModel.from_urdf_string(geometry_urdf(geometry), SPEC, name="candidate")


def camera_position(geometry: Geometry, theta) -> np.ndarray:
    """Camera position in the base frame [m] (3,) by numpy forward kinematics (no Pinocchio):
    p = mount + sum_i R_1..i-1 o_i with R_i = exp([a_i] theta_i) (links base-aligned at 0)."""
    theta = np.asarray(theta, dtype=float)
    origins = geometry.joint_origins()
    rotation = np.eye(3)
    position = reference().mount.copy()
    for i in range(7):
        if i > 0:
            position = position + rotation @ origins[i]
        rotation = rotation @ pin.exp3(axis_vector(geometry.axes[i]) * theta[i])
    return position + rotation @ origins[7]
