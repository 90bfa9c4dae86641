"""rns_ros.core.urdf_tree: the kinematic tree is the <link> and <joint> elements under <robot>;
the <joint> entries of <ros2_control> and <transmission> blocks and the <link> of a <gazebo>
plugin are not part of it. A description over the size or link limits, or whose entities multiply,
is one line before Pinocchio reads it."""

from __future__ import annotations

import time

import pytest
from rns_testing import chain_urdf

from rns_ros.core import load_model
from rns_ros.core.description import read_description
from rns_ros.core.errors import ModelError
from rns_ros.core.urdf_tree import MAX_URDF_BYTES, MAX_URDF_LINKS, UrdfTree

URDF = """<robot name="quirks">
  <link name="base"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="l1"/>
  <ros2_control name="System" type="system">
    <hardware><plugin>mock_components/GenericSystem</plugin></hardware>
    <joint name="j1"><command_interface name="velocity"/><state_interface name="position"/></joint>
  </ros2_control>
  <transmission name="t1">
    <type>transmission_interface/SimpleTransmission</type>
    <joint name="j1"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>
    <actuator name="m1"><mechanicalReduction>50</mechanicalReduction></actuator>
  </transmission>
  <gazebo><plugin name="p"><link name="l1"/><joint name="j1"/></plugin></gazebo>
  <joint name="tool" type="fixed"><parent link="l1"/><child link="tcp"/></joint>
  <link name="tcp"/>
</robot>"""


def test_only_the_elements_under_robot_make_the_tree():
    tree = UrdfTree.parse(URDF)
    assert tree.link_names == ("base", "l1", "tcp")
    assert [(j.name, j.type, j.parent, j.child) for j in tree.joints] == [
        ("j1", "revolute", "base", "l1"),
        ("tool", "fixed", "l1", "tcp"),
    ]
    assert tree.root_links() == ["base"]
    assert tree.non_kinematic() == ("ros2_control", "transmission", "gazebo")
    assert tree.link("tcp") is tree.links[2]
    assert tree.link("nowhere") is None
    assert tree.joints[0].element.find("limit").get("upper") == "1"


@pytest.mark.parametrize(
    ("joint", "message"),
    [
        ('<joint name="j2" type="fixed"><parent link="l1"/></joint>', r"joint 'j2' has no <child"),
        ('<joint name="j2" type="fixed"><child link="x"/></joint>', r"joint 'j2' has no <parent"),
        ('<joint name="j2"><parent/><child link="x"/></joint>', r"joint 'j2' has no <parent"),
        ('<joint type="fixed"><parent link="l1"/><child link="x"/></joint>', "has no name"),
    ],
)
def test_a_kinematic_joint_without_its_links_is_one_line_naming_it(joint, message):
    xml = URDF.replace("</robot>", f"{joint}</robot>")
    with pytest.raises(ModelError, match=message) as caught:
        UrdfTree.parse(xml, "my_arm")
    assert str(caught.value).startswith("my_arm: ")
    assert "\n" not in str(caught.value)


def test_text_that_is_not_xml_is_one_line():
    with pytest.raises(ModelError, match=r"^my_arm: URDF could not be parsed: "):
        UrdfTree.parse("<robot><link name='a'></robot>", "my_arm")


# --- input limits -------------------------------------------------------------------------------
def _laughs(levels: int) -> str:
    """A URDF whose mesh file name is an internal entity "billion laughs" (10 ** levels lols)."""
    entities = ['<!ENTITY lol0 "lol">']
    entities += [f'<!ENTITY lol{i} "{f"&lol{i - 1};" * 10}">' for i in range(1, levels + 1)]
    return (
        f'<?xml version="1.0"?>\n<!DOCTYPE robot [\n{chr(10).join(entities)}\n]>\n'
        f'<robot name="laughs"><link name="base"><visual><geometry><mesh filename="&lol{levels};"/>'
        "</geometry></visual></link></robot>"
    )


def test_a_description_with_more_links_than_the_limit_is_one_line_before_pinocchio(tmp_path):
    urdf = tmp_path / "chain.urdf"
    urdf.write_text(chain_urdf(1000))
    config = tmp_path / "chain.yaml"
    config.write_text("urdf: chain.urdf\ncamera_frame: l999\n")
    start = time.process_time()
    with pytest.raises(ModelError) as caught:
        load_model(config)
    assert time.process_time() - start < 1.0  # ~20 ms: nothing is built
    assert str(caught.value) == (
        f"chain: 1000 <link> elements, over the limit of {MAX_URDF_LINKS} for a robot description"
    )
    assert UrdfTree.parse(chain_urdf(MAX_URDF_LINKS)).link_names[-1] == f"l{MAX_URDF_LINKS - 1}"
    many_joints = URDF.replace("</robot>", '<joint name="j2"/>' * MAX_URDF_LINKS + "</robot>")
    with pytest.raises(ModelError, match=rf"{MAX_URDF_LINKS + 2} <joint> elements, over the"):
        UrdfTree.parse(many_joints)


def test_a_description_over_the_size_limit_is_one_line(tmp_path):
    padded = URDF.replace("<robot ", "<robot " + " " * MAX_URDF_BYTES, 1)
    with pytest.raises(ModelError, match="bytes of robot description, over the limit of"):
        UrdfTree.parse(padded, "my_arm")
    urdf = tmp_path / "big.urdf"
    urdf.write_text(padded)
    size = urdf.stat().st_size
    with pytest.raises(ModelError) as caught:
        read_description(urdf)
    assert str(caught.value) == (
        f"{urdf}: {size} bytes of robot description, over the limit of {MAX_URDF_BYTES}"
    )


def test_an_entity_billion_laughs_is_one_line_and_small_entities_are_expanded():
    start = time.process_time()
    with pytest.raises(ModelError) as caught:
        UrdfTree.parse(_laughs(9), "laughs")  # 3 GB once expanded
    assert time.process_time() - start < 2.0  # expat stops at its amplification limit
    message = str(caught.value)
    assert message.startswith("laughs: URDF could not be parsed: limit on input amplification")
    assert "\n" not in message
    tree = UrdfTree.parse(_laughs(2))
    assert tree.links[0].find("visual/geometry/mesh").get("filename") == "lol" * 100
