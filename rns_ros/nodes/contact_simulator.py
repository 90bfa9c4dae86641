"""rns_simulator, contact mode: a torque-driven fixed-base arm whose end effector touches a rigid
wall or cylinder (thesis Part II, chapters 6-7), as a ROS 2 node.

Physics is :class:`rns_ros.sim.contact.ContactSimulator` (eqs. 6.2 with the contact force, RK4,
Baumgarte-stabilized bilateral rigid contact; lambda = the force the end effector exerts on the
environment) or, with ``environment: none``, :class:`rns_ros.sim.free_arm.FreeArmSimulator`. This
node converts messages and keeps the arm safe; it steps from its own monotonic-clock thread
(absolute deadlines), like the free-floating :class:`rns_ros.nodes.simulator.SimulatorNode`.
Contract: docs/part2_ros.md.

Subscribes:
    joint_efforts   std_msgs/Float64MultiArray  joint torques [N m] in the order of the
                                                ``joints`` parameter; best effort, depth 1. A
                                                wrong length or a non-finite value is rejected
                                                (throttled error) and does not feed the watchdog.
Publishes, per state and all with the same stamp (sim time with ``publish_clock``, else now), in
this order so an event-driven controller that computes on ``joint_states`` already has the rest:
    wrist_wrench    geometry_msgs/WrenchStamped  the wrench the EE exerts on the environment, EE
                                                axes, frame_id = the EE frame [N, N m]
    contact         std_msgs/Float64MultiArray   layout :data:`CONTACT_LABELS`
    joint_states    sensor_msgs/JointState       position [rad], velocity [rad/s], effort [N m] =
                                                the torque held over the step that ended here
    /clock          rosgraph_msgs/Clock          with ``publish_clock``
and, latched once: ``environment`` (std_msgs/String, JSON) and ``robot_description`` (URDF).
Service ``~/reset`` (std_srvs/Trigger): back to the start state, the command cleared (the brake
holds the arm until the next command).

Safety: torques are clipped to the URDF effort limits (``saturate_torque``; the saturated joints
are counted in ``contact`` and named in a throttled warning). Without a valid command for
``command_timeout`` (wall time; simulated time in lockstep) - also before the first one - the
simulated robot's brakes take over: tau = g(q) - B q_dot, eq. (F.2) of
:mod:`rns_ros.sim.free_arm` (gravity held, joints damped with ``brake_damping``), so a killed
controller leaves the arm stopping and its push on the environment ends. A step that diverges is
logged once; the node then publishes the last finite state at rest until ``~/reset``. No
non-finite value is ever published.
"""

from __future__ import annotations

import json
import math
import threading
from pathlib import Path

import numpy as np
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, String
from std_srvs.srv import Trigger

from rns_ros.control.contact_topics import CONTACT_LABELS
from rns_ros.core.config import read_yaml_mapping
from rns_ros.core.contact_geometry import ArcConstraint, PlaneConstraint, project_onto_constraint
from rns_ros.core.errors import ConfigError, SimulationDivergedError
from rns_ros.core.fixed_base import FixedBaseState, load_fixed_base_model
from rns_ros.nodes.contact_simulator_parameters import NODE_NAME, PARAMETERS, SPECS
from rns_ros.nodes.lockstep import LOCKSTEP_PATIENCE, LockstepPacer
from rns_ros.nodes.parameters import declare_parameters, velocity_joint_order
from rns_ros.nodes.runner import stop_worker
from rns_ros.nodes.sim_clock import stamp_from_seconds
from rns_ros.nodes.simulator_parameters import check_parameter_changes
from rns_ros.resources import config_dir
from rns_ros.sim.contact import ContactSimulator
from rns_ros.sim.free_arm import FreeArmSimulator, JointBrake

DEFAULT_MODEL = "lwr_7dof.yaml"


#: Largest |phi| [m] of a start configuration with project_start false.
START_TOLERANCE = 1e-6


