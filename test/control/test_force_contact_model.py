"""The rigid-contact force model (rns_ros.control.force.contact_model) against the simulator."""

from __future__ import annotations

import math

import numpy as np
import pytest
from force_cases import LWR, PLANAR, START
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.control.force.contact_model import (
    RigidContactModel,
    normal_acceleration,
    predicted_contact_force,
)
from rns_ros.core.contact_geometry import ArcConstraint, PlaneConstraint
from rns_ros.core.fixed_base import FixedBaseState
from rns_ros.sim.contact import ContactSimulator


def _plane_sim(q, v, normal):
    state = FixedBaseState.compute(LWR, q, np.zeros(7))
    plane = PlaneConstraint(state.ee_position, normal)
    j_c = plane.normal @ state.jacobian[:3]
    v = v - j_c * (j_c @ v) / (j_c @ j_c)  # no normal velocity
    return ContactSimulator(LWR, plane, initial_q=q, initial_v=v), plane.normal


@settings(max_examples=25, deadline=None)
@given(
    q=st.lists(st.floats(-1.5, 1.5), min_size=7, max_size=7),
    v=st.lists(st.floats(-1.0, 1.0), min_size=7, max_size=7),
    normal=st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3).filter(
        lambda n: np.linalg.norm(n) > 0.2
    ),
    tau=st.lists(st.floats(-30.0, 30.0), min_size=7, max_size=7),
)
def test_predicted_force_matches_the_simulator_on_a_wall(q, v, normal, tau):
    sim, n = _plane_sim(START + np.array(q) * 0.5, np.array(v), np.array(normal))
    state = FixedBaseState.compute(LWR, sim.q, sim.v)
    if not RigidContactModel.at(state, n).inertia < 1e6:  # near-singular along n
        return
    sim.set_torque(tau)
    expected = sim.contact_force  # on the surface with phi_dot = 0: beta = 0
    predicted = predicted_contact_force(state, n, tau)
    assert predicted == pytest.approx(expected, rel=1e-6, abs=1e-6 * (1 + np.abs(tau).max()))


@settings(max_examples=25, deadline=None)
@given(
    q=st.lists(st.floats(-2.5, 2.5), min_size=3, max_size=3),
    v=st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    angle=st.floats(0.0, 2 * math.pi),
    taus=st.lists(
        st.lists(st.floats(-200.0, 200.0), min_size=3, max_size=3), min_size=2, max_size=2
    ),
)
def test_predicted_force_matches_the_simulator_on_the_arc(q, v, angle, taus):
    """On the cylinder beta = Lambda_n kappa != 0 (centripetal): estimated from one torque (as
    the controller does from the held effort and its wrench), then predicted for another."""
    q = np.array(q)
    state = FixedBaseState.compute(PLANAR, q, np.zeros(3))
    u = np.array([math.cos(angle), math.sin(angle), 0.0])
    arc = ArcConstraint(state.ee_position + 0.707 * u, 0.707)  # EE on the circle, normal +u
    j_c = u @ state.jacobian[:3]
    if np.linalg.norm(j_c) < 1e-3:
        return
    v = np.array(v) - j_c * (j_c @ np.array(v)) / (j_c @ j_c)
    sim = ContactSimulator(PLANAR, arc, initial_q=q, initial_v=v)
    state = FixedBaseState.compute(PLANAR, q, v)
    model = RigidContactModel.at(state, u)
    if not model.inertia < 1e6:
        return
    held, new = np.array(taus[0]), np.array(taus[1])
    sim.set_torque(held)
    beta = sim.contact_force - model.force(held)
    sim.set_torque(new)
    scale = 1.0 + abs(sim.contact_force)
    assert model.force(new) + beta == pytest.approx(sim.contact_force, rel=1e-6, abs=1e-6 * scale)
    # and f_ref along n adds exactly f_ref: lambda(tau + J^T n f) = lambda(tau) + f
    assert model.force(new + model.push * 3.0) - model.force(new) == pytest.approx(3.0)


def test_centripetal_feed_forward_is_minus_the_arc_curvature():
    """a_n = curvature |v_t|^2 with curvature = 1/R equals -ArcConstraint.curvature (the term
    motion_force_runs commands as [-constraint.curvature(p, p_dot)])."""
    arc = ArcConstraint([1.91, 1.91, 0.0], 0.707)
    rng = np.random.default_rng(3)
    for angle in rng.uniform(0, 2 * math.pi, 10):
        p = arc.center + 0.707 * np.array([math.cos(angle), math.sin(angle), 0.0])
        p_dot = rng.normal(size=3) * [1.0, 1.0, 0.0]
        n = arc.gradient(p)
        a_n = normal_acceleration(1 / 0.707, n, p_dot)
        assert a_n > 0.0  # toward the axis, i.e. along n
        assert a_n == pytest.approx(-arc.curvature(p, p_dot), rel=1e-12)
    assert normal_acceleration(0.0, n, p_dot) == 0.0  # a plane
