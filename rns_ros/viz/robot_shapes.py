"""What the 3D view draws of an arm whose meshes are not on this machine: its URDF with every
visual that resolves, and simple shapes for the links left without one.

A ``package://<package>/<path>`` mesh resolves through the ament index (the package's share
folder), a ``file://`` or plain path relative to the URDF's folder; a mesh that does not resolve
is left out (rerun's loader would draw nothing for it). Each link left without a visual is drawn
as (in the link's frame, so the joint transforms move it):

* the ellipsoid of equivalent inertia of its ``<inertial>``: the solid ellipsoid of the link's
  mass m with the same principal moments I_1..I_3 [kg m^2], semi-axes
  a_i = sqrt(5 / (2 m) (I_j + I_k - I_i)) along the principal axes (I_i = m (a_j^2 + a_k^2) / 5),
  centred at the inertial origin;
* its skeleton: a segment from the link origin to each child joint's origin.

No rerun here: :mod:`rns_ros.viz.robot` logs the shapes.
"""

from __future__ import annotations

import contextlib
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.core.urdf_prep import inertia_matrix
from rns_ros.core.urdf_tree import UrdfTree
from rns_ros.resources import share_folders

#: Smallest semi-axis drawn [m]: a flat or needle-like inertia still shows.
MIN_SEMI_AXIS = 0.005


@dataclass(frozen=True)
class LinkShape:
    """The simple shapes of one link, in its own frame.

    Attributes:
        link: URDF link name (the transform frame the shapes hang in).
        center: ellipsoid centre [m], shape (3,), or None without an inertial.
        half_sizes: ellipsoid semi-axes [m], shape (3,), or None.
        quaternion_xyzw: ellipsoid orientation (principal axes), shape (4,), or None.
        segments: skeleton segments [m], shape (k, 2, 3): link origin -> child joint origin.
    """

    link: str
    center: np.ndarray | None = None
    half_sizes: np.ndarray | None = None
    quaternion_xyzw: np.ndarray | None = None
    segments: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3)))


@dataclass(frozen=True)
class ResolvedDescription:
    """A URDF ready for rerun's loader, and the shapes of the links it leaves bare.

    Attributes:
        xml: the URDF text, mesh paths made absolute, unresolved visuals removed.
        unresolved: mesh file names that did not resolve (as the URDF writes them).
        shapes: :class:`LinkShape` of every link without a visual in ``xml``.
    """

    xml: str
    unresolved: tuple[str, ...]
    shapes: tuple[LinkShape, ...]


def equivalent_ellipsoid(mass: float, inertia) -> tuple[np.ndarray, np.ndarray]:
    """(semi-axes [m] (3,), rotation (3, 3) whose columns are the principal axes) of the solid
    ellipsoid of ``mass`` [kg] with rotational inertia ``inertia`` [kg m^2] (3, 3) about its
    centre. Semi-axes below :data:`MIN_SEMI_AXIS` (a degenerate inertia) are raised to it."""
    moments, axes = np.linalg.eigh(np.asarray(inertia, dtype=float))
    total = moments.sum()
    squares = 5.0 / (2.0 * mass) * (total - 2.0 * moments)  # I_j + I_k - I_i
    half_sizes = np.sqrt(np.clip(squares, MIN_SEMI_AXIS**2, None))
    if np.linalg.det(axes) < 0.0:
        axes[:, 2] = -axes[:, 2]
    return half_sizes, axes


def resolve_mesh(filename: str, folder: Path) -> Path | None:
    """The file a URDF mesh ``filename`` names, or None where it does not exist on this machine:
    ``package://<package>/<path>`` in the package's share folder (ament index, else the
    Python environment's prefix: :func:`rns_ros.resources.share_folders`), ``file://<path>``,
    or a path relative to the URDF's ``folder``."""
    if filename.startswith("package://"):
        package, _, rest = filename.removeprefix("package://").partition("/")
        found = [share / rest for share in share_folders(package) if (share / rest).is_file()]
        return found[0] if found else None
    if filename.startswith("file://"):
        path = Path(filename.removeprefix("file://"))
    else:
        path = folder / filename
    return path if path.is_file() else None


def resolve_description(xml: str, folder: Path) -> ResolvedDescription:
    """:class:`ResolvedDescription` of the URDF text ``xml`` whose relative paths start at
    ``folder``."""
    tree = UrdfTree.parse(xml)
    root = tree.root
    unresolved = []
    for link in tree.links:
        for visual in list(link.findall("visual")):
            for mesh in visual.iter("mesh"):
                path = resolve_mesh(mesh.get("filename", ""), folder)
                if path is None:
                    unresolved.append(mesh.get("filename", ""))
                    link.remove(visual)
                    break
                mesh.set("filename", str(path.resolve()))
    children: dict[str, list[np.ndarray]] = {}
    for joint in tree.joints:
        children.setdefault(joint.parent, []).append(_xyz(joint.element.find("origin")))
    shapes = tuple(
        _link_shape(link, children.get(link.get("name", ""), []))
        for link in tree.links
        if link.find("visual") is None
    )
    return ResolvedDescription(
        ET.tostring(root, encoding="unicode"),
        tuple(unresolved),
        tuple(shape for shape in shapes if shape.center is not None or len(shape.segments)),
    )


def _link_shape(link: ET.Element, child_origins: list[np.ndarray]) -> LinkShape:
    segments = np.array([(np.zeros(3), origin) for origin in child_origins]).reshape(-1, 2, 3)
    segments = segments[np.linalg.norm(segments[:, 1], axis=1) > 0.0]
    inertial = link.find("inertial")
    ellipsoid = None if inertial is None else _ellipsoid(inertial)
    if ellipsoid is None:
        return LinkShape(link.get("name", ""), segments=segments)
    return LinkShape(link.get("name", ""), *ellipsoid, segments=segments)


def _ellipsoid(inertial: ET.Element):
    """(centre, semi-axes, quaternion xyzw) of an ``<inertial>``, or None for a massless or
    unreadable one (a frame link: its skeleton is enough)."""
    with contextlib.suppress(TypeError, ValueError, AttributeError):
        mass = float(inertial.find("mass").get("value"))
        values = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
        matrix = inertia_matrix(values)
        if mass > 0.0 and np.all(np.isfinite(matrix)) and np.linalg.eigvalsh(matrix)[0] > 0.0:
            origin = inertial.find("origin")
            rotation = _rpy_matrix(_vector(origin, "rpy"))
            half_sizes, axes = equivalent_ellipsoid(mass, matrix)
            return _xyz(origin), half_sizes, _quaternion_xyzw(rotation @ axes)
    return None


def _vector(origin: ET.Element | None, key: str) -> np.ndarray:
    if origin is None or origin.get(key) is None:
        return np.zeros(3)
    return np.array([float(v) for v in origin.get(key).split()])


def _xyz(origin: ET.Element | None) -> np.ndarray:
    return _vector(origin, "xyz")


def _rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """URDF roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    return pin.rpy.rpyToMatrix(*rpy)


def _quaternion_xyzw(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion x y z w of a rotation matrix (3, 3)."""
    return np.array(pin.Quaternion(rotation).normalized().coeffs())
