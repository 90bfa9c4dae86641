"""The planar two-DoF space manipulator of thesis Fig. 3.1, generated as URDF text.

Base: m_b = 1000 kg, I_b = 667 kg m^2 about z. Links: l_i = 1.0 m, m_i = 100 kg, I_i = 8.33 kg m^2
about z (CoM at mid-length). Both joints turn about z; the arm lies along the base x axis at
theta = 0 and is attached at r [cos psi, sin psi, 0] from the base CoM, eq. (3.6). The thesis
gives only planar data: the base's x/y moments are set equal to I_b and each link's axial moment
to 0.01 kg m^2 (they do not enter planar motion; they keep the inertias physically valid).
"""

from __future__ import annotations

import math

from rns_ros.core.errors import ConfigError
from rns_ros.core.model import FreeFloatingModel, ModelSpec
from rns_ros.core.validation import positive

PLANAR_SPEC = ModelSpec(camera_frame="tip", wrist_frame="elbow")
_AXIAL_MOMENT = 0.01  # kg m^2, link moment about its own long axis (not in the thesis)


def planar_2dof_urdf(
    attach_distance: float = 0.0,
    attach_angle: float = 0.0,
    *,
    base_mass: float = 1000.0,
    base_inertia: float = 667.0,
    link_length: float = 1.0,
    link_mass: float = 100.0,
    link_inertia: float = 8.33,
) -> str:
    """URDF text of the Fig. 3.1 model.

    Args:
        attach_distance: r of eq. (3.6) [m], >= 0.
        attach_angle: psi of eq. (3.6) [rad].
        base_mass [kg], base_inertia [kg m^2], link_length [m], link_mass [kg],
        link_inertia [kg m^2]: all > 0.
    """
    if not (math.isfinite(attach_distance) and attach_distance >= 0.0):
        raise ConfigError(f"attach_distance must be finite and >= 0 m, got {attach_distance!r}")
    base_mass = positive(base_mass, "base_mass", "[kg]")
    base_inertia = positive(base_inertia, "base_inertia", "[kg m^2]")
    length = positive(link_length, "link_length", "[m]")
    link_mass = positive(link_mass, "link_mass", "[kg]")
    link_inertia = positive(link_inertia, "link_inertia", "[kg m^2]")
    x = attach_distance * math.cos(attach_angle)
    y = attach_distance * math.sin(attach_angle)

    def link(name: str) -> str:
        return (
            f'  <link name="{name}">\n'
            f'    <inertial><origin xyz="{length / 2} 0 0"/><mass value="{link_mass}"/>\n'
            f'      <inertia ixx="{_AXIAL_MOMENT}" ixy="0" ixz="0" iyy="{link_inertia}" iyz="0"'
            f' izz="{link_inertia}"/></inertial>\n'
            "  </link>\n"
        )

    def joint(name: str, parent: str, child: str, xyz: str, kind: str = "revolute") -> str:
        limit = (
            '    <axis xyz="0 0 1"/>\n'
            '    <limit lower="-6.283185307179586" upper="6.283185307179586" velocity="1.0"'
            ' effort="100"/>\n'
            if kind == "revolute"
            else ""
        )
        return (
            f'  <joint name="{name}" type="{kind}">\n'
            f'    <parent link="{parent}"/><child link="{child}"/>\n'
            f'    <origin xyz="{xyz}" rpy="0 0 0"/>\n{limit}'
            "  </joint>\n"
        )

    return (
        '<?xml version="1.0"?>\n<robot name="planar_2dof">\n'
        '  <link name="base_link">\n'
        f'    <inertial><origin xyz="0 0 0"/><mass value="{base_mass}"/>\n'
        f'      <inertia ixx="{base_inertia}" ixy="0" ixz="0" iyy="{base_inertia}" iyz="0"'
        f' izz="{base_inertia}"/></inertial>\n'
        "  </link>\n"
        + joint("joint_1", "base_link", "link_1", f"{x!r} {y!r} 0")
        + link("link_1")
        + joint("joint_2", "link_1", "link_2", f"{length} 0 0")
        + link("link_2")
        + joint("elbow_joint", "link_1", "elbow", f"{length} 0 0", kind="fixed")
        + '  <link name="elbow"/>\n'
        + joint("tip_joint", "link_2", "tip", f"{length} 0 0", kind="fixed")
        + '  <link name="tip"/>\n'
        + "</robot>\n"
    )


def planar_2dof_model(
    attach_distance: float = 0.0, attach_angle: float = 0.0, **kwargs
) -> FreeFloatingModel:
    """:class:`FreeFloatingModel` of the Fig. 3.1 arm (see :func:`planar_2dof_urdf`)."""
    xml = planar_2dof_urdf(attach_distance, attach_angle, **kwargs)
    return FreeFloatingModel.from_urdf_string(xml, PLANAR_SPEC, name="planar_2dof")
