r"""The Part II contact tasks in rerun: a fixed-base arm, its environment, contact and force arrows.

Thesis Part II (chapters 6-7) over ROS 2 (docs/part2_ros.md is the contract): ``rns_simulator`` in
contact mode publishes ``joint_states``, the latched ``environment`` (JSON), ``contact`` and
``wrist_wrench``; ``rns_force_controller`` publishes its task errors on ``~/errors``. This module
turns those, as plain values (no rclpy), into a rerun recording:

* :class:`ContactRecorder`, a :class:`~rns_ros.viz.recorder.TelemetryRecorder` for a
  :class:`~rns_ros.core.fixed_base.FixedBaseModel`: the URDF arm posed from ``joint_states``
  (base link fixed at the world origin), the environment as static entities, the contact point,
  the measured and the commanded force arrows, and the force / position-error / contact series.
  Entity paths: :mod:`rns_ros.viz.paths` (Part II section).
* :func:`parse_environment`, :class:`ContactSample`, :class:`ForceErrorSample`: the message
  contents checked (finite, complete) before anything is logged.
* :func:`load_arm_model`: a model YAML with ``ee_frame`` is a fixed-base arm, any other the
  free-floating robot.

Arrows (world axes, at the end-effector point p_e of the newest joint state, Pinocchio forward
kinematics of the model):

    measured   = R_e f_wrist * force_arrow_scale   (f_wrist: ``wrist_wrench`` force, EE axes [N];
                                                    the force the EE exerts on the environment,
                                                    so it points into it while pushing)
    commanded  = f_des n * force_arrow_scale        (f_des [N] and the unit normal n of the
                                                    force controller's errors sample; eq. 6.34's
                                                    force set-point along the contact normal)

Both point into the environment while the arm pushes; on a held contact they coincide.

Rates: ``contact``, ``wrist_wrench`` and the errors come at the simulator's 1 kHz; each stream is
logged at most at ``contact_log_rate`` [Hz] (:class:`ContactSettings`), by the sample's own clock
(``time`` of ``contact`` and of the errors, the header stamp of ``wrist_wrench``), so the viewer
is not flooded. ``contact`` and errors samples carry no header: they are placed on the timeline at
the newest ``joint_states`` stamp (the node passes it), like rns_simulator's ``energy``.
"""

from __future__ import annotations

import contextlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import rerun as rr

from rns_ros.control.contact_topics import ERROR_LABELS
from rns_ros.core.config import load_model
from rns_ros.core.contact_geometry import ArcConstraint, PlaneConstraint
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.fixed_base import FixedBaseModel, load_fixed_base_model
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import as_vector
from rns_ros.core.yaml_input import read_yaml_file
from rns_ros.viz import paths
from rns_ros.viz.blueprint import contact_blueprint
from rns_ros.viz.quantities import RateLimiter
from rns_ros.viz.recorder import TelemetryRecorder, _Rows

#: Wall plate drawn for ``{"type": "wall"}``: half extents in its plane and half thickness [m].
WALL_HALF_SIZE = (0.3, 0.3, 0.001)
#: Length of the cylinder drawn for ``{"type": "arc"}``, along its axis [m].
ARC_LENGTH = 0.4
#: Length of the wall normal arrow [m].
NORMAL_ARROW_LENGTH = 0.1
ENVIRONMENT_COLOR = (170, 170, 190, 90)
NORMAL_COLOR = (90, 90, 110)
#: Contact point colour per contact_state: +1 pushing, 0 no load, -1 pulling.
CONTACT_STATE_COLORS = {1: (40, 170, 60), 0: (150, 150, 150), -1: (220, 40, 40)}
CONTACT_POINT_RADIUS = 0.012
FORCE_MEASURED_COLOR = (60, 110, 230)
FORCE_DESIRED_COLOR = (255, 150, 0)
FORCE_ARROW_RADIUS = 0.006
#: Streams of a contact recording (counts and rate limiters).
CONTACT_STREAMS = ("joints", "environment", "contact", "wrench", "errors")


