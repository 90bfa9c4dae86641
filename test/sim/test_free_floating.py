"""Free-floating simulator core: conservation laws, reactionless invariance, RK4 order.

Tolerances follow the simulator issue: momentum drift < 1e-9 relative over 20 s of vigorous
motion at 1 ms in both modes; the CoM stays put with zero momentum; reactionless motion keeps the
base attitude to < 1e-6 deg over 20 s; halving dt divides the error by ~16. The vigorous
reference stays within the URDF velocity limits (its peak speeds are 60-91 % of them), so the
dynamic-mode servo runs unsaturated there, exactly as the plain computed-torque law; the limits
themselves are tested with steps far beyond them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from rns_testing import SATELLITE_OBSERVATION_DEG

from rns_ros.core import ConfigError, FreeFloatingState, InputError, load_model
from rns_ros.core.commands import VELOCITY_LIMIT_TOLERANCE
from rns_ros.core.errors import SimulationDivergedError
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.momentum import reactionless_joint_velocity
from rns_ros.sim.free_floating import FreeFloatingSimulator, ServoGains, SimulationMode

ARMS = Path(__file__).resolve().parents[1] / "data" / "arms"
THETA_0 = np.deg2rad(SATELLITE_OBSERVATION_DEG)
AMPLITUDE = np.array([0.6, -0.5, 0.5, 0.75, -0.8, 0.7, 1.1])  # rad
FREQUENCY = np.array([0.5, 0.7, 0.9, 0.6, 1.1, 1.3, 0.8])  # rad/s
MOMENTUM = np.array([0.1, -0.05, 0.02, 0.3, -0.2, 0.5])  # [kg m/s, kg m^2/s] about the CoM


def vigorous_reference(t: float):
    """Smooth rest-to-motion joint reference: positions, velocities, accelerations."""
    phase = FREQUENCY * t
    return (
        THETA_0 + AMPLITUDE * (1.0 - np.cos(phase)),
        AMPLITUDE * FREQUENCY * np.sin(phase),
        AMPLITUDE * FREQUENCY**2 * np.cos(phase),
    )


def _simulator(robot, mode, dt=1e-3, momentum=None, **kwargs):
    q0 = robot.configuration(THETA_0, [0.5, -0.2, 0.1], [0.1, -0.2, 0.05, 0.97])
    return FreeFloatingSimulator(
        robot, mode=mode, dt=dt, initial_q=q0, initial_momentum=momentum, **kwargs
    )


def _drive(simulator, duration, every=100):
    """Run the vigorous reference; return the largest momentum the joints carried [SI]."""
    robot = simulator.robot
    carried = 0.0
    for k in range(round(duration / simulator.dt)):
        simulator.set_reference(*vigorous_reference(simulator.time))
        simulator.step()
        if k % every == 0:
            centroidal_map = pin.computeCentroidalMap(robot.model, robot.data, simulator.q)
            carried = max(carried, np.linalg.norm(centroidal_map[:, 6:] @ simulator.v[6:]))
    return carried


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_momentum_is_conserved_over_20_s_of_vigorous_motion(robot, mode):
    simulator = _simulator(robot, mode, momentum=MOMENTUM)
    initial = simulator.centroidal_momentum()
    assert np.allclose(initial, MOMENTUM, atol=1e-12)
    carried = _drive(simulator, 20.0)
    assert np.abs(simulator.v[6:]).max() > 0.5  # rad/s: the arm really moved
    assert carried > 100.0  # kg m^2/s pushed around by the joints
    drift = np.abs(simulator.centroidal_momentum() - initial).max()
    assert drift / max(carried, np.abs(MOMENTUM).max()) < 1e-9


@pytest.mark.parametrize("mode", ["kinematic", "dynamic"])
def test_center_of_mass_stays_put_with_zero_momentum(robot, mode):
    simulator = _simulator(robot, mode)
    com_0 = pin.centerOfMass(robot.model, robot.data, simulator.q).copy()
    _drive(simulator, 5.0, every=10_000)
    com = pin.centerOfMass(robot.model, robot.data, simulator.q)
    assert np.linalg.norm(com - com_0) < 1e-9  # m


def test_center_of_mass_drifts_with_linear_momentum(robot):
    simulator = _simulator(robot, "kinematic", momentum=MOMENTUM)
    com_0 = pin.centerOfMass(robot.model, robot.data, simulator.q).copy()
    _drive(simulator, 2.0, every=10_000)
    com = pin.centerOfMass(robot.model, robot.data, simulator.q)
    assert np.allclose(com - com_0, MOMENTUM[:3] / robot.total_mass * 2.0, atol=1e-9)


def _generic(t, q):
    return AMPLITUDE * FREQUENCY * np.sin(FREQUENCY * t)


def test_reactionless_field_keeps_the_base_attitude_for_20_s(robot):
    def reactionless(t, q):
        return reactionless_joint_velocity(FreeFloatingState.compute(robot, q), _generic(t, q))

    simulator = _simulator(robot, "kinematic", dt=0.01)
    rotation_0 = simulator.q.copy()
    rotation_0 = FreeFloatingState.compute(robot, rotation_0).base_rotation
    worst = 0.0
    for _ in range(2000):
        simulator.step(reactionless)
        rotation = pin.Quaternion(simulator.q[3:7]).toRotationMatrix()
        worst = max(worst, attitude_deviation(rotation_0, rotation))
    assert np.rad2deg(worst) < 1e-6
    assert np.linalg.norm(simulator.q[7:] - THETA_0) > 0.5  # the arm moved a lot


def test_generic_motion_turns_the_base(robot):
    simulator = _simulator(robot, "kinematic", dt=0.01)
    rotation_0 = pin.Quaternion(simulator.q[3:7]).toRotationMatrix()
    for _ in range(400):
        simulator.step(_generic)
    rotation = pin.Quaternion(simulator.q[3:7]).toRotationMatrix()
    assert np.rad2deg(attitude_deviation(rotation_0, rotation)) > 0.1


def _final_attitude(robot, dt, duration=1.6, field=True):
    simulator = _simulator(robot, "kinematic", dt=dt)
    if not field:
        simulator.set_reference(velocities=AMPLITUDE * FREQUENCY)
    for _ in range(round(duration / dt)):
        simulator.step(_generic if field else None)
    return pin.Quaternion(simulator.q[3:7]).toRotationMatrix()


@pytest.mark.parametrize("field", [True, False], ids=["field", "held-reference"])
def test_halving_dt_divides_the_attitude_error_by_16(robot, field):
    reference = _final_attitude(robot, 0.00625, field=field)
    errors = [
        attitude_deviation(reference, _final_attitude(robot, dt, field=field)) for dt in (0.1, 0.05)
    ]
    assert errors[0] / errors[1] == pytest.approx(16.0, rel=0.25)


def test_dynamic_momentum_error_converges_at_fourth_order(robot):
    drifts = []
    for dt in (4e-3, 2e-3):
        simulator = _simulator(robot, "dynamic", dt=dt, momentum=MOMENTUM)
        _drive(simulator, 2.0, every=10_000)
        drifts.append(np.abs(simulator.centroidal_momentum() - MOMENTUM).max())
    assert drifts[0] / drifts[1] > 10.0


def test_servo_tracks_the_reference_in_dynamic_mode(robot):
    simulator = _simulator(robot, "dynamic")
    _drive(simulator, 3.0, every=10_000)
    positions, _, _ = vigorous_reference(simulator.time)
    assert np.abs(simulator.q[7:] - positions).max() < 1e-3  # rad
    assert np.abs(simulator.effort).max() > 1.0  # N m: torques did the work


def test_kinematic_joints_follow_the_command_exactly(robot):
    simulator = _simulator(robot, "kinematic")
    command = np.array([0.1, -0.2, 0.3, -0.1, 0.2, 0.4, -0.5])
    simulator.set_reference(velocities=command)
    for _ in range(500):
        simulator.step()
    assert np.allclose(simulator.q[7:], THETA_0 + 0.5 * command, atol=1e-12)
    assert np.allclose(simulator.v[6:], command)
    assert np.allclose(simulator.reference.positions, simulator.q[7:])


def test_a_late_reference_makes_up_the_missed_motion_in_one_step_with_its_reaction(robot):
    """set_reference(since=d): the joints end the next step where a switch d earlier would
    have put them, theta + dt v_new + d (v_new - v_old), and the base reacts to that motion
    (momentum stays zero); after it they run at v_new. A step of 1 ms and d = 0.7 ms."""
    simulator = _simulator(robot, "kinematic")
    old = np.array([0.1, -0.2, 0.3, -0.1, 0.2, 0.4, -0.5])
    new = np.array([-0.3, 0.1, 0.2, 0.25, -0.1, 0.0, 0.3])
    simulator.set_reference(velocities=old)
    for _ in range(20):
        simulator.step()
    momentum = simulator.centroidal_momentum()
    theta = simulator.q[7:].copy()
    simulator.set_reference(velocities=new, since=7e-4)
    simulator.step()
    np.testing.assert_allclose(simulator.q[7:], theta + 1e-3 * new + 7e-4 * (new - old), atol=1e-12)
    np.testing.assert_allclose(simulator.centroidal_momentum(), momentum, atol=1e-10)
    np.testing.assert_allclose(simulator.v[6:], new)
    theta = simulator.q[7:].copy()
    simulator.step()  # made up once only
    np.testing.assert_allclose(simulator.q[7:], theta + 1e-3 * new, atol=1e-12)


@pytest.mark.parametrize("since", [-1e-3, float("nan"), float("inf")])
def test_a_negative_or_non_finite_lateness_is_rejected(robot, since):
    simulator = _simulator(robot, "kinematic")
    with pytest.raises(InputError, match="since"):
        simulator.set_reference(velocities=np.zeros(7), since=since)


def test_viscous_friction_is_internal_so_momentum_is_kept(robot):
    gains = ServoGains.critically_damped(robot.n, friction=1.0)
    simulator = _simulator(robot, "dynamic", gains=gains, momentum=MOMENTUM)
    _drive(simulator, 1.0, every=10_000)
    assert np.abs(simulator.centroidal_momentum() - MOMENTUM).max() < 1e-9


def test_viscous_friction_slows_the_joints(robot):
    """Zero servo gains: the computed-torque feedforward alone spins the joints up to 0.2 rad/s
    (at 0.2 rad/s^2: at most 63 % of the effort limits, which 0.4 rad/s^2 would exceed), then
    holds theta_dd = 0; only friction can slow them afterwards."""

    def final_speed(friction):
        gains = ServoGains(np.zeros(7), np.zeros(7), np.full(7, friction))
        simulator = _simulator(robot, "dynamic", gains=gains)
        simulator.set_reference(accelerations=np.full(7, 0.2))
        for _ in range(1000):
            simulator.step()
        simulator.set_reference(accelerations=np.zeros(7))
        for _ in range(500):
            simulator.step()
        return np.abs(simulator.v[6:])

    free, braked = final_speed(0.0), final_speed(1.0)
    assert free == pytest.approx(np.full(7, 0.2), rel=1e-2)  # ZOH torque: ~0.2 % off
    # the light wrist joints (decay rate D / H*_ii of several 1/s) lose most of their speed
    assert braked[4:].max() < 0.5 * free[4:].min()


def test_too_stiff_friction_is_rejected(robot):
    gains = ServoGains.critically_damped(robot.n, friction=50.0)
    with pytest.raises(ConfigError, match="too stiff for dt"):
        _simulator(robot, "dynamic", gains=gains)


def test_reset_restores_the_initial_state(robot):
    simulator = _simulator(robot, "dynamic", momentum=MOMENTUM)
    q0, v0 = simulator.q.copy(), simulator.v.copy()
    _drive(simulator, 0.2, every=10_000)
    simulator.reset()
    assert simulator.time == 0.0
    assert np.array_equal(simulator.q, q0)
    assert np.allclose(simulator.v, v0)


def test_bad_settings_and_references_are_rejected(robot):
    with pytest.raises(ConfigError, match="mode must be one of"):
        FreeFloatingSimulator(robot, mode="teleport")
    with pytest.raises(ConfigError, match="dt must be"):
        FreeFloatingSimulator(robot, dt=0.5)
    with pytest.raises(ConfigError, match="dt must be"):
        FreeFloatingSimulator(robot, dt=0.0)
    simulator = FreeFloatingSimulator(robot)
    with pytest.raises(InputError, match="reference velocities must be finite"):
        simulator.set_reference(velocities=[0, 0, 0, np.inf, 0, 0, 0])
    with pytest.raises(InputError, match=r"shape \(7,\)"):
        simulator.set_reference(positions=np.zeros(3))
    dynamic = FreeFloatingSimulator(robot, mode=SimulationMode.DYNAMIC)
    with pytest.raises(ConfigError, match="needs mode 'kinematic'"):
        dynamic.step(_generic)


def _step_response(simulator, step, duration):
    """Hold theta_ref = theta_0 + step; return (peak |theta_dot| / limit (n,), peak |tau| [N m]
    (n,), largest |cos| gap between theta_dot and the step direction, momentum the joints
    carried [SI])."""
    robot = simulator.robot
    simulator.set_reference(positions=THETA_0 + step)
    speed, effort, off_direction, carried = np.zeros(robot.n), np.zeros(robot.n), 0.0, 0.0
    direction = step / np.linalg.norm(step)
    for _ in range(round(duration / simulator.dt)):
        simulator.step()
        theta_dot = simulator.v[6:]
        speed = np.maximum(speed, np.abs(theta_dot) / robot.velocity_limits)
        effort = np.maximum(effort, np.abs(simulator.effort))
        norm = np.linalg.norm(theta_dot)
        if norm > 0.1 * robot.velocity_limits.min():  # direction is meaningless near rest
            off_direction = max(off_direction, 1.0 - abs(direction @ theta_dot) / norm)
        centroidal_map = pin.computeCentroidalMap(robot.model, robot.data, simulator.q)
        carried = max(carried, np.linalg.norm(centroidal_map[:, 6:] @ theta_dot))
    return speed, effort, off_direction, carried


def test_a_step_far_beyond_the_servo_respects_the_joint_limits(robot):
    """A 1 rad step (unlimited, the servo ran the joints at 45 rad/s, 90x the URDF limit): the
    demanded velocity is scaled as a whole, so the joints move along the step direction within
    their velocity limits and the torques within their effort limits, and momentum is kept.
    Tolerance: the torque is held over each 1 ms step while H* and c* change, so the rates land
    up to 0.8 % past the limit (0.3 % at 0.5 ms); the command check allows 1 %."""
    step = np.array([1.0, -0.6, 0.8, 1.0, -0.9, 0.5, 1.0])  # rad
    simulator = _simulator(robot, "dynamic", momentum=MOMENTUM)
    speed, effort, off_direction, carried = _step_response(simulator, step, 2.5)
    assert speed.max() <= 1.0 + VELOCITY_LIMIT_TOLERANCE
    assert speed.max() > 0.95  # the limit was reached: the test exercised the saturation
    assert np.all(effort <= simulator.effort_limits * (1.0 + 1e-12))
    assert off_direction < 1e-3  # per-joint clipping would bend the path (and turn the base)
    drift = np.abs(simulator.centroidal_momentum() - MOMENTUM).max()
    assert drift / carried < 1e-9


def test_a_100_rad_reference_stays_finite_and_within_the_limits(robot):
    """The issue's input (unlimited: NaN after 5 ms). At full speed on every joint the
    velocity-product torques c* would exceed the 200 N m of joint 2 after ~3.4 s; the servo
    slows the arm before that instead of losing the joints."""
    simulator = _simulator(robot, "dynamic")
    speed, effort, _, _ = _step_response(simulator, np.full(robot.n, 100.0), 5.0)
    assert np.isfinite(simulator.q).all()
    assert np.isfinite(simulator.v).all()
    assert speed.max() <= 1.0 + VELOCITY_LIMIT_TOLERANCE
    assert np.all(effort <= simulator.effort_limits * (1.0 + 1e-12))


def test_a_diverging_step_keeps_the_last_finite_state_and_raises(robot, monkeypatch):
    simulator = _simulator(robot, "dynamic")
    simulator.set_reference(*vigorous_reference(0.0))
    for _ in range(10):
        simulator.step()
    before = simulator.snapshot()
    nan = np.full(robot.model.nv, np.nan)
    monkeypatch.setattr(simulator, "_acceleration", lambda q, v, tau, fraction=0.0: nan)
    with pytest.raises(SimulationDivergedError, match=r"t = 0\.01 s: non-finite q and v"):
        simulator.step()
    after = simulator.snapshot()
    assert after.time == before.time
    assert np.array_equal(after.q, before.q)
    assert np.array_equal(after.v, before.v)
    monkeypatch.undo()
    simulator.step()  # and it goes on from there
    assert simulator.time == pytest.approx(before.time + simulator.dt)


def test_an_undamped_servo_is_rejected(robot):
    gains = ServoGains(np.full(7, 100.0), np.zeros(7), np.zeros(7))
    with pytest.raises(ConfigError, match="damping must be > 0 wherever stiffness > 0"):
        _simulator(robot, "dynamic", gains=gains)


def test_the_speed_cap_keeps_unlimited_joints_unlimited():
    """Under a large velocity-product load the cap lowers the finite speed limits uniformly; a
    joint without a limit (+inf) stays unlimited, never inf * 0 = NaN."""
    from pathlib import Path

    from rns_ros.core.config import load_model
    from rns_ros.sim.free_floating import BIAS_SHARE

    robot = load_model(Path(__file__).resolve().parents[1] / "data/arms/cont6/model.yaml")
    sim = FreeFloatingSimulator(robot, mode="dynamic")
    bias = 4.0 * BIAS_SHARE * sim.effort_limits  # load 4 x the share: speeds halved
    sim.velocity_limits = np.array([np.inf, np.inf, np.inf, 0.8, 0.8, 0.8])
    theta_dot = np.array([5.0, 0.0, 0.0, 0.4, 0.0, 0.0])  # the bounded joints at half speed
    cap = sim._speed_cap(theta_dot, bias)
    np.testing.assert_allclose(cap, [np.inf, np.inf, np.inf, 0.2, 0.2, 0.2], rtol=1e-15)
    sim.velocity_limits = np.full(robot.n, np.inf)
    assert np.all(sim._speed_cap(theta_dot, bias) == np.inf)


def test_a_kinematic_joint_stops_at_its_limit_as_at_a_mechanical_stop():
    """gripper7's joint 5 is limited to [-2.9, 2.9] rad. Driven at 0.5 rad/s from 2.85 rad for
    0.5 s it stands at 2.9 rad exactly while the others follow their rates; the base moves as
    momentum conservation says throughout (the stop is a rate the arm takes, with its
    reaction); a rate away from the limit is followed at once."""
    robot = load_model(ARMS / "gripper7" / "model.yaml")
    theta = np.array(robot.initial_theta)
    joint = robot.joint_names.index("g7_joint5")
    theta[joint] = 2.85
    q0 = robot.configuration(theta, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
    simulator = FreeFloatingSimulator(
        robot, mode="kinematic", initial_q=q0, initial_momentum=MOMENTUM
    )
    command = np.full(robot.n, 0.05)
    command[joint] = 0.5
    simulator.set_reference(velocities=command)
    for _ in range(500):
        simulator.step()
        assert simulator.q[7 + joint] <= robot.upper_limits[joint]
    others = np.arange(robot.n) != joint
    np.testing.assert_allclose(simulator.q[7:][others], theta[others] + 0.5 * 0.05, atol=1e-12)
    assert simulator.q[7 + joint] == pytest.approx(2.9, abs=1e-12)
    assert simulator.at_stop.tolist() == [j == joint for j in range(robot.n)]
    assert simulator.joint_stop() == (joint, "upper", 2.9)
    assert simulator.v[6 + joint] == 0.0  # standing at the stop, as joint_states say
    np.testing.assert_allclose(simulator.centroidal_momentum(), MOMENTUM, atol=1e-9)
    command[joint] = -0.5
    simulator.set_reference(velocities=command)
    for _ in range(100):
        simulator.step()
    assert simulator.q[7 + joint] == pytest.approx(2.9 - 0.05, abs=1e-12)
    assert not simulator.at_stop.any()
