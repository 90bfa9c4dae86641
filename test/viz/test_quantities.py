"""The plotted quantities, computed without rerun or DDS."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from rns_testing import SATELLITE_OBSERVATION_DEG

from rns_ros.core import FreeFloatingState
from rns_ros.viz.quantities import (
    AttitudeDeviation,
    ControllerStatus,
    RateLimiter,
    Trail,
    achieved_angular_velocity,
    roll_pitch_yaw,
)


def _rz(angle):
    return pin.AngleAxis(angle, np.array([0.0, 0.0, 1.0])).toRotationMatrix()


def _ry(angle):
    return pin.AngleAxis(angle, np.array([0.0, 1.0, 0.0])).toRotationMatrix()


def _rx(angle):
    return pin.AngleAxis(angle, np.array([1.0, 0.0, 0.0])).toRotationMatrix()


@pytest.mark.parametrize(
    ("roll", "pitch", "yaw"), [(0.1, -0.2, 0.3), (-2.5, 1.2, 3.0), (0.0, 0.0, -1.0)]
)
def test_roll_pitch_yaw_recovers_the_angles_of_rz_ry_rx(roll, pitch, yaw):
    rotation = _rz(yaw) @ _ry(pitch) @ _rx(roll)
    assert roll_pitch_yaw(rotation) == pytest.approx([roll, pitch, yaw], abs=1e-12)


def test_attitude_deviation_is_relative_to_the_first_rotation_in_degrees():
    deviation = AttitudeDeviation()
    start = _rz(1.0) @ _rx(0.5)  # an arbitrary initial attitude, not identity
    assert deviation(start) == pytest.approx(np.zeros(4), abs=1e-12)
    # turning by 2 deg about the base's own y axis: pitch 2 deg, total 2 deg
    turned = start @ _ry(math.radians(2.0))
    assert deviation(turned) == pytest.approx([0.0, 2.0, 0.0, 2.0], abs=1e-9)
    roll, pitch, yaw = 0.01, -0.02, 0.03
    rpy = deviation(start @ _rz(yaw) @ _ry(pitch) @ _rx(roll))
    assert rpy[:3] == pytest.approx(np.degrees([roll, pitch, yaw]), abs=1e-9)
    angle = np.linalg.norm(pin.log3(_rz(yaw) @ _ry(pitch) @ _rx(roll)))
    assert rpy[3] == pytest.approx(math.degrees(angle), abs=1e-9)


def test_achieved_angular_velocity_matches_the_camera_rotation_rate(robot):
    """omega_e = R_b omega_b^B + J_omega theta_dot against a finite difference of the camera
    rotation along pin.integrate (base twist in base axes, as base_odom carries it)."""
    rng = np.random.default_rng(3)
    theta = np.radians(SATELLITE_OBSERVATION_DEG)
    quaternion = pin.Quaternion(pin.rpy.rpyToMatrix(0.3, -0.4, 1.1)).coeffs()  # x y z w
    q = robot.configuration(theta, [0.5, -1.0, 2.0], quaternion)
    theta_dot = rng.uniform(-0.3, 0.3, robot.n)
    base_omega = np.array([0.02, -0.05, 0.04])  # base axes
    v = np.concatenate(([0.01, 0.0, -0.02], base_omega, theta_dot))
    state = FreeFloatingState.compute(robot, q)
    omega = achieved_angular_velocity(state, theta_dot, base_omega)

    h = 1e-6
    later = FreeFloatingState.compute(robot, pin.integrate(robot.model, q, v * h))
    finite_difference = pin.log3(later.camera.rotation @ state.camera.rotation.T) / h
    assert omega == pytest.approx(finite_difference, abs=1e-5)
    # without odometry only the joints count
    joints_only = achieved_angular_velocity(state, theta_dot)
    assert joints_only == pytest.approx(omega - state.base_rotation @ base_omega, abs=1e-12)


def test_controller_status_parses_the_controllers_text_format():
    values = {
        "state": "SINGULAR_REGION",
        "sigma_min": "0.1234",
        "det_kinematic": "11.2",
        "det_coupling": "1.3e+13",
        "det_algorithmic": "0.04",
        "damping": "0.81",
        "speed_scale": "1",
        "coupling_momentum": "1e-16 -2e-16 3e-16",
    }
    status = ControllerStatus.parse(values)
    assert status.state == "SINGULAR_REGION"
    assert status.sigma_min == 0.1234
    assert status.det_coupling == 1.3e13
    assert status.coupling_momentum == pytest.approx([1e-16, -2e-16, 3e-16])
    # missing, non-numeric and non-finite values are None, not errors
    partial = ControllerStatus.parse(
        {"sigma_min": "nan", "damping": "high", "coupling_momentum": "1 2"}
    )
    assert partial == ControllerStatus()


def test_rate_limiter_keeps_at_most_the_rate_and_follows_time_jumps_back():
    limiter = RateLimiter(200.0)  # one sample per 5 ms
    kept = [t for t in range(0, 100_000_000, 1_000_000) if limiter.accept(t)]  # 1 kHz, 100 ms
    assert len(kept) == 20
    assert limiter.accept(0)  # a reset restarts the stream
    everything = RateLimiter(0.0)
    assert all(everything.accept(t) for t in [5, 5, 6])


def test_trail_keeps_the_newest_points_one_per_period():
    trail = Trail(length=3, period=0.1)
    added = [trail.add(k * 50_000_000, np.array([k, 0.0, 0.0])) for k in range(10)]
    assert added == [True, False] * 5
    assert trail.strip()[:, 0].tolist() == [4.0, 6.0, 8.0]
    off = Trail(length=0, period=0.1)
    assert not off.add(0, np.zeros(3))
    assert off.strip().shape == (0, 3)
