"""Chapter-6 cause runs: the model variants, the momentum approximation of C_hat_A, and verdict
rows that can fail (fast: no closed-loop runs)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.analysis.motion_force_variants import (
    planar_gravity,
    planar_ik,
    planar_lengths,
    with_payload,
)
from rns_ros.analysis.reproduce import chapter6_causes as causes
from rns_ros.analysis.reproduce.chapter6_remarks import reversals
from rns_ros.analysis.reproduce.registry import Verdict
from rns_ros.control.contact_tasks import ArcScenario
from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.core.errors import ConfigError
from rns_ros.core.fixed_base import FixedBaseState

G = 9.81


@pytest.fixture(scope="module")
def setup():
    return ArcScenario(half_cycles=1).setup()


def test_planar_gravity_acts_along_minus_y_with_the_rod_moments(setup):
    # arm stretched along +x: g_1 = g sum m_i x_ci = 9.81 * 10 * (0.5 + 1.5 + 2.5) N m
    robot = planar_gravity(setup.robot, G)
    state = FixedBaseState.compute(robot, np.zeros(3), np.zeros(3))
    assert state.gravity == pytest.approx(G * 10.0 * np.array([4.5, 2.0, 0.5]), rel=1e-9)
    # along +y the lever arms vanish
    up = FixedBaseState.compute(robot, np.array([math.pi / 2, 0.0, 0.0]), np.zeros(3))
    assert np.abs(up.gravity).max() < 1e-9
    assert not np.any(setup.robot.model.gravity.linear)  # the shared model is untouched


def test_payload_adds_a_point_mass_at_the_ee(setup):
    payload = with_payload(planar_gravity(setup.robot, G), causes.PAYLOAD)
    bare = FixedBaseState.compute(planar_gravity(setup.robot, G), np.zeros(3), np.zeros(3))
    state = FixedBaseState.compute(payload, np.zeros(3), np.zeros(3))
    assert state.gravity - bare.gravity == pytest.approx(
        G * causes.PAYLOAD * np.array([3.0, 2.0, 1.0]), rel=1e-9
    )
    # the payload's inertia at the tip: M_33 grows by m l_3^2
    assert state.mass_matrix[2, 2] - bare.mass_matrix[2, 2] == pytest.approx(causes.PAYLOAD)


@pytest.mark.parametrize(("psi_deg", "elbow"), [(4.5, -1), (65.0, -1), (110.0, 1)])
def test_planar_ik_puts_the_ee_on_the_point_with_the_last_link_at_psi(setup, psi_deg, elbow):
    point = np.array([1.203, 1.91])
    q = planar_ik(setup.robot, point, math.radians(psi_deg), elbow)
    state = FixedBaseState.compute(setup.robot, q, np.zeros(3))
    assert state.ee_position[:2] == pytest.approx(point, abs=1e-12)
    assert math.degrees(q.sum()) == pytest.approx(psi_deg)
    assert np.sign(q[1]) == elbow
    assert planar_lengths(setup.robot) == pytest.approx((1.0, 1.0, 1.0))


def test_planar_ik_rejects_a_wrist_out_of_reach(setup):
    with pytest.raises(ConfigError, match="out of reach"):
        planar_ik(setup.robot, [1.203, 1.91], math.radians(-90.0), -1)


@pytest.mark.parametrize("virtual_mass", [10.0, 1e5])
def test_momentum_approximation_misses_v_a_cross_p_in_the_angular_rows(setup, virtual_mass):
    # L_A about the moving point A obeys dL_A/dt = n_A - v_A x p, so the exact C_hat_A and
    # (M_hat_dot q_hat_dot)[:6] agree in the linear rows and differ by v_A x p in the angular ones
    rng = np.random.default_rng(3)
    model = ReversedModel(setup.robot, setup.rows, virtual_mass=virtual_mass)
    for _ in range(3):
        q, v = setup.initial_q + 0.3 * rng.standard_normal(3), rng.standard_normal(3)
        state = FixedBaseState.compute(setup.robot, q, v)
        exact = model.dynamics(state)
        approx = model.dynamics(state, momentum_approximation=True)
        momentum = (model.evaluate(q).mass @ exact.velocity)[:3]
        scale = np.abs(exact.bias[:6]).max()
        assert approx.bias[:3] == pytest.approx(exact.bias[:3], abs=1e-7 * scale)
        difference = exact.bias[3:6] - approx.bias[3:6]
        expected = np.cross(exact.velocity[:3], momentum)  # central difference: O(h^2) error
        assert difference == pytest.approx(expected, rel=1e-5, abs=1e-9 * scale)
        assert np.linalg.norm(difference) > 1e-3
        assert approx.bias[6:] == pytest.approx(exact.bias[6:])


def test_force_spread_row_can_fail():
    position = {"RNS-C": 0.01, "OS-C": 0.01, "OS-C-kinematic": 0.01}
    good = causes.force_spread_row({"RNS-C": 1.0, "OS-C": 1.5, "OS-C-kinematic": 0.9}, position)
    assert good.verdict is Verdict.QUALITATIVE
    assert good.ours == pytest.approx(1.5 / 0.9)
    bad = causes.force_spread_row({"RNS-C": 0.1, "OS-C": 1.0, "OS-C-kinematic": 0.2}, position)
    assert bad.verdict is Verdict.NOT_REPRODUCED
    assert bad.ours == pytest.approx(10.0)


def _sweep(**ratios):
    return {label: {"ratio": {"OS-C": r}} for label, r in ratios.items()}


def test_ratio_cause_says_which_factor_reproduces_the_thesis_ratio_or_that_it_is_open():
    timing, start, gravity = (
        f.label for f in (causes.FULL_FACTORS[0], causes.FULL_FACTORS[3], causes.GRAVITY_FACTOR)
    )
    hit = causes.ratio_cause(
        _sweep(baseline=1.84, **{timing: 1.84, start: causes.THESIS_RATIO * 1.05, gravity: 22.0}),
        "OS-C",
    )
    assert f"{start} ({causes.THESIS_RATIO * 1.05:.3g}), within 10%" in hit
    assert "keeps it within 5%" in hit
    assert "open" not in hit
    miss = causes.ratio_cause(_sweep(baseline=1.84, **{timing: 2.5, start: 3.0}), "OS-C")
    assert f"Closest to the thesis' 5.78: {start} (3)" in miss
    assert "timing and gains moves it" in miss
    assert "remaining cause is open" in miss


def test_reversals_count_hysteresis_crossings_only():
    t = np.linspace(0.0, 1.0, 1001)
    assert reversals(np.sin(2 * np.pi * 1.5 * t)) == 2  # + - + : two reversals
    assert reversals(1.0 + 0.05 * np.sin(40 * t)) == 0  # one sign throughout
    # chatter inside the band around zero does not count
    assert reversals(np.concatenate([np.ones(10), 0.01 * (-1) ** np.arange(50), np.ones(10)])) == 0
