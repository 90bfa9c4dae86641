"""One rerun recording of a running rns_ros system, fed with plain arrays (no rclpy).

:class:`TelemetryRecorder` owns a private ``RecordingStream`` and its sink. The rerun logger node
converts each message into arrays and calls one method; everything that is computed or logged
happens here, so tests drive it directly and read the ``.rrd`` back. Entity paths:
:mod:`rns_ros.viz.paths`.

Samples are buffered per entity and sent as columns (``send_columns`` with an explicit
``ros_time`` column) every ``send_period`` of wall time, and on :meth:`TelemetryRecorder.send` /
:meth:`TelemetryRecorder.close`: a ``log`` call per sample and entity costs 40-140 µs in rerun
0.41, which at 100 Hz on ~40 entities would take a third of a core (and of the GIL of a process
that may also run the simulator). Columns cost a few µs per sample.

Methods are thread-safe (one lock: the node's executor may run callbacks on several threads).
:meth:`TelemetryRecorder.close` sends what is pending, flushes and finalizes the sink: a saved
``.rrd`` is complete (footer included) when it returns.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections import defaultdict
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import rerun as rr

from rns_ros.control.controller import TwistFrame
from rns_ros.core.conventions import rotation_from_quaternion
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import as_vector
from rns_ros.viz import paths
from rns_ros.viz.blueprint import default_blueprint
from rns_ros.viz.quantities import (
    AttitudeDeviation,
    ControllerStatus,
    PtpStatus,
    RateLimiter,
    Trail,
    achieved_angular_velocity,
)
from rns_ros.viz.readback import rrd_problem
from rns_ros.viz.robot import RobotView
from rns_ros.viz.sinks import OpenSink, SinkSettings, open_sink

#: Stamps below this [ns] (2001-09-09) are simulated time: logged as durations, not timestamps.
SIM_TIME_LIMIT_NS = 10**18
#: Longest wait for buffered data to reach the sink when closing [s].
FLUSH_TIMEOUT = 10.0
_TEXT_LEVEL = {0: rr.TextLogLevel.INFO, 1: rr.TextLogLevel.WARN, 2: rr.TextLogLevel.ERROR}
_STREAMS = (
    "joints",
    "odom",
    "momentum",
    "status",
    "twist",
    "ptp_status",
    "ptp_goal",
    "energy",
    "wheels",
)
#: Ghost arm of a ptp goal: translucent so the real arm shows through it.
GHOST_COLOR = (120, 170, 255, 110)
GHOST_LINE_RADIUS = 0.03
GHOST_JOINT_RADIUS = 0.06


@dataclass(frozen=True)
class RecorderSettings:
    """What to record and how densely.

    Attributes:
        application_id: rerun application id (recordings with the same id share a blueprint).
        recording_name: name shown in the viewer's recording list; empty: rerun's default.
        trail_length: camera trail points kept [-]; 0 disables the trail.
        trail_period: stamp time between two trail points [s].
        max_rate: highest logged rate per input stream [Hz]; 0 logs every message.
        send_period: wall time between two batches sent to the sink [s]; 0 sends every sample.
    """

    application_id: str = "rns_ros"
    recording_name: str = ""
    trail_length: int = 300
    trail_period: float = 0.1
    max_rate: float = 200.0
    send_period: float = 0.1

    def __post_init__(self) -> None:
        if not self.application_id:
            raise ConfigError("application_id must not be empty")
        if self.trail_length < 0:
            raise ConfigError(f"trail_length must be >= 0, got {self.trail_length}")
        for name in ("trail_period", "max_rate", "send_period"):
            value = getattr(self, name)
            if not value >= 0.0:
                raise ConfigError(f"{name} must be >= 0, got {value}")


class _Rows:
    """Samples of one entity waiting to be sent: stamps [ns] and one payload per stamp."""

    __slots__ = ("rows", "stamps")

    def __init__(self) -> None:
        self.stamps: list[int] = []
        self.rows: list = []

    def add(self, stamp_ns: int, row) -> None:
        self.stamps.append(stamp_ns)
        self.rows.append(row)

    def take(self) -> tuple[list[int], list]:
        stamps, rows = self.stamps, self.rows
        self.stamps, self.rows = [], []
        return stamps, rows


class TelemetryRecorder:
    """A rerun recording of one robot: 3D scene, time series, controller log.

    Args:
        robot: the model (for forward kinematics and the joint order).
        urdf_path: the URDF ``robot`` was built from (the viewer draws its geometry).
        sink: where the recording goes.
        settings: :class:`RecorderSettings`.
        env: environment for ``auto`` sink resolution (tests); None = ``os.environ``.

    Raises:
        ModelError: rerun cannot read the URDF or its joints do not match ``robot``.
        SinkError: the sink could not be opened.
    """

    def __init__(
        self,
        robot: FreeFloatingModel,
        urdf_path: str | Path,
        sink: SinkSettings,
        settings: RecorderSettings | None = None,
        env: Mapping[str, str] | None = None,
    ) -> None:
        self.robot = robot
        self.settings = settings or RecorderSettings()
        self.view = RobotView(robot, urdf_path)
        self._lock = threading.Lock()
        self._closed = False
        #: why a saved recording could not be written whole (it is removed), else None
        self.problem: str | None = None
        # A private stream with a fresh id: several recorders can live in one process.
        self.rec = rr.RecordingStream(self.settings.application_id, recording_id=uuid.uuid4())
        self.sink: OpenSink = open_sink(self.rec, sink, self._blueprint(), env)
        if self.settings.recording_name:
            self.rec.send_recording_name(self.settings.recording_name)
        self.view.log_static(self.rec)
        for path, series in self._series_table().items():
            self.rec.log(
                path, rr.SeriesLines(names=series.label, colors=[series.color]), static=True
            )

        self._time_kind: str | None = None
        self._limiters = {name: RateLimiter(self.settings.max_rate) for name in self.STREAMS}
        self._scalars: defaultdict[str, _Rows] = defaultdict(_Rows)
        self._joints = _Rows()  # (theta, camera origin, camera +z axis)
        self._base = _Rows()  # (position, quaternion xyzw)
        self._last_send = time.monotonic()
        self._trail = Trail(self.settings.trail_length, self.settings.trail_period)
        self._attitude = AttitudeDeviation()
        self._base_position = np.zeros(3)
        self._base_orientation = np.array([0.0, 0.0, 0.0, 1.0])
        self._base_omega: np.ndarray | None = None
        self._base_logged = False
        self._state: FreeFloatingState | None = None
        self._controller_state: str | None = None
        self._ptp_step: tuple[str | None, str | None] = (None, None)  # (state, phase)
        #: Messages recorded per input stream (the others were above ``max_rate``).
        self.counts = dict.fromkeys(self.STREAMS, 0)

    #: Input streams, each with its rate limiter and message count.
    STREAMS: tuple[str, ...] = _STREAMS

    def _blueprint(self):
        """The default viewer layout sent with the recording (subclasses: their own)."""
        return default_blueprint()

    def _series_table(self) -> dict[str, paths.Series]:
        """Legend label and colour of every time series (logged as static styles)."""
        return paths.series_table(self.robot.joint_names)

    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def state(self) -> FreeFloatingState | None:
        """The state at the newest recorded joint state (None before the first)."""
        return self._state

    # --- inputs ---------------------------------------------------------------------------------
    def joint_state(self, stamp_ns: int, theta, theta_dot=None) -> None:
        """Joint angles [rad] (n,) and optionally velocities [rad/s] (n,), model order.

        Records the joint transforms, the camera arrow and trail, joint velocities and the
        achieved camera angular velocity (with the newest base pose and twist).

        Raises:
            InputError: wrong length or not finite.
        """
        with self._lock:
            if not self._accept("joints", stamp_ns):
                return
            q = self.robot.configuration(theta, self._base_position, self._base_orientation)
            state = FreeFloatingState.compute(self.robot, q)
            if theta_dot is not None:
                theta_dot = as_vector(theta_dot, self.robot.n, "joint velocities")
            self._state = state
            self.counts["joints"] += 1
            if not self._base_logged:  # connect the robot to the world before any odometry
                self._base.add(stamp_ns, (self._base_position, self._base_orientation))
                self._base_logged = True
            camera = state.camera
            self._joints.add(stamp_ns, (state.theta, camera.position, camera.rotation[:, 2]))
            if self._trail.add(stamp_ns, camera.position):
                self._set_time(stamp_ns)
                self.view.log_trail(self.rec, self._trail.strip())
            if theta_dot is not None:
                for joint, value in zip(self.robot.joint_names, theta_dot, strict=True):
                    self._scalar(paths.joint_velocity(joint), stamp_ns, value)
                omega = achieved_angular_velocity(state, theta_dot, self._base_omega)
                self._vector(paths.ACHIEVED_ANGULAR_VELOCITY_AXES, stamp_ns, omega)
            self._send_if_due()

    def base_odom(
        self, stamp_ns: int, position, quaternion_xyzw, angular_velocity_base=None
    ) -> None:
        """Base pose in world (position [m] (3,), quaternion x y z w (4,)) and optionally its
        angular velocity in base axes [rad/s] (3,). Records the base pose and attitude deviation.

        Raises:
            InputError: not finite, or a zero quaternion.
        """
        with self._lock:
            rotation = rotation_from_quaternion(quaternion_xyzw)  # validates before storing
            position = as_vector(position, 3, "base position")
            quaternion = np.asarray(quaternion_xyzw, dtype=float)
            self._base_position = position
            self._base_orientation = quaternion / np.linalg.norm(quaternion)
            if angular_velocity_base is not None:
                self._base_omega = as_vector(angular_velocity_base, 3, "base angular velocity")
            if not self._accept("odom", stamp_ns):
                return
            self.counts["odom"] += 1
            self._base.add(stamp_ns, (position, self._base_orientation))
            self._base_logged = True
            deviation = self._attitude(rotation)
            for path, value in zip(paths.BASE_ATTITUDE_SERIES, deviation, strict=True):
                self._scalar(path, stamp_ns, value)
            self._send_if_due()

    def momentum(self, stamp_ns: int, linear, angular) -> None:
        """System momentum: linear p [kg m/s] (3,), angular about the CoM [kg m^2/s] (3,)."""
        with self._lock:
            if not self._accept("momentum", stamp_ns):
                return
            self.counts["momentum"] += 1
            self._scalar(paths.MOMENTUM_LINEAR, stamp_ns, np.linalg.norm(linear))
            self._scalar(paths.MOMENTUM_ANGULAR, stamp_ns, np.linalg.norm(angular))
            self._send_if_due()

    def controller_status(
        self, stamp_ns: int, values: Mapping[str, str], level: int = 0, message: str = ""
    ) -> None:
        """One controller status (key/values as published by rns_controller, diagnostic level
        0 OK / 1 WARN / 2 ERROR, message). Missing or unparsable keys are skipped; the state
        goes to ``log/controller`` when it changes."""
        with self._lock:
            if not self._accept("status", stamp_ns):
                return
            self.counts["status"] += 1
            status = ControllerStatus.parse(values)
            scalars = {
                paths.SIGMA_MIN: status.sigma_min,
                paths.DET_KINEMATIC: status.det_kinematic,
                paths.DET_COUPLING: status.det_coupling,
                paths.DET_ALGORITHMIC: status.det_algorithmic,
                paths.CONTROLLER_DAMPING: status.damping,
                paths.CONTROLLER_SPEED_SCALE: status.speed_scale,
                paths.CONTROLLER_STATE: paths.CONTROLLER_STATE_CODES.get(status.state or ""),
            }
            for path, value in scalars.items():
                if value is not None:
                    self._scalar(path, stamp_ns, value)
            if status.coupling_momentum is not None:
                self._vector(paths.COUPLING_MOMENTUM_AXES, stamp_ns, status.coupling_momentum)
                norm = np.linalg.norm(status.coupling_momentum)
                self._scalar(paths.COUPLING_MOMENTUM_NORM, stamp_ns, norm)
            if status.state is not None and status.state != self._controller_state:
                self._controller_state = status.state
                self._set_time(stamp_ns)
                self.rec.log(
                    paths.CONTROLLER_LOG,
                    rr.TextLog(message or status.state, level=_TEXT_LEVEL.get(level)),
                )
            self._send_if_due()

    def commanded_twist(self, stamp_ns: int, angular, frame: TwistFrame | str) -> bool:
        """Operator's angular velocity [rad/s] (3,) in ``frame`` axes, recorded in world axes.

        ``base`` axes turn with the newest odometry, ``camera`` axes with the camera at the newest
        joint state. Returns False (nothing recorded) for ``camera`` before the first joint state.

        Raises:
            ConfigError: unknown frame. InputError: not a finite 3-vector.
        """
        frame = TwistFrame.parse(frame)
        angular = as_vector(angular, 3, "commanded angular velocity")
        with self._lock:
            if frame is TwistFrame.CAMERA:
                if self._state is None:
                    return False
                omega = self._state.camera.rotation @ angular
            elif frame is TwistFrame.BASE:
                omega = rotation_from_quaternion(self._base_orientation) @ angular
            else:
                omega = angular
            if self._accept("twist", stamp_ns):
                self.counts["twist"] += 1
                self._vector(paths.COMMANDED_ANGULAR_VELOCITY_AXES, stamp_ns, omega)
                self._send_if_due()
            return True

    def energy(self, stamp_ns: int, values: Mapping[str, float]) -> None:
        """One sample of rns_simulator's ``energy`` topic as {label: value} (labels of its
        layout: base, arm, coupling, wheels, total [J], lambda_arm, lambda_wheels [J], c_max [J],
        c_sum [J s]); unknown labels are skipped, a non-finite value is an InputError."""
        paths_by_label = {term: paths.energy_term(term) for term in paths.ENERGY_TERMS}
        paths_by_label |= {f"lambda_{p}": paths.energy_lambda(p) for p in paths.ENERGY_LAMBDA}
        paths_by_label |= {name: paths.energy_cost(name) for name in paths.ENERGY_COSTS}
        rows = {paths_by_label[k]: v for k, v in values.items() if k in paths_by_label}
        if not np.isfinite(list(rows.values())).all():
            raise InputError(f"energy values must be finite, got {dict(values)}")
        with self._lock:
            if not self._accept("energy", stamp_ns):
                return
            self.counts["energy"] += 1
            for path, value in rows.items():
                self._scalar(path, stamp_ns, value)
            self._send_if_due()

    def wheel_state(self, stamp_ns: int, speeds, torques) -> None:
        """Reaction wheels: rates relative to the base [rad/s] (3,) and applied torques [N m]
        (3,), base x y z.

        Raises:
            InputError: not finite 3-vectors.
        """
        speeds = as_vector(speeds, 3, "wheel speeds")
        torques = as_vector(torques, 3, "wheel torques")
        with self._lock:
            if not self._accept("wheels", stamp_ns):
                return
            self.counts["wheels"] += 1
            self._vector(paths.WHEEL_SPEED_AXES, stamp_ns, speeds)
            self._vector(paths.WHEEL_TORQUE_AXES, stamp_ns, torques)
            self._send_if_due()

    def ptp_status(
        self, stamp_ns: int, values: Mapping[str, str], level: int = 0, message: str = ""
    ) -> None:
        """One rns_ptp status (key/values as published, diagnostic level, message): phase code,
        progress and the predicted coupling momentum norm; ``log/ptp`` gets a line whenever the
        state or the phase changes. Missing or unparsable keys are skipped."""
        with self._lock:
            if not self._accept("ptp_status", stamp_ns):
                return
            self.counts["ptp_status"] += 1
            status = PtpStatus.parse(values)
            if status.phase in paths.PTP_PHASE_CODES:
                self._scalar(paths.PTP_PHASE, stamp_ns, paths.PTP_PHASE_CODES[status.phase])
            if status.progress is not None:
                self._scalar(paths.PTP_PROGRESS, stamp_ns, status.progress)
            if status.coupling_momentum is not None:
                self._scalar(paths.COUPLING_MOMENTUM_NORM, stamp_ns, status.coupling_momentum)
            step = (status.state, status.phase)
            if status.state is not None and step != self._ptp_step:
                self._ptp_step = step
                self._set_time(stamp_ns)
                text = message or status.state
                if status.phase is not None:
                    text = f"phase {status.phase}: {text}"
                self.rec.log(paths.PTP_LOG, rr.TextLog(text, level=_TEXT_LEVEL.get(level)))
            self._send_if_due()

    def ptp_goal(self, stamp_ns: int, theta_goal=None) -> None:
        """A point-to-point goal: the ghost arm at joint angles ``theta_goal`` [rad] (n,), placed
        at the newest base pose; None (a deployment, whose end is not a fixed configuration)
        clears the ghost.

        Raises:
            InputError: wrong length or not finite.
        """
        with self._lock:
            if theta_goal is not None:
                q = self.robot.configuration(
                    theta_goal, self._base_position, self._base_orientation
                )
            if not self._accept("ptp_goal", stamp_ns):
                return
            self.counts["ptp_goal"] += 1
            self._set_time(stamp_ns)
            if theta_goal is None:
                self.rec.log(paths.PTP_GOAL, rr.Clear(recursive=True))
                return
            points = self.robot.skeleton(q)
            self.rec.log(
                paths.PTP_GOAL,
                rr.LineStrips3D([points], colors=[GHOST_COLOR], radii=[GHOST_LINE_RADIUS]),
            )
            self.rec.log(
                paths.PTP_GOAL_JOINTS,
                rr.Points3D(points, colors=[GHOST_COLOR], radii=[GHOST_JOINT_RADIUS]),
            )

    # --- sending, closing -----------------------------------------------------------------------
    def send(self) -> None:
        """Send every buffered sample to the sink now (the node calls this from a timer so a
        quiet system still shows its last samples)."""
        with self._lock:
            if not self._closed:
                self._send()

    def close(self) -> None:
        """Send what is pending, flush, finalize the sink (idempotent).

        For ``save`` the file is complete when this returns, or else removed and
        :attr:`problem` says why (a full disk or a file-size limit stops rerun's file writer:
        the file is read back whole, as ``rerun rrd verify`` does); a ``serve`` web viewer is
        stopped.
        """
        with self._lock:
            if self._closed:
                return
            self._closed = True
            stopped = None
            try:
                self._send()
                self.rec.flush(timeout_sec=FLUSH_TIMEOUT)
            except RuntimeError as exc:  # "File-writer thread shut down prematurely"
                stopped = " ".join(str(exc).split())
            finally:
                # disconnect() finalizes file sinks (writes the footer) and closes connections.
                self.rec.disconnect()
                self.sink.close()
            path = self.sink.rrd_path
            if path is not None and (problem := rrd_problem(path) or stopped):
                self.problem = f"cannot write {path}: {problem}; the file is removed"
                path.unlink(missing_ok=True)

    # --- helpers --------------------------------------------------------------------------------
    def _accept(self, stream: str, stamp_ns: int) -> bool:
        """False when closed or when ``stream`` is above ``max_rate``."""
        if self._closed or not self._limiters[stream].accept(stamp_ns):
            return False
        if self._time_kind is None:
            # A timeline's type is fixed: mixing durations and timestamps corrupts the file.
            self._time_kind = "duration" if stamp_ns < SIM_TIME_LIMIT_NS else "timestamp"
        return True

    def _set_time(self, stamp_ns: int) -> None:
        """Timeline for the next ``log`` call (rerun keeps it per thread: set it every time)."""
        if self._time_kind == "duration":
            self.rec.set_time(paths.TIMELINE, duration=np.timedelta64(stamp_ns, "ns"))
        else:
            self.rec.set_time(paths.TIMELINE, timestamp=np.datetime64(stamp_ns, "ns"))

    def _time_column(self, stamps: list[int]) -> rr.TimeColumn:
        stamps = np.asarray(stamps, dtype=np.int64)
        if self._time_kind == "duration":
            return rr.TimeColumn(paths.TIMELINE, duration=stamps.astype("timedelta64[ns]"))
        return rr.TimeColumn(paths.TIMELINE, timestamp=stamps.astype("datetime64[ns]"))

    def _scalar(self, path: str, stamp_ns: int, value) -> None:
        self._scalars[path].add(stamp_ns, float(value))

    def _vector(self, entity_paths: tuple[str, ...], stamp_ns: int, vector) -> None:
        for path, value in zip(entity_paths, vector, strict=True):
            self._scalars[path].add(stamp_ns, float(value))

    def _send_if_due(self) -> None:
        if time.monotonic() - self._last_send >= self.settings.send_period:
            self._send()

    def _send(self) -> None:
        self._last_send = time.monotonic()
        rec, view = self.rec, self.view
        for path, pending in self._scalars.items():
            stamps, values = pending.take()
            if stamps:
                rec.send_columns(
                    path,
                    indexes=[self._time_column(stamps)],
                    columns=rr.Scalars.columns(scalars=np.asarray(values)),
                )
        stamps, rows = self._base.take()
        if stamps:
            positions, quaternions = zip(*rows, strict=True)
            columns = view.base_pose_columns(np.array(positions), np.array(quaternions))
            rec.send_columns(paths.BASE_POSE, indexes=[self._time_column(stamps)], columns=columns)
        stamps, rows = self._joints.take()
        if stamps:
            theta, origins, axes = (np.array(part) for part in zip(*rows, strict=True))
            times = self._time_column(stamps)
            for path, columns in view.joint_columns(theta):
                rec.send_columns(path, indexes=[times], columns=columns)
            rec.send_columns(
                paths.CAMERA_POINTING, indexes=[times], columns=view.camera_columns(origins, axes)
            )
