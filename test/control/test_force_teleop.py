"""rns_force_controller's step logic (rns_ros.control.force_teleop) without ROS.

The central check: the step function fed as DDS feeds it (each state with the wrench measured
under the torque held over the previous step, the twist sampled from the scenario reference)
reproduces the in-process reference loop ``run_closed_loop`` of thesis chapter 6.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rns_ros.analysis.contact_tasks import ArcScenario, WallScenario
from rns_ros.analysis.motion_force_runs import QUICK_PERIOD, run_closed_loop
from rns_ros.control.force_teleop import (
    ERROR_LABELS,
    CommandFrame,
    ForceControlSettings,
    ForceControlState,
    ForceSetpoint,
    ForceTeleopController,
    JointMeasurement,
    RigidContactModel,
    TwistCommand,
    WrenchSample,
    command_frames,
    normal_acceleration,
    predicted_contact_force,
    validate_force_setpoint,
    validate_twist,
)
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseState, load_fixed_base_model
from rns_ros.resources import config_dir
from rns_ros.sim.contact import ArcConstraint, ContactSimulator, PlaneConstraint

LWR = load_fixed_base_model(config_dir() / "lwr_7dof.yaml")
PLANAR = load_fixed_base_model(config_dir() / "planar_3dof.yaml")
START = np.radians([20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0])
ZERO = np.zeros(3)


def _ns(t: float) -> int:
    return round(t * 1e9)


def _dds_loop(scenario, settings, dt, *, drop_wrench_every=0, twist_every=1, late=0):
    """The controller against a ContactSimulator, fed like DDS: each state comes with the wrench
    and effort of the torque held over the step that ended there; twist and force setpoint are
    the scenario's reference velocity and force, one message every ``twist_every`` states,
    arriving ``late`` states after their stamp.

    Returns:
        (force error (k,) [N], joint speed (k,) [rad/s], the states seen, the simulator,
        |p_des - p| (k,) [m]).
    """
    setup = scenario.setup()
    controller = ForceTeleopController(setup.robot, settings)
    sim = ContactSimulator(setup.robot, setup.constraint, initial_q=setup.initial_q, dt=dt)
    steps = round(setup.duration / dt)
    force_error, joint_speed, position_error, states = [], [], [], set()
    for i in range(steps + 1):
        t = i * dt
        if i % twist_every == 0 and i >= late:
            sampled = t - late * dt  # the instant the operator sampled (the message's stamp)
            controller.set_twist(
                TwistCommand(
                    setup.reference(sampled).velocity, ZERO, CommandFrame.WORLD, _ns(sampled), t
                )
            )
            normal = sim.contact_normal()
            controller.set_force(
                ForceSetpoint(setup.force(sampled) * normal, ZERO, CommandFrame.WORLD, t)
            )
        wrench = sim.wrist_wrench()  # under the torque held over the previous step
        if not drop_wrench_every or i % drop_wrench_every:
            controller.add_wrench(WrenchSample(_ns(t), wrench[:3], wrench[3:]))
        out = controller.step(JointMeasurement(_ns(t), sim.q, sim.v, sim.torque.copy()), t)
        assert out.torque is not None
        assert np.isfinite(out.torque).all()
        states.add(out.state)
        sim.set_torque(out.torque)
        force_error.append(out.force_desired - sim.contact_force)  # as run_closed_loop logs it
        joint_speed.append(np.abs(sim.v).max())
        position_error.append(np.linalg.norm(out.position_error))
        if i < steps:
            sim.step()
    return (
        np.array(force_error),
        np.array(joint_speed),
        states,
        sim,
        np.array(position_error),
    )


#: rns_force_controller on the planar arc (config/force_controller_arc.yaml).
ARC_SETTINGS = {
    "task_axes": ("x", "y"),
    "constrained_frame": "world",
    "constrained_axis": (1.0, 0.0, 0.0),
    "surface_curvature": 1.0 / 0.707,
    "default_twist_frame": "world",
    "max_linear_speed": 2.0,
    "max_linear_acceleration": 10.0,
}


@pytest.mark.parametrize("normal_mode", ["fixed", "wrench"])
@pytest.mark.parametrize(("method", "label"), [("rns", "RNS-C"), ("os", "OS-C")])
def test_dds_fed_loop_reproduces_the_planar_arc(method, label, normal_mode):
    """The planar arc (one half cycle, 2 ms): the normal from the surface model (a circle of
    radius 1/kappa through the start point) or from the pushing wrench gives the in-process
    loop's peak joint speed (RNS-C 0.741, OS-C 1.365 rad/s on the full cycle at 1 ms) and
    force. The wrench alone failed here: the bilateral contact pulls while the force ramps in,
    and a pull points the normal the wrong way."""
    scenario = ArcScenario(half_cycles=1)
    reference = run_closed_loop(scenario, label, dt=QUICK_PERIOD)
    settings = ForceControlSettings(
        method=method, nominal_period=QUICK_PERIOD, normal_mode=normal_mode, **ARC_SETTINGS
    )
    force_error, joint_speed, states, _, _ = _dds_loop(scenario, settings, QUICK_PERIOD)
    assert joint_speed.max() == pytest.approx(reference.peak_joint_speed, rel=0.02)
    assert np.abs(force_error).max() < 1e-3
    assert states <= {ForceControlState.OK}


def test_late_twists_keep_their_acceleration_feed_forward():
    """Twists every 2 ms reaching the controller one 1 ms step after their stamp (what the
    operator's sim-time timer and DDS give): the first-order hold extrapolates each over up to
    two of its periods, so the feed-forward never drops out. Measured 0.028 mm on one stroke
    (0.020 mm with on-time twists); holding for one period only gave 1.3 mm."""
    settings = ForceControlSettings(nominal_period=1e-3)
    *_, position_error = _dds_loop(WallScenario(strokes=1), settings, 1e-3, twist_every=2, late=1)
    assert position_error.max() < 1e-4


@pytest.mark.parametrize(("method", "label"), [("rns", "RNS-C"), ("os", "OS-C")])
def test_dds_fed_loop_reproduces_the_in_process_loop(method, label):
    """Predicted force (same instant, sensor-corrected) over DDS-timed inputs == run_closed_loop
    (one stroke of the LWR wall task, 2 ms period). Measured: peak joint speed 1.0432 vs 1.0432
    (RNS-C), 1.5420 vs 1.5419 (OS-C); max force error 1.24e-6 / 4.3e-7 N in both loops."""
    reference = run_closed_loop(WallScenario(strokes=1), label, dt=QUICK_PERIOD)
    settings = ForceControlSettings(method=method, nominal_period=QUICK_PERIOD)
    force_error, joint_speed, states, sim, _ = _dds_loop(
        WallScenario(strokes=1), settings, QUICK_PERIOD
    )
    print(label, joint_speed.max(), reference.peak_joint_speed, np.abs(force_error).max())
    assert joint_speed.max() == pytest.approx(reference.peak_joint_speed, rel=0.02)
    assert np.abs(force_error).max() < 1e-3
    assert reference.max_force_error < 1e-3
    assert sim.pulling_steps == reference.pulling_steps  # (lambda ~ -1e-9 N at the start)
    assert states <= {ForceControlState.OK}


def test_a_missing_wrench_reuses_the_previous_bias():
    """Every 5th wrench lost (arrived after its state): the bias of the step before is used; the
    force still follows (measured 1.3e-6 N)."""
    settings = ForceControlSettings(nominal_period=QUICK_PERIOD)
    scenario = WallScenario(strokes=1, stroke=1.0)
    force_error, *_ = _dds_loop(scenario, settings, QUICK_PERIOD, drop_wrench_every=5)
    assert np.abs(force_error).max() < 1e-3


def test_sampled_force_is_rejected_for_k_f_of_one_or_more():
    with pytest.raises(ConfigError, match=r"k_f < 1.*e_\{k\+1\} = -k_f e_k.*predicted"):
        ForceControlSettings(force_measurement="sampled", k_f=5.0)
    with pytest.raises(ConfigError, match="k_f < 1"):
        ForceControlSettings(force_measurement="sampled", k_f=1.0)


def test_sampled_force_with_a_small_gain_is_stable():
    """(6.34) on the one-step-late sample: e_{k+1} = -k_f e_k + ..., stable for k_f = 0.5: the
    force settles on f_des (after the 1 s ramp, the error stays below 0.05 N)."""
    settings = ForceControlSettings(
        force_measurement="sampled", k_f=0.5, nominal_period=QUICK_PERIOD
    )
    scenario = WallScenario(strokes=1, stroke=1.5)
    force_error, joint_speed, *_ = _dds_loop(scenario, settings, QUICK_PERIOD)
    settled = force_error[round(1.0 / QUICK_PERIOD) :]
    print("sampled k_f 0.5: max |e| after the ramp", np.abs(settled).max())
    assert np.abs(settled).max() < 0.05
    assert np.isfinite(joint_speed).all()


# --- the predicted contact force --------------------------------------------------------------
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
    part2_runs commands as [-constraint.curvature(p, p_dot)])."""
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


# --- safety ------------------------------------------------------------------------------------
def _free_arm(controller, q, steps, *, dt=1e-3, wrench=ZERO, setpoint=None, twist=None):
    """The LWR without any contact (RK4 of pin.aba, zero-order hold); returns EE positions and
    step results."""
    data = LWR.model.createData()
    v = np.zeros(7)
    tau = np.zeros(7)
    positions, outs = [], []

    def accel(q_, v_):
        return pin.aba(LWR.model, data, q_, v_, tau)

    for i in range(steps):
        t = i * dt
        if setpoint is not None:
            controller.set_force(ForceSetpoint(setpoint, ZERO, CommandFrame.EE, t))
        if twist is not None:
            controller.set_twist(TwistCommand(twist, ZERO, CommandFrame.WORLD, _ns(t), t))
        controller.add_wrench(WrenchSample(_ns(t), np.asarray(wrench, float), ZERO))
        out = controller.step(JointMeasurement(_ns(t), q, v, tau.copy()), t)
        outs.append(out)
        positions.append(FixedBaseState.compute(LWR, q, v).ee_position)
        tau = out.torque
        k1q, k1v = v, accel(q, v)
        k2q, k2v = v + 0.5 * dt * k1v, accel(q + 0.5 * dt * k1q, v + 0.5 * dt * k1v)
        k3q, k3v = v + 0.5 * dt * k2v, accel(q + 0.5 * dt * k2q, v + 0.5 * dt * k2v)
        k4q, k4v = v + dt * k3v, accel(q + dt * k3q, v + dt * k3v)
        q = q + dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
        v = v + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return np.array(positions), outs


@pytest.mark.parametrize("method", ["rns", "os"])
def test_no_contact_stops_the_force_task_and_holds_the_pose(method):
    """A free arm asked to push 5 N: no force is measured -> NO_CONTACT after contact_loss_time
    (20 ms), latched; then pure motion control holds where the arm was: it moves < 5 mm."""
    controller = ForceTeleopController(LWR, ForceControlSettings(method=method))
    positions, outs = _free_arm(controller, START, 400, setpoint=np.array([0.0, 0.0, 5.0]))
    stopped = next(i for i, out in enumerate(outs) if out.state is ForceControlState.NO_CONTACT)
    assert 0.02 <= outs[stopped].time <= 0.02 + 2e-3
    assert all(out.state is ForceControlState.NO_CONTACT for out in outs[stopped:])
    assert not outs[stopped].force_active
    assert outs[stopped].force_reference == 0.0
    assert "no contact made" in outs[stopped].detail
    moved = np.linalg.norm(positions[stopped:] - positions[stopped], axis=1).max()
    print(f"{method}: EE moved {moved * 1e3:.2f} mm after the stop")
    assert moved < 5e-3
    assert np.linalg.norm(outs[-1].position_error) < 5e-3
    # a new setpoint does not restart the force task; ~/reset then a setpoint does
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, 5.0]), ZERO, CommandFrame.EE, 1.0))
    assert controller.fault is not None
    controller.reset()
    assert controller.fault is None