def _model_path(value: str) -> str:
    """``model_config``: '' -> config/lwr_7dof.yaml; an existing path as given; else a file name
    of the package's config/ folder (``planar_3dof.yaml``).

    Raises:
        ConfigError: neither exists (the message lists the shipped fixed-base models).
    """
    if not value:
        return str(config_dir() / DEFAULT_MODEL)
    if Path(value).is_file():
        return value
    shipped = config_dir() / value
    if shipped.is_file():
        return str(shipped)
    raise ConfigError(
        f"parameter 'model_config' {value!r} is neither a file nor a file of {config_dir()} "
        f"(Part II models: {DEFAULT_MODEL}, planar_3dof.yaml)"
    )


def _urdf_text(model_path: str) -> str:
    """The URDF text a Part II model YAML names (already validated by the model loader)."""
    path, content = read_yaml_mapping(model_path, {"urdf", "ee_frame", "description"}, "model")
    return (path.parent / content["urdf"]).resolve().read_text()


class ContactSimulatorNode(Node):
    """ROS 2 wrapper of :class:`ContactSimulator` / :class:`FreeArmSimulator` (see the module
    docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        try:
            self._start()
        except BaseException:
            # a failed start-up leaves nothing registered: rcl keeps one /rosout publisher per
            # node name, and a leaked node would swallow the logs of the next rns_simulator
            Node.destroy_node(self)
            raise

    def _start(self) -> None:
        params = declare_parameters(self, PARAMETERS)
        model_path = _model_path(params["model_config"])
        self.robot = load_fixed_base_model(model_path, gravity=params["gravity"])
        robot, n = self.robot, self.robot.n
        description = self._build_simulator(params)
        dt = params["step_size"]
        self.brake = JointBrake(robot, params["brake_damping"], dt)
        self._limits = self.simulator.effort_limits
        self._saturate = params["saturate_torque"]
        self._threshold = params["contact_threshold"]
        self._publish_every = max(1, round(1.0 / (params["publish_rate"] * dt)))
        self._command_timeout = params["command_timeout"]
        self._publish_clock = params["publish_clock"]
        self._world_frame = params["world_frame"]
        self._ee_frame = robot.model.frames[robot.ee_frame_id].name

        # lockstep: the period counts from the simulated time of a torque command's receipt
        self._pacer = LockstepPacer.from_parameters(self.simulator, params)
        self._lock, self._stop = self._pacer.lock, self._pacer.stop
        self._command_arrived = self._pacer.wake
        self._steps = 0  # since the start or the last reset
        self._reset_requested = False
        self._command: np.ndarray | None = None  # newest valid torque, model order [N m]
        self._braking_logged = True  # braked from the start: that is not a stale controller
        self._fault = False
        self._saturated = 0  # joints saturated in the torque held over the next step
        self.braking = True  # the brake torque (F.2) is applied (read in tests)

        self._create_topics()
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self._environment_pub = self.create_publisher(String, "environment", latched)
        self.environment_description = dict(description, frame=self._world_frame)
        self._environment_pub.publish(String(data=json.dumps(self.environment_description)))
        self._description_pub = self.create_publisher(String, "robot_description", latched)
        self._description_pub.publish(String(data=_urdf_text(model_path)))
        self.create_service(Trigger, "~/reset", self._on_reset)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)

        with self._lock:
            self._apply_brake()
        self._thread = threading.Thread(
            target=self._pacer.run, args=(self,), name="rns_contact_sim_loop", daemon=True
        )
        self._thread.start()
        self.get_logger().info(
            f"contact simulation of {robot.name} ({n} joints, EE frame '{self._ee_frame}'), "
            f"environment {self.environment_description}, dt {dt} s, publishing at "
            f"{params['publish_rate']} Hz, real-time factor {params['real_time_factor'] or 'max'}; "
            "joint brakes hold the arm until the first joint_efforts command"
        )

    def _build_simulator(self, params) -> dict:
        """The simulator, its start state and joint order from the parameters; returns the
        environment's JSON description without the frame."""
        robot, n = self.robot, self.robot.n
        q0 = np.array(params["initial_joint_positions"], dtype=float)
        if q0.shape != (n,):
            raise ConfigError(
                f"parameter 'initial_joint_positions' needs {n} values for joints "
                f"{list(robot.joint_names)}, got {q0.size}"
            )
        try:
            self._order = velocity_joint_order(params["joints"], robot.joint_names)
        except ConfigError as exc:
            raise ConfigError(
                f"{exc}; parameter 'joints' must be a permutation of the model's joints"
            ) from None
        self._joints = list(params["joints"])
        self.environment = params["environment"]
        self.constraint, description = self._environment(params, q0)
        dt = params["step_size"]
        if self.constraint is None:
            self.simulator = FreeArmSimulator(
                robot, initial_q=q0, dt=dt, clip_torque=params["saturate_torque"]
            )
        else:
            q0 = self._start_on_surface(params, q0)
            self.simulator = ContactSimulator(
                robot,
                self.constraint,
                initial_q=q0,
                dt=dt,
                clip_torque=params["saturate_torque"],
            )
        self.initial_q = q0
        return description

    def _create_topics(self) -> None:
        """The state publishers, their prebuilt messages and the torque subscription."""
        state_qos = QoSProfile(depth=10)
        self._wrench_pub = self.create_publisher(WrenchStamped, "wrist_wrench", state_qos)
        self._contact_pub = self.create_publisher(Float64MultiArray, "contact", state_qos)
        self._joint_pub = self.create_publisher(JointState, "joint_states", state_qos)
        self._clock_pub = (
            self.create_publisher(Clock, "/clock", QoSProfile(depth=1))
            if self._publish_clock
            else None
        )
        # prebuilt messages: the 1 kHz publish path only fills numbers in
        self._joint_msg = JointState()
        self._joint_msg.name = list(self.robot.joint_names)
        self._wrench_msg = WrenchStamped()
        self._wrench_msg.header.frame_id = self._ee_frame
        self._contact_msg = Float64MultiArray()
        self._contact_msg.layout.dim = [
            MultiArrayDimension(
                label=" ".join(CONTACT_LABELS), size=len(CONTACT_LABELS), stride=len(CONTACT_LABELS)
            )
        ]
        self._clock_msg = Clock()

        command_qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.create_subscription(Float64MultiArray, "joint_efforts", self._on_efforts, command_qos)

    # --- start-up -----------------------------------------------------------------------------
    def _environment(self, params, q0) -> tuple:
        """(constraint or None, its JSON description without the frame)."""
        kind = params["environment"]
        if kind == "none":
            return None, {"type": "none"}
        if kind == "wall":
            start = FixedBaseState.compute(self.robot, q0, np.zeros(self.robot.n))
            point = params["wall_point"] or start.ee_position
            normal = params["wall_normal"] or start.ee_rotation[:, 2]
            try:
                wall = PlaneConstraint(point, normal)
            except ConfigError as exc:
                raise ConfigError(f"parameters 'wall_point' / 'wall_normal': {exc}") from None
            return wall, {
                "type": "wall",
                "point": wall.point.tolist(),
                "normal": wall.normal.tolist(),
            }
        try:
            arc = ArcConstraint(params["arc_center"], params["arc_radius"], params["arc_axis"])
        except ConfigError as exc:
            raise ConfigError(
                f"parameters 'arc_center' / 'arc_radius' / 'arc_axis': {exc}"
            ) from None
        return arc, {
            "type": "arc",
            "center": arc.center.tolist(),
            "radius": arc.radius,
            "axis": arc.axis.tolist(),
        }

    def _start_on_surface(self, params, q0: np.ndarray) -> np.ndarray:
        """The start configuration on the surface: projected (logged) or checked."""
        start = FixedBaseState.compute(self.robot, q0, np.zeros(self.robot.n))
        phi = self.constraint.phi(start.ee_position)
        if not params["project_start"]:
            if abs(phi) > START_TOLERANCE:
                side = "inside" if phi > 0 else "outside"
                raise ConfigError(
                    f"initial_joint_positions put the end effector {abs(phi):.4g} m {side} the "
                    f"{params['environment']} ({self.constraint!r}); |gap| must be <= "
                    f"{START_TOLERANCE:g} m with project_start false"
                )
            return q0
        projected, _ = project_onto_constraint(self.robot, self.constraint, q0)
        moved = float(np.abs(projected - q0).max())
        self.get_logger().info(
            f"project_start: the start EE point was {abs(phi):.3g} m off the "
            f"{params['environment']}; joints moved by at most {moved:.3g} rad onto it"
        )
        return projected

    # --- commands (executor thread) -----------------------------------------------------------
    def _on_efforts(self, msg: Float64MultiArray) -> None:
        n = self.robot.n
        data = np.asarray(msg.data, dtype=float)
        if data.shape != (n,):
            self._reject(
                f"expected {n} torques [N m] in the order of parameter 'joints' {self._joints}, "
                f"got {data.size}"
            )
            return
        if not np.isfinite(data).all():
            self._reject(f"torques must be finite, got {data.tolist()}")
            return
        tau = data[self._order]
        over = np.abs(tau) > self._limits
        if over.any():
            names = [name for name, bad in zip(self.robot.joint_names, over, strict=True) if bad]
            action = "clipped to" if self._saturate else "NOT clipped (saturate_torque false):"
            self.get_logger().warn(
                f"torque above the effort limit on {names}: {action} the limits "
                f"{self._limits[over].tolist()} N m",
                throttle_duration_sec=1.0,
            )
        with self._lock:
            if self._fault or self._reset_requested:
                return
            self.simulator.set_torque(tau)
            self._saturated = int(over.sum())
            self._command = tau
            self._pacer.command_received(self.simulator.time)
            self.braking = False
            self._braking_logged = False
            self._command_arrived.set()

    def _reject(self, reason: str) -> None:
        self.get_logger().error(f"rejected joint_efforts: {reason}", throttle_duration_sec=1.0)

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        with self._lock:
            self._reset_requested = True
        response.success = True
        response.message = "contact simulation reset to its start state; brakes on until a command"
        return response

    def _on_set_parameters(self, parameters) -> SetParametersResult:
        """Accept or reject run-time changes (applied in :meth:`_on_parameters_set`)."""
        return check_parameter_changes(SPECS, parameters)

    def _on_parameters_set(self, parameters) -> None:
        for parameter in parameters:
            if parameter.name == "real_time_factor":
                self._pacer.set_real_time_factor(float(parameter.value))
            elif parameter.name == "command_timeout":
                self._command_timeout = float(parameter.value)

    # --- simulation loop (own thread) ---------------------------------------------------------
    def _apply_brake(self) -> None:
        """Hold the brake torque (F.2) at the current state over the next step (lock held)."""
        sim = self.simulator
        tau = self.brake.torque(sim.q, sim.v)
        self._saturated = int((np.abs(tau) > self._limits).sum())
        sim.set_torque(tau)

    # --- SteppedSimulation (driven by the LockstepPacer) ---------------------------------------
    def faulted(self) -> bool:
        return self._fault and not self._reset_requested

    def steps_in_callback(self) -> bool:
        return False  # the simulation thread takes every step

    def advance(self) -> float | None:
        """One step (after a requested reset) and what it publishes, /clock with every step;
        the simulated time after it [s], None when it diverged."""
        with self._lock:
            if self._reset_requested:
                self.simulator.reset()
                self._command = None
                self._pacer.reset()
                self._reset_requested, self._fault = False, False
                self.braking, self._braking_logged = True, True
                self._steps = 0
            self._watchdog()
            if self.braking:
                self._apply_brake()
            saturated = self._saturated
            try:
                self.simulator.step()
            except SimulationDivergedError as exc:
                self._fault = True
                self.get_logger().error(
                    f"{exc}. Stopped: publishing that state at rest until ~/reset"
                )
                return None
            self._steps += 1
            publish = self._steps % self._publish_every == 0 or self._pacer.pauses_here()
            sample = self._sample(saturated) if publish else None
            sim_time = self.simulator.time
        if sample is not None:
            self._publish(*sample)
        if self._clock_pub is not None:
            self._clock_msg.clock = stamp_from_seconds(sim_time)
            self._clock_pub.publish(self._clock_msg)
        return sim_time

    def patience_over(self) -> bool:
        """The controller is gone (killed, hung): a torque loop must not leave the arm pushing,
        so brake and run on in real time, as before the first command, until torques come back
        (logged). Lock held."""
        self.get_logger().warn(
            f"lockstep: no joint_efforts for {LOCKSTEP_PATIENCE} s (wall clock) at "
            f"t = {self.simulator.time:.3f} s: joint brakes on, running in real time "
            "until torque commands come back",
            throttle_duration_sec=5.0,
        )
        self._pacer.last_command = None
        self.braking = self._braking_logged = True
        self._pacer.reanchor = True
        return False

    def _watchdog(self) -> None:
        """No valid torque for ``command_timeout``: brakes on, logged once (lock held)."""
        pacer = self._pacer
        if pacer.last_command is None or self.braking:
            return
        if pacer.command_age(pacer.last_command, pacer.command_sim_time) > self._command_timeout:
            self.braking = True
            if not self._braking_logged:
                self.get_logger().warn(
                    f"no valid joint_efforts for {self._command_timeout} s (command_timeout): "
                    "joint brakes on (gravity held, joints damped); the push on the "
                    "environment ends"
                )
                self._braking_logged = True

    def _sample(self, saturated: int):
        """(time, q, v, effort, wrench (6,), contact sample) of the current state (lock held)."""
        sim = self.simulator
        force = sim.contact_force
        phi, phi_dot = sim.constraint_error()
        point = sim.ee_position()
        normal = sim.contact_normal()
        if force >= self._threshold:
            state = 1.0
        elif force <= -self._threshold:
            state = -1.0
        else:
            state = 0.0
        contact = [sim.time, state, force, phi, phi_dot, *point.tolist(), *normal.tolist()]
        contact.append(float(saturated))
        return sim.time, sim.q, sim.v, sim.torque, sim.wrist_wrench(), contact

    def publish_held_state(self) -> None:
        """Faulted: the last finite state at rest (zero velocity, effort, wrench, force)."""
        with self._lock:
            sim = self.simulator
            n = self.robot.n
            phi, _ = sim.constraint_error()
            contact = [sim.time, 0.0, 0.0, phi, 0.0, *sim.ee_position().tolist()]
            contact += [*sim.contact_normal().tolist(), 0.0]
            sample = (sim.time, sim.q.copy(), np.zeros(n), np.zeros(n), np.zeros(6), contact)
        self._publish(*sample)

    def _publish(self, sim_time, q, v, effort, wrench, contact) -> None:
        if not (
            np.isfinite(q).all()
            and np.isfinite(v).all()
            and np.isfinite(effort).all()
            and np.isfinite(wrench).all()
            and all(math.isfinite(x) for x in contact)
        ):
            # the core never keeps a non-finite state; this guards the topics regardless
            self.get_logger().error(
                f"non-finite state at t = {sim_time:.6g} s not published", throttle_duration_sec=1.0
            )
            return
        stamp = (
            stamp_from_seconds(sim_time) if self._publish_clock else self.get_clock().now().to_msg()
        )
        msg = self._wrench_msg
        msg.header.stamp = stamp
        f, m = msg.wrench.force, msg.wrench.torque
        f.x, f.y, f.z, m.x, m.y, m.z = wrench.tolist()
        self._wrench_pub.publish(msg)
        self._contact_msg.data = contact
        self._contact_pub.publish(self._contact_msg)
        joints = self._joint_msg
        joints.header.stamp = stamp
        joints.position = q.tolist()
        joints.velocity = v.tolist()
        joints.effort = effort.tolist()
        self._joint_pub.publish(joints)

    def destroy_node(self) -> None:
        stop_worker(self._thread, self._stop)
        super().destroy_node()
