"""URDF text as published, made into what the free-floating model is built from.

Two jobs on the URDF text, before Pinocchio reads it:

* :func:`check_urdf_inertials` checks every ``<inertial>`` as written: Pinocchio's parser turns an
  unreadable number into zero without failing, so a typo would otherwise become a massless body.
* :func:`prepare_urdf` rewrites what our joint layout cannot take and adds the satellite:

  - a ``continuous`` joint becomes ``revolute`` (Pinocchio would build a unit-complex joint with
    two position coordinates, q = (cos, sin)); the model then sets its position limits to
    -inf / +inf, so it stays unbounded whatever its ``<limit>`` tag says;
  - the satellite body (:class:`BaseBody`, mass and inertia about its centre of mass) becomes the
    root link, its frame the base frame {B} at the base centre of mass (thesis chapter 2); the
    arm's root link hangs on it by a fixed joint at the mount pose. A massless root link named
    ``world`` (a fixed-base description) is replaced by the satellite: its child joints are
    re-attached to the satellite at mount * (their origin).

Mesh references (``package://``, ``file://``) are never read: only inertials, joints and links
matter here, and Pinocchio's model builder ignores geometry.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ModelError
from rns_ros.core.urdf_tree import UrdfTree

#: Relative tolerance of the triangle inequality on principal moments (I1 + I2 >= I3): URDFs
#: exported from CAD round their moments, and a thin disk (I, I, 2I) sits exactly on the bound.
TRIANGLE_RTOL = 1e-4
#: An ``<inertial>`` with mass [kg] and every moment [kg m^2] at most these is a placeholder that
#: a description puts on a frame link (Sawyer writes 1e-8 in all ten numbers, a matrix of rank
#: 1): it is not read, as if the link had no ``<inertial>``. The lightest arm bodies weigh tens
#: of grams, so the mass dropped is below their rounding.
PLACEHOLDER_MASS_KG = 1e-6
PLACEHOLDER_MOMENT_KG_M2 = 1e-6
#: The six moments of a URDF <inertia> [kg m^2].
INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
#: Name of the satellite link added as the URDF root (a suffix is added if the arm has one).
SATELLITE_LINK = "satellite"
#: A root link of this name (massless) stands for the ground of a fixed-base description.
WORLD_LINK = "world"
#: Placeholder position limits [rad] of a continuous joint rewritten as revolute; the model
#: replaces them by -inf / +inf once Pinocchio has read the file.
_PLACEHOLDER_LIMIT = math.pi


@dataclass(frozen=True)
class BaseBody:
    """The satellite body carrying the arm (model YAML key ``base``).

    Attributes:
        mass: m_0 [kg], > 0.
        inertia: rotational inertia about the centre of mass in the base frame, (3, 3) [kg m^2].
        mount_xyz: origin of the arm's root link in the base centre-of-mass frame [m], (3,).
        mount_rpy: orientation of the arm's root link, URDF roll-pitch-yaw [rad], (3,).
    """

    mass: float
    inertia: tuple[tuple[float, float, float], ...]
    mount_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mount_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def check(self, where: str) -> None:
        """Raise a one-line :class:`ModelError` when the body is not physical."""
        if not (math.isfinite(self.mass) and self.mass > 0.0):
            raise ModelError(f"{where}: mass must be finite and > 0 kg, got {self.mass}")
        check_inertia_matrix(np.array(self.inertia, dtype=float), where)
        pose = np.array([*self.mount_xyz, *self.mount_rpy], dtype=float)
        if pose.shape != (6,) or not np.all(np.isfinite(pose)):
            raise ModelError(f"{where}: mount_xyz and mount_rpy must be 3 finite numbers each")


#: The thesis satellite (section 4.1.1): 2550 kg, principal moments diag(6200, 3540, 7090)
#: kg m^2 about its centre of mass, the arm's root at [-0.79, -0.29, 1.0] m.
THESIS_BASE = BaseBody(
    mass=2550.0,
    inertia=((6200.0, 0.0, 0.0), (0.0, 3540.0, 0.0), (0.0, 0.0, 7090.0)),
    mount_xyz=(-0.79, -0.29, 1.0),
)


class MimicRule(NamedTuple):
    """A ``<mimic>`` joint's position: multiplier * leader + offset [rad or m]."""

    leader: str
    multiplier: float
    offset: float


