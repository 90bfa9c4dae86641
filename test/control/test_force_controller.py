"""The force controller step (rns_ros.control.force.controller) without ROS.

The central check: the step function fed as DDS feeds it (each state with the wrench measured
under the torque held over the previous step, the twist sampled from the scenario reference)
reproduces the in-process reference loop ``run_closed_loop`` of thesis chapter 6.
"""

from __future__ import annotations

import numpy as np
import pytest
from force_cases import LWR, START, ZERO, ns, one_step

from rns_ros.analysis.motion_force_runs import QUICK_PERIOD, run_closed_loop
from rns_ros.control.contact_tasks import ArcScenario, WallScenario
from rns_ros.control.force.commands import (
    ForceSetpoint,
    JointMeasurement,
    TwistCommand,
    WrenchSample,
)
from rns_ros.control.force.controller import ForceTeleopController
from rns_ros.control.force.settings import CommandFrame, ForceControlSettings
from rns_ros.control.force.status import ForceControlState
from rns_ros.core.fixed_base import FixedBaseState
from rns_ros.sim.contact import ContactSimulator


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
                    setup.reference(sampled).velocity, ZERO, CommandFrame.WORLD, ns(sampled), t
                )
            )
            normal = sim.contact_normal()
            controller.set_force(
                ForceSetpoint(setup.force(sampled) * normal, ZERO, CommandFrame.WORLD, t)
            )
        wrench = sim.wrist_wrench()  # under the torque held over the previous step
        if not drop_wrench_every or i % drop_wrench_every:
            controller.add_wrench(WrenchSample(ns(t), wrench[:3], wrench[3:]))
        out = controller.step(JointMeasurement(ns(t), sim.q, sim.v, sim.torque.copy()), t)
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
@pytest.mark.slow
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


@pytest.mark.slow
def test_late_twists_keep_their_acceleration_feed_forward():
    """Twists every 2 ms reaching the controller one 1 ms step after their stamp (what the
    operator's sim-time timer and DDS give): the first-order hold extrapolates each over up to
    two of its periods, so the feed-forward never drops out. Measured 0.028 mm on one stroke
    (0.020 mm with on-time twists); holding for one period only gave 1.3 mm."""
    settings = ForceControlSettings(nominal_period=1e-3)
    *_, position_error = _dds_loop(WallScenario(strokes=1), settings, 1e-3, twist_every=2, late=1)
    assert position_error.max() < 1e-4


@pytest.mark.parametrize(("method", "label"), [("rns", "RNS-C"), ("os", "OS-C")])
@pytest.mark.slow
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


def test_rejected_inputs_keep_the_previous_setpoint_and_hold():
    controller = ForceTeleopController(LWR, ForceControlSettings())
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, 4.0]), ZERO, CommandFrame.EE, 0.0))
    controller.reject_force("force_setpoint force must be 3 finite numbers, got [nan, 0, 0]")
    out = one_step(controller, wrench=[0.0, 0.0, 4.0])
    assert out.state is ForceControlState.INVALID_COMMAND
    assert "nan" in out.detail
    assert out.force_desired == pytest.approx(4.0)
    controller.reject_twist("bad twist")
    out = one_step(controller, t=1e-3, wrench=[0.0, 0.0, 4.0])
    assert out.state is ForceControlState.INVALID_COMMAND
    assert "bad twist" in out.detail


def test_constrained_components_are_ignored_and_reported():
    """The default normal is the EE z axis at activation: a twist along it (EE frame) is removed
    and reported; the tangential part passes; a too-fast tangential twist is scaled to the limit
    as a whole vector."""
    controller = ForceTeleopController(LWR, ForceControlSettings())
    rotation = FixedBaseState.compute(LWR, START, np.zeros(7)).ee_rotation
    controller.set_twist(TwistCommand(np.array([0.0, 0.1, 0.3]), ZERO, CommandFrame.EE, 0, 0.0))
    out = one_step(controller)
    assert "ignored 0.3 m/s" in out.detail
    v_des = controller._v_des[:3]
    np.testing.assert_allclose(rotation.T @ v_des, [0.0, 0.005, 0.0], atol=1e-12)  # 5 m/s^2 ramp
    assert np.linalg.norm(out.normal - rotation[:, 2]) < 1e-12
    fast = ForceTeleopController(LWR, ForceControlSettings(max_linear_acceleration=1e3))
    fast.set_twist(TwistCommand(np.array([3.0, 4.0, 0.0]), ZERO, CommandFrame.EE, 0, 0.0))
    out = one_step(fast)
    assert out.state is ForceControlState.SPEED_LIMITED
    assert "5 m/s scaled to 0.5" in out.detail
    np.testing.assert_allclose(rotation.T @ fast._v_des[:3], [0.3, 0.4, 0.0], atol=1e-12)


def test_force_setpoint_projection_and_clipping():
    controller = ForceTeleopController(LWR, ForceControlSettings(max_force_setpoint=30.0))
    rotation = FixedBaseState.compute(LWR, START, np.zeros(7)).ee_rotation
    world = rotation @ np.array([2.0, 0.0, 12.0])  # 12 N along the normal, 2 N off it
    controller.set_force(ForceSetpoint(world, np.array([0.0, 0.0, 1.0]), CommandFrame.WORLD, 0.0))
    out = one_step(controller, wrench=[0.0, 0.0, 12.0])
    assert out.force_desired == pytest.approx(12.0)
    assert "ignored 2 N" in out.detail
    assert "1 N m" in out.detail
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, 50.0]), ZERO, CommandFrame.EE, 0.0))
    out = one_step(controller, t=1e-3, wrench=[0.0, 0.0, 12.0])
    assert out.force_desired == 30.0
    assert "clipped to [0, 30] N" in out.detail
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, -5.0]), ZERO, CommandFrame.EE, 0.0))
    assert one_step(controller, t=2e-3, wrench=[0.0, 0.0, 12.0]).force_desired == 0.0
    # a stale setpoint holds the last f_des (WARN)
    controller.set_force(ForceSetpoint(np.array([0.0, 0.0, 7.0]), ZERO, CommandFrame.EE, 0.0))
    one_step(controller, t=3e-3, wrench=[0.0, 0.0, 7.0])
    controller.add_wrench(WrenchSample(ns(1.0), np.array([0.0, 0.0, 7.0]), ZERO))
    out = controller.step(JointMeasurement(ns(1.0), START, np.zeros(7)), 1.0)
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
        out = one_step(controller, t=t)
        speeds.append(np.linalg.norm(controller._v_des[:3]))
    speeds = np.array(speeds)
    assert np.abs(np.diff(speeds)).max() <= 1e-3 * 1.0 + 1e-12  # no jump, 1 m/s^2
    assert speeds[199] == pytest.approx(0.1)
    assert speeds[-1] == 0.0
    assert out.state is ForceControlState.HOLDING
