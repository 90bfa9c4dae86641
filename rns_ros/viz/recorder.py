"""One rerun recording of a running rns_ros system, fed with plain arrays (no rclpy).

:class:`TelemetryRecorder` owns a private ``RecordingStream`` and its sink. The rerun logger node
converts each message into arrays and calls one method; everything that is computed or logged
happens here, so tests drive it directly and read the ``.rrd`` back. Entity paths:
:mod:`rns_ros.viz.paths`.

Samples are buffered per entity and sent as columns (``send_columns`` with an explicit
``ros_time`` column) in blocks: once per flush tick of wall time, as soon as one entity holds
``flush_num_rows`` rows, and on :meth:`TelemetryRecorder.send` / :meth:`TelemetryRecorder.close`.
A ``log`` call per sample and entity costs 40-140 µs in rerun 0.41, which at 100 Hz on ~40
entities would take a third of a core (and of the GIL of a process that may also run the
simulator); columns cost a few µs per sample.

Each block becomes one chunk: rerun sends ``send_columns`` data as it is given, past its chunk
batcher. Small chunks are what a viewer pays for: every chunk carries its own schema, row ids
and index entries. The rows still logged one at a time (camera trail, controller and ptp logs,
ghost arm, static data) go through the private stream's batcher, configured with the same
thresholds (:meth:`RecorderSettings.batcher_config`). The tick is what a live viewer waits at
most (``flush_tick``, 1 s: a 100 Hz stream arrives in chunks of 100 rows); a file has no one
waiting and gets the longer ``file_flush_tick``.

Methods are thread-safe (one lock: the node's executor may run callbacks on several threads).
:meth:`TelemetryRecorder.close` sends what is pending, flushes and finalizes the sink: a saved
``.rrd`` is complete (footer included) when it returns.
"""

from __future__ import annotations

import math
import threading
import time
import uuid
from collections import defaultdict
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from datetime import timedelta
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
from rns_ros.viz.sinks import OpenSink, SinkKind, SinkSettings, open_sink, resolve_kind

#: Stamps below this [ns] (2001-09-09) are simulated time: logged as durations, not timestamps.
SIM_TIME_LIMIT_NS = 10**18
#: Longest wait for buffered data to reach the sink when closing [s].
FLUSH_TIMEOUT = 10.0
#: Largest accepted flush tick [s]: beyond it a live view would look stopped.
MAX_FLUSH_TICK = 60.0
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
    "predicted",
    "telemetry",
    "ground_predictor",
    "ground_link",
)
#: Ghost arm of a ptp goal: translucent so the real arm shows through it.
GHOST_COLOR = (120, 170, 255, 110)
#: The ground's arms (ground_arm): the prediction orange, the received telemetry grey.
GROUND_ARMS = {
    "predicted": (paths.PREDICTED_ARM, paths.PREDICTED_ARM_JOINTS, (255, 150, 40, 150)),
    "telemetry": (paths.TELEMETRY_ARM, paths.TELEMETRY_ARM_JOINTS, (160, 160, 160, 130)),
}
GHOST_LINE_RADIUS = 0.03
GHOST_JOINT_RADIUS = 0.06
#: The predicted camera's frustum, drawn for orientation only (the thesis gives no camera
#: model): vertical field of view [rad], width / height, and the drawn depth [m].
FRUSTUM_FOV_Y = np.deg2rad(60.0)
FRUSTUM_ASPECT = 4.0 / 3.0
FRUSTUM_DEPTH = 0.4
#: rns_predictor's status keys logged under paths.PREDICTION_ERROR.
PREDICTION_ERROR_KEYS = {
    "prediction_error_camera_deg": paths.PREDICTION_ERROR_CAMERA,
    "prediction_error_base_deg": paths.PREDICTION_ERROR_BASE,
}
#: rns_link's status keys ("<direction> <key>") logged under paths.LINK/<direction>/<figure>.
LINK_KEYS = {"last delay [s]": "delay_s", "in flight": "in_flight", "lost": "lost"}
LINK_DIRECTIONS = ("uplink", "downlink")