class PreparedUrdf(NamedTuple):
    """What :func:`prepare_urdf` returns.

    Attributes:
        xml: URDF text for Pinocchio (continuous joints rewritten, satellite added).
        continuous_joints: names of the joints that were ``continuous``.
        mimic: follower joint name -> :class:`MimicRule`, as the file writes them.
        root_link: the arm's root link in the file.
        satellite: the base body added, or None (the URDF root is the satellite).
        notes: one line per change made, for the start-up summary.
    """

    xml: str
    continuous_joints: tuple[str, ...]
    mimic: dict[str, MimicRule]
    root_link: str
    satellite: BaseBody | None
    notes: tuple[str, ...]


# inertial checks --------------------------------------------------------------------------------
def check_urdf_inertials(xml: str, name: str = "robot") -> None:
    """Check every ``<link>``'s ``<inertial>`` as the URDF text writes it.

    Links without ``<inertial>`` (frames such as ``camera``) are accepted, and so are an explicit
    empty one (mass 0 and all six moments 0) and a placeholder (:func:`placeholder_inertials`),
    which published descriptions put on frame links: whether the body such a link belongs to is
    physical is checked after Pinocchio merges the fixed links
    (:func:`rns_ros.core.model.check_moving_bodies`). For the others: mass [kg]
    finite and > 0; the six moments ``ixx ixy ixz iyy iyz izz`` [kg m^2] present and finite; the
    inertia matrix positive definite; its principal moments obey the triangle inequality
    I1 + I2 >= I3 (relative tolerance :data:`TRIANGLE_RTOL`).

    Raises:
        ModelError: one line naming the link and the bad value; or the text is not XML.
    """
    for link in UrdfTree.parse(xml, name).links:
        inertial = link.find("inertial")
        if inertial is None:
            continue
        where = f"{name}: link '{link.get('name')}'"
        mass = _number(inertial.find("mass"), "value", f"{where} <mass>")
        element = inertial.find("inertia")
        values = {key: _number(element, key, f"{where} <inertia>") for key in INERTIA_KEYS}
        if mass == 0.0 and not any(values.values()):
            continue  # an empty inertial: a frame link
        if _is_placeholder(mass, values):
            continue  # not read (prepare_urdf)
        if not mass > 0.0:
            raise ModelError(f"{where}: mass must be finite and > 0 kg, got {mass}")
        check_inertia_matrix(inertia_matrix(values), where)


def placeholder_inertials(tree: UrdfTree) -> tuple[str, ...]:
    """Names of the links whose ``<inertial>`` is a placeholder: a mass in
    (0, :data:`PLACEHOLDER_MASS_KG`] kg and every moment within +-:data:`PLACEHOLDER_MOMENT_KG_M2`
    kg m^2. Such a link is read as a frame link (its inertial removed by :func:`prepare_urdf`)."""
    names = []
    for link in tree.links:
        inertial = link.find("inertial")
        if inertial is None:
            continue
        try:
            mass = _number(inertial.find("mass"), "value", "")
            values = {key: _number(inertial.find("inertia"), key, "") for key in INERTIA_KEYS}
        except ModelError:
            continue  # check_urdf_inertials names it
        if _is_placeholder(mass, values):
            names.append(link.get("name"))
    return tuple(names)


def _is_placeholder(mass: float, moments: Mapping[str, float]) -> bool:
    small = all(abs(value) <= PLACEHOLDER_MOMENT_KG_M2 for value in moments.values())
    return 0.0 < mass <= PLACEHOLDER_MASS_KG and small


def inertia_matrix(moments: Mapping[str, float]) -> np.ndarray:
    """The rotational inertia [kg m^2] (3, 3) of a URDF ``<inertia>``'s six moments
    (``ixx ixy ixz iyy iyz izz``, :data:`INERTIA_KEYS`)."""
    m = moments
    return np.array(
        [
            [m["ixx"], m["ixy"], m["ixz"]],
            [m["ixy"], m["iyy"], m["iyz"]],
            [m["ixz"], m["iyz"], m["izz"]],
        ],
        dtype=float,
    )