def _wall_push(controller, sim, steps, *, wrench_from: int, wrench_until: int, dt=1e-3):
    """10 N asked from the first step on, against ``sim`` (a wall); the wrist wrench reaches the
    controller only for steps in [wrench_from, wrench_until). Returns the step results and the
    simulator's contact force [N] after each step."""
    outs, forces = [], []
    for i in range(steps):
        t = i * dt
        controller.set_force(
            ForceSetpoint(10.0 * sim.contact_normal(), ZERO, CommandFrame.WORLD, t)
        )
        if wrench_from <= i < wrench_until:
            wrench = sim.wrist_wrench()
            controller.add_wrench(WrenchSample(_ns(t), wrench[:3], wrench[3:]))
        out = controller.step(JointMeasurement(_ns(t), sim.q, sim.v, sim.torque.copy()), t)
        assert out.torque is not None
        assert np.isfinite(out.torque).all()
        outs.append(out)
        sim.set_torque(out.torque)
        sim.step()
        forces.append(sim.contact_force)
    return outs, np.array(forces)


def test_a_late_wrench_stream_pauses_the_push_instead_of_stopping_on_no_contact():
    """The wrist wrench stream starts 100 ms after the setpoint (over DDS its subscription can
    match after joint_states'): the force task pauses (WRENCH_STALE, f_des 0: the arm does not
    push blind) rather than latching NO_CONTACT after contact_loss_time (20 ms) on a force that
    was never measured; once wrenches arrive the push builds to 10 N. The stream then stops: after
    wrench_timeout (50 ms) the push pauses again, with no latched stop."""
    setup = WallScenario(strokes=1).setup()
    controller = ForceTeleopController(setup.robot, ForceControlSettings())
    sim = ContactSimulator(setup.robot, setup.constraint, initial_q=setup.initial_q, dt=1e-3)
    outs, force = _wall_push(controller, sim, 400, wrench_from=100, wrench_until=250)
    states = [out.state for out in outs]
    assert controller.fault is None
    assert set(states[:100]) == {ForceControlState.WRENCH_STALE}
    assert all(out.force_desired == 0.0 and out.force_reference <= 0.0 for out in outs[:100])
    assert np.abs(force[:100]).max() < 1.0  # held at 0 N on the wall
    assert "no fresh wrist_wrench (none yet" in outs[0].detail
    assert ForceControlState.WRENCH_STALE not in states[100:250]
    assert force[130:250] == pytest.approx(10.0, abs=0.1)
    # the stream stops at step 250: the last sample stays fresh for wrench_timeout
    assert ForceControlState.WRENCH_STALE not in states[250:299]
    assert set(states[301:]) == {ForceControlState.WRENCH_STALE}
    assert np.abs(force[330:]).max() < 1.0