def labelled_values(labels_text: str, data, default_labels: tuple[str, ...], what: str) -> dict:
    """{label: value} of a Float64MultiArray: labels = its ``layout.dim[0].label`` split on
    spaces (the publisher's own layout), or ``default_labels`` when it carries none.

    Raises:
        InputError: the number of values is not the number of labels.
    """
    labels = labels_text.split() if labels_text else list(default_labels)
    values = list(data)
    if len(labels) != len(values):
        raise InputError(f"{what}: {len(values)} values for the {len(labels)} labels {labels}")
    return dict(zip(labels, values, strict=True))


def _fields(values, labels: tuple[str, ...], what: str) -> dict[str, float]:
    missing = [label for label in labels if label not in values]
    if missing:
        raise InputError(f"{what}: no {missing} in the labels {sorted(values)}")
    picked = {label: float(values[label]) for label in labels}
    bad = {label: value for label, value in picked.items() if not math.isfinite(value)}
    if bad:
        raise InputError(f"{what}: values must be finite, got {bad}")
    return picked


@dataclass(frozen=True)
class ContactSample:
    """One ``contact`` sample.

    Attributes:
        time: the state's time [s].
        state: +1 pushing, 0 no load, -1 pulling [-].
        normal_force: lambda, the force the EE exerts on the environment [N].
        gap: phi [m] (> 0 penetration).
        point: contact point = EE point, world [m], (3,).
        normal: unit contact normal into the environment, world, (3,) (zero without one).
    """

    time: float
    state: int
    normal_force: float
    gap: float
    point: np.ndarray
    normal: np.ndarray

    @classmethod
    def from_values(cls, values) -> ContactSample:
        """From {label: value} (labels of :data:`CONTACT_LABELS`; extra labels are ignored).

        Raises:
            InputError: a label missing, a non-finite value, a contact_state not -1, 0 or 1.
        """
        names = ("time", "contact_state", "normal_force", "gap")
        names += ("point_x", "point_y", "point_z", "normal_x", "normal_y", "normal_z")
        v = _fields(values, names, "contact")
        state = v["contact_state"]
        if state not in (-1.0, 0.0, 1.0):
            raise InputError(f"contact: contact_state must be -1, 0 or 1, got {state}")
        return cls(
            time=v["time"],
            state=int(state),
            normal_force=v["normal_force"],
            gap=v["gap"],
            point=np.array([v["point_x"], v["point_y"], v["point_z"]]),
            normal=np.array([v["normal_x"], v["normal_y"], v["normal_z"]]),
        )


@dataclass(frozen=True)
class ForceErrorSample:
    """One sample of the force controller's ``~/errors``.

    Attributes:
        time: stamp of the state used [s].
        position_error: p_des - p, world [m], (3,).
        orientation_error: |log(R_des R^T)| [rad].
        force_desired, force_measured, force_error, force_reference: f_des, f, f_des - f and
            f_ref of (6.34) [N], along the contact normal.
        normal: the contact normal used, world, (3,).
        force_active: the force task is active.
    """

    time: float
    position_error: np.ndarray
    orientation_error: float
    force_desired: float
    force_measured: float
    force_error: float
    force_reference: float
    normal: np.ndarray
    force_active: bool

    @classmethod
    def from_values(cls, values) -> ForceErrorSample:
        """From {label: value} (labels of :data:`ERROR_LABELS`; extra labels are ignored).

        Raises:
            InputError: a label missing or a non-finite value.
        """
        needed = tuple(label for label in ERROR_LABELS if label != "joint_speed")
        v = _fields(values, needed, "errors")
        return cls(
            time=v["time"],
            position_error=np.array(
                [v["position_error_x"], v["position_error_y"], v["position_error_z"]]
            ),
            orientation_error=v["orientation_error"],
            force_desired=v["force_desired"],
            force_measured=v["force_measured"],
            force_error=v["force_error"],
            force_reference=v["force_reference"],
            normal=np.array([v["normal_x"], v["normal_y"], v["normal_z"]]),
            force_active=v["force_active"] != 0.0,
        )