def check_inertia_matrix(matrix: np.ndarray, where: str) -> None:
    """Rotational inertia [kg m^2] (3, 3): finite, symmetric, positive definite, triangle."""
    if not np.all(np.isfinite(matrix)):
        raise ModelError(f"{where}: inertia must be finite, got {matrix.tolist()}")
    if not np.allclose(matrix, matrix.T, rtol=1e-9, atol=0.0):
        raise ModelError(f"{where}: inertia must be symmetric, got {matrix.tolist()}")
    moments = np.linalg.eigvalsh(matrix)  # ascending
    if not moments[0] > 0.0:
        raise ModelError(
            f"{where}: inertia must be positive definite, got principal moments "
            f"{_fmt(moments)} kg m^2 from {_fmt(matrix)}"
        )
    if moments[0] + moments[1] < moments[2] * (1.0 - TRIANGLE_RTOL):
        raise ModelError(
            f"{where}: principal moments {_fmt(moments)} kg m^2 break the triangle inequality "
            f"I1 + I2 >= I3 ({moments[0] + moments[1]:.6g} < {moments[2]:.6g}); no rigid body "
            "has them"
        )


def _number(element: ET.Element | None, key: str, where: str) -> float:
    """The finite float in attribute ``key`` of ``element``, else ModelError naming it."""
    if element is None:
        raise ModelError(f"{where} is missing")
    text = element.get(key)
    if text is None:
        raise ModelError(f"{where}: attribute {key} is missing")
    try:
        value = float(text)
    except ValueError:
        raise ModelError(f"{where}: {key}={text!r} is not a number") from None
    if not math.isfinite(value):
        raise ModelError(f"{where}: {key}={text!r} must be finite")
    return value


def _fmt(values: np.ndarray) -> str:
    return np.array2string(np.asarray(values), precision=6, separator=", ").replace("\n", "")


# preparation ------------------------------------------------------------------------------------
def prepare_urdf(xml: str, base: BaseBody | None = None, name: str = "robot") -> PreparedUrdf:
    """Rewrite continuous joints and add the satellite (module docstring).

    The satellite is ``base`` when given; else :data:`THESIS_BASE` when the URDF's root body
    (its root link plus the links fixed to it) has no mass or the root is a ``world`` link; else
    none (the URDF root link is the satellite, as in ``config/urdf/rns_7dof_arm.urdf``).

    Raises:
        ModelError: the text is not XML, has no single root link, or a ``<mimic>`` is unreadable.
    """
    tree = UrdfTree.parse(xml, name)
    root = tree.root
    notes: list[str] = []
    joints = [joint.element for joint in tree.joints]
    continuous = tuple(joint.get("name") for joint in joints if joint.get("type") == "continuous")
    for joint in joints:
        if joint.get("type") == "continuous":
            _make_revolute(joint)
    if continuous:
        notes.append(f"continuous joints {list(continuous)}: revolute without position limits")
    skipped = [f"<{tag}>" for tag in tree.non_kinematic() if tag != "material"]
    if skipped:
        notes.append(f"{', '.join(skipped)} not read: not part of the kinematic tree")
    mimic = _mimic_rules(joints, name)
    placeholders = placeholder_inertials(tree)
    for link in tree.links:
        if link.get("name") in placeholders:
            link.remove(link.find("inertial"))
    if placeholders:
        notes.append(
            f"links {list(placeholders)}: placeholder inertials (mass <= "
            f"{PLACEHOLDER_MASS_KG:g} kg, moments <= {PLACEHOLDER_MOMENT_KG_M2:g} kg m^2) "
            "not read: frame links"
        )
    roots = tree.root_links()
    if len(roots) != 1:
        raise ModelError(f"{name}: the URDF must have exactly one root link, found {roots}")
    root_link = roots[0]
    world = root_link == WORLD_LINK and _link_mass(root, root_link) == 0.0
    satellite = base
    if base is None and (world or _root_body_mass(root, joints, root_link) == 0.0):
        satellite = THESIS_BASE
        inertia = np.diag(THESIS_BASE.inertia).tolist()
        notes.append(
            f"base: the URDF root '{root_link}' has no mass and the model YAML no 'base'; "
            f"using the thesis satellite ({THESIS_BASE.mass:g} kg, diag{tuple(inertia)} kg m^2, "
            f"mount {list(THESIS_BASE.mount_xyz)} m)"
        )
    if satellite is not None:
        satellite.check(f"{name}: base")
        _add_satellite(root, joints, root_link, satellite, replace=world)
        if world:
            notes.append(f"base: the fixed-base root link '{WORLD_LINK}' is replaced by the base")
    text = ET.tostring(root, encoding="unicode")
    return PreparedUrdf(text, continuous, mimic, root_link, satellite, tuple(notes))


