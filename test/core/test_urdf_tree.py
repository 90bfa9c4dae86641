"""rns_ros.core.urdf_tree: the kinematic tree is the <link> and <joint> elements under <robot>;
the <joint> entries of <ros2_control> and <transmission> blocks and the <link> of a <gazebo>
plugin are not part of it."""

from __future__ import annotations

import pytest

from rns_ros.core.errors import ModelError
from rns_ros.core.urdf_tree import UrdfTree

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
