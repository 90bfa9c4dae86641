"""The free fixed-base arm (environment none) and the joint brake: physics checks.

Energy: with the torque held over each RK4 step the work W = sum tau . (q_{k+1} - q_k) is exact,
so KE + PE - W is constant up to the RK4 error (relative 1e-9 over the runs below); with zero
torque and gravity on, KE + PE is conserved.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rns_ros.core import ConfigError, InputError
from rns_ros.core.errors import SimulationDivergedError
from rns_ros.core.fixed_base import FixedBaseState, load_fixed_base_model
from rns_ros.sim.free_arm import FreeArmSimulator, JointBrake

CONFIG = Path(__file__).resolve().parents[2] / "config"
LWR_START = np.radians([20, -20, 0, 100, 0, 10, 0])
PLANAR_START = np.radians([106.4, -45.7, -56.2])


def _robot(name: str, gravity: bool = False):
    return load_fixed_base_model(CONFIG / f"{name}.yaml", gravity=gravity)


def _torque(robot, q0, t: float) -> np.ndarray:
    """Smooth torques [N m] scaled by the start inertias (joint accelerations ~1 rad/s^2)."""
    k = np.arange(1, robot.n + 1)
    inertia = np.diag(FixedBaseState.compute(robot, q0, np.zeros(robot.n)).mass_matrix)
    return inertia * np.sin(2.0 * t * k)


@pytest.mark.parametrize(
    ("name", "start"), [("lwr_7dof", LWR_START), ("planar_3dof", PLANAR_START)]
)
def test_kinetic_energy_change_equals_the_work_of_the_torque(name, start):
    robot = _robot(name)
    sim = FreeArmSimulator(robot, initial_q=start, dt=1e-3)
    for _ in range(1000):
        sim.set_torque(_torque(robot, start, sim.time))
        sim.step()
    ke = sim.kinetic_energy()
    assert ke > 1e-3  # the torque did move the arm
    assert sim.potential_energy() == 0.0
    assert abs(ke - sim.work) <= 1e-9 * ke
    assert np.abs(sim.v).max() > 0.05


def test_gravity_without_torque_conserves_kinetic_plus_potential_energy():
    robot = _robot("lwr_7dof", gravity=True)
    sim = FreeArmSimulator(robot, initial_q=LWR_START, dt=1e-3)
    start = sim.kinetic_energy() + sim.potential_energy()
    for _ in range(300):  # 0.3 s: the light wrist reaches ~7 rad/s (later tens of rad/s)
        sim.step()
    ke = sim.kinetic_energy()
    assert ke > 1.0  # it fell
    assert sim.work == 0.0
    total = ke + sim.potential_energy()
    assert abs(total - start) <= 1e-9 * ke


def test_acceleration_solves_the_equation_of_motion_and_the_interface_is_contact_free():
    robot = _robot("lwr_7dof", gravity=True)
    sim = FreeArmSimulator(robot, initial_q=LWR_START, initial_v=np.full(7, 0.1), dt=1e-3)
    tau = np.linspace(-3.0, 3.0, 7)
    sim.set_torque(tau)
    state = FixedBaseState.compute(robot, sim.q, sim.v)
    lhs = state.mass_matrix @ sim.acceleration + state.coriolis + state.gravity
    assert np.allclose(lhs, tau, atol=1e-10)
    assert sim.contact_force == 0.0
    assert not sim.wrist_wrench().any()
    assert not sim.contact_wrench().any()
    assert sim.constraint_error() == (0.0, 0.0)
    assert np.allclose(sim.ee_position(), state.ee_position)
    snap = sim.snapshot()
    assert snap.contact_force == 0.0
    assert np.array_equal(snap.torque, tau)
    sim.step()
    sim.reset()
    assert sim.time == 0.0
    assert not sim.torque.any()
    assert np.array_equal(sim.q, LWR_START)


def test_torque_clipping_and_bad_inputs():
    robot = _robot("lwr_7dof")
    sim = FreeArmSimulator(robot, initial_q=LWR_START, clip_torque=True)
    sim.set_torque(np.full(7, 1e4))
    assert np.array_equal(sim.torque, robot.effort_limits)
    assert sim.torque_clipped.all()
    with pytest.raises(InputError):
        sim.set_torque([1.0, np.nan, 0, 0, 0, 0, 0])
    with pytest.raises(InputError):
        sim.set_torque([1.0, 2.0])
    with pytest.raises(ConfigError, match="dt must be"):
        FreeArmSimulator(robot, initial_q=LWR_START, dt=0.5)


def test_a_diverged_step_keeps_the_last_finite_state():
    robot = _robot("planar_3dof")
    sim = FreeArmSimulator(robot, initial_q=PLANAR_START)
    sim.step()
    q, t = sim.q.copy(), sim.time
    sim._acceleration = lambda q, v: np.full(3, np.nan)
    with pytest.raises(SimulationDivergedError, match="non-finite"):
        sim.step()
    assert np.array_equal(sim.q, q)
    assert sim.time == t


@pytest.mark.parametrize("damping", [5.0, 20.0, 1000.0])
def test_the_brake_stops_the_arm_stably_for_any_damping(damping):
    """Explicit damping d q_dot held over a 1 ms step diverges on the LWR's light wrist for
    d > ~1 N m s/rad; the implicit brake (F.2) stops every joint, gravity held."""
    robot = _robot("lwr_7dof", gravity=True)
    sim = FreeArmSimulator(robot, initial_q=LWR_START, initial_v=np.full(7, 0.5), dt=1e-3)
    brake = JointBrake(robot, damping, sim.dt)
    assert 0.0 < brake.contraction(sim.q) < 1.0
    speeds = []
    for _ in range(3000):
        sim.set_torque(brake.torque(sim.q, sim.v))
        sim.step()
        speeds.append(np.abs(sim.v).max())
    assert np.all(np.isfinite(speeds))
    assert max(speeds) < 0.6  # no overshoot blow-up
    assert speeds[-1] < 1e-3  # stopped (3 s; the slowest mode decays with m / d)
    gain = brake.gain(sim.q)
    assert np.allclose(gain, gain.T)
    assert np.linalg.eigvalsh(gain).min() > 0.0


def test_explicit_damping_of_the_same_size_would_diverge():
    """The reason for (F.2): tau = -d q_dot_k held over the step, d = 20 N m s/rad, 1 ms."""
    robot = _robot("lwr_7dof")
    sim = FreeArmSimulator(robot, initial_q=LWR_START, initial_v=np.full(7, 0.5), dt=1e-3)
    for _ in range(3):
        sim.set_torque(-20.0 * sim.v)
        sim.step()
    assert np.abs(sim.v).max() > 1e4  # from 0.5 rad/s (non-finite two steps later)
