"""Candidate 7-DoF geometries: the URDF generator, the reference data and forward kinematics."""

import math
import re

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.analysis import arm_geometry as ag
from rns_ros.core import load_model
from rns_ros.core.errors import InputError, ModelError
from rns_ros.core.model import FreeFloatingModel, check_urdf_inertials

MODEL_YAML = ag.REFERENCE_URDF.parents[1] / "model.yaml"


@pytest.fixture(scope="module")
def default_robot():
    """The first, inferred geometry (config/urdf/rns_7dof_arm_inferred.urdf)."""
    return FreeFloatingModel.from_urdf(ag.REFERENCE_URDF, ag.SPEC)


def test_the_default_model_is_the_identified_geometry():
    """config/model.yaml's URDF is the identified geometry's: same frames and inertia everywhere."""
    default, identified = load_model(MODEL_YAML), ag.build_model(ag.IDENTIFIED_GEOMETRY)
    assert (MODEL_YAML.parent / "urdf" / "rns_7dof_arm.urdf").read_text() == ag.geometry_urdf(
        ag.IDENTIFIED_GEOMETRY, name="rns_7dof_arm"
    )
    rng = np.random.default_rng(1)
    for _ in range(10):
        q = default.configuration(rng.uniform(-math.pi, math.pi, 7))
        for robot in (default, identified):
            pin.framesForwardKinematics(robot.model, robot.data, q)
        for frame in ("camera", "wrist"):
            a = default.data.oMf[default.model.getFrameId(frame)]
            b = identified.data.oMf[identified.model.getFrameId(frame)]
            np.testing.assert_allclose(a.homogeneous, b.homogeneous, atol=1e-12)
        np.testing.assert_allclose(
            pin.crba(default.model, default.data, q),
            pin.crba(identified.model, identified.data, q),
            atol=1e-9,
        )


@pytest.fixture(scope="module")
def current_robot():
    return ag.build_model(ag.INFERRED_GEOMETRY)


def test_generator_with_current_parameters_reproduces_the_default_urdf(
    default_robot, current_robot
):
    rng = np.random.default_rng(0)
    for _ in range(20):
        theta = rng.uniform(-math.pi, math.pi, 7)
        q = default_robot.configuration(theta, base_position=rng.normal(size=3))
        for robot in (default_robot, current_robot):
            pin.framesForwardKinematics(robot.model, robot.data, q)
        for frame in ("camera", "wrist"):
            a = default_robot.data.oMf[default_robot.model.getFrameId(frame)]
            b = current_robot.data.oMf[current_robot.model.getFrameId(frame)]
            np.testing.assert_allclose(a.translation, b.translation, atol=1e-12)
            np.testing.assert_allclose(a.rotation, b.rotation, atol=1e-12)
        np.testing.assert_allclose(
            ag.camera_position(ag.INFERRED_GEOMETRY, theta),
            default_robot.data.oMf[default_robot.camera_frame_id].translation - q[:3],
            atol=1e-12,
        )
        # same masses and inertias too: the joint-space inertia matrices agree
        m_default = pin.crba(default_robot.model, default_robot.data, q)
        m_current = pin.crba(current_robot.model, current_robot.data, q)
        np.testing.assert_allclose(m_default, m_current, atol=1e-9)


def test_reference_data_are_table_4_1_and_the_mount():
    ref = ag.load_reference()
    np.testing.assert_allclose(ref.mount, [-0.79, -0.29, 1.0])
    assert [link.mass for link in ref.links] == [30.0, 30.0, 45.0, 40.0, 20.0, 20.0, 25.0]
    assert [link.axial for link in ref.links] == pytest.approx(
        [0.0851, 0.0843, 0.127, 0.113, 0.025, 0.025, 0.0313]
    )
    assert [link.perpendicular for link in ref.links] == pytest.approx(
        [0.0671, 0.267, 3.81, 2.19, 0.213, 0.0292, 0.099]
    )
    assert ag.uniform_lengths()[2] == pytest.approx(1.000, abs=1e-3)


@pytest.mark.parametrize(
    "geometry",
    [
        ag.INFERRED_GEOMETRY,
        ag.Geometry(
            direction="-x",
            axes=("+z", "+y", "-x", "-z", "-x", "+y", "-x"),
            lengths=(0.07, 0.4, 1.2, 0.6, 0.3, 0.12, 0.25),
            shoulder=(0.1, -0.2),
            elbow=(-0.15, 0.05),
            wrist=(0.0, 0.1),
        ),
    ],
)
def test_generated_urdfs_pass_the_inertial_validation(geometry):
    xml = ag.geometry_urdf(geometry)
    check_urdf_inertials(xml, "candidate")  # positive mass, SPD, triangle inequality
    robot = ag.build_model(geometry)
    masses = [robot.model.inertias[i].mass for i in range(2, 9)]
    assert masses == [30.0, 30.0, 45.0, 40.0, 20.0, 20.0, 25.0]
    for i in range(2, 9):
        assert np.linalg.eigvalsh(robot.model.inertias[i].inertia).min() > 0.0
    assert len(re.findall("<joint ", xml)) == 9


def test_bad_geometries_and_reference_fail_with_typed_errors(tmp_path):
    with pytest.raises(InputError, match="axis label"):
        ag.Geometry(axes=("+z", "+q", "+z", "+y", "+z", "+y", "+z"))
    with pytest.raises(InputError, match="lengths"):
        ag.Geometry(lengths=(0.1, 0.3, -1.0, 0.8, 0.3, 0.1, 0.2))
    bad = tmp_path / "bad.urdf"
    bad.write_text('<robot name="x"><link name="base_link"/></robot>')
    with pytest.raises(ModelError, match="joint_1"):
        ag.load_reference(bad)
