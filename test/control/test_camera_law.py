"""Reactionless camera control, eq. (4.5)-(4.15), and the conventional baseline (4.7)-(4.8)."""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import assume, given, settings
from rns_testing import SATELLITE_OBSERVATION_DEG, configurations, vectors

from rns_ros.control.camera_law import (
    ControlGains,
    ConventionalWrist,
    Method,
    ReactionlessInverse,
    law_rates,
    reactionless_camera_control,
    singularity_treatment,
    wrist_offset,
)
from rns_ros.core import ConfigError, FreeFloatingState
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.timing import quintic
from rns_ros.sim.free_floating import FreeFloatingSimulator

SETTINGS = settings(max_examples=40, deadline=None)
THETA_0 = np.deg2rad(SATELLITE_OBSERVATION_DEG)


def _regular_state(robot, config):
    position, quaternion, theta = config
    state = FreeFloatingState.compute(robot, robot.configuration(theta, position, quaternion))
    sigma = state.coupling_singular_values
    assume(sigma[-1] > 1e-3 * sigma[0])
    assume(np.linalg.svd(state.restricted_jacobian, compute_uv=False)[-1] > 0.25)
    return state


@SETTINGS
@given(configurations(), vectors(3, 0.05))
def test_reactionless_methods_produce_no_coupling_momentum(robot, config, omega):
    state = _regular_state(robot, config)
    reference = wrist_offset(state) + np.array([0.01, -0.02, 0.005])
    for method in ("dls", "sc", "pinv"):
        out = reactionless_camera_control(
            robot, state, omega, method=method, wrist_reference=reference
        )
        assert np.abs(out.coupling_momentum).max() < 1e-9
        omega_b = np.linalg.solve(
            state.base_rotational_inertia,
            -state.coupling_angular_momentum_matrix @ out.joint_velocity,
        )
        assert np.abs(omega_b).max() < 1e-12


@SETTINGS
@given(configurations(), vectors(3, 0.05))
def test_dls_tracks_outside_the_singular_region_and_sc_keeps_direction(robot, config, omega):
    state = _regular_state(robot, config)
    dls = reactionless_camera_control(robot, state, omega, method="dls")
    assume(dls.limit_scale == 1.0)
    assert dls.damping == 0.0
    assert np.allclose(dls.angular_residual, 0.0, atol=1e-12)
    sc = reactionless_camera_control(robot, state, omega, method="sc")
    achieved = omega - sc.angular_residual
    assert np.allclose(achieved, sc.speed_scale * omega, atol=1e-12)