def _make_revolute(joint: ET.Element) -> None:
    """A continuous joint as a revolute one with placeholder bounds (keeps effort/velocity)."""
    joint.set("type", "revolute")
    limit = joint.find("limit")
    if limit is None:
        limit = ET.SubElement(joint, "limit")
    limit.set("lower", repr(-_PLACEHOLDER_LIMIT))
    limit.set("upper", repr(_PLACEHOLDER_LIMIT))
    for key in ("effort", "velocity"):  # 0 reads as "no limit" in the model
        limit.set(key, limit.get(key, "0"))


def _mimic_rules(joints: list[ET.Element], name: str) -> dict[str, MimicRule]:
    rules = {}
    for joint in joints:
        element = joint.find("mimic")
        if element is None:
            continue
        where = f"{name}: joint '{joint.get('name')}' <mimic>"
        leader = element.get("joint")
        if not leader:
            raise ModelError(f"{where}: attribute joint (the leader) is missing")
        multiplier = _number(element, "multiplier", where) if "multiplier" in element.attrib else 1
        offset = _number(element, "offset", where) if "offset" in element.attrib else 0.0
        rules[joint.get("name")] = MimicRule(leader, float(multiplier), float(offset))
    return rules


def _link_of(joint: ET.Element, role: str) -> str | None:
    element = joint.find(role)
    return None if element is None else element.get("link")


def _link_mass(root: ET.Element, link: str) -> float:
    element = root.find(f"link[@name='{link}']/inertial/mass")
    return 0.0 if element is None else float(element.get("value", "0"))


def _root_body_mass(root: ET.Element, joints: list[ET.Element], root_link: str) -> float:
    """Mass [kg] of the root link plus every link fixed to it (Pinocchio's root body)."""
    body, frontier = {root_link}, [root_link]
    while frontier:
        parent = frontier.pop()
        for joint in joints:
            child = _link_of(joint, "child")
            if joint.get("type") == "fixed" and _link_of(joint, "parent") == parent:
                body.add(child)
                frontier.append(child)
    return sum(_link_mass(root, link) for link in body)


def _add_satellite(
    root: ET.Element, joints: list[ET.Element], root_link: str, base: BaseBody, *, replace: bool
) -> None:
    """Insert the satellite link as the new root; attach (or, ``replace``, re-parent the
    children of) the old root at the mount pose."""
    names = {link.get("name") for link in root.findall("link")}
    satellite, suffix = SATELLITE_LINK, 1
    while satellite in names:
        satellite, suffix = f"{SATELLITE_LINK}_{suffix}", suffix + 1
    link = ET.Element("link", name=satellite)
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(float(base.mass)))
    matrix = np.array(base.inertia, dtype=float)
    moments = dict(zip(INERTIA_KEYS, matrix[np.triu_indices(3)].tolist(), strict=True))
    ET.SubElement(inertial, "inertia", {key: repr(value) for key, value in moments.items()})
    root.insert(0, link)
    mount = pin.SE3(pin.rpy.rpyToMatrix(*map(float, base.mount_rpy)), np.array(base.mount_xyz))
    if not replace:
        joint = ET.SubElement(root, "joint", name=f"{satellite}_mount", type="fixed")
        ET.SubElement(joint, "parent", link=satellite)
        ET.SubElement(joint, "child", link=root_link)
        _set_origin(joint, mount)
        return
    root.remove(root.find(f"link[@name='{root_link}']"))
    for joint in joints:
        if _link_of(joint, "parent") == root_link:
            joint.find("parent").set("link", satellite)
            _set_origin(joint, mount * _origin(joint))


def _origin(joint: ET.Element) -> pin.SE3:
    element = joint.find("origin")
    xyz = [0.0] * 3 if element is None else [float(v) for v in element.get("xyz", "0 0 0").split()]
    rpy = [0.0] * 3 if element is None else [float(v) for v in element.get("rpy", "0 0 0").split()]
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz))


def _set_origin(joint: ET.Element, placement: pin.SE3) -> None:
    element = joint.find("origin")
    if element is None:
        element = ET.SubElement(joint, "origin")
    element.set("xyz", " ".join(repr(float(v)) for v in placement.translation))
    rpy = pin.rpy.matrixToRpy(placement.rotation)
    element.set("rpy", " ".join(repr(float(v)) for v in rpy))
