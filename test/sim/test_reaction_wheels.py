"""Reaction wheels in the free-floating simulator: momentum exchange, energy, limits.

The wheels are a gyrostat (rns_ros.sim.reaction_wheels): their spin momentum H joins the rigid
system's. Tested against conservation laws and the work-energy identity, not against our output.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from rns_testing import SATELLITE_OBSERVATION_DEG

from rns_ros.core import ConfigError, InputError, ModelError
from rns_ros.core.integration import attitude_deviation
from rns_ros.sim.free_floating import FreeFloatingSimulator
from rns_ros.sim.reaction_wheels import ReactionWheels, limit_wheel_torque, spin_reduced_model

THETA_0 = np.deg2rad(SATELLITE_OBSERVATION_DEG)
WHEELS = ReactionWheels(inertia=0.11, torque_limit=0.1)


def _simulator(robot, mode="kinematic", **kwargs):
    q0 = robot.configuration(THETA_0, [0.5, -0.2, 0.1], [0.1, -0.2, 0.05, 0.97])
    return FreeFloatingSimulator(robot, mode=mode, initial_q=q0, wheels=WHEELS, **kwargs)


def _rotation(q):
    return pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()


def _kinetic_energy(robot, q, v, wheel_speeds) -> float:
    """Physical kinetic energy: the locked system (the URDF model, wheels in the base) plus the
    wheels' relative spin, eq. (5.1) with M~_r = M~_omega_r = I_r E."""
    data = robot.model.createData()
    locked = pin.computeKineticEnergy(robot.model, data, q, v)
    omega = v[3:6]
    return (
        locked
        + 0.5 * WHEELS.inertia * wheel_speeds @ wheel_speeds
        + (WHEELS.inertia * wheel_speeds @ omega)
    )


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_wheel_torque_turns_the_base_and_keeps_the_total_momentum(robot, mode):
    """A still arm, 0.1 N m on the z wheel for 2 s: the wheel gains 0.2 N m s, the base turns the
    other way, and base + arm + wheels keep their (zero) momentum."""
    simulator = _simulator(robot, mode)
    rotation_0 = _rotation(simulator.q)
    simulator.set_wheel_torque([0.0, 0.0, 0.1])
    for _ in range(2000):
        simulator.set_reference(velocities=np.zeros(robot.n))
        simulator.step()
    assert simulator.wheel_momentum == pytest.approx([0.0, 0.0, 0.2], abs=1e-12)
    assert np.abs(simulator.centroidal_momentum()).max() < 1e-12
    # the base's angular momentum is -R_b H: it turns about -z of the base
    omega_world = _rotation(simulator.q) @ simulator.v[3:6]
    assert (_rotation(simulator.q) @ [0, 0, 1]) @ omega_world < 0.0
    assert attitude_deviation(rotation_0, _rotation(simulator.q)) > 1e-6
    assert simulator.wheel_speeds[2] > 1.0  # rad/s, relative to the base
    assert not simulator.wheel_saturated.any()


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_momentum_is_conserved_with_spinning_wheels_and_a_moving_arm(robot, mode):
    """Wheels spun up on all axes, then the arm moves while the wheels keep spinning: the base
    rotates with spinning rotors (gyroscopic coupling), and the total momentum stays put."""
    simulator = _simulator(robot, mode)
    simulator.set_wheel_torque([0.1, -0.07, 0.05])
    for _ in range(1000):
        simulator.step()
    simulator.set_wheel_torque([-0.03, 0.02, 0.1])
    initial = simulator.centroidal_momentum()
    for k in range(3000):
        t = k * simulator.dt
        rates = 0.3 * np.sin(np.arange(1, robot.n + 1) * 0.7 * t + 0.3)
        simulator.set_reference(velocities=rates, positions=simulator.q[7:] + 0.0)
        simulator.step()
    drift = np.abs(simulator.centroidal_momentum() - initial).max()
    assert np.abs(simulator.v[6:]).max() > 0.1
    assert drift < 1e-9, drift


def test_motor_work_equals_the_kinetic_energy_gained(robot):
    """Kinematic mode, arm still: the only power is the motors' tau . phi_dot; its integral equals
    the change of the kinetic energy of base + wheels (work-energy theorem)."""
    simulator = _simulator(robot)
    torque = np.array([0.1, -0.05, 0.08])
    simulator.set_wheel_torque(torque)
    energy_0 = _kinetic_energy(robot, simulator.q, simulator.v, simulator.wheel_speeds)
    work = 0.0
    for _ in range(3000):
        before = simulator.wheel_speeds
        simulator.step()
        work += simulator.dt * torque @ (0.5 * (before + simulator.wheel_speeds))
    energy = _kinetic_energy(robot, simulator.q, simulator.v, simulator.wheel_speeds)
    assert energy - energy_0 == pytest.approx(work, rel=1e-6)
    # and the reduced-model form: 1/2 v^T M' v + |H|^2 / (2 I_r)
    reduced = spin_reduced_model(robot.model, WHEELS)
    data = reduced.createData()
    split = pin.computeKineticEnergy(reduced, data, simulator.q, simulator.v) + (
        simulator.wheel_momentum @ simulator.wheel_momentum / (2 * WHEELS.inertia)
    )
    assert split == pytest.approx(energy, rel=1e-12)


def test_torque_limit_clips_and_reports(robot):
    simulator = _simulator(robot)
    simulator.set_wheel_torque([1.0, -0.05, -3.0])
    simulator.step()
    assert simulator.wheel_torque == pytest.approx([0.1, -0.05, -0.1])
    assert simulator.wheel_saturated.tolist() == [True, False, True]
    assert simulator.wheel_momentum == pytest.approx(1e-3 * np.array([0.1, -0.05, -0.1]))


def test_speed_limit_stops_the_spin_up():
    wheels = ReactionWheels(speed_limit=10.0)
    speeds = np.array([10.0, -10.5, 3.0])
    applied, limited = limit_wheel_torque([0.05, -0.05, 0.05], speeds, wheels)
    assert applied.tolist() == [0.0, 0.0, 0.05]
    assert limited.tolist() == [True, True, False]
    applied, limited = limit_wheel_torque([-0.05, 0.05, 0.0], speeds, wheels)  # braking is fine
    assert applied.tolist() == [-0.05, 0.05, 0.0]
    assert not limited.any()


def test_no_wheels_means_no_wheel_commands(robot):
    simulator = FreeFloatingSimulator(robot)
    with pytest.raises(ConfigError, match="no reaction wheels"):
        simulator.set_wheel_torque([0.0, 0.0, 0.0])
    assert simulator.wheel_speeds.tolist() == [0.0, 0.0, 0.0]


def test_bad_wheel_parameters_and_commands_are_rejected(robot):
    with pytest.raises(ConfigError, match="torque_limit must be finite and > 0 N m"):
        ReactionWheels(torque_limit=-1.0)
    with pytest.raises(ConfigError, match="inertia"):
        ReactionWheels(inertia=math.nan)
    with pytest.raises(ModelError, match="must include the wheel assemblies"):
        spin_reduced_model(robot.model, ReactionWheels(inertia=5000.0))
    simulator = _simulator(robot)
    with pytest.raises(InputError, match="wheel torque"):
        simulator.set_wheel_torque([0.0, math.inf, 0.0])
