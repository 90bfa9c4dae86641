"""The kinematic tree a URDF describes, read in one place for the model loader, /tf, the rerun
shapes and ``rns_model check``.

Only the ``<link>`` and ``<joint>`` elements directly under ``<robot>`` are the tree. Published
descriptions carry more: ``<ros2_control>`` and ``<transmission>`` blocks name joints without a
parent or child link, ``<gazebo>`` blocks name links for plugins. Reading the document
recursively mistakes those for kinematic joints; here they are ignored.

A description is refused (one line, before Pinocchio reads it) over :data:`MAX_URDF_BYTES` of
text or :data:`MAX_URDF_LINKS` links or joints: arms have tens, and what Pinocchio and the
checks build grows with their number. XML entities are expanded by the standard library's
expat, whose amplification limit refuses an entity "billion laughs" as a parse error.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

from rns_ros.core.errors import ModelError

#: Largest robot description read, URDF text or expanded xacro [bytes]; meshes are separate files.
MAX_URDF_BYTES = 2_000_000
#: Most ``<link>`` elements, and most ``<joint>`` elements, of a robot description.
MAX_URDF_LINKS = 100


def check_urdf_size(size: int, name: str) -> None:
    """Raise a one-line :class:`ModelError` when a description of ``size`` bytes is over
    :data:`MAX_URDF_BYTES`; ``name`` labels it."""
    if size > MAX_URDF_BYTES:
        raise ModelError(
            f"{name}: {size} bytes of robot description, over the limit of {MAX_URDF_BYTES}"
        )


@dataclass(frozen=True)
class UrdfJoint:
    """One kinematic joint: ``name``, URDF ``type``, ``parent`` and ``child`` link names, and
    its ``element`` (``<origin>``, ``<axis>``, ``<limit>``, ``<mimic>`` inside)."""

    name: str
    type: str
    parent: str
    child: str
    element: ET.Element


@dataclass(frozen=True)
class UrdfTree:
    """The links and joints of one URDF document, in document order.

    Attributes:
        root: the ``<robot>`` element (edited in place by :mod:`rns_ros.core.urdf_prep`).
        links: the ``<link>`` elements under it.
        joints: its kinematic joints.
    """

    root: ET.Element
    links: tuple[ET.Element, ...]
    joints: tuple[UrdfJoint, ...]

    @classmethod
    def parse(cls, xml: str | bytes, name: str = "robot") -> UrdfTree:
        """The tree of the URDF text ``xml``; ``name`` labels errors.

        Raises:
            ModelError: over :data:`MAX_URDF_BYTES` or :data:`MAX_URDF_LINKS`, not XML, or a
                kinematic joint without a name, or without the link attribute of its
                ``<parent>`` / ``<child>`` (one line naming the joint).
        """
        data = xml.encode() if isinstance(xml, str) else xml
        check_urdf_size(len(data), name)
        try:
            root = ET.fromstring(data)
        except ET.ParseError as exc:
            raise ModelError(f"{name}: URDF could not be parsed: {exc}") from None
        for tag in ("link", "joint"):
            count = len(root.findall(tag))
            if count > MAX_URDF_LINKS:
                raise ModelError(
                    f"{name}: {count} <{tag}> elements, over the limit of {MAX_URDF_LINKS} "
                    "for a robot description"
                )
        return cls.of(root, name)

    @classmethod
    def of(cls, root: ET.Element, name: str = "robot") -> UrdfTree:
        """The tree under the ``<robot>`` element ``root`` (see :meth:`parse`)."""
        joints = []
        for element in root.findall("joint"):
            joint_name = element.get("name")
            if not joint_name:
                raise ModelError(f"{name}: a <joint> has no name attribute")
            links = {}
            for role in ("parent", "child"):
                tag = element.find(role)
                link = None if tag is None else tag.get("link")
                if not link:
                    raise ModelError(
                        f"{name}: joint '{joint_name}' has no <{role} link=\"...\"/>; a kinematic "
                        "joint needs both (joints inside <ros2_control> or <transmission> are "
                        "not read)"
                    )
                links[role] = link
            joints.append(
                UrdfJoint(
                    joint_name,
                    element.get("type", ""),
                    links["parent"],
                    links["child"],
                    element,
                )
            )
        return cls(root, tuple(root.findall("link")), tuple(joints))

    @property
    def link_names(self) -> tuple[str, ...]:
        """Names of :attr:`links`."""
        return tuple(link.get("name", "") for link in self.links)

    def root_links(self) -> list[str]:
        """Links that are no joint's child (a tree has exactly one)."""
        children = {joint.child for joint in self.joints}
        return [name for name in self.link_names if name not in children]

    def link(self, name: str) -> ET.Element | None:
        """The ``<link>`` element named ``name`` (None when there is none)."""
        for link in self.links:
            if link.get("name") == name:
                return link
        return None

    def non_kinematic(self) -> tuple[str, ...]:
        """Tags of the elements under ``<robot>`` other than links and joints, once each, in
        document order (e.g. ``ros2_control``, ``transmission``)."""
        tags: dict[str, None] = {}
        for element in self.root:
            if isinstance(element.tag, str) and element.tag not in ("link", "joint"):
                tags.setdefault(element.tag)
        return tuple(tags)