@dataclass(frozen=True)
class Environment:
    """The ``environment`` JSON: ``kind`` wall / arc / none, its ``frame`` and the constraint
    (:class:`~rns_ros.core.contact_geometry.PlaneConstraint`,
    :class:`~rns_ros.core.contact_geometry.ArcConstraint`, None for ``none``) with its vectors
    checked and normalized."""

    kind: str
    frame: str
    constraint: PlaneConstraint | ArcConstraint | None


def parse_environment(text: str) -> Environment:
    """The ``environment`` message: ``{"type": "wall", "frame", "point", "normal"}``,
    ``{"type": "arc", "frame", "center", "radius", "axis"}`` or ``{"type": "none", "frame"}``.

    Raises:
        InputError: not JSON, not an object, an unknown type, a missing key or a bad vector (its
            message names the value and the valid range).
    """
    try:
        content = json.loads(text)
    except (json.JSONDecodeError, TypeError) as exc:
        raise InputError(f"environment is not JSON: {exc}") from None
    if not isinstance(content, dict):
        raise InputError(f"environment must be a JSON object, got {text!r}")
    kind = content.get("type")
    required = {"wall": ("point", "normal"), "arc": ("center", "radius", "axis"), "none": ()}
    if kind not in required:
        raise InputError(f"environment type must be one of {list(required)}, got {kind!r}")
    missing = [key for key in ("frame", *required[kind]) if key not in content]
    if missing:
        raise InputError(f"environment {kind}: missing {missing} in {text!r}")
    try:
        if kind == "wall":
            constraint = PlaneConstraint(content["point"], content["normal"])
        elif kind == "arc":
            constraint = ArcConstraint(content["center"], content["radius"], content["axis"])
        else:
            constraint = None
    except ConfigError as exc:
        raise InputError(f"environment {kind}: {exc}") from None
    return Environment(kind, str(content["frame"]), constraint)


def quaternion_z_to(direction) -> np.ndarray:
    """Unit quaternion (x, y, z, w) of the shortest rotation taking +z to unit ``direction``."""
    direction = np.asarray(direction, dtype=float)
    quaternion = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), direction)
    return np.array(quaternion.coeffs(), dtype=float)  # Eigen order x y z w


def load_arm_model(path: str | Path) -> tuple[FreeFloatingModel | FixedBaseModel, Path]:
    """The model of a model YAML and its URDF path: a file with ``ee_frame`` is a Part II
    fixed-base arm (:func:`~rns_ros.core.fixed_base.load_fixed_base_model`), any other the
    free-floating robot (:func:`~rns_ros.core.config.load_model_config`).

    Raises:
        ConfigError, ModelError: from the loader (missing file, unknown key, bad URDF ...).
    """
    content = None
    with contextlib.suppress(ConfigError):  # the loader below reports it
        content = read_yaml_file(path, "model config")
    if isinstance(content, dict) and "ee_frame" in content:
        robot = load_fixed_base_model(path)
        return robot, (Path(path).parent / str(content["urdf"])).resolve()
    robot = load_model(path)
    return robot, Path(robot.source_path)


@dataclass(frozen=True)
class ContactSettings:
    """How the contact streams are drawn.

    Attributes:
        contact_log_rate: highest logged rate of ``contact``, ``wrist_wrench`` and the errors,
            by their own clock [Hz]; 0 logs every sample.
        force_arrow_scale: arrow length per newton [m/N], > 0.
    """

    contact_log_rate: float = 50.0
    force_arrow_scale: float = 0.01

    def __post_init__(self) -> None:
        if not (math.isfinite(self.contact_log_rate) and self.contact_log_rate >= 0.0):
            raise ConfigError(
                f"contact_log_rate must be a finite number >= 0 Hz, got {self.contact_log_rate}"
            )
        if not (math.isfinite(self.force_arrow_scale) and self.force_arrow_scale > 0.0):
            raise ConfigError(
                f"force_arrow_scale must be a finite number > 0 m/N, got {self.force_arrow_scale}"
            )