@dataclass(frozen=True)
class RecorderSettings:
    """What to record, how densely, and in what chunks.

    Attributes:
        application_id: rerun application id (recordings with the same id share a blueprint).
        recording_name: name shown in the viewer's recording list; empty: rerun's default.
        trail_length: camera trail points kept [-]; 0 disables the trail.
        trail_period: stamp time between two trail points [s].
        max_rate: highest logged rate per input stream [Hz]; 0 logs every message.
        flush_tick: longest wall time a sample waits in this process before it is sent to a
            live sink (spawn, connect, serve) [s]: the period of the column blocks and the tick
            of rerun's chunk batcher. A viewer shows a sample within about this time; a 100 Hz
            stream is sent in chunks of ``100 * flush_tick`` rows.
        file_flush_tick: the same for the ``save`` sink [s]: longer, as nobody watches the
            file grow, so a run slower than real time still makes chunks of many rows.
        flush_num_rows: rows of one entity that are sent at once, before the tick [-]: the
            largest chunk. The default is the row limit up to which rerun's chunk store
            compacts chunks, so a viewer keeps these chunks as they are.
        flush_num_bytes: bytes of one entity's rows logged one at a time (camera trail, logs)
            that make rerun's batcher send them before the tick [bytes]; rerun 0.41's default.
    """

    application_id: str = "rns_ros"
    recording_name: str = ""
    trail_length: int = 300
    trail_period: float = 0.1
    max_rate: float = 200.0
    flush_tick: float = 1.0
    file_flush_tick: float = 10.0
    flush_num_rows: int = 4096
    flush_num_bytes: int = 2 << 20

    def __post_init__(self) -> None:
        if not self.application_id:
            raise ConfigError("application_id must not be empty")
        if self.trail_length < 0:
            raise ConfigError(f"trail_length must be >= 0, got {self.trail_length}")
        for name in ("trail_period", "max_rate"):
            value = getattr(self, name)
            if not value >= 0.0:
                raise ConfigError(f"{name} must be >= 0, got {value}")
        for name in ("flush_tick", "file_flush_tick"):
            value = getattr(self, name)
            if not 0.0 < value <= MAX_FLUSH_TICK:
                raise ConfigError(f"{name} must be in (0, {MAX_FLUSH_TICK}] s, got {value}")
        for name in ("flush_num_rows", "flush_num_bytes"):
            value = getattr(self, name)
            if value < 1:
                raise ConfigError(f"{name} must be >= 1, got {value}")

    def tick(self, kind: SinkKind | str) -> float:
        """The flush tick for a sink of ``kind`` [s]: ``file_flush_tick`` for ``save``, else
        ``flush_tick``."""
        return self.file_flush_tick if SinkKind.parse(kind) is SinkKind.SAVE else self.flush_tick

    def batcher_config(self, kind: SinkKind | str) -> rr.ChunkBatcherConfig:
        """The thresholds of rerun's chunk batcher for the rows logged one at a time to a sink
        of ``kind`` (given to the stream explicitly, they also apply to network sinks, whose
        default tick is 8 ms, and win over rerun's ``RERUN_FLUSH_*`` variables)."""
        return rr.ChunkBatcherConfig(
            flush_tick=timedelta(seconds=self.tick(kind)),
            flush_num_bytes=self.flush_num_bytes,
            flush_num_rows=self.flush_num_rows,
        )


