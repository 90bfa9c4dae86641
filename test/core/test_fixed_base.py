"""Fixed-base arms of Part II: the model files load, and the state's terms match their
definitions (RNEA identity, finite differences of the Jacobian drift and of the potential)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.core import ConfigError, InputError, ModelError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState, load_fixed_base_model

CONFIG = Path(__file__).resolve().parents[2] / "config"
MODELS = {"planar_3dof": "planar_3dof.yaml", "lwr_7dof": "lwr_7dof.yaml"}


@pytest.fixture(params=sorted(MODELS))
def arm(request) -> FixedBaseModel:
    return load_fixed_base_model(CONFIG / MODELS[request.param])


def _random_state(arm, seed: int):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.5, 1.5, arm.n)
    v = rng.normal(size=arm.n)
    return q, v, FixedBaseState.compute(arm, q, v)


def test_terms_reproduce_inverse_dynamics(arm):
    """tau = M(q) a + c(q, v) + g(q) for any a (RNEA, computed independently)."""
    for seed in range(5):
        q, v, state = _random_state(arm, seed)
        a = np.random.default_rng(100 + seed).normal(size=arm.n)
        tau = pin.rnea(arm.model, arm.model.createData(), q, v, a)
        expected = state.mass_matrix @ a + state.coriolis + state.gravity
        np.testing.assert_allclose(expected, tau, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(state.mass_matrix, state.mass_matrix.T, atol=1e-14)
        assert np.linalg.eigvalsh(state.mass_matrix)[0] > 0.0


def test_jacobian_drift_is_the_derivative_of_the_ee_twist(arm):
    """J_dot q_dot = d/dt (J(q) q_dot) at constant q_dot (central difference along q_dot)."""
    q, v, state = _random_state(arm, 7)
    h = 1e-6
    plus = FixedBaseState.compute(arm, q + h * v, v).jacobian @ v
    minus = FixedBaseState.compute(arm, q - h * v, v).jacobian @ v
    np.testing.assert_allclose(state.jacobian_dot_v, (plus - minus) / (2 * h), atol=1e-6)


def test_jacobian_is_the_derivative_of_the_ee_position(arm):
    q, _, state = _random_state(arm, 3)
    h = 1e-7
    for j in range(arm.n):
        step = np.zeros(arm.n)
        step[j] = h
        diff = (arm.frame_position(q + step, "ee") - arm.frame_position(q - step, "ee")) / (2 * h)
        np.testing.assert_allclose(state.jacobian[:3, j], diff, atol=1e-7)


def test_gravity_is_off_by_default_and_the_potential_gradient_when_on():
    arm = load_fixed_base_model(CONFIG / "planar_3dof.yaml")
    assert not arm.gravity
    q = np.array([0.3, -0.4, 0.5])
    assert np.all(FixedBaseState.compute(arm, q, np.zeros(3)).gravity == 0.0)
    heavy = load_fixed_base_model(CONFIG / "lwr_7dof.yaml", gravity=True)
    q = np.radians([20, -20, 0, 100, 0, 10, 0])
    g = FixedBaseState.compute(heavy, q, np.zeros(7)).gravity
    data = heavy.model.createData()
    h = 1e-6
    for j in range(7):
        step = np.zeros(7)
        step[j] = h
        up = pin.computePotentialEnergy(heavy.model, data, q + step)
        down = pin.computePotentialEnergy(heavy.model, data, q - step)
        assert g[j] == pytest.approx((up - down) / (2 * h), abs=1e-6)


def test_thesis_start_configurations():
    """Planar: the IJ-chosen start [106.4 -45.7 -56.2] deg is on the arc (centre (1.91, 1.91),
    R = 0.707 m; thesis_rest A-4.6). LWR: [20 -20 0 100 0 10 0] deg puts the flange where the
    standard LWR4 DH does, (0.515, 0.187, 0.465) m."""
    planar = load_fixed_base_model(CONFIG / "planar_3dof.yaml")
    p = planar.frame_position(np.radians([106.4, -45.7, -56.2]), "ee")
    assert math.dist(p[:2], (1.91, 1.91)) == pytest.approx(0.707, abs=2e-3)
    lwr = load_fixed_base_model(CONFIG / "lwr_7dof.yaml")
    p = lwr.frame_position(np.radians([20, -20, 0, 100, 0, 10, 0]), "ee")
    np.testing.assert_allclose(p, [0.515, 0.187, 0.465], atol=2e-3)


def test_bad_models_and_inputs_fail_clearly(tmp_path):
    with pytest.raises(ModelError, match="ee_frame 'tool' is not a frame"):
        FixedBaseModel.from_urdf(CONFIG / "urdf" / "planar_3dof.urdf", "tool")
    with pytest.raises(ModelError, match="not found"):
        FixedBaseModel.from_urdf(tmp_path / "missing.urdf", "ee")
    bad = tmp_path / "bad.yaml"
    bad.write_text("urdf: urdf/x.urdf\nee_frame: ee\ncolour: red\n")
    with pytest.raises(ConfigError, match="unknown key"):
        load_fixed_base_model(bad)
    text = (
        (CONFIG / "urdf" / "planar_3dof.urdf").read_text().replace('value="10.0"', 'value="-1"', 1)
    )
    (tmp_path / "neg.urdf").write_text(text)
    with pytest.raises(ModelError, match="mass"):
        FixedBaseModel.from_urdf(tmp_path / "neg.urdf", "ee")
    arm = load_fixed_base_model(CONFIG / "planar_3dof.yaml")
    with pytest.raises(InputError, match="finite"):
        FixedBaseState.compute(arm, [0.0, math.nan, 0.0], np.zeros(3))


def test_continuous_joint_is_rejected_with_the_part_two_requirement():
    xml = (
        "<robot name='c'><link name='base'/><link name='l'><inertial><mass value='1'/>"
        "<inertia ixx='1' iyy='1' izz='1' ixy='0' ixz='0' iyz='0'/></inertial></link>"
        "<joint name='spin' type='continuous'><parent link='base'/><child link='l'/>"
        "<axis xyz='0 0 1'/></joint><link name='tool'/><joint name='t' type='fixed'>"
        "<parent link='l'/><child link='tool'/></joint></robot>"
    )
    with pytest.raises(ModelError, match=r"joint 'spin' is .*; Part II arms need revolute joints"):
        FixedBaseModel(pin.buildModelFromXML(xml), "tool", name="c")