def _seconds_to_ns(seconds: float) -> int:
    return round(seconds * 1e9)


class ContactRecorder(TelemetryRecorder):
    """A recording of a fixed-base arm in contact (see the module docstring).

    Args:
        robot: the fixed-base model (forward kinematics, joint order).
        urdf_path: the URDF ``robot`` was built from.
        sink, settings, env: as :class:`~rns_ros.viz.recorder.TelemetryRecorder` (``max_rate``
            limits ``joint_states``).
        contact: :class:`ContactSettings`.
        clock: as :class:`~rns_ros.viz.recorder.TelemetryRecorder`.

    Only :meth:`joint_state`, :meth:`environment`, :meth:`contact`, :meth:`wrist_wrench` and
    :meth:`force_errors` apply to a fixed-base arm (the free-floating inputs are not fed).
    """

    STREAMS = CONTACT_STREAMS

    def __init__(
        self,
        robot: FixedBaseModel,
        urdf_path: str | Path,
        sink,
        settings=None,
        env=None,
        contact: ContactSettings | None = None,
        clock=None,
    ) -> None:
        self.contact_settings = contact or ContactSettings()
        super().__init__(robot, urdf_path, sink, settings, env, clock)
        rate = self.contact_settings.contact_log_rate
        # contact and errors are limited by their own ``time`` (the timeline stamp is the newest
        # joint state's, shared by several samples); the wrench by its header stamp.
        self._limiters["contact"] = RateLimiter(0.0)
        self._limiters["errors"] = RateLimiter(0.0)
        self._limiters["environment"] = RateLimiter(0.0)
        self._limiters["wrench"] = RateLimiter(rate)
        self._sample_limiters = {"contact": RateLimiter(rate), "errors": RateLimiter(rate)}
        self._fk_data = robot.model.createData()
        self._theta: np.ndarray | None = None
        self._ee: tuple[np.ndarray, np.ndarray] | None = None
        self._arm = _Rows()  # theta
        self._points = _Rows()  # (point, rgb)
        self._measured = _Rows()  # (origin, vector)
        self._desired = _Rows()  # (origin, vector)
        #: The newest environment (None before the first message).
        self.environment_seen: Environment | None = None
        self.view.log_fixed_base(self.rec)
        self.rec.log(
            paths.CONTACT_POINT,
            rr.Points3D.from_fields(radii=[CONTACT_POINT_RADIUS]),
            static=True,
        )
        for path, color in (
            (paths.FORCE_MEASURED_ARROW, FORCE_MEASURED_COLOR),
            (paths.FORCE_DESIRED_ARROW, FORCE_DESIRED_COLOR),
        ):
            self.rec.log(
                path,
                rr.Arrows3D.from_fields(colors=[color], radii=[FORCE_ARROW_RADIUS]),
                static=True,
            )

    def _blueprint(self):
        return contact_blueprint()

    def _series_table(self) -> dict[str, paths.Series]:
        return paths.contact_series_table(self.robot.joint_names)

    @property
    def state(self) -> None:
        """No free-floating state: see :attr:`theta` and :meth:`ee_pose`."""
        return None

    @property
    def theta(self) -> np.ndarray | None:
        """Joint angles of the newest joint state [rad] (n,); None before the first."""
        return self._theta

    def ee_pose(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(p_e [m] (3,), R_e world <- EE (3, 3)) at the newest joint state; None before one."""
        with self._lock:
            return self._ee_pose()

    def _ee_pose(self) -> tuple[np.ndarray, np.ndarray] | None:
        if self._ee is None and self._theta is not None:
            model = self.robot.model
            pin.framesForwardKinematics(model, self._fk_data, self._theta)
            placement = self._fk_data.oMf[self.robot.ee_frame_id]
            self._ee = (placement.translation.copy(), placement.rotation.copy())
        return self._ee

    # --- inputs ---------------------------------------------------------------------------------
    def joint_state(self, stamp_ns: int, theta, theta_dot=None) -> None:
        """Joint angles [rad] (n,) and optionally velocities [rad/s] (n,), model order.

        Every state becomes the pose the arrows are drawn at; at most ``max_rate`` of them pose
        the arm (joint transforms) and enter the joint-velocity series.

        Raises:
            InputError: wrong length or not finite.
        """
        theta = as_vector(theta, self.robot.n, "joint angles").copy()
        if theta_dot is not None:
            theta_dot = as_vector(theta_dot, self.robot.n, "joint velocities")
        with self._lock:
            if self._closed:
                return
            self._theta, self._ee = theta, None
            if not self._accept("joints", stamp_ns):
                return
            self.counts["joints"] += 1
            self._add(self._arm, stamp_ns, theta)
            if theta_dot is not None:
                for joint, value in zip(self.robot.joint_names, theta_dot, strict=True):
                    self._scalar(paths.joint_velocity(joint), stamp_ns, value)
            self._send_if_due()

    def environment(self, text: str) -> Environment:
        """Draw the ``environment`` JSON as static entities (a new message replaces the old).

        Raises:
            InputError: see :func:`parse_environment`.
        """
        environment = parse_environment(text)
        with self._lock:
            if self._closed:
                return environment
            self.environment_seen = environment
            self.counts["environment"] += 1
            self._log_environment(environment)
        return environment

    def _log_environment(self, environment: Environment) -> None:
        rec, constraint = self.rec, environment.constraint
        cleared = {
            paths.ENVIRONMENT_WALL: rr.Boxes3D.from_fields(clear_unset=True),
            paths.ENVIRONMENT_ARC: rr.Cylinders3D.from_fields(clear_unset=True),
            paths.ENVIRONMENT_NORMAL: rr.Arrows3D.from_fields(clear_unset=True),
        }
        drawn = {}
        if isinstance(constraint, PlaneConstraint):
            drawn[paths.ENVIRONMENT_WALL] = rr.Boxes3D(
                centers=[constraint.point],
                half_sizes=[WALL_HALF_SIZE],
                quaternions=[rr.Quaternion(xyzw=quaternion_z_to(constraint.normal))],
                colors=[ENVIRONMENT_COLOR],
                fill_mode=rr.components.FillMode.TransparentFillMajorWireframe,
            )
            drawn[paths.ENVIRONMENT_NORMAL] = rr.Arrows3D(
                origins=[constraint.point],
                vectors=[constraint.normal * NORMAL_ARROW_LENGTH],
                colors=[NORMAL_COLOR],
                radii=[0.004],
            )
        elif isinstance(constraint, ArcConstraint):
            drawn[paths.ENVIRONMENT_ARC] = rr.Cylinders3D(
                lengths=[ARC_LENGTH],
                radii=[constraint.radius],
                centers=[constraint.center],
                quaternions=[rr.Quaternion(xyzw=quaternion_z_to(constraint.axis))],
                colors=[ENVIRONMENT_COLOR],
                fill_mode=rr.components.FillMode.TransparentFillMajorWireframe,
            )
        for path, empty in cleared.items():
            rec.log(path, drawn.get(path, empty), static=True)

    def contact(self, stamp_ns: int, values) -> bool:
        """One ``contact`` sample as {label: value}, placed at ``stamp_ns`` (the newest joint
        state's stamp [ns]). Returns True when it was logged (False: above the rate or closed).

        Raises:
            InputError: see :meth:`ContactSample.from_values`.
        """
        sample = ContactSample.from_values(values)
        with self._lock:
            if not self._accept_sample("contact", sample.time, stamp_ns):
                return False
            self._scalar(paths.CONTACT_NORMAL_FORCE, stamp_ns, sample.normal_force)
            self._scalar(paths.CONTACT_GAP, stamp_ns, sample.gap)
            self._add(self._points, stamp_ns, (sample.point, CONTACT_STATE_COLORS[sample.state]))
            self._send_if_due()
            return True

    def wrist_wrench(self, stamp_ns: int, force_ee, torque_ee=None) -> bool:
        """The wrist force in EE axes [N] (3,) (torque [N m] (3,) checked, not drawn): the
        measured force arrow R_e f * force_arrow_scale at p_e of the newest joint state.
        Returns True when it was logged (False: no joint state yet, above the rate, closed).

        Raises:
            InputError: not finite 3-vectors.
        """
        force = as_vector(force_ee, 3, "wrist force")
        if torque_ee is not None:
            as_vector(torque_ee, 3, "wrist torque")
        with self._lock:
            pose = self._ee_pose()
            if pose is None or not self._accept("wrench", stamp_ns):
                return False
            self.counts["wrench"] += 1
            position, rotation = pose
            vector = rotation @ force * self.contact_settings.force_arrow_scale
            self._add(self._measured, stamp_ns, (position, vector))
            self._send_if_due()
            return True

    def force_errors(self, stamp_ns: int, values) -> bool:
        """One errors sample of the force controller as {label: value}, placed at ``stamp_ns``
        (the newest joint state's stamp [ns]): force and position-error series, and the
        commanded force arrow f_des n * force_arrow_scale at p_e (once a joint state is known).
        Returns True when it was logged.

        Raises:
            InputError: see :meth:`ForceErrorSample.from_values`.
        """
        sample = ForceErrorSample.from_values(values)
        with self._lock:
            if not self._accept_sample("errors", sample.time, stamp_ns):
                return False
            series = {
                paths.FORCE_DESIRED: sample.force_desired,
                paths.FORCE_MEASURED: sample.force_measured,
                paths.FORCE_ERROR: sample.force_error,
                paths.FORCE_REFERENCE: sample.force_reference,
                paths.POSITION_ERROR_ORIENTATION: sample.orientation_error,
            }
            for path, value in series.items():
                self._scalar(path, stamp_ns, value)
            self._vector(paths.POSITION_ERROR_AXES, stamp_ns, sample.position_error)
            pose = self._ee_pose()
            if pose is not None:
                scale = self.contact_settings.force_arrow_scale
                arrow = (pose[0], sample.force_desired * sample.normal * scale)
                self._add(self._desired, stamp_ns, arrow)
            self._send_if_due()
            return True

    # --- helpers --------------------------------------------------------------------------------
    def _accept_sample(self, stream: str, time_s: float, stamp_ns: int) -> bool:
        """Rate limit by the sample's own ``time`` [s], then the common checks (closed, time
        kind); counts the sample."""
        if self._closed or not self._sample_limiters[stream].accept(_seconds_to_ns(time_s)):
            return False
        if not self._accept(stream, stamp_ns):
            return False
        self.counts[stream] += 1
        return True

    def _buffers(self) -> list[_Rows]:
        return [*super()._buffers(), self._arm, self._points, self._measured, self._desired]

    def _send(self, minimum_rows: int = 1) -> None:
        super()._send(minimum_rows)
        rec, view = self.rec, self.view
        stamps, rows = self._arm.take(minimum_rows)
        if stamps:
            times = self._time_column(stamps)
            for path, columns in view.joint_columns(np.array(rows)):
                rec.send_columns(path, indexes=[times], columns=columns)
        stamps, rows = self._points.take(minimum_rows)
        if stamps:
            points, colors = zip(*rows, strict=True)
            rec.send_columns(
                paths.CONTACT_POINT,
                indexes=[self._time_column(stamps)],
                columns=rr.Points3D.columns(
                    positions=np.array(points), colors=np.array(colors, dtype=np.uint8)
                ),
            )
        for path, pending in (
            (paths.FORCE_MEASURED_ARROW, self._measured),
            (paths.FORCE_DESIRED_ARROW, self._desired),
        ):
            stamps, rows = pending.take(minimum_rows)
            if stamps:
                origins, vectors = (np.array(part) for part in zip(*rows, strict=True))
                rec.send_columns(
                    path,
                    indexes=[self._time_column(stamps)],
                    columns=rr.Arrows3D.columns(origins=origins, vectors=vectors),
                )
