"""Identify the thesis' 7-DoF geometry from what its text determines (issue 13).

The thesis prints the masses, principal moments (Table 4.1) and mount (section 4.1.1) of its arm,
never the joint axes, the theta = 0 pose, the link lengths or the offsets. This module

* generates a URDF for a candidate geometry (:class:`Geometry`, :func:`geometry_urdf`), reusing the
  base, the mount and every link's mass and moments from ``config/urdf/rns_7dof_arm_inferred.urdf``;
* scores a candidate on each constraint the thesis text gives, one function per constraint, each
  returning a :class:`Score` (value, pass/fail, thesis target):

  - :func:`score_end_effector`: camera at [-1.7, 0.45, 1.7] m at the 3-phase final configuration
    [-120 50 0 -60 180 180 0] deg (section 4.4.2, thesis_rest 2.3);
  - :func:`score_fold_phase_one` / :func:`score_fold_phase_three`: the 1-D reactionless elbow family
    of eq. (4.3) (driven by eqs. 4.17-4.18) reaches theta_4 = -pi from the 3-phase initial / final
    configuration without a turning point;
  - :func:`score_stowed` (stowed pose well-conditioned, eq. 4.19), :func:`score_full_deployment`
    (theta_4 from -pi up by 0.183 rad/s x 30 s, section 4.5.1) and
    :func:`score_partial_deployment` (final [90 50 0 -300 0 20 0] deg to the fold);
  - :func:`score_singular_window`: sigma_min(J-bar) < 0.2 interval (thesis 1.71-4.18 s, section
    4.3.2) and joints 5 and 7 counter-rotating near it (section 4.3.1);
  - :func:`score_inspection`: the two section-4.2.2 scenarios with k_g = 100.

The path checks integrate the reactionless family by arc length (RK2): d theta_P / ds = n(theta),
n the unit null vector of M~_P_omega_m (3 x 4) kept sign-continuous; a turning point is where n_4
changes sign (theta_4 reaches an extremum, eq. 4.17 divides by n_4). The closed-loop checks use
:func:`rns_ros.analysis.closed_loop.run_scenario` (coarse: 20 Hz, 10 ms steps; full: its defaults).
"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.analysis.closed_loop import PeriodSample, run_scenario
from rns_ros.control.reactionless_path import positioning_null_vector
from rns_ros.control.scenario import Scenario, load_scenario
from rns_ros.core.errors import InputError, ModelError
from rns_ros.core.model import FreeFloatingModel, ModelSpec

_ROOT = Path(__file__).resolve().parents[2]
#: The default arm whose base, mount, masses and moments every candidate reuses.
#: The first (inferred) geometry: Table 4.1 masses and moments, mount and base are read from it.
REFERENCE_URDF = _ROOT / "config" / "urdf" / "rns_7dof_arm_inferred.urdf"
SCENARIO_DIR = _ROOT / "config" / "scenarios"

#: Thesis targets (section 4.4.2, thesis_rest 2.3).
THESIS_EE_POSITION = np.array([-1.7, 0.45, 1.7])  # [m], base CoM frame
THREE_PHASE_INITIAL_DEG = (-20.0, -40.0, 0.0, -60.0, 180.0, 180.0, 0.0)
THREE_PHASE_FINAL_DEG = (-120.0, 50.0, 0.0, -60.0, 180.0, 180.0, 0.0)
#: Section 4.5: stowed configuration (eq. 4.19) [rad], elbow speed [rad/s] and duration [s].
STOWED = (math.pi / 2, -math.pi / 2, 0.0, -math.pi, math.pi, math.pi, 0.0)
DEPLOY_SPEED = 0.183
DEPLOY_TIME = 30.0
PARTIAL_FINAL_DEG = (90.0, 50.0, 0.0, -300.0, 0.0, 20.0, 0.0)
#: Section 4.3.2: DLS singular region epsilon and the thesis window [s].
SINGULAR_EPSILON = 0.2
THESIS_WINDOW = (1.71, 4.18)
#: Tolerances of the pass/fail decisions.
EE_TOLERANCE = 0.15  # [m]
N4_MIN = 0.05  # |n_4| below which eq. (4.17) counts as losing the theta_4 direction [-]
WINDOW_TOLERANCE = 0.5  # [s] on each end of the singular window
INSPECTION_TOLERANCE_DEG = 0.1  # final camera error [deg]
STOWED_N4_MIN = 0.3  # |n_4| at the stowed pose for "well-conditioned" [-]

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
    root = ET.fromstring(Path(path).read_text())
    links = {link.get("name"): link for link in root.iter("link")}
    joints = {joint.get("name"): joint for joint in root.iter("joint")}
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
        v = {k: float(element.get(k)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        matrix = np.array(
            [
                [v["ixx"], v["ixy"], v["ixz"]],
                [v["ixy"], v["iyy"], v["iyz"]],
                [v["ixz"], v["iyz"], v["izz"]],
            ]
        )
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


#: The current default geometry (docs/model.md).
#: The first, inferred geometry (config/urdf/rns_7dof_arm_inferred.urdf).
CURRENT = Geometry()
#: The identified geometry, best of ``scripts/identify_arm.py`` (seed 13): the default model since
#: issue 13 (config/urdf/rns_7dof_arm.urdf is ``geometry_urdf(IDENTIFIED, "rns_7dof_arm")``).
IDENTIFIED = Geometry(
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


# ---- scores -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Score:
    """One constraint: ``value`` (units in ``unit``), ``passed``, the thesis ``target`` (text),
    and ``shortfall`` >= 0 (0 when met; a continuous distance for ranking and optimisation)."""

    name: str
    value: float
    passed: bool
    target: str
    unit: str = ""
    shortfall: float = 0.0
    detail: str = ""


def _q(robot: FreeFloatingModel, theta) -> np.ndarray:
    return robot.configuration(theta)


def score_end_effector(robot: FreeFloatingModel) -> Score:
    """|p_camera - [-1.7, 0.45, 1.7]| [m] at the 3-phase final configuration (section 4.4.2),
    base CoM frame, base at rest (the 1.95 deg deviation of Table 4.2 is ignored)."""
    model, data = robot.model, robot.data
    pin.framesForwardKinematics(model, data, _q(robot, np.deg2rad(THREE_PHASE_FINAL_DEG)))
    position = data.oMf[robot.camera_frame_id].translation
    error = float(np.linalg.norm(position - THESIS_EE_POSITION))
    return Score(
        "ee_position",
        error,
        error <= EE_TOLERANCE,
        "[-1.7, 0.45, 1.7] m (0 m error)",
        "m",
        max(0.0, error - EE_TOLERANCE) + 0.1 * error,
        "p = " + np.array2string(position, precision=3),
    )


@dataclass(frozen=True)
class FoldPath:
    """Result of :func:`elbow_path`.

    Attributes:
        reached: the target theta_4 was reached before any turning point.
        theta4_end: theta_4 where the path stopped [rad] (target, extremum, or arc limit).
        min_n4: smallest |n_4| seen [-] (n unit null vector of M~_P_omega_m).
        max_ratio: largest max_i<4 |n_i / n_4|: joint 1-3 speed per unit elbow speed, eq. (4.17).
        arc: joint-space arc length travelled [rad].
        theta_end: configuration at the stop [rad] (7,).
    """

    reached: bool
    theta4_end: float
    min_n4: float
    max_ratio: float
    arc: float
    theta_end: np.ndarray


def elbow_path(
    robot: FreeFloatingModel,
    theta0,
    theta4_target: float,
    *,
    step: float = 0.01,
    max_arc: float = 12.0,
) -> FoldPath:
    """Follow the reactionless elbow family of eq. (4.3) from ``theta0`` towards theta_4 =
    ``theta4_target`` [rad] by arc length (RK2, ``step`` [rad]); wrist joints held.

    The direction starts with n_4 pointing towards the target and stays sign-continuous; the path
    stops at the target (reached), where n_4 changes sign (a turning point: eq. 4.17-4.18 cannot
    drive theta_4 further) or after ``max_arc`` [rad] of joint-space arc.
    """
    theta = np.array(theta0, dtype=float)
    sense = 1.0 if theta4_target > theta[3] else -1.0
    n = positioning_null_vector(robot, theta)
    n = n if n[3] * sense >= 0.0 else -n
    min_n4, max_ratio, arc = abs(n[3]), 0.0, 0.0
    while arc < max_arc:
        if abs(n[3]) > 1e-12:
            max_ratio = max(max_ratio, float(np.abs(n[:3] / n[3]).max()))
        mid = theta.copy()
        mid[:4] += 0.5 * step * n
        n_mid = positioning_null_vector(robot, mid)
        n_mid = n_mid if n_mid @ n >= 0.0 else -n_mid
        new = theta.copy()
        new[:4] += step * n_mid
        n_new = positioning_null_vector(robot, new)
        n_new = n_new if n_new @ n_mid >= 0.0 else -n_new
        arc += step
        min_n4 = min(min_n4, abs(n_new[3]))
        if (new[3] - theta4_target) * sense >= 0.0:
            fraction = (theta4_target - theta[3]) / (new[3] - theta[3])
            end = theta + fraction * (new - theta)
            return FoldPath(True, theta4_target, min_n4, max_ratio, arc, end)
        if n_new[3] * sense <= 0.0:
            return FoldPath(False, float(new[3]), min_n4, max_ratio, arc, new)
        theta, n = new, n_new
    return FoldPath(False, float(theta[3]), min_n4, max_ratio, arc, theta)


def _fold_score(name: str, path: FoldPath, start4: float, target4: float, target: str) -> Score:
    covered = (path.theta4_end - start4) / (target4 - start4)
    passed = path.reached and path.min_n4 >= N4_MIN
    shortfall = abs(target4 - path.theta4_end) + max(0.0, N4_MIN - path.min_n4) * 10.0
    return Score(
        name,
        math.degrees(path.theta4_end),
        passed,
        target,
        "deg (theta4 reached)",
        shortfall,
        f"covered {covered:.0%}, min|n4| {path.min_n4:.3f}, max|n_i/n4| {path.max_ratio:.1f}",
    )


def score_fold_phase_one(robot: FreeFloatingModel, step: float = 0.01) -> Score:
    """Phase I (section 4.4.1): reactionless fold from [-20 -40 0 -60 180 180 0] deg to
    theta_4 = -pi without a turning point."""
    theta0 = np.deg2rad(THREE_PHASE_INITIAL_DEG)
    path = elbow_path(robot, theta0, -math.pi, step=step)
    return _fold_score("fold_phase_I", path, theta0[3], -math.pi, "-180 deg, no turning point")


def score_fold_phase_three(robot: FreeFloatingModel, step: float = 0.01) -> Score:
    """Phase III (section 4.4.1): reactionless fold from [-120 50 0 -60 180 180 0] deg to
    theta_4 = -pi without a turning point."""
    theta0 = np.deg2rad(THREE_PHASE_FINAL_DEG)
    path = elbow_path(robot, theta0, -math.pi, step=step)
    return _fold_score("fold_phase_III", path, theta0[3], -math.pi, "-180 deg, no turning point")


def score_stowed(robot: FreeFloatingModel) -> Score:
    """Stowed pose [pi/2 -pi/2 0 -pi pi pi 0] rad (eq. 4.19) "well-conditioned for the reactionless
    motion": |n_4| there (the elbow can move reactionlessly) and sigma_3 / sigma_1 of
    M~_P_omega_m."""
    theta = np.array(STOWED)
    q = robot.configuration(theta)
    tilde = pin.computeCentroidalMap(robot.model, robot.data, q)[3:, 6:10]
    _, sigma, vt = np.linalg.svd(tilde)
    n4 = abs(float(vt[-1][3]))
    ratio = float(sigma[-1] / sigma[0])
    return Score(
        "stowed",
        n4,
        n4 >= STOWED_N4_MIN,
        "well-conditioned (|n4| >= 0.3)",
        "|n4|",
        max(0.0, STOWED_N4_MIN - n4),
        f"sigma3/sigma1 of M~_Pwm {ratio:.3f}",
    )


def score_full_deployment(robot: FreeFloatingModel, step: float = 0.01) -> Score:
    """Section 4.5.1: from the stowed pose, theta_4 rises 0.183 rad/s x 30 s (-pi -> 2.349 rad)
    along the reactionless family without a turning point."""
    theta0 = np.array(STOWED)
    target = theta0[3] + DEPLOY_SPEED * DEPLOY_TIME
    path = elbow_path(robot, theta0, target, step=step, max_arc=25.0)
    return _fold_score(
        "full_deployment", path, theta0[3], target, "134.6 deg (+0.183 rad/s x 30 s)"
    )


def score_partial_deployment(robot: FreeFloatingModel, step: float = 0.01) -> Score:
    """Section 4.5.2 Phase III: from [90 50 0 -300 0 20 0] deg, theta_4 up to -pi (the fold,
    A-2.11 reading) without a turning point."""
    theta0 = np.deg2rad(PARTIAL_FINAL_DEG)
    path = elbow_path(robot, theta0, -math.pi, step=step)
    return _fold_score("partial_deployment", path, theta0[3], -math.pi, "-180 deg, no turning")


def _scenario(name: str, wrist_gain: float = 100.0) -> Scenario:
    scenario = load_scenario(SCENARIO_DIR / f"{name}.yaml")
    controller = {**scenario.controller, "wrist_gain": wrist_gain}
    return dataclasses.replace(scenario, controller=controller)


def _run(robot: FreeFloatingModel, scenario: Scenario, coarse: bool, on_period=None):
    if coarse:
        return run_scenario(robot, scenario, rate=20.0, simulation_step=0.01, on_period=on_period)
    return run_scenario(robot, scenario, on_period=on_period)


@dataclass(frozen=True)
class SingularWindow:
    """sigma_min(J-bar) < epsilon intervals of the section 4.3.1 run.

    Attributes:
        start, end: first interval [s] (nan when none).
        intervals: every interval [(start, end)] [s].
        min_sigma: smallest sigma_min [-] and its time [s].
        counter_rotating: at the sigma_min period joints 5 and 7 turn in opposite directions and
            are the two fastest joints.
    """

    start: float
    end: float
    intervals: tuple[tuple[float, float], ...]
    min_sigma: float
    min_time: float
    counter_rotating: bool


def singular_window(robot: FreeFloatingModel, coarse: bool = True) -> SingularWindow:
    """Run ``algorithmic_singularity.yaml`` (omega = [0, -0.2, 0] rad/s, DLS, k_g = 100) and
    find where sigma_min(J-bar) < 0.2 (section 4.3.2)."""
    samples: list[tuple[float, float, np.ndarray]] = []

    def record(sample: PeriodSample) -> None:
        out = sample.step.output
        samples.append((sample.t, out.sigma_min, np.array(out.joint_velocity)))

    _run(robot, _scenario("algorithmic_singularity"), coarse, record)
    times = np.array([s[0] for s in samples])
    sigma = np.array([s[1] for s in samples])
    inside = sigma < SINGULAR_EPSILON
    intervals, k = [], 0
    while k < len(inside):
        if inside[k]:
            j = k
            while j + 1 < len(inside) and inside[j + 1]:
                j += 1
            intervals.append((float(times[k]), float(times[j])))
            k = j + 1
        else:
            k += 1
    low = int(np.argmin(sigma))
    rates = samples[low][2]
    fastest = set(np.argsort(-np.abs(rates))[:2].tolist())
    counter = bool(rates[4] * rates[6] < 0.0 and fastest == {4, 6})
    start, end = intervals[0] if intervals else (math.nan, math.nan)
    return SingularWindow(
        start, end, tuple(intervals), float(sigma[low]), float(times[low]), counter
    )


def score_singular_window(robot: FreeFloatingModel, coarse: bool = True) -> Score:
    """Section 4.3.1-4.3.2: the DLS singular region sigma_3 < 0.2 at 1.71-4.18 s and joints 5, 7
    counter-rotating near it. Value: the larger end mismatch [s] (inf when no window)."""
    window = singular_window(robot, coarse)
    if not window.intervals:
        mismatch = math.inf
        shortfall = 10.0 + max(0.0, window.min_sigma - SINGULAR_EPSILON) * 10.0
    else:
        mismatch = max(abs(window.start - THESIS_WINDOW[0]), abs(window.end - THESIS_WINDOW[1]))
        shortfall = max(0.0, mismatch - WINDOW_TOLERANCE) + 0.1 * mismatch
    shortfall += 0.0 if window.counter_rotating else 0.5
    passed = mismatch <= WINDOW_TOLERANCE and window.counter_rotating
    windows = ", ".join(f"{a:.2f}-{b:.2f}" for a, b in window.intervals) or "none"
    return Score(
        "singular_window",
        mismatch,
        passed,
        "1.71-4.18 s, joints 5/7 counter-rotate",
        "s (max end mismatch)",
        shortfall,
        f"windows {windows} s, min sigma {window.min_sigma:.3f} at {window.min_time:.2f} s, "
        f"5/7 counter-rotating {window.counter_rotating}",
    )


def score_inspection(robot: FreeFloatingModel, name: str, coarse: bool = True) -> Score:
    """Section 4.2.2 scenario ``name`` (satellite_observation / own_device_inspection) with
    k_g = 100: final camera error [deg] (thesis: task accomplished), wrist drift [m]."""
    result = _run(robot, _scenario(name), coarse)
    error = result.final_orientation_error_deg
    return Score(
        name,
        error,
        error <= INSPECTION_TOLERANCE_DEG and result.min_sigma >= SINGULAR_EPSILON,
        "camera on target (error ~0 deg), k_g = 100",
        "deg",
        max(0.0, error - INSPECTION_TOLERANCE_DEG) / 10.0
        + max(0.0, SINGULAR_EPSILON - result.min_sigma),
        f"wrist drift {result.max_wrist_drift:.3f} m, min sigma {result.min_sigma:.3f}",
    )


#: Cheap constraints (path integrals, no closed loop).
CHEAP = ("ee_position", "fold_phase_I", "fold_phase_III", "stowed", "full_deployment",
         "partial_deployment")  # fmt: skip
#: Closed-loop constraints.
CLOSED_LOOP = ("singular_window", "satellite_observation", "own_device_inspection")


def score_all(
    geometry: Geometry, *, closed_loop: bool = True, coarse: bool = True, step: float = 0.01
) -> dict[str, Score]:
    """Every score of ``geometry`` (the closed-loop ones only with ``closed_loop``)."""
    robot = build_model(geometry)
    scores = [
        score_end_effector(robot),
        score_fold_phase_one(robot, step),
        score_fold_phase_three(robot, step),
        score_stowed(robot),
        score_full_deployment(robot, step),
        score_partial_deployment(robot, step),
    ]
    if closed_loop:
        scores += [
            score_singular_window(robot, coarse),
            score_inspection(robot, "satellite_observation", coarse),
            score_inspection(robot, "own_device_inspection", coarse),
        ]
    return {score.name: score for score in scores}


def total_shortfall(scores: dict[str, Score]) -> float:
    """Ranking key: sum of the shortfalls (0 when every constraint is met)."""
    return float(sum(score.shortfall for score in scores.values()))
