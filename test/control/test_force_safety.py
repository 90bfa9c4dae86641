"""Safety stops of the force controller (rns_ros.control.force.safety) in closed loop."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from force_cases import LWR, START, ZERO, ns

from rns_ros.control.contact_tasks import WallScenario
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
            controller.set_twist(TwistCommand(twist, ZERO, CommandFrame.WORLD, ns(t), t))
        controller.add_wrench(WrenchSample(ns(t), np.asarray(wrench, float), ZERO))
        out = controller.step(JointMeasurement(ns(t), q, v, tau.copy()), t)
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
            controller.add_wrench(WrenchSample(ns(t), wrench[:3], wrench[3:]))
        out = controller.step(JointMeasurement(ns(t), sim.q, sim.v, sim.torque.copy()), t)
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
        controller.add_wrench(WrenchSample(ns(i * 1e-3), force, ZERO))
        out = controller.step(JointMeasurement(ns(i * 1e-3), START, np.zeros(7)), i * 1e-3)
        if i < 10:
            assert out.contact == "in_contact"
    assert out.state is ForceControlState.CONTACT_LOST
    assert out.contact == "lost"
