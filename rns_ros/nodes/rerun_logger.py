"""rns_rerun_logger: the running system in rerun (3D robot from its URDF, time series, log).

Recording, kinematics and sinks are :class:`rns_ros.viz.TelemetryRecorder`; this node only turns
messages into arrays. Entity paths and units: :mod:`rns_ros.viz.paths`. One timeline,
``ros_time``, from the header stamps (sim time when the simulator publishes /clock; a zero stamp
is replaced by this node's clock).

Subscribes (best effort, depth QUEUE_DEPTH = 2000: matches reliable and best-effort publishers,
and holds 20 s of 100 Hz state, longer than a file's flush tick and the block sent then, while
a busy logger catches up instead of dropping samples):
    joint_states              sensor_msgs/JointState (by joint name, other joints ignored): joint
                              transforms, camera arrow and trail, joint velocities, achieved
                              camera angular velocity
    base_odom                 nav_msgs/Odometry: base pose, attitude deviation from the first
                              message; its twist (base axes) enters the achieved velocity
    momentum                  geometry_msgs/WrenchStamped: |p| (force) and |l| (torque)
    <controller_status_topic> diagnostic_msgs/DiagnosticArray of rns_controller: singularity
                              measures, predicted coupling momentum, damping, state
    cmd_twist                 geometry_msgs/TwistStamped: commanded angular velocity, turned into
                              world axes (``header.frame_id``: ``world_frame``, the base link or the
                              camera frame; empty: ``default_twist_frame``; others are skipped)
    <ptp_status_topic>        diagnostic_msgs/DiagnosticArray of rns_ptp: phase (code and a log
                              line per change), progress, predicted coupling momentum
    energy                    std_msgs/Float64MultiArray of rns_simulator (labels from its
                              layout): kinetic-energy terms, Lambda costs, C_max, C_sum; stamped
                              with the newest joint_states stamp (published in the same step;
                              skipped before the first joint_states)
    wheel_states              sensor_msgs/JointState of the reaction wheels: rates, torques
    ptp_goal                  sensor_msgs/JointState goal of rns_ptp (by joint name; joints it
                              does not name at their newest measured angle): a translucent ghost
                              arm at the goal; the ``["deploy"]`` goal clears it
    <ground_namespace>/predicted/joint_states, .../predicted/base_odom
                              (with ``ground_namespace``, teleoperation from the ground) the arm
                              rns_predictor predicts, an orange ghost at each predicted instant;
    <ground_namespace>/joint_states, <ground_namespace>/base_odom
                              the telemetry as the ground receives it, a grey ghost at its
                              receipt on this node's clock (each pair matched by stamp)
    <ground_namespace>/<predictor_status_topic>, <link_status_topic>
                              (with ``ground_namespace``) rns_predictor's prediction error and
                              rns_link's delay, messages in flight and lost per direction,
                              under plots/ground (the predicted camera is also drawn
                              as a frustum)

Part II contact mode (docs/part2_ros.md): when ``model_config`` is a fixed-base arm (its YAML has
``ee_frame``, e.g. config/lwr_7dof.yaml), the arm is drawn from ``joint_states`` with its base link
at the world origin, and the free-floating topics above are replaced by (drawing and entity paths:
:mod:`rns_ros.viz.contact`):
    joint_states              sensor_msgs/JointState: joint transforms, joint velocities, the EE
                              pose the force arrows are drawn at
    environment               std_msgs/String JSON (transient local, depth 1): wall / arc as
                              static translucent geometry under world/environment
    contact                   std_msgs/Float64MultiArray (labels from its layout, else the
                              contract's CONTACT_LABELS): contact point coloured by contact_state,
                              normal force and gap series
    wrist_wrench              geometry_msgs/WrenchStamped (EE axes): the measured force arrow
    <force_errors_topic>      std_msgs/Float64MultiArray of rns_force_controller (ERROR_LABELS):
                              commanded force arrow, force and position-error series
contact and the errors carry no header: they are placed at the newest joint_states stamp (skipped
before the first). The three 1 kHz streams are logged at most at ``contact_log_rate``.

Sinks (``sink``): ``spawn`` a native viewer, ``connect`` to one, ``serve`` a local web viewer,
``save`` an .rrd, or ``auto`` (spawn with a display, else save). Everything binds 127.0.0.1.
Samples are sent in blocks, one chunk per entity every ``flush_tick`` seconds of wall time to a
viewer (it lags by about that much; large chunks keep a browser's memory small), every
``file_flush_tick`` to a file.
``destroy_node()`` sends what is buffered and closes the recording: a saved file is complete.
"""

