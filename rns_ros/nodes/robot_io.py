"""Robot-side messages shared by the nodes that command the joints (rns_controller, rns_ptp):
the base pose from ``base_odom``, the joint command in a shape stock ros2_control controllers
execute (docs/ros2_control.md), and the check of the measured state (stale or from two sources)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from builtin_interfaces.msg import Duration as DurationMsg
from builtin_interfaces.msg import Time as TimeMsg
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from rns_ros.nodes.parameters import velocity_joint_order


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


#: The output interfaces: JointTrajectory (joint_trajectory_controller and rns_simulator),
#: Float64MultiArray of velocities (JointGroupVelocityController) or of positions
#: (JointGroupPositionController), each on its topic.
OUTPUT_TOPICS = {
    "trajectory": "joint_references",
    "velocity": "joint_velocities",
    "position": "joint_positions",
}
#: A streamed JointTrajectory comes to rest this many output periods after its stamp (its
#: point 1): the next one replaces it one period later, and the arm stops this long after the
#: last one.
TRAJECTORY_HORIZON_PERIODS = 2.0
#: time_from_start [s] of a streamed JointTrajectory's last point (point 2, point 1's positions
#: at rest): joint_trajectory_controller refuses a trajectory that ends before it arrives, so a
#: message delivered up to this long after its stamp (latency plus the offset between our clock
#: and the controller's) is still taken, and played as a hold at rest once past point 1. Above
#: the receipt lag of a loaded machine (max 163 ms, p99 43 ms at 100 Hz).
TRAJECTORY_DELIVERY_MARGIN = 0.25


def trajectory_horizon(period: float) -> float:
    """time_from_start [s] of a streamed JointTrajectory's point 1, where it comes to rest, for
    the output ``period`` [s]."""
    return TRAJECTORY_HORIZON_PERIODS * period


def trajectory_end(horizon: float) -> float:
    """time_from_start [s] of a streamed JointTrajectory's last point for point 1 at
    ``horizon`` [s]: :data:`TRAJECTORY_DELIVERY_MARGIN`, or twice ``horizon`` when that is later
    (long output periods: the points' times must increase)."""
    return max(TRAJECTORY_DELIVERY_MARGIN, 2.0 * horizon)


def hold_end_positions(positions, velocities, horizon: float) -> np.ndarray:
    """theta + horizon theta_dot [rad] (n,): where the held command ``velocities`` [rad/s] takes
    ``positions`` [rad] in ``horizon`` [s]."""
    return np.asarray(positions, dtype=float) + horizon * np.asarray(velocities, dtype=float)


def duration_msg(seconds: float) -> DurationMsg:
    """builtin_interfaces/Duration of ``seconds`` [s] >= 0 (nanoseconds rounded)."""
    sec, nanosec = divmod(round(seconds * 1e9), 1_000_000_000)
    return DurationMsg(sec=int(sec), nanosec=int(nanosec))


def streamed_trajectory(
    stamp: TimeMsg, joint_names: Sequence[str], positions, velocities, horizon: float
) -> JointTrajectory:
    """The streamed JointTrajectory of one output period, stamped ``stamp`` (the instant its
    first point applies).

    Point 0 (time_from_start 0): ``positions`` [rad] and ``velocities`` [rad/s] (n,), the held
    command; rns_simulator reads this point. Point 1 (time_from_start ``horizon`` [s]):
    positions + horizon velocities, no velocities: joint_trajectory_controller interpolates
    linearly between the two (at exactly ``velocities``), so the arm is at rest there. Point 2
    (time_from_start :func:`trajectory_end` of ``horizon``, [s]): point 1's positions, zero
    velocities: the hold at rest that keeps a late message valid, and the trajectory ends at
    rest, as JTC's default ``allow_nonzero_velocity_at_trajectory_end: false`` requires.
    """
    end_positions = hold_end_positions(positions, velocities, horizon).tolist()
    msg = JointTrajectory()
    msg.header.stamp = stamp
    msg.joint_names = list(joint_names)
    msg.points = [
        JointTrajectoryPoint(
            positions=np.asarray(positions, dtype=float).tolist(),
            velocities=np.asarray(velocities, dtype=float).tolist(),
        ),
        JointTrajectoryPoint(positions=end_positions, time_from_start=duration_msg(horizon)),
        JointTrajectoryPoint(
            positions=end_positions,
            velocities=[0.0] * len(end_positions),
            time_from_start=duration_msg(trajectory_end(horizon)),
        ),
    ]
    return msg


def plan_trajectory(
    stamp: TimeMsg, joint_names: Sequence[str], times, positions, velocities
) -> JointTrajectory:
    """A whole plan as one JointTrajectory stamped ``stamp`` (when its first point applies):
    point k at time_from_start ``times[k]`` [s] (k,) with ``positions[k]`` [rad] and
    ``velocities[k]`` [rad/s] (k, n); the caller's last velocities are zero (at rest)."""
    msg = JointTrajectory()
    msg.header.stamp = stamp
    msg.joint_names = list(joint_names)
    msg.points = [
        JointTrajectoryPoint(
            positions=np.asarray(theta, dtype=float).tolist(),
            velocities=np.asarray(theta_dot, dtype=float).tolist(),
            time_from_start=duration_msg(float(t)),
        )
        for t, theta, theta_dot in zip(times, positions, velocities, strict=True)
    ]
    return msg


class JointCommand:
    """The joint output of rns_controller and rns_ptp on one ``output_interface``.

    Args:
        interface: ``trajectory`` (:func:`streamed_trajectory` on joint_references),
            ``velocity`` (Float64MultiArray of theta_dot [rad/s] on joint_velocities) or
            ``position`` (Float64MultiArray of theta + T theta_dot [rad], the end of the held
            period, on joint_positions); the arrays in the order of ``joints``.
        joint_names: the model's joints, in model order.
        joints: the ``joints`` parameter (Float64MultiArray order), a permutation of them.
        period: the output period T [s].
    """

    def __init__(
        self, interface: str, joint_names: Sequence[str], joints: Sequence[str], period: float
    ) -> None:
        self.interface = interface
        self.topic = OUTPUT_TOPICS[interface]
        self.message_type = JointTrajectory if interface == "trajectory" else Float64MultiArray
        self.joint_names = list(joint_names)
        self.period = period
        self.horizon = trajectory_horizon(period)
        #: how long the command holds its velocities [s], the horizon its positions are bounded
        #: over: to a trajectory's point 1, else one period
        self.bound_horizon = self.horizon if interface == "trajectory" else period
        #: how long one command acts without a newer one before the plant holds still [s]: a
        #: trajectory ends at rest at its horizon, a position target is reached after a
        #: period, a velocity is held (until the plant's own timeout)
        self.acting_horizon = {"trajectory": self.horizon, "position": period}.get(
            interface, math.inf
        )
        #: time_from_start [s] of a streamed trajectory's last point (at rest)
        self.end = trajectory_end(self.horizon)
        # data[order[i]] is model joint i (ros2_control's forward_command_controller order)
        self.order = (
            None if interface == "trajectory" else velocity_joint_order(joints, joint_names)
        )

    def message(self, stamp: TimeMsg, positions, velocities) -> JointTrajectory | Float64MultiArray:
        """The command for ``positions`` [rad] and ``velocities`` [rad/s] (n, model order) held
        from ``stamp`` on (Float64MultiArray has no stamp)."""
        if self.order is None:
            return streamed_trajectory(stamp, self.joint_names, positions, velocities, self.horizon)
        values = np.asarray(velocities, dtype=float)
        if self.interface == "position":
            values = hold_end_positions(positions, velocities, self.period)
        data = np.empty(values.size)
        data[self.order] = values
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


class StampPairs:
    """joint_states and base_odom halves of one robot state, matched by stamp [ns] (a robot
    publishes both per step; at most :data:`MAX_UNPAIRED` of each kept while waiting)."""

    def __init__(self) -> None:
        self._joints: dict[int, object] = {}
        self._poses: dict[int, object] = {}

    def joints(self, stamp: int, theta):
        return self._add(self._joints, self._poses, stamp, theta, joints_first=True)

    def pose(self, stamp: int, pose):
        return self._add(self._poses, self._joints, stamp, pose, joints_first=False)

    @staticmethod
    def _add(mine: dict, theirs: dict, stamp: int, value, joints_first: bool):
        """(stamp, theta, pose) once both halves of ``stamp`` are in, else None."""
        other = theirs.pop(stamp, None)
        if other is None:
            mine[stamp] = value
            while len(mine) > MAX_UNPAIRED:
                del mine[min(mine)]
            return None
        return (stamp, value, other) if joints_first else (stamp, other, value)


#: Halves of a robot state kept while waiting for their other half.
MAX_UNPAIRED = 200
