"""Robot-side messages shared by the nodes that command the joints (rns_controller, rns_ptp):
the base pose from ``base_odom``, the joint command in the ros2_control-compatible contract, and
the check of the measured state (stale or from two sources)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint


def base_pose(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """(position [m] (3,), unit quaternion x y z w (4,)) of the base in world from an Odometry's
    pose ``pose`` (7,): position x y z, orientation x y z w (``OdometryFields.pose`` of
    :mod:`rns_ros.nodes.cdr`); None when it is not finite or its quaternion is far from unit
    (norm <= 0.5)."""
    position, orientation = np.array(pose[:3], dtype=float), np.array(pose[3:7], dtype=float)
    norm = math.sqrt(float(orientation @ orientation))
    if np.isfinite(position).all() and math.isfinite(norm) and norm > 0.5:
        return position, orientation / norm
    return None


def joint_command(
    stamp: TimeMsg,
    joint_names: Sequence[str],
    positions,
    velocities,
    velocity_order: np.ndarray | None,
) -> JointTrajectory | Float64MultiArray:
    """The joint output of rns_controller and rns_ptp.

    Args:
        positions, velocities: model joint order [rad], [rad/s], shape (n,).
        velocity_order: None for a JointTrajectory (one point, named joints); else the index
            array p of :func:`rns_ros.nodes.parameters.velocity_joint_order` for a
            Float64MultiArray of velocities in the ``joints`` parameter's order.
    """
    velocities = np.asarray(velocities, dtype=float)
    if velocity_order is None:
        msg = JointTrajectory()
        msg.header.stamp = stamp
        msg.joint_names = list(joint_names)
        msg.points = [
            JointTrajectoryPoint(
                positions=np.asarray(positions, dtype=float).tolist(),
                velocities=velocities.tolist(),
            )
        ]
        return msg
    data = np.empty(velocities.size)
    data[velocity_order] = velocities
    return Float64MultiArray(data=data.tolist())


def measured_state_problem(
    now: float,
    state_publishers: Sequence[str],
    state_topic: str,
    state_received: float,
    odom_received: float | None,
    timeout: float,
) -> tuple[str, str] | None:
    """Why the measured state cannot be trusted, or None.

    Returns ("CONFLICTING_STATE", reason) for more than one ``joint_states`` publisher, or
    ("STALE_STATE", reason) when joint_states (or base_odom, once received) are older than
    ``timeout`` [s] at ``now`` [s], on the clock of the receipt times (the node's input clock:
    simulated time under use_sim_time, else monotonic).
    """
    if len(state_publishers) > 1:
        return (
            "CONFLICTING_STATE",
            f"{len(state_publishers)} publishers on {state_topic} "
            f"({', '.join(state_publishers)}): remap to exactly one source",
        )
    age = now - state_received
    if age > timeout:
        return "STALE_STATE", f"joint_states {age:.3f} s old (state_timeout {timeout} s)"
    if odom_received is not None and now - odom_received > timeout:
        return (
            "STALE_STATE",
            f"base_odom {now - odom_received:.3f} s old (state_timeout {timeout} s)",
        )
    return None