def test_wrench_timeout_is_validated():
    with pytest.raises(ConfigError, match=r"wrench_timeout must be in \[0.0001, 10.0\] \[s\]"):
        ForceControlSettings(wrench_timeout=0.0)


def test_wrench_over_the_limit_stops_and_reset_clears_it():
    controller = ForceTeleopController(LWR, ForceControlSettings())
    _, outs = _free_arm(controller, START, 3, wrench=[0.0, 0.0, 41.0])
    assert outs[0].state is ForceControlState.WRENCH_LIMIT
    assert "41 N" in outs[0].detail
    controller.reset()
    _, outs = _free_arm(controller, START, 3)
    assert outs[-1].state is ForceControlState.HOLDING
    torque_limit = ForceTeleopController(LWR, ForceControlSettings())
    torque_limit.add_wrench(WrenchSample(0, ZERO, np.array([0.0, 11.0, 0.0])))
    out = torque_limit.step(JointMeasurement(0, START, np.zeros(7)), 0.0)
    assert out.state is ForceControlState.WRENCH_LIMIT


def test_contact_lost_after_contact_was_made():
    """Measured 5 N (in contact), then 0: CONTACT_LOST, not NO_CONTACT."""
    controller = ForceTeleopController(LWR, ForceControlSettings())
    setpoint = ForceSetpoint(np.array([0.0, 0.0, 5.0]), ZERO, CommandFrame.EE, 0.0)
    for i in range(40):
        controller.set_force(setpoint._replace(received=i * 1e-3))
        force = np.array([0.0, 0.0, 5.0 if i < 10 else 0.0])
        controller.add_wrench(WrenchSample(_ns(i * 1e-3), force, ZERO))
        out = controller.step(JointMeasurement(_ns(i * 1e-3), START, np.zeros(7)), i * 1e-3)
        if i < 10:
            assert out.contact == "in_contact"
    assert out.state is ForceControlState.CONTACT_LOST
    assert out.contact == "lost"


