"""Contact simulation of Part II: physics checks of the constrained fixed-base dynamics.

Scenario of the long runs (one per model, 10 s at dt = 1 ms): the thesis starts (planar arm on
the cylinder of radius 0.707 m at (1.91, 1.91) m, thesis_rest A-4.8; LWR against a wall through
its flange normal to the flange z axis, section 6.2.2), driven by a smooth torque: inertia-scaled
sinusoids, a weak joint spring-damper about the start, and a normal push rising to 10 N over 1 s
(quintic, like the thesis force reference). Peak joint speeds stay within the URDF limits.

Tolerances (measured values in docs/part2.md): |phi| < 1e-9 m, |phi_dot| < 1e-8 m/s over 10 s;
the energy balance KE + PE - W = const to 1e-8 J against the exactly held-torque work, and to 1e-5
J against the trapezoidal integral of tau . q_dot.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.core import ConfigError, InputError
from rns_ros.core.contact_geometry import ArcConstraint, PlaneConstraint, project_onto_constraint
from rns_ros.core.errors import SimulationDivergedError
from rns_ros.core.fixed_base import FixedBaseState, load_fixed_base_model
from rns_ros.sim.contact import Baumgarte, ContactSimulator

CONFIG = Path(__file__).resolve().parents[2] / "config"
PLANAR_START = np.radians([106.4, -45.7, -56.2])  # thesis_rest, about 1 mm off the arc
LWR_START = np.radians([20, -20, 0, 100, 0, 10, 0])
CENTER, RADIUS = np.array([1.91, 1.91, 0.0]), 0.707
PUSH = 10.0  # N, the thesis force reference
DURATION = 10.0  # s


def _setup(name: str, gravity: bool = False):
    """(robot, constraint, start q exactly on the constraint)."""
    if name == "planar":
        robot = load_fixed_base_model(CONFIG / "planar_3dof.yaml", gravity=gravity)
        constraint = ArcConstraint(CENTER, RADIUS)
        start = PLANAR_START
    else:
        robot = load_fixed_base_model(CONFIG / "lwr_7dof.yaml", gravity=gravity)
        state = FixedBaseState.compute(robot, LWR_START, np.zeros(7))
        constraint = PlaneConstraint(state.ee_position, state.ee_rotation[:, 2])
        start = LWR_START
    q0, _ = project_onto_constraint(robot, constraint, start, tolerance=1e-14)
    return robot, constraint, q0


def _quintic(t: float, duration: float = 1.0) -> float:
    s = min(max(t / duration, 0.0), 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def _smooth_torque(robot, q0, seed: int = 0):
    """tau(t, sim) [N m]: inertia-scaled sinusoids + a weak spring-damper to q0 + a normal push
    (quintic to PUSH over 1 s) + gravity compensation when gravity is on."""
    rng = np.random.default_rng(seed)
    amplitude = rng.uniform(0.3, 1.0, robot.n)  # rad/s^2
    frequency = rng.uniform(0.5, 2.0, robot.n)  # rad/s
    inertia = FixedBaseState.compute(robot, q0, np.zeros(robot.n)).mass_matrix
    data = robot.model.createData()

    def torque(t: float, sim: ContactSimulator) -> np.ndarray:
        acceleration = amplitude * np.sin(frequency * t) + 4.0 * (q0 - sim.q) - 2.0 * sim.v
        tau = inertia @ acceleration + sim.constraint_jacobian() * PUSH * _quintic(t)
        if robot.gravity:
            tau = tau + pin.computeGeneralizedGravity(robot.model, data, sim.q)
        return tau

    return torque


def _run(name: str, duration: float, gravity: bool = False) -> dict:
    """Simulate and record per step: phi, phi_dot, energy balance, trapezoidal power integral."""
    robot, constraint, q0 = _setup(name, gravity)
    sim = ContactSimulator(robot, constraint, initial_q=q0)
    torque = _smooth_torque(robot, q0)
    energy0 = sim.kinetic_energy() + sim.potential_energy()
    p0 = sim.ee_position()
    record = {"phi": [], "phi_dot": [], "balance": [], "trapezoid": [], "force": []}
    record.update(travel=0.0, speed=0.0, speed_ratio=0.0, potential=[])
    trapezoid = 0.0
    for _ in range(round(duration / sim.dt)):
        sim.set_torque(torque(sim.time, sim))
        before = sim.power()
        sim.step()
        trapezoid += 0.5 * sim.dt * (before + sim.power())  # tau held: tau . (v_k + v_k+1) / 2
        phi, phi_dot = sim.constraint_error()
        record["phi"].append(phi)
        record["phi_dot"].append(phi_dot)
        record["force"].append(sim.contact_force)
        if len(record["phi"]) % 10 == 0:
            energy = sim.kinetic_energy() + sim.potential_energy() - energy0
            record["balance"].append(energy - sim.work)
            record["trapezoid"].append(energy - trapezoid)
            record["potential"].append(sim.potential_energy())
            record["travel"] = max(record["travel"], float(np.linalg.norm(sim.ee_position() - p0)))
            record["speed"] = max(record["speed"], float(np.max(np.abs(sim.v))))
            ratio = float(np.max(np.abs(sim.v) / robot.velocity_limits))
            record["speed_ratio"] = max(record["speed_ratio"], ratio)
    record["sim"] = sim
    return {
        key: np.array(value) if isinstance(value, list) else value for key, value in record.items()
    }


@pytest.fixture(scope="module", params=["planar", "lwr"])
def long_run(request) -> dict:
    return _run(request.param, DURATION)


def test_constraint_holds_over_10_s_of_motion(long_run):
    assert long_run["sim"].time == pytest.approx(DURATION)
    assert long_run["travel"] > 0.1  # m: the end effector really slides along the surface
    sim = long_run["sim"]
    assert long_run["speed"] > 0.2  # rad/s: the joints really move
    assert long_run["speed_ratio"] < 1.0  # and stay within their URDF velocity limits
    assert np.max(np.abs(long_run["phi"])) < 1e-9
    assert np.max(np.abs(long_run["phi_dot"])) < 1e-8
    # the bilateral constraint also pulls when the sinusoids outweigh the push: counted
    assert sim.pulling_steps == np.count_nonzero(long_run["force"] < 0.0)
    assert np.max(long_run["force"]) > 0.0


def test_energy_balance_without_gravity(long_run):
    """dKE = integral of tau . q_dot: the scleronomic constraint does no work."""
    assert np.max(np.abs(long_run["balance"])) < 1e-8  # J, work = sum tau_k . (q_k+1 - q_k)
    assert np.max(np.abs(long_run["trapezoid"])) < 1e-5  # J, trapezoidal power integral
    assert np.all(long_run["potential"] == 0.0)


def test_energy_balance_with_gravity_includes_the_potential():
    run = _run("lwr", 2.0, gravity=True)
    assert np.ptp(run["potential"]) > 0.05  # J: the arm moves in the gravity field
    assert np.max(np.abs(run["balance"])) < 1e-8
    assert np.max(np.abs(run["phi"])) < 1e-9


@pytest.mark.parametrize("name", ["planar", "lwr"])
def test_static_push_gives_the_pushed_force_and_no_motion(name):
    robot, constraint, q0 = _setup(name)
    sim = ContactSimulator(robot, constraint, initial_q=q0)
    state = FixedBaseState.compute(robot, q0, np.zeros(robot.n))
    normal = constraint.gradient(state.ee_position)
    J_c = normal @ state.jacobian[:3]
    sim.set_torque(J_c * 7.5)  # tau = J_c^T f, f = 7.5 N into the environment
    # lambda = f + K_p phi / (J_c M^-1 J_c^T): the projected start has |phi| ~ 1e-12 m
    assert sim.contact_force == pytest.approx(7.5, abs=1e-7)
    np.testing.assert_allclose(sim.acceleration, 0.0, atol=1e-9)
    for _ in range(200):
        sim.step()
    np.testing.assert_allclose(sim.q, q0, atol=1e-12)
    np.testing.assert_allclose(sim.v, 0.0, atol=1e-10)
    assert sim.contact_force == pytest.approx(7.5, abs=1e-7)
    assert not sim.pulling
    assert sim.pulling_steps == 0
    np.testing.assert_allclose(sim.contact_wrench()[:3], 7.5 * normal, atol=1e-9)

    sim.set_torque(J_c * -2.0)  # pulling: the bilateral constraint holds, and says so
    sim.step()
    sim.step()
    assert sim.contact_force == pytest.approx(-2.0, abs=1e-7)
    assert sim.pulling
    assert sim.pulling_steps == 2
    snapshot = sim.snapshot()
    assert snapshot.time == pytest.approx(0.202)
    assert snapshot.contact_force == sim.contact_force
    np.testing.assert_array_equal(snapshot.torque, J_c * -2.0)
    sim.reset()
    assert (sim.time, sim.work, sim.pulling, sim.pulling_steps) == (0.0, 0.0, False, 0)
    np.testing.assert_array_equal(sim.q, q0)


@pytest.mark.parametrize("name", ["planar", "lwr"])
def test_multiplier_satisfies_the_equation_of_motion(name):
    """At random states on the surface and random torques, recompute (C.1)-(C.2) independently:
    RNEA(q, v, q_ddot) = tau - J_c^T lambda and n . a_ee + kappa = -K_v phi_dot - K_p phi."""
    robot, constraint, q0 = _setup(name)
    rng = np.random.default_rng(4)
    data = robot.model.createData()
    for _ in range(5):
        q, v = project_onto_constraint(
            robot, constraint, q0 + rng.normal(0.0, 0.1, robot.n), rng.normal(0.0, 0.5, robot.n)
        )
        tau = rng.normal(0.0, 20.0, robot.n)
        sim = ContactSimulator(robot, constraint, initial_q=q, initial_v=v)
        sim.set_torque(tau)
        q_ddot, force = sim.acceleration, sim.contact_force
        state = FixedBaseState.compute(robot, q, v)
        normal = constraint.gradient(state.ee_position)
        J_c = normal @ state.jacobian[:3]
        np.testing.assert_allclose(
            pin.rnea(robot.model, data, q, v, q_ddot), tau - J_c * force, atol=1e-9
        )
        np.testing.assert_allclose(state.jacobian.T @ sim.contact_wrench(), J_c * force, atol=1e-9)
        ee_acceleration = state.jacobian[:3] @ q_ddot + state.jacobian_dot_v[:3]
        p_dot = state.jacobian[:3] @ v
        phi_ddot = normal @ ee_acceleration + constraint.curvature(state.ee_position, p_dot)
        phi, phi_dot = sim.constraint_error()
        assert phi_ddot == pytest.approx(-100.0 * phi_dot - 2500.0 * phi, abs=1e-9)


def test_wrist_wrench_is_the_contact_force_in_ee_axes():
    robot, constraint, q0 = _setup("lwr")
    sim = ContactSimulator(robot, constraint, initial_q=q0)
    sim.set_torque(sim.constraint_jacobian() * 4.0)
    state = FixedBaseState.compute(robot, q0, np.zeros(7))
    wrench = sim.wrist_wrench()
    np.testing.assert_allclose(
        wrench[:3], state.ee_rotation.T @ (4.0 * constraint.normal), atol=1e-12
    )
    np.testing.assert_allclose(wrench[:3], [0.0, 0.0, 4.0], atol=1e-9)  # the wall is EE z
    np.testing.assert_allclose(wrench[3:], 0.0, atol=1e-12)


def test_baumgarte_pulls_a_start_offset_back_critically_damped():
    """Start 0.1 mm off the arc: phi(t) = phi0 (1 + w t) exp(-w t), w = 50 rad/s; without
    stabilization the offset stays."""
    robot = load_fixed_base_model(CONFIG / "planar_3dof.yaml")
    arc = ArcConstraint(CENTER, RADIUS)
    q_off, _ = project_onto_constraint(robot, ArcConstraint(CENTER, RADIUS + 1e-4), PLANAR_START)
    sim = ContactSimulator(robot, arc, initial_q=q_off, tolerance=1e-3)
    phi0 = sim.constraint_error()[0]
    assert phi0 == pytest.approx(-1e-4)
    for _ in range(200):
        sim.step()
        phi = sim.constraint_error()[0]
        w_t = 50.0 * sim.time
        assert phi == pytest.approx(phi0 * (1.0 + w_t) * math.exp(-w_t), abs=1e-10)
    free = ContactSimulator(robot, arc, initial_q=q_off, tolerance=1e-3, stabilization=None)
    for _ in range(200):
        free.step()
    assert free.constraint_error() == pytest.approx((phi0, 0.0), abs=1e-12)


def test_bad_parameters_fail_with_typed_errors():
    with pytest.raises(ConfigError, match="velocity_gain must be finite and >= 0 1/s"):
        Baumgarte(velocity_gain=-1.0)

    robot, arc, q0 = _setup("planar")
    with pytest.raises(ConfigError, match="dt must be"):
        ContactSimulator(robot, arc, initial_q=q0, dt=0.0)
    with pytest.raises(ConfigError, match="too stiff for dt"):
        ContactSimulator(robot, arc, initial_q=q0, stabilization=Baumgarte.critically_damped(5e3))
    with pytest.raises(ConfigError, match=r"0\.000958 m off the surface \(inside"):
        ContactSimulator(robot, arc, initial_q=PLANAR_START)  # the rounded thesis start
    with pytest.raises(ConfigError, match="along the contact normal"):
        ContactSimulator(robot, arc, initial_q=q0, initial_v=[1.0, 0.0, 0.0])
    with pytest.raises(ConfigError, match="ArcConstraint or PlaneConstraint"):
        ContactSimulator(robot, "wall", initial_q=q0)
    sim = ContactSimulator(robot, arc, initial_q=q0)
    with pytest.raises(InputError, match=r"tau must have shape \(3,\)"):
        sim.set_torque([1.0, 2.0])
    with pytest.raises(InputError, match="tau must be finite"):
        sim.set_torque([1.0, math.inf, 0.0])
    clipped = ContactSimulator(robot, arc, initial_q=q0, clip_torque=True)
    clipped.set_torque([5e3, -5e3, 10.0])
    np.testing.assert_array_equal(clipped.torque, [1000.0, -1000.0, 10.0])  # URDF effort
    np.testing.assert_array_equal(clipped.torque_clipped, [True, True, False])


def test_divergence_keeps_the_last_state():
    robot, arc, q0 = _setup("planar")
    sim = ContactSimulator(robot, arc, initial_q=q0)
    sim.set_torque([1.0, -1.0, 0.5])
    for _ in range(3):
        sim.step()
    before = (sim.time, sim.q.copy(), sim.v.copy(), sim.work)
    sim.set_torque([1e300, -1e300, 1e300])
    with pytest.raises(SimulationDivergedError, match=r"t = 0\.003 s.*kept the last finite"):
        sim.step()
    assert sim.time == before[0]
    assert sim.work == before[3]
    np.testing.assert_array_equal(sim.q, before[1])
    np.testing.assert_array_equal(sim.v, before[2])
    sim.set_torque(np.zeros(3))
    sim.step()  # still usable
    assert math.isfinite(sim.contact_force)


def test_a_constraint_the_arm_cannot_act_on_is_reported_singular():
    """A floor under the planar arm (normal +z): J_c = 0, J_c M^-1 J_c^T = 0, no force defined."""
    robot, _, q0 = _setup("planar")
    floor = PlaneConstraint(robot.frame_position(q0, "ee"), [0.0, 0.0, 1.0])
    sim = ContactSimulator(robot, floor, initial_q=q0)
    np.testing.assert_array_equal(sim.constraint_jacobian(), 0.0)
    with pytest.raises(SimulationDivergedError, match="singular constraint"):
        sim.step()
    assert sim.time == 0.0
