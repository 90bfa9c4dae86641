"""Arrays and figures from the topics a run recorded: the robot's samples, its energy.

:func:`robot_arrays` turns recorded ``joint_states`` / ``base_odom`` / ``momentum`` /
``cmd_twist`` into the arrays of :func:`rns_ros.analysis.recorded_run.run_figures` (rns_demo and
rns_observer); :func:`energy_figures` reads rns_simulator's ``energy`` topic (thesis chapter 5);
:func:`latest_status_values` reads a node's newest ``~/status``.
"""

from __future__ import annotations

import signal
from dataclasses import dataclass

import numpy as np

from rns_ros.core import RnsError
from rns_ros.harness import TopicLog, header_seconds


def latest_status_values(log: TopicLog) -> dict[str, str]:
    """Key values of the first entry of the newest DiagnosticArray in ``log`` ({} before one)."""
    latest = log.latest()
    if latest is None or not latest.status:
        return {}
    return {kv.key: kv.value for kv in latest.status[0].values}


@dataclass(frozen=True)
class EnergyFigures:
    """Energy of one run from rns_simulator's ``energy`` topic (thesis chapter 5).

    Attributes:
        c_max: C_max of eq. (5.12): peak of 1/2 theta_dot^T Lambda theta_dot [J] (the arm's
            motion costed as if wheels cancelled its reaction: zero for the Lambda_r part of a
            reactionless motion).
        c_sum: C_sum of eq. (5.13) [J s].
        peak_wheel_energy: largest kinetic energy of the wheels' spin in the run [J] (0 without
            wheels).
        wheel_saturation_s: time with a wheel at its torque limit per rns_attitude_control [s]
            (None without it).
    """

    c_max: float
    c_sum: float
    peak_wheel_energy: float
    wheel_saturation_s: float | None


def energy_figures(
    energy: TopicLog, attitude: TopicLog | None, until: float = np.inf
) -> EnergyFigures | None:
    """C_max, C_sum, peak wheel energy from the ``energy`` topic (labels from its layout; samples
    up to simulated time ``until`` [s]), and the saturation time from the newest
    rns_attitude_control status; None without samples."""
    if not len(energy):
        return None
    labels = energy.latest().layout.dim[0].label.split()
    rows = [dict(zip(labels, msg.data, strict=True)) for msg in energy.messages]
    rows = [row for row in rows if row.get("time", -np.inf) <= until]
    if not rows:
        return None
    saturation = None
    if attitude is not None and len(attitude):
        values = {kv.key: kv.value for kv in attitude.latest().status[0].values}
        saturation = float(values.get("saturated_time_s", "nan"))
    return EnergyFigures(
        c_max=rows[-1]["c_max"],
        c_sum=rows[-1]["c_sum"],
        peak_wheel_energy=max(row["wheels"] for row in rows),
        wheel_saturation_s=saturation,
    )


def robot_arrays(
    streams: dict[str, TopicLog], until: float = np.inf, since: float = -np.inf
) -> dict[str, np.ndarray]:
    """Robot samples where joint_states and base_odom share a stamp (the simulator publishes
    both per step), plus momentum and commands; only messages stamped in [``since``,
    ``until``] [s]."""
    streams = {name: _within(log, since, until) for name, log in streams.items()}
    joints, odom = streams["joints"], streams["odom"]
    poses = {}
    for msg in odom.messages:
        stamp = (msg.header.stamp.sec, msg.header.stamp.nanosec)
        p, o = msg.pose.pose.position, msg.pose.pose.orientation
        w = msg.twist.twist.angular
        poses[stamp] = ([p.x, p.y, p.z], [o.x, o.y, o.z, o.w], [w.x, w.y, w.z])
    rows = [
        (msg, poses[key])
        for msg in joints.messages
        if (key := (msg.header.stamp.sec, msg.header.stamp.nanosec)) in poses
    ]
    if len(rows) < 2:
        raise RnsError("fewer than two robot states were recorded; is DDS working on loopback?")
    commands = streams["commands"]
    return {
        "times": np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m, _ in rows]),
        "joint_positions": np.array([m.position for m, _ in rows]),
        "joint_velocities": np.array([m.velocity for m, _ in rows]),
        "base_positions": np.array([pose[0] for _, pose in rows]),
        "base_orientations": np.array([pose[1] for _, pose in rows]),
        "base_angular_velocities": np.array([pose[2] for _, pose in rows]),
        "angular_momentum": streams["momentum"].array(
            lambda m: [m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z]
        ),
        "command_times": commands.stamps() if len(commands) else np.zeros(0),
        "commands": commands.array(
            lambda m: [m.twist.angular.x, m.twist.angular.y, m.twist.angular.z]
        ).reshape(-1, 3),
    }


class PartialRecordingError(RnsError):
    """A run's recording misses samples: this process waited for a core longer than DDS held
    them. In lockstep the run itself is complete and repeatable, so it can be run again."""


class InterruptedRun(KeyboardInterrupt):
    """A run stopped by Ctrl-C or SIGTERM once its recordings were closed.

    Attributes:
        signum: the signal (SIGINT for Ctrl-C).
        row: the run's figures so far (its ``ended`` says so), None when its task had not
            started.
        unwritten: recordings of the run that could not be written, one line each.
    """

    def __init__(self, cause: KeyboardInterrupt, row, unwritten: list[str]) -> None:
        super().__init__(str(cause))
        self.signum = getattr(cause, "signum", signal.SIGINT)
        self.row = row
        self.unwritten = list(unwritten)


def missed_samples(stamps: np.ndarray) -> int:
    """How many samples of a periodic stream are missing between ``stamps`` [s], shape (k,),
    increasing: a gap of more than 1.5 periods (the median spacing) misses round(gap / period)
    - 1 of them. 0 for fewer than three stamps."""
    stamps = np.asarray(stamps, dtype=float)
    if len(stamps) < 3:
        return 0
    gaps = np.diff(stamps)
    period = float(np.median(gaps))
    if not period > 0.0:
        return 0
    long = gaps[gaps > 1.5 * period]
    return int(np.sum(np.round(long / period) - 1))


def _within(log: TopicLog, since: float, until: float) -> TopicLog:
    """``log`` without the messages stamped after ``until`` or before ``since`` [s] (messages
    without a header are kept)."""
    unbounded = until == np.inf and since == -np.inf
    if unbounded or not log.messages or not hasattr(log.messages[0], "header"):
        return log
    kept = TopicLog(log.topic)
    for msg, received in zip(log.messages, log.received, strict=True):
        if since <= header_seconds(msg) <= until:
            kept.messages.append(msg)
            kept.received.append(received)
    return kept