# --- inputs ------------------------------------------------------------------------------------
FRAMES = command_frames("map", "ee")


def test_bad_commands_are_rejected_with_the_value_named():
    with pytest.raises(InputError, match=r"linear velocity must be 3 finite numbers.*nan"):
        validate_twist([math.nan, 0, 0], ZERO, "", FRAMES, CommandFrame.EE, 0, 0.0)
    with pytest.raises(InputError, match="'camera' is not one of"):
        validate_twist(ZERO, ZERO, "camera", FRAMES, CommandFrame.EE, 0, 0.0)
    with pytest.raises(InputError, match="force must be 3 finite"):
        validate_force_setpoint([0, 0, math.inf], ZERO, "", FRAMES, 0.0)
    assert validate_twist(ZERO, ZERO, "", FRAMES, CommandFrame.WORLD, 0, 0.0).frame == "world"
    assert validate_twist(ZERO, ZERO, "map", FRAMES, CommandFrame.EE, 0, 0.0).frame == "world"
    assert validate_force_setpoint(ZERO, ZERO, "", FRAMES, 0.0).frame == "ee"


def _one_step(controller, *, t=0.0, wrench=ZERO):
    controller.add_wrench(WrenchSample(_ns(t), np.asarray(wrench, float), ZERO))
    return controller.step(JointMeasurement(_ns(t), START, np.zeros(7)), t)


