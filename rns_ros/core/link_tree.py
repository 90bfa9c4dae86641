"""The link tree of a model as robot_state_publisher publishes it on /tf and /tf_static: one
transform per URDF joint, parent link -> child link, at the current configuration.

Joints the model drives (its controlled joints) move; fixed and held joints, and the mount of an
added satellite, are static. A root link the loader replaced by the satellite (a fixed-base
``world``) hands its children to the satellite, as the model does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.urdf_tree import UrdfTree


@dataclass(frozen=True)
class LinkEdge:
    """One transform of the tree.

    Attributes:
        parent, child: link names (frame ids on /tf).
        parent_frame, child_frame: their Pinocchio BODY frame ids.
        static: True for /tf_static (independent of theta).
    """

    parent: str
    child: str
    parent_frame: int
    child_frame: int
    static: bool


def link_edges(robot: FreeFloatingModel) -> tuple[LinkEdge, ...]:
    """The edges of ``robot``'s link tree, from its URDF text (:attr:`urdf_xml`)."""
    model = robot.model
    frames = {
        frame.name: index
        for index, frame in enumerate(model.frames)
        if frame.type == pin.FrameType.BODY
    }
    controlled = set(robot.joint_names)
    tree = UrdfTree.parse(robot.urdf_xml, robot.name)
    edges = []
    for joint in tree.joints:
        if joint.child not in frames:
            continue
        parent = joint.parent if joint.parent in frames else robot.base_link  # a replaced root
        static = joint.name not in controlled
        edges.append(LinkEdge(parent, joint.child, frames[parent], frames[joint.child], static))
    for link in tree.root_links():
        if link in frames and link != robot.base_link:  # the arm's root on an added satellite
            frame = frames[robot.base_link]
            edges.insert(0, LinkEdge(robot.base_link, link, frame, frames[link], True))
    return tuple(edges)


def edge_transforms(
    robot: FreeFloatingModel,
    edges: tuple[LinkEdge, ...],
    q: np.ndarray,
    data: pin.Data | None = None,
) -> np.ndarray:
    """Parent-to-child transforms of ``edges`` at configuration q (7 + n,): rows [x, y, z, qx,
    qy, qz, qw] ([m], unit quaternion), shape (len(edges), 7). ``data``: a ``pin.Data`` of the
    model to work in (a caller that publishes every state keeps one); default a new one, never
    ``robot.data``, which holds the current state's quantities."""
    data = robot.model.createData() if data is None else data
    pin.framesForwardKinematics(robot.model, data, np.asarray(q, dtype=float))
    rows = np.empty((len(edges), 7))
    for k, edge in enumerate(edges):
        relative = data.oMf[edge.parent_frame].actInv(data.oMf[edge.child_frame])
        rows[k] = pin.SE3ToXYZQUAT(relative)
    return rows