class _Rows:
    """Samples of one entity waiting to be sent: stamps [ns] and one payload per stamp."""

    __slots__ = ("rows", "stamps")

    def __init__(self) -> None:
        self.stamps: list[int] = []
        self.rows: list = []

    def __len__(self) -> int:
        return len(self.stamps)

    def add(self, stamp_ns: int, row) -> int:
        """Append one sample; returns the number now waiting."""
        self.stamps.append(stamp_ns)
        self.rows.append(row)
        return len(self.stamps)

    def take(self, minimum: int = 1) -> tuple[list[int], list]:
        """All waiting samples when there are at least ``minimum``, else none (kept)."""
        if len(self.stamps) < minimum:
            return [], []
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
        clock: wall clock [s] that times the flush tick (tests pace a run with it); None =
            ``time.monotonic``. rerun's batcher keeps its own clock.

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
        clock: Callable[[], float] | None = None,
    ) -> None:
        self.robot = robot
        self.settings = settings or RecorderSettings()
        self._clock = clock or time.monotonic
        self.view = RobotView(robot, urdf_path)
        self._lock = threading.Lock()
        self._closed = False
        #: why a saved recording could not be written whole (it is removed), else None
        self.problem: str | None = None
        # A private stream with a fresh id: several recorders can live in one process.
        self.rec = rr.RecordingStream(
            self.settings.application_id,
            recording_id=uuid.uuid4(),
            batcher_config=self.settings.batcher_config(resolve_kind(sink.kind, env)),
        )
        self.sink: OpenSink = open_sink(self.rec, sink, self._blueprint(), env)
        #: Wall time between two blocks [s] (a spawn that fell back to save: the file's).
        self.flush_tick = self.settings.tick(self.sink.kind)
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
        self._last_send = self._clock()
        self._full = False  # some entity holds flush_num_rows rows
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
                self._add(self._base, stamp_ns, (self._base_position, self._base_orientation))
                self._base_logged = True
            camera = state.camera
            self._add(self._joints, stamp_ns, (state.theta, camera.position, camera.rotation[:, 2]))
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
            self._add(self._base, stamp_ns, (position, self._base_orientation))
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

    def ground_arm(self, kind: str, stamp_ns: int, q) -> None:
        """One of the ground's arms (:data:`GROUND_ARMS`): ``predicted``, rns_predictor's arm for
        the on-board instant ``stamp_ns``; ``telemetry``, the arm the ground has received by
        ``stamp_ns``. Drawn as a ghost (base, joint origins, camera) of configuration ``q``
        (7 + n,) [m, rad].

        Raises:
            InputError: an unknown kind, or ``q`` of the wrong length or not finite.
        """
        if kind not in GROUND_ARMS:
            raise InputError(f"ground arm must be one of {list(GROUND_ARMS)}, got {kind!r}")
        q = as_vector(q, self.robot.model.nq, f"{kind} arm q")
        path, joints_path, color = GROUND_ARMS[kind]
        with self._lock:
            if not self._accept(kind, stamp_ns):
                return
            self.counts[kind] += 1
            self._set_time(stamp_ns)
            points = self.robot.skeleton(q)
            strip = rr.LineStrips3D([points], colors=[color], radii=[GHOST_LINE_RADIUS])
            self.rec.log(path, strip)
            spheres = rr.Points3D(points, colors=[color], radii=[GHOST_JOINT_RADIUS])
            self.rec.log(joints_path, spheres)
            if kind == "predicted":
                rotation, position = self.robot.camera_pose(q)
                self.rec.log(
                    paths.PREDICTED_CAMERA,
                    rr.Transform3D(translation=position, mat3x3=rotation),
                    rr.Pinhole(
                        fov_y=FRUSTUM_FOV_Y,
                        aspect_ratio=FRUSTUM_ASPECT,
                        camera_xyz=rr.ViewCoordinates.RDF,  # +z forward: the optical axis
                        image_plane_distance=FRUSTUM_DEPTH,
                        color=color,
                    ),
                )

    def ground_status(self, source: str, stamp_ns: int, values: Mapping[str, str]) -> int:
        """The ground's figures from one status of ``source``: ``predictor`` (rns_predictor:
        the prediction error, :data:`PREDICTION_ERROR_KEYS`) or ``link`` (rns_link: per
        direction the newest delay, the messages in flight and those lost, :data:`LINK_KEYS`),
        key/values as published. Values that do not parse as finite numbers are skipped.
        Returns the number of scalars logged.

        Raises:
            InputError: an unknown source.
        """
        if source == "predictor":
            scalars = {path: values.get(key) for key, path in PREDICTION_ERROR_KEYS.items()}
        elif source == "link":
            scalars = {
                f"{paths.LINK}/{direction}/{figure}": values.get(f"{direction} {key}")
                for direction in LINK_DIRECTIONS
                for key, figure in LINK_KEYS.items()
            }
        else:
            raise InputError(f"ground status source must be 'predictor' or 'link', got {source!r}")
        logged = 0
        with self._lock:
            if not self._accept(f"ground_{source}", stamp_ns):
                return 0
            for path, text in scalars.items():
                try:
                    value = float(text) if text is not None else math.nan
                except ValueError:
                    continue
                if math.isfinite(value):
                    self._scalar(path, stamp_ns, value)
                    logged += 1
            if logged:
                self.counts[f"ground_{source}"] += 1
            self._send_if_due()
        return logged

    # --- sending, closing -----------------------------------------------------------------------
    @property
    def pending_rows(self) -> int:
        """Rows waiting in this process to be sent (the largest count over the entities)."""
        with self._lock:
            return max((len(rows) for rows in self._buffers()), default=0)

    def send(self) -> None:
        """Send every buffered sample to the sink now."""
        with self._lock:
            if not self._closed:
                self._send()

    def send_due(self) -> None:
        """Send the buffered samples if :attr:`flush_tick` has passed since the last block
        (the node calls this from a timer, so a quiet system still shows its newest samples)."""
        with self._lock:
            if not self._closed:
                self._send_if_due()

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

    def _add(self, pending: _Rows, stamp_ns: int, row) -> None:
        if pending.add(stamp_ns, row) >= self.settings.flush_num_rows:
            self._full = True

    def _scalar(self, path: str, stamp_ns: int, value) -> None:
        self._add(self._scalars[path], stamp_ns, float(value))

    def _vector(self, entity_paths: tuple[str, ...], stamp_ns: int, vector) -> None:
        for path, value in zip(entity_paths, vector, strict=True):
            self._add(self._scalars[path], stamp_ns, float(value))

    def _buffers(self) -> list[_Rows]:
        """Every buffer of samples (subclasses add theirs)."""
        return [*self._scalars.values(), self._base, self._joints]

    def _send_if_due(self) -> None:
        if self._clock() - self._last_send >= self.flush_tick:
            self._send()
        elif self._full:
            # only the full entities: the others keep filling their blocks until the tick
            self._send(minimum_rows=self.settings.flush_num_rows)

    def _send(self, minimum_rows: int = 1) -> None:
        """Send the buffers holding at least ``minimum_rows`` rows, each as one chunk per
        entity (1: all, and the next tick starts now)."""
        if minimum_rows <= 1:
            self._last_send = self._clock()
        self._full = False
        rec, view = self.rec, self.view
        for path, pending in self._scalars.items():
            stamps, values = pending.take(minimum_rows)
            if stamps:
                rec.send_columns(
                    path,
                    indexes=[self._time_column(stamps)],
                    columns=rr.Scalars.columns(scalars=np.asarray(values)),
                )
        stamps, rows = self._base.take(minimum_rows)
        if stamps:
            positions, quaternions = zip(*rows, strict=True)
            columns = view.base_pose_columns(np.array(positions), np.array(quaternions))
            rec.send_columns(paths.BASE_POSE, indexes=[self._time_column(stamps)], columns=columns)
        stamps, rows = self._joints.take(minimum_rows)
        if stamps:
            theta, origins, axes = (np.array(part) for part in zip(*rows, strict=True))
            times = self._time_column(stamps)
            for path, columns in view.joint_columns(theta):
                rec.send_columns(path, indexes=[times], columns=columns)
            rec.send_columns(
                paths.CAMERA_POINTING, indexes=[times], columns=view.camera_columns(origins, axes)
            )