def test_rejected_inputs_keep_the_previous_setpoint_and_hold():
    controller = ForceTeleopController(LWR, ForceControlSettings())
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, 4.0]), ZERO, CommandFrame.EE, 0.0))
    controller.reject_force("force_setpoint force must be 3 finite numbers, got [nan, 0, 0]")
    out = _one_step(controller, wrench=[0.0, 0.0, 4.0])
    assert out.state is ForceControlState.INVALID_COMMAND
    assert "nan" in out.detail
    assert out.force_desired == pytest.approx(4.0)
    controller.reject_twist("bad twist")
    out = _one_step(controller, t=1e-3, wrench=[0.0, 0.0, 4.0])
    assert out.state is ForceControlState.INVALID_COMMAND
    assert "bad twist" in out.detail


def test_constrained_components_are_ignored_and_reported():
    """The default normal is the EE z axis at activation: a twist along it (EE frame) is removed
    and reported; the tangential part passes; a too-fast tangential twist is scaled to the limit
    as a whole vector."""
    controller = ForceTeleopController(LWR, ForceControlSettings())
    rotation = FixedBaseState.compute(LWR, START, np.zeros(7)).ee_rotation
    controller.set_twist(TwistCommand(np.array([0.0, 0.1, 0.3]), ZERO, CommandFrame.EE, 0, 0.0))
    out = _one_step(controller)
    assert "ignored 0.3 m/s" in out.detail
    v_des = controller._v_des[:3]
    np.testing.assert_allclose(rotation.T @ v_des, [0.0, 0.005, 0.0], atol=1e-12)  # 5 m/s^2 ramp
    assert np.linalg.norm(out.normal - rotation[:, 2]) < 1e-12
    fast = ForceTeleopController(LWR, ForceControlSettings(max_linear_acceleration=1e3))
    fast.set_twist(TwistCommand(np.array([3.0, 4.0, 0.0]), ZERO, CommandFrame.EE, 0, 0.0))
    out = _one_step(fast)
    assert out.state is ForceControlState.SPEED_LIMITED
    assert "5 m/s scaled to 0.5" in out.detail
    np.testing.assert_allclose(rotation.T @ fast._v_des[:3], [0.3, 0.4, 0.0], atol=1e-12)


