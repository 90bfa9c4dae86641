"""Sampled controller: hold-interval correction, position limits, twist frames, theta_ref."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from rns_testing import SATELLITE_OBSERVATION_DEG, vectors

from rns_ros.analysis.closed_loop import run_scenario
from rns_ros.control.camera_law import (
    ControlGains,
    Method,
    arm_law_rates,
    control_output,
    law_rates,
    reactionless_camera_control,
    wrist_offset,
)
from rns_ros.control.controller import (
    HOLD_CONSISTENCY,
    HOLD_SPEED_FLOOR,
    ControllerSettings,
    ReactionlessController,
    TwistFrame,
    angular_velocity_in_world,
)
from rns_ros.core import ConfigError, FreeFloatingState
from rns_ros.core.integration import attitude_deviation
from rns_ros.sim.free_floating import FreeFloatingSimulator

THETA_0 = np.deg2rad(SATELLITE_OBSERVATION_DEG)


def test_position_limit_halts_the_whole_motion_reactionlessly(robot):
    theta = THETA_0.copy()
    state = FreeFloatingState.compute(robot, robot.configuration(theta))
    omega = np.array([0.1, 0.0, 0.0])
    free = reactionless_camera_control(robot, state, omega, limit_horizon=0.01)
    assert not free.position_limited
    # put the fastest-moving joint exactly at the limit it is heading for
    joint = int(np.argmax(np.abs(free.joint_velocity)))
    limit = robot.upper_limits if free.joint_velocity[joint] > 0 else robot.lower_limits
    theta[joint] = limit[joint]
    state = FreeFloatingState.compute(robot, robot.configuration(theta))
    out = reactionless_camera_control(robot, state, omega, limit_horizon=0.01)
    assert out.position_limited
    assert out.limit_scale == 0.0
    assert np.all(out.joint_velocity == 0.0)
    # the opposite command moves away from the limit and is not held back
    back = reactionless_camera_control(robot, state, -omega, limit_horizon=0.01)
    assert not back.position_limited


@settings(max_examples=30, deadline=None)
@given(vectors(3, 0.2))
def test_twist_frames_rotate_into_world(robot, omega):
    state = FreeFloatingState.compute(
        robot, robot.configuration(THETA_0, [0, 0, 0], [0.1, 0.2, 0.3, 0.9])
    )
    world = angular_velocity_in_world(state, omega, TwistFrame.WORLD)
    assert np.array_equal(world, omega)
    base = angular_velocity_in_world(state, omega, TwistFrame.BASE)
    assert np.allclose(state.base_rotation.T @ base, omega, atol=1e-14)
    camera = angular_velocity_in_world(state, omega, TwistFrame.CAMERA)
    # a camera-frame command is achieved in camera axes: R_c^T J_omega theta_dot = omega
    out = reactionless_camera_control(robot, state, camera)
    if out.limit_scale == 1.0:
        achieved = state.camera.rotation.T @ (state.camera.jacobian[3:] @ out.joint_velocity)
        assert np.allclose(achieved, omega, atol=1e-12)


def test_reference_positions_integrate_the_held_velocity(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    controller = ReactionlessController(robot, ControllerSettings(period=0.02))
    controller.reset(state)
    first = controller.step(state, [0.1, 0.0, 0.0])
    assert np.array_equal(first.reference_positions, state.theta)
    second = controller.step(state, [0.1, 0.0, 0.0])
    assert np.allclose(second.reference_positions, state.theta + 0.02 * first.joint_velocity)
    # the midpoint output is reactionless where it was evaluated, not at the sample
    out = second.output
    assert np.abs(out.coupling_momentum).max() < 1e-9
    assert not np.allclose(second.evaluated_theta, state.theta)


@pytest.mark.parametrize("held_periods", [0.3, 1.3])
def test_end_hold_keeps_the_reference_on_the_plant_when_outputs_come_early_or_late(
    robot, held_periods
):
    """Outputs that are not T apart: commands served at once (rns_controller's immediate
    reaction) end a hold after 30 % of T, a busy executor's late timer after 130 %. The plant
    holds theta_dot until the next output; end_hold puts theta_ref where that took the arm, so
    over 40 holds the reference stays on the (kinematic) plant instead of running ahead (early)
    or falling behind (late) by |1 - elapsed/T| T theta_dot per hold, and the base stays put."""
    period = 0.02
    held = held_periods * period
    q0 = robot.configuration(THETA_0)
    state = FreeFloatingState.compute(robot, q0)
    simulator = FreeFloatingSimulator(robot, dt=0.001, initial_q=q0)
    controller = ReactionlessController(robot, ControllerSettings(period=period))
    controller.reset(state)
    base_0 = state.base_rotation
    worst_base, worst_reference = 0.0, 0.0
    for k in range(40):
        omega = [0.1, 0.05 * (-1) ** k, 0.0]  # a new command every cycle
        step = controller.step(state, omega)
        worst_reference = max(
            worst_reference, float(np.abs(step.reference_positions - state.theta).max())
        )
        simulator.set_reference(velocities=step.joint_velocity)
        for _ in range(round(held / simulator.dt)):
            simulator.step()
        controller.end_hold(held)
        state = FreeFloatingState.compute(robot, simulator.q)
        worst_base = max(worst_base, attitude_deviation(base_0, state.base_rotation))
    assert worst_reference < 1e-12
    assert np.degrees(worst_base) < 3e-5  # [deg]; 1.3-1.9e-5 on the identified geometry


def test_end_hold_is_a_no_op_without_a_hold_and_never_goes_back(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    controller = ReactionlessController(robot, ControllerSettings(period=0.01))
    controller.reset(state)
    before = controller.reference_positions.copy()
    controller.end_hold(0.001)
    assert np.array_equal(controller.reference_positions, before)
    step = controller.step(state, [0.1, 0.0, 0.0])
    controller.end_hold(-1.0)  # a clock that went backwards holds, it does not rewind
    assert np.array_equal(controller.reference_positions, before)
    step = controller.step(state, [0.1, 0.0, 0.0])
    controller.end_hold(0.05)
    assert np.allclose(controller.reference_positions, before + 0.05 * step.joint_velocity)


def test_end_hold_takes_a_longer_limit_for_a_stall_checked_on_a_steady_clock(robot):
    """0.08 s between two outputs is past max_hold (a jump or a stall): by default the hold is
    dropped (theta_ref stays where it started); with the caller's longer limit (a stall its
    steady clock saw) theta_ref moves on over it, as a plant holding theta_dot did."""
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    controller = ReactionlessController(robot, ControllerSettings(period=0.01))
    controller.reset(state)
    before = controller.reference_positions.copy()
    controller.step(state, [0.1, 0.0, 0.0])
    assert not controller.end_hold(0.08)
    assert np.array_equal(controller.reference_positions, before)
    step = controller.step(state, [0.1, 0.0, 0.0])
    assert controller.end_hold(0.08, limit=0.1)
    assert np.allclose(controller.reference_positions, before + 0.08 * step.joint_velocity)
    controller.step(state, [0.1, 0.0, 0.0])
    assert not controller.end_hold(0.12, limit=0.1)


def test_bad_settings_are_rejected():
    with pytest.raises(ConfigError, match="hold_iterations"):
        ControllerSettings(hold_iterations=0)
    with pytest.raises(ConfigError, match="hold_correction must be one of"):
        ControllerSettings(hold_correction="euler")
    with pytest.raises(ConfigError, match="period"):
        ControllerSettings(period=-0.01)


def test_midpoint_hold_is_second_order_where_naive_is_first(robot, scenario):
    """Halving the period halves the naive hold error and quarters the midpoint one."""
    short = dataclasses.replace(scenario("satellite_observation"), duration=4.0, angle=np.pi / 4)

    def deviation(hold, rate):
        return run_scenario(robot, short, hold_correction=hold, rate=rate).max_base_deviation_deg

    naive = deviation("naive", 50.0) / deviation("naive", 100.0)
    midpoint = deviation("midpoint", 50.0) / deviation("midpoint", 100.0)
    assert 1.6 < naive < 2.5
    assert midpoint > 3.2


def test_a_controller_that_starts_with_resync_still_holds_the_wrist(robot):
    """rns_controller resyncs before its first step (it starts stopped). The wrist reference
    p_w^init of eq. (4.6) must be taken then too: without it the k_g term was silently off over
    DDS (the demo's wrist drifted 0.64 m, the k_g = 0 figure, instead of 0.09 m)."""
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    started_by_resync = ReactionlessController(robot, ControllerSettings())
    started_by_resync.resync(state)
    started_by_reset = ReactionlessController(robot, ControllerSettings())
    started_by_reset.reset(state)
    assert started_by_resync.wrist_reference is not None
    np.testing.assert_array_equal(
        started_by_resync.wrist_reference, started_by_reset.wrist_reference
    )
    omega = [0.1, 0.0, 0.0]
    np.testing.assert_allclose(
        started_by_resync.step(state, omega).joint_velocity,
        started_by_reset.step(state, omega).joint_velocity,
    )


def _run_states(robot, scenario, duration, method="dls"):
    """(state, omega) of every period of a midpoint closed-loop run, in order (the rotation
    shortened with the duration: same peak rate as the 20 s, 180 deg scenario)."""
    short = dataclasses.replace(scenario, duration=duration, angle=np.pi * duration / 20.0)
    samples = []
    run_scenario(robot, short, method=method, on_period=samples.append)
    first = FreeFloatingState.compute(robot, robot.configuration(short.initial_theta))
    states = [first] + [sample.state for sample in samples[:-1]]
    return [(state, sample.omega_ref) for state, sample in zip(states, samples, strict=True)]


@pytest.mark.parametrize("method", ["dls", "sc", "pinv"])
def test_closed_form_midpoint_law_is_the_law_on_the_full_state(robot, method):
    """The midpoint's partial state (ArmKinematics: no P_RNS, no SVD) gives the law of the full
    FreeFloatingState there, to rounding (one 6 x 6 inverse instead of an SVD, eq. 4.5/4.15)."""
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    omega = np.array([0.1, -0.05, 0.02])
    reference = wrist_offset(state) + np.array([0.01, -0.02, 0.005])
    gains = ControlGains()
    rng = np.random.default_rng(7)
    for _ in range(20):
        theta = THETA_0 + rng.uniform(-0.3, 0.3, robot.n)
        arm = state.arm_kinematics(theta)
        full = state.with_joint_angles(theta)
        np.testing.assert_allclose(arm.wrist_offset, wrist_offset(full), atol=1e-14)
        closed = arm_law_rates(
            robot,
            arm,
            omega,
            Method.parse(method),
            gains,
            reference,
            0.005,
            float(state.coupling_singular_values[0]),
        )
        exact = law_rates(robot, full, omega, Method.parse(method), gains, reference, 0.005)
        if closed is None:  # DLS inside its singular region: the caller takes the full state
            assert method == "dls"
            assert exact.sigma_min <= gains.epsilon
            continue
        rates, output = closed
        np.testing.assert_allclose(rates.joint_velocity, exact.joint_velocity, atol=1e-11)
        assert rates.sigma_min == pytest.approx(exact.sigma_min, rel=1e-10)
        assert rates.algorithmic == pytest.approx(exact.algorithmic, rel=1e-9)
        assert rates.sc_scale == pytest.approx(exact.sc_scale, rel=1e-10)
        expected = control_output(full, omega, exact)
        for name in ("kinematic", "coupling", "algorithmic"):
            assert getattr(output.determinants, name) == pytest.approx(
                getattr(expected.determinants, name), rel=1e-9
            )
        np.testing.assert_allclose(output.angular_residual, expected.angular_residual, atol=1e-11)
        np.testing.assert_allclose(output.coupling_momentum, expected.coupling_momentum, atol=1e-9)
        assert output.speed_scale == pytest.approx(expected.speed_scale, rel=1e-10)


def test_dls_inside_its_singular_region_falls_back_to_the_full_state(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    arm = state.arm_kinematics(THETA_0)
    gains = ControlGains(epsilon=0.9)  # puts the start inside the singular region
    closed = arm_law_rates(robot, arm, [0.1, 0.0, 0.0], Method.DLS, gains, None, None, 400.0)
    assert closed is None
    controller = ReactionlessController(robot, ControllerSettings(gains=gains))
    controller.reset(state)
    step = controller.step(state, [0.1, 0.0, 0.0])
    assert step.output.damping > 0.0
    assert np.abs(step.output.coupling_momentum).max() < 1e-9


def test_warm_midpoint_is_consistent_and_closer_to_the_implicit_midpoint(robot, scenario):
    """Along 3 s of satellite observation: each output is within the stated consistency of the
    midpoint it was evaluated at, and closer to the converged (5-iteration) implicit midpoint
    theta_dot = law(theta_k + T/2 theta_dot) than the one-iteration output predicted by the law
    at the sample (the cold path)."""
    period = 0.01
    warm = ReactionlessController(robot, ControllerSettings(period=period))
    run = _run_states(robot, scenario("satellite_observation"), 3.0)
    warm.reset(run[0][0])
    warm_miss, cold_miss = [], []
    for k, (state, omega) in enumerate(run):
        step = warm.step(state, omega)
        theta_dot = step.joint_velocity
        off = np.abs(step.evaluated_theta - (state.theta + 0.5 * period * theta_dot)).max()
        speed = max(np.abs(theta_dot).max(), HOLD_SPEED_FLOOR)
        if k > 0:  # no history yet: predicted by the law at the sample
            assert off <= 0.5 * HOLD_CONSISTENCY * period**2 * speed * (1 + 1e-9), k
        converged = _cold_step(robot, warm, state, omega, 5)
        cold = _cold_step(robot, warm, state, omega, 1)
        warm_miss.append(np.abs(theta_dot - converged).max())
        cold_miss.append(np.abs(cold - converged).max())
    # measured: median 3.8e-7 vs 2.5e-5 rad/s, largest 5.9e-7 vs 4.0e-5 rad/s
    assert np.median(warm_miss) < 0.05 * np.median(cold_miss)
    assert max(warm_miss) < 0.1 * max(cold_miss)


def _cold_step(robot, template, state, omega, iterations):
    """theta_dot of a fresh controller (no history: the law at the sample as predictor)."""
    settings = dataclasses.replace(template.settings, hold_iterations=iterations)
    fresh = ReactionlessController(robot, settings)
    fresh.reset(state)
    fresh._wrist_reference = template.wrist_reference
    return fresh.step(state, omega).joint_velocity


def test_reset_resync_and_configure_drop_the_predictor_history(robot):
    """After reset, resync or a settings change the next step is the cold step (law at the
    sample as predictor) of a fresh controller, not an extrapolation of older outputs."""
    state = FreeFloatingState.compute(robot, robot.configuration(THETA_0))
    omega = np.array([0.1, 0.0, 0.0])

    def used(controller):
        for _ in range(3):
            controller.step(state, omega)
        return controller

    fresh = ReactionlessController(robot, ControllerSettings())
    fresh.reset(state)
    expected = fresh.step(state, omega).joint_velocity
    for restart in ("reset", "resync", "configure"):
        controller = used(ReactionlessController(robot, ControllerSettings()))
        controller.step(state, -omega)  # history now points the other way
        if restart == "configure":
            controller.configure(ControllerSettings())
        else:
            getattr(controller, restart)(state)
        np.testing.assert_array_equal(controller.step(state, omega).joint_velocity, expected)


def _base_turn_over_a_hold(robot, hold_steps: int, announced: bool) -> float:
    """Base turn [rad] while the output of one step (period 10 ms) is held for hold_steps ms,
    with or without announcing the hold to the controller."""
    theta = np.deg2rad(SATELLITE_OBSERVATION_DEG)
    state = FreeFloatingState.compute(robot, robot.configuration(theta))
    controller = ReactionlessController(robot, ControllerSettings(period=0.01))
    controller.reset(state)
    hold = 1e-3 * hold_steps if announced else None
    step = controller.step(state, np.array([0.3, -0.1, 0.2]), hold)
    simulator = FreeFloatingSimulator(
        robot, dt=1e-3, initial_q=state.q, initial_momentum=np.zeros(6)
    )
    simulator.set_reference(velocities=step.joint_velocity)
    for _ in range(hold_steps):
        simulator.step()
    after = FreeFloatingState.compute(robot, simulator.q)
    return attitude_deviation(state.base_rotation, after.base_rotation)


def test_a_hold_shorter_than_the_period_is_reactionless_when_announced(robot):
    """A command served between ticks cuts the hold short. Evaluated for T = 10 ms, a hold of
    h leaves a residue of order h (T - h); announced (step(..., hold=h)) the midpoint moves to
    h/2 and the residue is third order: 8x for twice the hold, and 10-330x smaller."""
    announced = {h: _base_turn_over_a_hold(robot, h, True) for h in (2, 4, 7)}
    for h, turn in announced.items():
        assert turn < 0.2 * _base_turn_over_a_hold(robot, h, False), h
    assert announced[4] / announced[2] == pytest.approx(8.0, rel=0.25)


def test_a_bad_hold_is_rejected(robot):
    state = FreeFloatingState.compute(robot, robot.configuration(np.zeros(7)))
    controller = ReactionlessController(robot, ControllerSettings())
    with pytest.raises(ConfigError, match="hold"):
        controller.step(state, np.zeros(3), hold=-1e-3)