def test_wrist_term_does_not_disturb_the_camera(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    omega = np.array([0.1, 0.0, 0.0])
    far = wrist_offset(state) + np.array([0.002, 0.002, -0.002])
    out = reactionless_camera_control(robot, state, omega, wrist_reference=far)
    plain = reactionless_camera_control(robot, state, omega)
    assert out.limit_scale == 1.0
    assert not np.allclose(out.joint_velocity, plain.joint_velocity)
    assert np.allclose(out.angular_residual, 0.0, atol=1e-12)


def test_conventional_baseline_tracks_but_disturbs_the_base(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    omega = np.array([0.1, -0.05, 0.02])
    out = reactionless_camera_control(robot, state, omega, method="conventional")
    assert np.allclose(out.joint_velocity[:4], 0.0)  # eq. (4.8)
    assert np.allclose(out.angular_residual, 0.0, atol=1e-12)
    assert np.linalg.norm(out.coupling_momentum) > 0.01  # kg m^2/s


def _wrist_potential(state, reference):
    return 0.5 * np.sum((wrist_offset(state) - reference) ** 2)


def test_wrist_term_descends_the_potential_of_eq_4_6(robot):
    """omega_ref = 0: the wrist potential falls; with the sign printed in (4.5) it would rise."""
    q0 = robot.configuration(THETA_0)
    state_0 = FreeFloatingState.compute(robot, q0)
    reference = wrist_offset(state_0) + np.array([0.02, -0.01, 0.015])

    def law(sign):
        gains = ControlGains(wrist_gain=sign * 100.0) if sign > 0 else None

        def field(t, q):
            state = FreeFloatingState.compute(robot, q)
            out = reactionless_camera_control(
                robot, state, np.zeros(3), gains=gains, wrist_reference=reference
            )
            return out.joint_velocity

        return field

    simulator = FreeFloatingSimulator(robot, dt=0.01, initial_q=q0)
    potentials = [_wrist_potential(state_0, reference)]
    for _ in range(200):
        simulator.step(law(+1))
        potentials.append(
            _wrist_potential(FreeFloatingState.compute(robot, simulator.q), reference)
        )
    # only the part of dp_w inside the remaining null space can be corrected: V falls monotonically
    assert potentials[-1] < potentials[0] - 1e-6
    assert all(b <= a + 1e-15 for a, b in itertools.pairwise(potentials))
    # the printed sign: the same law with dp_w negated climbs the potential
    state = state_0
    printed = reactionless_camera_control(
        robot, state, np.zeros(3), wrist_reference=2 * wrist_offset(state) - reference
    )
    rate = (wrist_offset(state) - reference) @ (state.wrist.jacobian[:3] @ printed.joint_velocity)
    assert rate > 0.0


def test_uniform_speed_scaling_stays_reactionless_where_clipping_does_not(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    out = reactionless_camera_control(robot, state, np.array([3.0, -2.0, 1.0]))
    assert out.limit_scale < 1.0
    assert np.abs(out.joint_velocity).max() <= robot.velocity_limits.max() + 1e-12
    assert np.all(np.abs(out.joint_velocity) <= robot.velocity_limits * (1 + 1e-12))
    assert np.abs(out.coupling_momentum).max() < 1e-9
    unscaled = out.joint_velocity / out.limit_scale
    clipped = np.clip(unscaled, -robot.velocity_limits, robot.velocity_limits)
    disturbance = state.coupling_angular_momentum_matrix @ clipped
    assert np.linalg.norm(disturbance) > 1e-3


def test_each_method_has_its_own_treatment():
    treatments = {method: singularity_treatment(method) for method in Method}
    assert len({id(treatment) for treatment in treatments.values()}) == len(Method)
    for method, treatment in treatments.items():
        assert treatment.method is method
        assert singularity_treatment(method.value) is treatment
    # the baseline is the only treatment that does not move in the reaction null space
    assert isinstance(treatments[Method.CONVENTIONAL], ConventionalWrist)
    assert all(
        isinstance(treatments[method], ReactionlessInverse)
        for method in (Method.DLS, Method.SC, Method.PINV)
    )


def test_bad_gains_and_method_are_rejected(robot):
    with pytest.raises(ConfigError, match="wrist_gain"):
        ControlGains(wrist_gain=-1.0)
    with pytest.raises(ConfigError, match="epsilon"):
        ControlGains(epsilon=0.0)
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    with pytest.raises(ConfigError, match="method must be one of"):
        reactionless_camera_control(robot, state, np.zeros(3), method="magic")


def _satellite_observation(robot, method, duration=20.0, dt=0.02):
    """Thesis scenario (i): rotate the camera by pi about world x with a quintic profile.

    Continuous time (the law evaluated at every RK4 stage), wrist stabilization off as in the
    shipped scenario file: with k_g = 100 our model drifts into the DLS singular region
    (sigma_min ~ 0.10) and misses the target by ~4.6 deg (docs/controller.md).
    """
    q0 = robot.configuration(THETA_0)
    state_0 = FreeFloatingState.compute(robot, q0)
    gains = ControlGains(wrist_gain=0.0)

    def field(t, q):
        state = FreeFloatingState.compute(robot, q)
        omega = np.array([np.pi * quintic(t, duration)[1], 0.0, 0.0])
        return reactionless_camera_control(
            robot, state, omega, method=method, gains=gains
        ).joint_velocity

    simulator = FreeFloatingSimulator(robot, dt=dt, initial_q=q0)
    worst = 0.0
    for _ in range(round(duration / dt)):
        simulator.step(field)
        rotation = pin.Quaternion(simulator.q[3:7]).toRotationMatrix()
        worst = max(worst, attitude_deviation(state_0.base_rotation, rotation))
    final = FreeFloatingState.compute(robot, simulator.q)
    target = pin.exp3(np.array([np.pi, 0.0, 0.0])) @ state_0.camera.rotation
    return np.rad2deg(worst), np.rad2deg(attitude_deviation(target, final.camera.rotation))


def test_satellite_observation_continuous_time(robot):
    dls_deviation, dls_error = _satellite_observation(robot, "dls")
    conventional_deviation, _ = _satellite_observation(robot, "conventional")
    assert dls_deviation < 1e-5  # deg
    assert dls_error < 1.0  # deg
    # The baseline turns the satellite (~0.2 deg, over the ETS-VII +-0.05 deg). Its camera error
    # (~24 deg here) comes from the wrist-only Jacobian nearing its own singularity on our
    # geometry (sigma_min ~ 5e-4, speed scaled to 0.5 %): documented, not asserted.
    assert conventional_deviation > 0.05
    assert conventional_deviation > 1e3 * max(dls_deviation, 1e-9)


@SETTINGS
@given(configurations(), vectors(3, 0.2))
def test_closed_form_law_is_the_svd_law(robot, config, omega):
    """Away from the singular region (4.10-4.15) the one-solve closed form of law_rates gives the
    joint velocity of the SVD form (4.9, 4.11, 4.13) to rounding, wrist term included."""
    state = _regular_state(robot, config)
    reference = wrist_offset(state) + np.array([0.01, -0.02, 0.005])
    gains = ControlGains()
    for method in (Method.DLS, Method.SC, Method.PINV):
        rates = law_rates(robot, state, omega, method, gains, reference, None)
        svd = singularity_treatment(method).svd_rates(
            state, state.restricted_jacobian, omega, gains, reference
        )
        theta_dot = rates.limit_scale * svd.joint_velocity
        scale = max(1.0, float(np.abs(theta_dot).max()))
        np.testing.assert_allclose(rates.joint_velocity, theta_dot, atol=1e-10 * scale)
        assert rates.damping == svd.damping == 0.0
        assert rates.sc_scale == pytest.approx(svd.sc_scale, rel=1e-10)
        assert rates.sigma_min == pytest.approx(svd.sigma_min, rel=1e-10)
        assert rates.algorithmic == pytest.approx(svd.algorithmic, rel=1e-10)