def test_force_setpoint_projection_and_clipping():
    controller = ForceTeleopController(LWR, ForceControlSettings(max_force_setpoint=30.0))
    rotation = FixedBaseState.compute(LWR, START, np.zeros(7)).ee_rotation
    world = rotation @ np.array([2.0, 0.0, 12.0])  # 12 N along the normal, 2 N off it
    controller.set_force(ForceSetpoint(world, np.array([0.0, 0.0, 1.0]), CommandFrame.WORLD, 0.0))
    out = _one_step(controller, wrench=[0.0, 0.0, 12.0])
    assert out.force_desired == pytest.approx(12.0)
    assert "ignored 2 N" in out.detail
    assert "1 N m" in out.detail
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, 50.0]), ZERO, CommandFrame.EE, 0.0))
    out = _one_step(controller, t=1e-3, wrench=[0.0, 0.0, 12.0])
    assert out.force_desired == 30.0
    assert "clipped to [0, 30] N" in out.detail
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, -5.0]), ZERO, CommandFrame.EE, 0.0))
    assert _one_step(controller, t=2e-3, wrench=[0.0, 0.0, 12.0]).force_desired == 0.0
    # a stale setpoint holds the last f_des (WARN)
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, 7.0]), ZERO, CommandFrame.EE, 0.0))
    _one_step(controller, t=3e-3, wrench=[0.0, 0.0, 7.0])
    controller.add_wrench(WrenchSample(_ns(1.0), np.array([0.0, 0.0, 7.0]), ZERO))
    out = controller.step(JointMeasurement(_ns(1.0), START, np.zeros(7)), 1.0)
    assert out.state is ForceControlState.FORCE_SETPOINT_STALE
    assert out.force_desired == pytest.approx(7.0)


def test_stale_twist_decelerates_then_holds():
    settings = ForceControlSettings(max_linear_acceleration=1.0, command_timeout=0.05)
    controller = ForceTeleopController(LWR, settings)
    twist = TwistCommand(np.array([0.1, 0.0, 0.0]), ZERO, CommandFrame.EE, 0, 0.0)
    speeds = []
    for i in range(400):
        t = i * 1e-3
        if t < 0.2:
            controller.set_twist(twist._replace(received=t))
        out = _one_step(controller, t=t)
        speeds.append(np.linalg.norm(controller._v_des[:3]))
    speeds = np.array(speeds)
    assert np.abs(np.diff(speeds)).max() <= 1e-3 * 1.0 + 1e-12  # no jump, 1 m/s^2
    assert speeds[199] == pytest.approx(0.1)
    assert speeds[-1] == 0.0
    assert out.state is ForceControlState.HOLDING


def test_settings_errors_name_the_value():
    with pytest.raises(ConfigError, match="task_axes must be distinct names"):
        ForceControlSettings(task_axes=("x", "q"))
    with pytest.raises(ConfigError, match="no linear axis"):
        ForceControlSettings(task_axes=("wx", "wy", "wz"))
    with pytest.raises(ConfigError, match="method must be one of"):
        ForceControlSettings(method="pid")
    with pytest.raises(ConfigError, match="not task_axes"):
        ForceControlSettings(task_axes=("x", "y"), constrained_frame="world")
    with pytest.raises(ConfigError, match="exceed the 3 joints"):
        ForceTeleopController(PLANAR, ForceControlSettings())


def test_error_sample_layout():
    controller = ForceTeleopController(LWR, ForceControlSettings())
    out = _one_step(controller, t=0.25)
    sample = out.error_sample()
    assert sample.shape == (len(ERROR_LABELS),)
    assert np.isfinite(sample).all()
    assert sample[0] == pytest.approx(0.25)
    np.testing.assert_allclose(sample[10:13], out.normal)
