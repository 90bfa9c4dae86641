"""Figures of a recorded run: what the robot did, from the topics a run published (ROS-free).

Input is plain arrays (the demo records them with :class:`rns_ros.harness.Harness`); output is a
:class:`RunFigures` record. Camera and wrist poses are recomputed from the recorded joint angles
and base poses with the model, so the figures do not trust the controller's own reports.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.control.camera_law import THESIS_EPSILON, wrist_offset
from rns_ros.control.controller import TwistFrame
from rns_ros.control.scenario import Scenario
from rns_ros.core.errors import InputError
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState


@dataclass(frozen=True)
class RunFigures:
    """Figures of one run (units in the names).

    Attributes:
        max_base_deviation_deg: largest base attitude change from the first sample [deg].
        final_camera_error_deg: camera orientation at the end vs the scenario's target [deg].
        rms_tracking_error: RMS of |omega_achieved - omega_commanded| at the robot samples within
            the commanded span, world axes [rad/s] (includes the command-to-motion latency).
        max_wrist_drift_m: largest |p_w - p_w(0)|, wrist relative to the base [m].
        max_joint_speed: largest |theta_dot_i| measured [rad/s].
        angular_momentum_drift: largest |l(t) - l(0)| about the CoM [kg m^2/s].
        samples: robot states used.
        min_sigma: smallest sigma_min of the restricted Jacobian J-bar_omega_e (eq. 4.5) over
            the samples [-] (SVD).
        singular_time_s: time spent with sigma_min below the singular-region threshold
            (the DLS epsilon of section 4.3.2) [s], each sample counting until the next.
    """

    max_base_deviation_deg: float
    final_camera_error_deg: float
    rms_tracking_error: float
    max_wrist_drift_m: float
    max_joint_speed: float
    angular_momentum_drift: float
    samples: int
    min_sigma: float
    singular_time_s: float
    #: smallest and largest prod(sigma_i) of J-bar [-]: the SC method scales the commanded rate
    #: by b times it (eq. 4.13), so the camera turns slower than commanded below 1 / b and
    #: faster above (None: not computed)
    min_singular_product: float | None = None
    max_singular_product: float | None = None
    #: camera orientation at the end vs the attitude the recorded cmd_twist samples add up to
    #: (:func:`commanded_rotation`) [deg]: what the controller was asked for, which differs
    #: from the scenario's target when the operator's stream was late or thinned out (a
    #: starved operator on the wall clock); None: no command recorded
    commanded_camera_error_deg: float | None = None


def run_figures(
    robot: FreeFloatingModel,
    scenario: Scenario,
    *,
    times: np.ndarray,
    joint_positions: np.ndarray,
    joint_velocities: np.ndarray,
    base_positions: np.ndarray,
    base_orientations: np.ndarray,
    base_angular_velocities: np.ndarray,
    angular_momentum: np.ndarray,
    command_times: np.ndarray,
    commands: np.ndarray,
    singular_threshold: float = THESIS_EPSILON,
) -> RunFigures:
    """Compute :class:`RunFigures` from recorded streams.

    Args:
        times: robot-state stamps [s], shape (k,), increasing.
        joint_positions, joint_velocities: [rad], [rad/s], shape (k, n), model joint order.
        base_positions: [m], shape (k, 3); base_orientations: quaternions x y z w, shape (k, 4).
        base_angular_velocities: base angular velocity in base axes (Odometry twist) [rad/s],
            shape (k, 3).
        angular_momentum: angular momentum about the CoM, world axes [kg m^2/s], shape (m, 3).
        command_times: stamps of the operator's twists [s], shape (c,).
        commands: their angular velocities in ``scenario.frame`` axes [rad/s], shape (c, 3).
        singular_threshold: sigma_min below which a sample is in the singular region [-].
    """
    k = len(times)
    if k < 2 or joint_positions.shape[0] != k or base_orientations.shape[0] != k:
        raise InputError(f"need >= 2 aligned robot samples, got {k} stamps")
    states = [
        FreeFloatingState.compute(
            robot, robot.configuration(theta, position, quaternion / np.linalg.norm(quaternion))
        )
        for theta, position, quaternion in zip(
            joint_positions, base_positions, base_orientations, strict=True
        )
    ]
    first, last = states[0], states[-1]
    base = max(attitude_deviation(first.base_rotation, s.base_rotation) for s in states)
    target = scenario.target_rotation(first.camera.rotation, first.base_rotation, scenario.duration)
    wrist = (
        max(float(np.linalg.norm(wrist_offset(s) - wrist_offset(first))) for s in states)
        if first.wrist is not None
        else 0.0
    )
    momentum = np.asarray(angular_momentum, dtype=float).reshape(-1, 3)
    singular = np.array([np.linalg.svd(s.restricted_jacobian, compute_uv=False) for s in states])
    sigma = singular[:, -1]
    held = np.diff(times, append=times[-1])  # each sample until the next
    return RunFigures(
        max_base_deviation_deg=float(np.rad2deg(base)),
        final_camera_error_deg=float(np.rad2deg(attitude_deviation(target, last.camera.rotation))),
        rms_tracking_error=_rms_tracking_error(
            states,
            times,
            joint_velocities,
            base_angular_velocities,
            command_times,
            commands,
            scenario,
        ),
        max_wrist_drift_m=wrist,
        max_joint_speed=float(np.abs(joint_velocities).max()),
        angular_momentum_drift=float(np.linalg.norm(momentum - momentum[0], axis=1).max())
        if len(momentum)
        else 0.0,
        samples=k,
        min_sigma=float(sigma.min()),
        singular_time_s=float(held[sigma < singular_threshold].sum()),
        min_singular_product=float(np.prod(singular, axis=1).min()),
        max_singular_product=float(np.prod(singular, axis=1).max()),
        commanded_camera_error_deg=None
        if len(command_times) == 0
        else float(
            np.rad2deg(
                attitude_deviation(
                    commanded_rotation(
                        scenario,
                        first.camera.rotation,
                        first.base_rotation,
                        command_times,
                        commands,
                    ),
                    last.camera.rotation,
                )
            )
        ),
    )


def commanded_rotation(
    scenario: Scenario,
    camera_0: np.ndarray,
    base_0: np.ndarray,
    command_times: np.ndarray,
    commands: np.ndarray,
) -> np.ndarray:
    """The camera attitude (world <- camera, (3, 3)) the recorded commands add up to: the
    initial camera rotation ``camera_0`` (3, 3) turned by each command [rad/s] (c, 3), in
    ``scenario.frame`` axes, held from its stamp to the next one's (``command_times`` [s] (c,);
    the last one counts for nothing: the operator's stream ends in zeros). The base is taken as
    not turning (``base_0`` (3, 3)), as in :meth:`Scenario.target_rotation`."""
    rotation = np.array(camera_0, dtype=float)
    times = np.asarray(command_times, dtype=float)
    for omega, dt in zip(np.asarray(commands, dtype=float), np.diff(times), strict=False):
        turn = pin.exp3(omega * max(float(dt), 0.0))
        if scenario.frame is TwistFrame.WORLD:
            rotation = turn @ rotation
        elif scenario.frame is TwistFrame.CAMERA:
            rotation = rotation @ turn
        else:
            rotation = base_0 @ turn @ base_0.T @ rotation
    return rotation


def _rms_tracking_error(
    states, times, joint_velocities, base_rates, command_times, commands, scenario: Scenario
) -> float:
    """Achieved camera angular velocity at each sample, omega_c = R_b omega_b + J_omega theta_dot
    (world axes; exact, unlike a finite difference over jittery wall-clock stamps), vs the command
    in force at the sample's stamp, rotated into world axes."""
    if len(command_times) == 0:
        return 0.0
    errors = []
    for state, t, theta_dot, base_rate in zip(
        states, times, joint_velocities, base_rates, strict=True
    ):
        if not command_times[0] <= t <= command_times[-1]:
            continue
        achieved = state.base_rotation @ base_rate + state.camera.jacobian[3:] @ theta_dot
        command = commands[np.searchsorted(command_times, t, side="right") - 1]
        if scenario.frame is TwistFrame.CAMERA:
            command = state.camera.rotation @ command
        elif scenario.frame is TwistFrame.BASE:
            command = state.base_rotation @ command
        errors.append(np.sum((achieved - command) ** 2))
    return float(np.sqrt(np.mean(errors))) if errors else 0.0
