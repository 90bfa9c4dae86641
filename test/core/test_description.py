"""rns_ros.core.description: a xacro description (test/data/arms/xacro7: an argument, a macro, an
include found through $(find ...)) is expanded to the URDF it stands for, with the model YAML's
xacro_args and packages; what cannot be expanded is one line."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from rns_ros.core import ModelError, load_model
from rns_ros.core.description import read_description

XACRO7 = Path(__file__).resolve().parents[1] / "data" / "arms" / "xacro7"
SOURCE = XACRO7 / "urdf" / "robot.urdf.xacro"
PACKAGES = {"x7_description": XACRO7}


def test_the_model_yaml_loads_the_expanded_arm():
    robot = load_model(XACRO7 / "model.yaml")
    assert robot.joint_names == tuple(f"x7_joint_{i}" for i in range(1, 8))
    assert robot.name == "robot"
    np.testing.assert_allclose(robot.upper_limits, np.radians(170.0))
    np.testing.assert_allclose(robot.lower_limits, -np.radians(170.0))
    # the macro's solid cylinder (r 0.05 m, 4 kg, 0.3 m), written out here
    root = ET.fromstring(read_description(SOURCE, {"prefix": "x7_"}, PACKAGES))
    inertia = root.find("link[@name='x7_link_1']/inertial/inertia")
    assert float(inertia.get("ixx")) == pytest.approx(4.0 * (3 * 0.05**2 + 0.3**2) / 12)
    assert float(inertia.get("izz")) == pytest.approx(4.0 * 0.05**2 / 2)
    total = sum(float(m.get("value")) for m in root.iter("mass"))
    assert robot.total_mass == pytest.approx(2550.0 + total)  # on the thesis satellite


def test_xacro_args_take_their_defaults_when_not_given():
    root = ET.fromstring(read_description(SOURCE, None, PACKAGES))
    names = [joint.get("name") for joint in root.findall("joint")]
    assert names[:2] == ["joint_1", "joint_2"]


def test_an_unknown_package_is_one_line_naming_it():
    from xacro import substitution_args

    ament = substitution_args._eval_find
    with pytest.raises(ModelError) as caught:
        read_description(SOURCE, {"prefix": "x7_"}, {})
    text = str(caught.value)
    assert "xacro could not expand it" in text
    assert "$(find x7_description): package not found" in text
    assert text.count("package not found") == 1  # said once, not wrapped by xacro's own error
    assert "\n" not in text
    assert substitution_args._eval_find is ament  # put back


def test_a_broken_xacro_is_one_line(tmp_path):
    broken = tmp_path / "broken.urdf.xacro"
    broken.write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="b">'
        '<link name="${undefined_property}"/></robot>'
    )
    with pytest.raises(ModelError, match=r"broken\.urdf\.xacro: xacro could not expand it: "):
        read_description(broken)


def test_a_urdf_is_read_as_it_is_and_a_missing_file_is_named(tmp_path):
    urdf = tmp_path / "arm.urdf"
    urdf.write_text('<robot name="a"><link name="l"/></robot>')
    assert read_description(urdf) == urdf.read_text()
    with pytest.raises(ModelError, match=r"URDF file not found: .*missing\.xacro"):
        read_description(tmp_path / "missing.xacro")


def test_xacro_math_is_evaluated_not_copied():
    root = ET.fromstring(read_description(SOURCE, {"prefix": "x7_"}, PACKAGES))
    limit = root.find("joint[@name='x7_joint_3']/limit")
    assert float(limit.get("upper")) == pytest.approx(math.radians(170.0))