from __future__ import annotations

import contextlib

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, String

from rns_ros.control.contact_topics import CONTACT_LABELS, ERROR_LABELS
from rns_ros.control.teleop import twist_frame_ids
from rns_ros.core.commands import ExtraJointsReport, match_joint_state, partial_joint_goal
from rns_ros.core.errors import InputError
from rns_ros.core.fixed_base import FixedBaseModel
from rns_ros.nodes import rerun_logger_parameters
from rns_ros.nodes.parameters import declare_parameters, from_parameters
from rns_ros.nodes.ptp import DEPLOY_GOAL
from rns_ros.nodes.robot_io import StampPairs
from rns_ros.nodes.runner import run_node
from rns_ros.resources import default_model_config
from rns_ros.viz.contact import (
    ContactRecorder,
    ContactSettings,
    labelled_values,
    load_arm_model,
    parse_environment,
)
from rns_ros.viz.recorder import RecorderSettings, TelemetryRecorder
from rns_ros.viz.sinks import SinkSettings

#: Wall time between two checks whether a block of samples is due [s]: a sample waits at most
#: the flush tick plus this before it is sent, also when no more messages come.
DUE_CHECK_PERIOD = 0.1


class RerunLoggerNode(Node):
    """ROS 2 front end of :class:`TelemetryRecorder` (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(rerun_logger_parameters.NODE_NAME, **node_kwargs)
        params = declare_parameters(self, rerun_logger_parameters.PARAMETERS)
        self.robot, urdf_path = load_arm_model(params["model_config"] or default_model_config())
        #: A Part II fixed-base arm (contact topics) instead of the free-floating robot.
        self.fixed_base = isinstance(self.robot, FixedBaseModel)
        self._world_frame = params["world_frame"]
        self._last_state_stamp: int | None = None  # [ns], of the newest joint_states
        if not self.fixed_base:
            self._limits = (self.robot.lower_limits, self.robot.upper_limits)
            self._frames = twist_frame_ids(
                self.robot, params["world_frame"], params["default_twist_frame"]
            )
        sink = from_parameters(SinkSettings, params, kind=params["sink"])
        settings = from_parameters(RecorderSettings, params)
        # From here on the recording is open: close it if the rest of the set-up is interrupted
        # (Ctrl-C during start-up), or the file would lack its footer.
        if self.fixed_base:
            contact = from_parameters(ContactSettings, params)
            self.recorder = ContactRecorder(self.robot, urdf_path, sink, settings, contact=contact)
        else:
            self.recorder = TelemetryRecorder(self.robot, urdf_path, sink, settings)
        try:
            # deep queue: a recorder should not drop samples while rerun work (a block of a
            # flush tick) or a busy CPU holds it up
            qos = QoSProfile(depth=QUEUE_DEPTH, reliability=ReliabilityPolicy.BEST_EFFORT)
            self._extra_joints = ExtraJointsReport()  # joint_states names beyond the model's
            self.create_subscription(JointState, "joint_states", self._on_joint_state, qos)
            if self.fixed_base:
                self._subscribe_contact(qos, params["force_errors_topic"])
            else:
                self._subscribe_free_floating(qos, params)
            # A quiet system still shows its newest samples: send a due block from a timer, by
            # wall time (a sim-time timer would fire 100x as often at real_time_factor 100).
            self._timer = self.create_timer(
                DUE_CHECK_PERIOD,
                self.recorder.send_due,
                clock=Clock(clock_type=ClockType.STEADY_TIME),
            )
            self.get_logger().info(f"{self.robot.name}: {self.recorder.sink.description}")
        except BaseException:
            self.recorder.close()
            raise

    def _subscribe_free_floating(self, qos: QoSProfile, params) -> None:
        self.create_subscription(Odometry, "base_odom", self._on_odom, qos)
        self.create_subscription(WrenchStamped, "momentum", self._on_momentum, qos)
        self.create_subscription(
            DiagnosticArray, params["controller_status_topic"], self._on_status, qos
        )
        self.create_subscription(TwistStamped, "cmd_twist", self._on_twist, qos)
        self.create_subscription(
            DiagnosticArray, params["ptp_status_topic"], self._on_ptp_status, qos
        )
        self.create_subscription(Float64MultiArray, "energy", self._on_energy, qos)
        self.create_subscription(JointState, "wheel_states", self._on_wheel_states, qos)
        # goals are rare and must not be missed by a late logger: reliable, like rns_ptp's
        self.create_subscription(JointState, "ptp_goal", self._on_ptp_goal, 10)
        ground = params["ground_namespace"].strip("/")
        if ground:
            arms = (("predicted", f"/{ground}/predicted"), ("telemetry", f"/{ground}"))
            for kind, prefix in arms:
                pairs = StampPairs()
                self.create_subscription(
                    JointState,
                    f"{prefix}/joint_states",
                    lambda msg, k=kind, p=pairs: self._on_ground_joints(k, p, msg),
                    qos,
                )
                self.create_subscription(
                    Odometry,
                    f"{prefix}/base_odom",
                    lambda msg, k=kind, p=pairs: self._on_ground_odom(k, p, msg),
                    qos,
                )
            predictor = params["predictor_status_topic"]
            if not predictor.startswith("/"):
                predictor = f"/{ground}/{predictor}"
            for source, topic in (("predictor", predictor), ("link", params["link_status_topic"])):
                self.create_subscription(
                    DiagnosticArray,
                    topic,
                    lambda msg, s=source: self._on_ground_status(s, msg),
                    qos,
                )

    def _subscribe_contact(self, qos: QoSProfile, errors_topic: str) -> None:
        self._ee_frame = self.robot.model.frames[self.robot.ee_frame_id].name
        # latched by the simulator: a late logger still gets the newest environment
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.create_subscription(String, "environment", self._on_environment, latched)
        self.create_subscription(Float64MultiArray, "contact", self._on_contact, qos)
        self.create_subscription(WrenchStamped, "wrist_wrench", self._on_wrist_wrench, qos)
        self.create_subscription(Float64MultiArray, errors_topic, self._on_force_errors, qos)

    # --- inputs ---------------------------------------------------------------------------------
    def _stamp_ns(self, header) -> int:
        stamp = header.stamp.sec * 1_000_000_000 + header.stamp.nanosec
        return stamp if stamp > 0 else self.get_clock().now().nanoseconds

    def _on_joint_state(self, msg: JointState) -> None:
        try:
            state, extras = match_joint_state(
                msg.name, self.robot.joint_names, positions=msg.position, velocities=msg.velocity
            )
            if state.positions is None:
                raise InputError("joint_states has no positions")
            self._last_state_stamp = self._stamp_ns(msg.header)
            self.recorder.joint_state(self._last_state_stamp, state.positions, state.velocities)
            self.get_logger().info("receiving joint_states", once=True)
        except InputError as exc:
            self._ignored("joint_states", exc)
            return
        note = self._extra_joints.note(extras)
        if note is not None:
            self.get_logger().info(note)

    def _on_ground_joints(self, kind: str, pairs: StampPairs, msg: JointState) -> None:
        try:
            state, _ = match_joint_state(msg.name, self.robot.joint_names, positions=msg.position)
            if state.positions is None:
                raise InputError("no positions")
        except InputError as exc:
            self._ignored(f"{kind} joint_states", exc)
            return
        self._ground_pair(kind, pairs.joints(self._stamp_ns(msg.header), state.positions))

    def _on_ground_odom(self, kind: str, pairs: StampPairs, msg: Odometry) -> None:
        p, o = msg.pose.pose.position, msg.pose.pose.orientation
        pose = ([p.x, p.y, p.z], [o.x, o.y, o.z, o.w])
        self._ground_pair(kind, pairs.pose(self._stamp_ns(msg.header), pose))

    def _ground_pair(self, kind: str, pair) -> None:
        """A ground arm whose joint_states and base_odom are both in: drawn at its stamp
        (predicted) or at its receipt on this node's clock (telemetry)."""
        if pair is None:
            return
        stamp, theta, (position, orientation) = pair
        if kind == "telemetry":
            stamp = self.get_clock().now().nanoseconds
        try:
            q = self.robot.configuration(theta, position, orientation)
            self.recorder.ground_arm(kind, stamp, q)
        except InputError as exc:
            self._ignored(f"{kind} arm", exc)

    def _on_odom(self, msg: Odometry) -> None:
        pose, twist = msg.pose.pose, msg.twist.twist
        p, o, w = pose.position, pose.orientation, twist.angular
        try:
            self.recorder.base_odom(
                self._stamp_ns(msg.header), [p.x, p.y, p.z], [o.x, o.y, o.z, o.w], [w.x, w.y, w.z]
            )
        except InputError as exc:
            self._ignored("base_odom", exc)

    def _on_momentum(self, msg: WrenchStamped) -> None:
        f, t = msg.wrench.force, msg.wrench.torque
        self.recorder.momentum(self._stamp_ns(msg.header), [f.x, f.y, f.z], [t.x, t.y, t.z])

    def _on_status(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            values = {kv.key: kv.value for kv in status.values}
            if "state" in values:  # the controller's entry; other diagnostics are not ours
                level = status.level[0] if isinstance(status.level, bytes) else int(status.level)
                self.recorder.controller_status(
                    self._stamp_ns(msg.header), values, level, status.message
                )
                return

    def _on_ground_status(self, source: str, msg: DiagnosticArray) -> None:
        """rns_predictor's or rns_link's status (``source``): the ground's figures (prediction
        error; link delay, in flight, lost) as time series."""
        for status in msg.status:
            self.recorder.ground_status(
                source, self._stamp_ns(msg.header), {kv.key: kv.value for kv in status.values}
            )

    def _on_energy(self, msg: Float64MultiArray) -> None:
        labels = msg.layout.dim[0].label.split() if msg.layout.dim else []
        if len(labels) != len(msg.data):
            self._ignored("energy", f"{len(msg.data)} values for labels {labels}")
            return
        stamp = self._last_state_stamp
        if stamp is None:
            return  # no joint state yet to place it on the timeline
        try:
            self.recorder.energy(stamp, dict(zip(labels, msg.data, strict=True)))
        except InputError as exc:
            self._ignored("energy", exc)

    def _on_wheel_states(self, msg: JointState) -> None:
        try:
            if len(msg.velocity) != 3 or len(msg.effort) != 3:
                raise InputError("wheel_states needs 3 velocities and 3 efforts")
            self.recorder.wheel_state(self._stamp_ns(msg.header), msg.velocity, msg.effort)
        except InputError as exc:
            self._ignored("wheel_states", exc)

    def _on_ptp_status(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            values = {kv.key: kv.value for kv in status.values}
            if "phase" in values or "state" in values:
                level = status.level[0] if isinstance(status.level, bytes) else int(status.level)
                self.recorder.ptp_status(self._stamp_ns(msg.header), values, level, status.message)
                return

    def _on_ptp_goal(self, msg: JointState) -> None:
        stamp = self._stamp_ns(msg.header)
        if list(msg.name) == DEPLOY_GOAL:
            self.recorder.ptp_goal(stamp, None)
            return
        state = self.recorder.state
        robot = self.robot
        try:
            if state is None and len(set(msg.name)) < robot.n:
                raise InputError("a partial goal before the first joint_states")
            current = robot.lower_limits if state is None else state.theta  # all named if None
            goal = partial_joint_goal(
                msg.name, msg.position, robot.joint_names, current, *self._limits
            )
            self.recorder.ptp_goal(stamp, goal)
        except InputError as exc:
            self._ignored("ptp_goal", exc)

    def _on_twist(self, msg: TwistStamped) -> None:
        frame = self._frames.get(msg.header.frame_id)
        if frame is None:
            self._ignored(
                "cmd_twist", f"frame_id {msg.header.frame_id!r} is not one of {list(self._frames)}"
            )
            return
        a = msg.twist.angular
        try:
            self.recorder.commanded_twist(self._stamp_ns(msg.header), [a.x, a.y, a.z], frame)
        except InputError as exc:
            self._ignored("cmd_twist", exc)

    # --- Part II contact inputs -------------------------------------------------------------------
    def _on_environment(self, msg: String) -> None:
        try:
            environment = parse_environment(msg.data)
            if environment.frame != self._world_frame:
                raise InputError(
                    f"frame {environment.frame!r} is not the world_frame {self._world_frame!r}"
                )
            self.recorder.environment(msg.data)
            self.get_logger().info(f"environment: {environment.kind} {environment.constraint}")
        except InputError as exc:
            self._ignored("environment", exc)

    def _on_contact(self, msg: Float64MultiArray) -> None:
        self._labelled("contact", msg, CONTACT_LABELS, self.recorder.contact)

    def _on_force_errors(self, msg: Float64MultiArray) -> None:
        self._labelled("force errors", msg, ERROR_LABELS, self.recorder.force_errors)

    def _labelled(self, topic: str, msg: Float64MultiArray, labels, record) -> None:
        """Values by the labels of the message's own layout (else the contract's), placed at the
        newest joint_states stamp; skipped before the first joint_states."""
        try:
            label = msg.layout.dim[0].label if msg.layout.dim else ""
            values = labelled_values(label, msg.data, labels, topic)
            if self._last_state_stamp is not None:
                record(self._last_state_stamp, values)
        except InputError as exc:
            self._ignored(topic, exc)

    def _on_wrist_wrench(self, msg: WrenchStamped) -> None:
        frame = msg.header.frame_id
        f, t = msg.wrench.force, msg.wrench.torque
        try:
            if frame not in ("", self._ee_frame):
                raise InputError(f"frame_id {frame!r} is not the EE frame {self._ee_frame!r}")
            self.recorder.wrist_wrench(self._stamp_ns(msg.header), [f.x, f.y, f.z], [t.x, t.y, t.z])
        except InputError as exc:
            self._ignored("wrist_wrench", exc)

    def _ignored(self, topic: str, reason) -> None:
        self.get_logger().warn(f"ignored {topic}: {reason}", throttle_duration_sec=2.0)

    # --- shutdown -------------------------------------------------------------------------------
    def destroy_node(self) -> None:
        """Send the buffered samples, flush and close the recording, then tear down."""
        recorder = getattr(self, "recorder", None)
        if recorder is not None and not recorder.closed:
            recorder.close()
            counts = ", ".join(f"{key} {value}" for key, value in recorder.counts.items())
            # The logging context may already be shut down (Ctrl-C): the file is closed anyway.
            with contextlib.suppress(Exception):
                if recorder.problem is not None:
                    self.get_logger().error(f"recording lost: {recorder.problem}")
                else:
                    self.get_logger().info(
                        f"recording closed ({counts} messages): {recorder.sink.description}"
                    )
        super().destroy_node()


#: Messages each subscription holds while the node is busy: 20 s of a 100 Hz stream.
QUEUE_DEPTH = 2000


def main(args=None) -> int:
    return run_node(RerunLoggerNode, rerun_logger_parameters, args)


if __name__ == "__main__":
    raise SystemExit(main())
