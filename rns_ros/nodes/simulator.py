"""rns_simulator: the free-floating satellite + arm, integrated at a fixed step, as a ROS 2 node.

Physics is :class:`rns_ros.sim.free_floating.FreeFloatingSimulator`; this node only converts
messages. It steps from its own monotonic-clock thread (absolute deadlines, so no drift), not from
an executor timer (in lockstep at ``real_time_factor`` 0: from the command callback, below).

Publishes (all remappable):
    joint_states  sensor_msgs/JointState      names, positions [rad], velocities [rad/s],
                                              efforts [N m] (dynamic mode only)
    base_odom     nav_msgs/Odometry           base pose in ``world_frame``; twist in the base
                                              frame (child_frame_id = base link)
    momentum      geometry_msgs/WrenchStamped force = linear momentum p [kg m/s], torque =
                                              angular momentum about the system CoM [kg m^2/s],
                                              both in ``world_frame`` axes
    energy        std_msgs/Float64MultiArray  at ``energy_rate`` (20 Hz): kinetic energy of the
                                              true state, layout
                                              :data:`ENERGY_LABELS` (eq. 5.1 terms, the
                                              Lambda_m / Lambda_r cost of the joint motion,
                                              running C_max and C_sum, sim time) [J, J s, s]
    wheel_states  sensor_msgs/JointState      with ``reaction_wheels``: wheel_x/y/z spin angle
                                              [rad], rate relative to the base [rad/s], applied
                                              motor torque [N m] (after the limits)
    /clock        rosgraph_msgs/Clock         when ``publish_clock`` is true: every step; in
                                              lockstep only with each state publication (the
                                              ``publish_rate`` grid and every pause), so other
                                              nodes' sim-time timers fire at those instants
With ``lockstep_period`` > 0 the simulation pauses whenever it is that far (simulated time) past
the newest joint command, so a controller sees the same sampling at any ``real_time_factor``;
before the first command it runs in real time, and a controller that stops answering pauses it
(after ``LOCKSTEP_PATIENCE`` of wall time one step is taken, with its state and /clock).
The period counts on the grid of the command's header stamp when /clock is published and the
stamp is a recent simulated time (from the stamp itself, or from the last point of its grid
before now for a command older than a period; a controller ticking on this clock: the next
pause is its next tick, whatever the command's latency), else from its receipt. A
JointTrajectory stamped ahead of the simulated time (with /clock, by at most
``lockstep_period``, or ``MAX_CATCH_UP`` without lockstep) waits for its stamp, as a trajectory
controller starts a trajectory at its header stamp: a controller that stamps its output one
period after its tick (rns_controller ``output_lead``) computes while this node simulates the
period before it, so the two run side by side instead of in turn. ``command_timeout`` then counts
simulated time, and the state is also published at each pause (off the ``publish_rate`` grid
if the controller's ticks are), so the controller's tick there samples that instant. At
``real_time_factor`` 0 the command callback itself steps to the next pause (up to
``CALLBACK_STEPS`` steps, the simulation thread goes on beyond them): the executor thread runs
the whole period, with no hand-off between threads.
Subscribes:
    joint_references  trajectory_msgs/JointTrajectory (``command_interface: trajectory``),
                      first point: positions/velocities/accelerations matched by joint name
    joint_velocities  std_msgs/Float64MultiArray (``command_interface: velocity``), one velocity
                      [rad/s] per joint in the order of the ``joints`` parameter (the
                      ros2_control forward_command_controller convention)
    wheel_torque      geometry_msgs/Vector3Stamped (with ``reaction_wheels``): motor torques of
                      the x, y, z wheels [N m] (frame_id empty or the base link), clipped to
                      ``wheel_torque_limit``; older than ``command_timeout``: motors off
Also publishes, once, ``robot_description`` (std_msgs/String, transient local, depth 1): the URDF
text of the simulated model, for robot_state_publisher / rviz users (latched: late joiners get it).
Service:
    ~/reset       std_srvs/Trigger            back to the initial state, at rest; clears a fault

Safety: a JointTrajectory whose positions lie outside the URDF position limits or farther than
``max_reference_error`` from the current joint angles is rejected (logged, no motion). For
``reset_hold`` of simulated time after ``~/reset`` joint commands are ignored, so every controller
sees the reset state before it commands again (a stale one would pull the arm back); a
JointTrajectory that starts at the reset state ends the hold early (a resynchronized
controller). In dynamic mode the servo keeps the URDF velocity and effort limits (see
:mod:`rns_ros.sim.free_floating`).
If a step diverges anyway (:class:`SimulationDivergedError`) the node logs one error and stops
stepping: it keeps publishing the last finite state with zero velocities (joint and base) and
zero efforts until ``~/reset``; no non-finite value is ever published.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from typing import NamedTuple

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import Vector3Stamped, WrenchStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import SetParametersResult
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from rclpy.utilities import remove_ros_args
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, String
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from rns_ros.core import FreeFloatingModel, FreeFloatingState, load_model_config
from rns_ros.core.commands import (
    check_reference_positions,
    check_velocity_limits,
    match_named_command,
)
from rns_ros.core.conventions import base_twist_to_world
from rns_ros.core.energy import EnergyCost, energy_metric, kinetic_energy
from rns_ros.core.errors import ConfigError, InputError, SimulationDivergedError
from rns_ros.nodes.cdr import (
    JointTrajectoryReader,
    SerializedTemplate,
    TemplateError,
    clock_template,
    joint_state_template,
    odometry_template,
    wrench_template,
)
from rns_ros.nodes.parameters import (
    JOINTS,
    MODEL_CONFIG,
    WORLD_FRAME,
    ParameterSpec,
    declare_parameters,
    specs_by_name,
    velocity_joint_order,
)
from rns_ros.nodes.runner import ROS_STARTUP_ERRORS, parameter_help, run_node, stop_worker
from rns_ros.resources import default_model_config
from rns_ros.sim.free_floating import FreeFloatingSimulator, ServoGains, SimulationState
from rns_ros.sim.reaction_wheels import WHEEL_NAMES, ReactionWheels

NODE_NAME = "rns_simulator"
SUMMARY = (
    "Free-floating space robot simulator (kinematic or dynamic mode, fixed-step RK4); contact "
    "mode (-p mode:=contact): the fixed-base Part II arm against a wall or cylinder, below."
)
#: Oldest JointTrajectory stamp [s] the kinematic mode still catches up to (older: another clock
#: or a stale command, acted on at receipt).
MAX_CATCH_UP = 0.05
#: Lockstep: a command stamped up to this long [s] before the simulated time still puts the
#: pauses on its stamp's grid (older: another clock; the period counts from its receipt).
MAX_GRID_AGE = 1.0
#: Largest lag [s] of a state's stamp behind its publication (an overloaded simulator re-anchors
#: its pace at 0.5 s behind).
MAX_STAMP_LAG = 0.5
#: A lockstep pause longer than this [s] (wall time) is reported and ends with one step, so a
#: controller whose sim-time timer waits for a later /clock is never deadlocked.
LOCKSTEP_PATIENCE = 2.0
#: Lockstep at real_time_factor 0: a command callback runs at most this many steps to the next
#: pause itself (a long lockstep_period goes on in the simulation thread, so the executor is
#: not blocked for long).
CALLBACK_STEPS = 200
#: After ~/reset, a JointTrajectory starting this close to the reset angles [rad] ends the
#: reset hold (a resynchronized controller); the hold otherwise lasts ``reset_hold``.
RESET_MATCH_TOLERANCE = 0.01
#: Layout of the ``energy`` topic (Float64MultiArray; also the label of its one dimension):
#: eq. (5.1) terms of the true state [J], the arm's motion costed with Lambda_m and Lambda_r of
#: eq. (5.3) [J], the running C_max [J] and C_sum [J s] of eqs. (5.12)-(5.13) since the start or
#: the last ~/reset, and the simulated time of the sample [s].
ENERGY_LABELS = (
    "base",
    "arm",
    "coupling",
    "wheels",
    "total",
    "lambda_arm",
    "lambda_wheels",
    "c_max",
    "c_sum",
    "time",
)
SATELLITE_OBSERVATION_RAD = [math.radians(a) for a in (-90.0, -30.0, 0.0, -70.0, 180.0, -30.0, 0.0)]

PARAMETERS = (
    MODEL_CONFIG,
    ParameterSpec(
        "mode",
        "kinematic",
        "kinematic: joints follow commanded velocities exactly; dynamic: ABA + joint servo; "
        "contact: the fixed-base Part II arm driven by joint torques, its end effector on a "
        "rigid wall or cylinder (its own parameters: see 'contact mode' in --help, "
        "config/contact_simulator.yaml)",
        choices=("kinematic", "dynamic", "contact"),
    ),
    ParameterSpec("step_size", 0.001, "Fixed RK4 integration step", "[s]", 1e-5, 0.1),
    ParameterSpec(
        "publish_rate", 100.0, "State publishing rate in simulated time", "[Hz]", 1.0, 1000.0
    ),
    ParameterSpec(
        "real_time_factor",
        1.0,
        "Simulated seconds per wall-clock second; 0 runs as fast as possible",
        "[-]",
        0.0,
        1000.0,
        read_only=False,
    ),
    ParameterSpec(
        "initial_joint_positions",
        SATELLITE_OBSERVATION_RAD,
        "Initial joint angles in model joint order (default: thesis satellite observation)",
        "[rad]",
        -2 * math.pi,
        2 * math.pi,
    ),
    ParameterSpec(
        "initial_base_position",
        [0.0, 0.0, 0.0],
        "Initial base CoM position in world",
        "[m]",
        -1e6,
        1e6,
        length=(3,),
    ),
    ParameterSpec(
        "initial_base_orientation",
        [0.0, 0.0, 0.0, 1.0],
        "Initial base attitude quaternion x y z w (normalized on use)",
        "[-]",
        -1.0,
        1.0,
        length=(4,),
    ),
    ParameterSpec(
        "initial_momentum",
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        "Conserved momentum [p; l] about the system CoM, world axes",
        "[kg m/s, kg m^2/s]",
        -1e6,
        1e6,
        length=(6,),
    ),
    ParameterSpec(
        "command_interface",
        "trajectory",
        "trajectory: JointTrajectory on joint_references; velocity: Float64MultiArray on "
        "joint_velocities (order: the joints parameter)",
        choices=("trajectory", "velocity"),
    ),
    JOINTS,
    ParameterSpec(
        "command_timeout",
        0.5,
        "A command older than this (by receipt time; simulated time in lockstep) is dropped and "
        "the joints stop",
        "[s]",
        0.01,
        60.0,
        read_only=False,
    ),
    ParameterSpec(
        "publish_clock",
        False,
        "Publish /clock (sim time) and stamp messages with it: every step; in lockstep with each "
        "state publication only",
    ),
    ParameterSpec(
        "lockstep_period",
        0.0,
        "Lockstep with a controller: never run more than this much simulated time past the "
        "newest joint command (set it to the controller's period to sample as in real time at "
        "any real_time_factor; real time before the first command, paused when they stop); "
        "command_timeout then counts simulated time; 0: off",
        "[s]",
        0.0,
        10.0,
    ),
    WORLD_FRAME,
    ParameterSpec(
        "servo_natural_frequency",
        50.0,
        "Dynamic-mode joint servo bandwidth omega_n",
        "[rad/s]",
        1.0,
        1000.0,
    ),
    ParameterSpec(
        "servo_damping_ratio", 1.0, "Dynamic-mode joint servo damping ratio", "[-]", 0.1, 10.0
    ),
    ParameterSpec(
        "joint_friction",
        0.0,
        "Viscous joint friction in the dynamic plant",
        "[N m s/rad]",
        0.0,
        1e4,
    ),
    ParameterSpec(
        "catch_up_late_commands",
        True,
        "Kinematic mode: a JointTrajectory acts from its header stamp, as a trajectory "
        "controller samples it; one that arrives late (up to 50 ms) makes up the motion it "
        "missed in the next step (false: it acts on receipt, at the next step)",
    ),
    ParameterSpec(
        "max_reference_error",
        0.25,
        "A JointTrajectory position farther than this from the current joint angle is rejected "
        "(rns_controller resyncs beyond 0.2 rad; its references track within ~1e-2 rad)",
        "[rad]",
        0.01,
        10.0,
    ),
    ParameterSpec(
        "energy_rate",
        20.0,
        "Rate of the energy topic and of its running C_max / C_sum (sampled with the state: "
        "rounded to a whole number of state publications; 0: no energy topic)",
        "[Hz]",
        0.0,
        1000.0,
    ),
    ParameterSpec(
        "reaction_wheels",
        False,
        "Three orthogonal reaction wheels on the base (spin axes base x, y, z; their mass and "
        "locked inertia are part of the URDF base): wheel_torque in, wheel_states out",
    ),
    ParameterSpec(
        "wheel_inertia",
        0.11,
        "Spin inertia I_r of one wheel (also the I_r of the energy metric Lambda_r)",
        "[kg m^2]",
        1e-6,
        1e3,
    ),
    ParameterSpec(
        "wheel_torque_limit", 0.1, "Motor torque limit per wheel (ETS-VII: 0.1)", "[N m]", 1e-6, 1e3
    ),
    ParameterSpec(
        "wheel_speed_limit",
        200.0 * math.pi,
        "Spin-rate limit per wheel, relative to the base (6000 rpm)",
        "[rad/s]",
        1e-3,
        1e5,
    ),
    ParameterSpec(
        "reset_hold",
        0.2,
        "After ~/reset, joint commands are ignored for this long (simulated time) and the arm "
        "rests at the reset state, so controllers see the new state before commanding",
        "[s]",
        0.0,
        10.0,
    ),
)
SPECS = specs_by_name(PARAMETERS)


class WheelSnapshot(NamedTuple):
    """Wheel state to publish: angles [rad], speeds relative to the base [rad/s] and applied
    torques [N m], each (3,) in base x, y, z order."""

    angles: np.ndarray
    speeds: np.ndarray
    torques: np.ndarray


class _StateTemplates(NamedTuple):
    """Pre-serialized state messages (see :meth:`SimulatorNode._state_templates`)."""

    joints: SerializedTemplate
    odom: SerializedTemplate
    momentum: SerializedTemplate
    clock: SerializedTemplate


def pace_lead(pace: tuple[float, float, float], sim_time: float) -> float:
    """Wall time [s] until the real-time pace (wall anchor [s], simulated anchor [s], real-time
    factor > 0) reaches ``sim_time`` [s]; negative once it is past."""
    wall_anchor, sim_anchor, factor = pace
    return wall_anchor + (sim_time - sim_anchor) / factor - time.monotonic()


def stamp_from_seconds(seconds: float) -> TimeMsg:
    """builtin_interfaces/Time for a simulated time [s], rounded to the nanosecond (so a time
    summed from steps, 1.9999999999 s, is 2 s: the tick a sim-time timer waits for)."""
    sec, nanosec = divmod(round(seconds * 1e9), 1_000_000_000)
    return TimeMsg(sec=int(sec), nanosec=int(nanosec))


class SimulatorNode(Node):
    """ROS 2 wrapper of :class:`FreeFloatingSimulator` (see the module docstring)."""

    def __init__(self, **node_kwargs) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        params = declare_parameters(self, PARAMETERS)
        urdf_path, spec = load_model_config(params["model_config"] or default_model_config())
        self.robot = FreeFloatingModel.from_urdf(urdf_path, spec)
        n = self.robot.n
        if len(params["initial_joint_positions"]) != n:
            raise ConfigError(
                f"parameter 'initial_joint_positions' needs {n} values for joints "
                f"{list(self.robot.joint_names)}, got {len(params['initial_joint_positions'])}"
            )
        gains = ServoGains.critically_damped(
            n,
            params["servo_natural_frequency"],
            params["servo_damping_ratio"],
            params["joint_friction"],
        )
        initial_q = self.robot.configuration(
            params["initial_joint_positions"],
            params["initial_base_position"],
            params["initial_base_orientation"],
        )
        self.simulator = FreeFloatingSimulator(
            self.robot,
            mode=params["mode"],
            dt=params["step_size"],
            initial_q=initial_q,
            initial_momentum=params["initial_momentum"],
            gains=gains,
            wheels=ReactionWheels(
                inertia=params["wheel_inertia"],
                torque_limit=params["wheel_torque_limit"],
                speed_limit=params["wheel_speed_limit"],
            )
            if params["reaction_wheels"]
            else None,
        )
        self._wheels = params["reaction_wheels"]
        self._wheel_inertia = params["wheel_inertia"]
        self._energy_cost = EnergyCost()
        # the energy needs one CRBA and a message (~0.4 ms): every k-th state, not every one
        self._energy_every = (
            0
            if params["energy_rate"] <= 0.0
            else max(1, round(params["publish_rate"] / params["energy_rate"]))
        )
        self._state_publications = 0
        self._last_wheel_command: float | None = None  # monotonic receipt time [s]
        self._wheel_command_sim_time = 0.0
        self._wheel_stale_logged = False
        self._publish_every = max(1, round(1.0 / (params["publish_rate"] * params["step_size"])))
        self._real_time_factor = params["real_time_factor"]
        self._command_timeout = params["command_timeout"]
        self._publish_clock = params["publish_clock"]
        self._lockstep = params["lockstep_period"]
        self._world_frame = params["world_frame"]
        self._dynamic = params["mode"] == "dynamic"
        self._max_reference_error = params["max_reference_error"]
        self._catch_up = params["catch_up_late_commands"]
        self._reset_hold = params["reset_hold"]
        self._publish_period = 1.0 / params["publish_rate"]  # [s], wall time while faulted

        self._lock = threading.Lock()
        # held by whoever steps (the simulation thread, or a command callback: _run_to_pause)
        self._stepping = threading.Lock()
        self._steps = 0  # since the start or the last reset
        self._stop = threading.Event()
        # (wall anchor [s], simulated anchor [s], real-time factor) of the stepping thread's
        # pace, for the stamps; None off real time (a step run from a command callback)
        self._pace: tuple[float, float, float] | None = None
        self._reset_requested = False
        self._last_command = None  # monotonic receipt time of the active command
        # simulated time the lockstep period and the age of that command count from [s]: its
        # stamp when that is a recent simulated time (see _command_anchor), else its receipt
        self._command_sim_time = 0.0
        self._command_arrived = threading.Event()
        # a JointTrajectory stamped ahead (sim time): (stamp [s], positions, velocities,
        # accelerations), set as the reference at the first step from its stamp
        self._pending: tuple | None = None
        self._paused_since: float | None = None  # monotonic start of a lockstep pause [s]
        self._stale_logged = False
        self._reanchor = True
        self._hold_until = -math.inf  # simulated time [s] before which commands are ignored
        self._hold_logged = False
        self._fault = False  # a step diverged: frozen at the last finite state until ~/reset

        # State streams: reliable, shallow; consumers want the latest state.
        state_qos = QoSProfile(depth=10)
        self._joint_pub = self.create_publisher(JointState, "joint_states", state_qos)
        self._odom_pub = self.create_publisher(Odometry, "base_odom", state_qos)
        self._momentum_pub = self.create_publisher(WrenchStamped, "momentum", state_qos)
        self._energy_pub = self.create_publisher(Float64MultiArray, "energy", state_qos)
        self._wheel_pub = (
            self.create_publisher(JointState, "wheel_states", state_qos) if self._wheels else None
        )
        self._clock_pub = (
            self.create_publisher(Clock, "/clock", QoSProfile(depth=1))
            if self._publish_clock
            else None
        )
        # reused messages: only the stamp and the values change from one state to the next
        self._joints_msg = JointState(name=list(self.robot.joint_names))
        self._odom_msg = Odometry(child_frame_id=self.robot.base_link)
        self._odom_msg.header.frame_id = self._world_frame
        self._momentum_msg = WrenchStamped()
        self._momentum_msg.header.frame_id = self._world_frame
        self._clock_msg = Clock()
        self._templates = self._state_templates()
        # Commands: best effort, depth 1 - the newest command is the only one that matters, and
        # a best-effort subscription accepts reliable and best-effort publishers alike.
        command_qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        if params["command_interface"] == "trajectory":
            # depth 10: a trajectory stamped ahead (lockstep side by side) follows the one
            # before it, so none may be dropped while a callback steps; they are taken in order
            # taken serialized: the simulator reads the first point from the bytes
            # (rns_ros.nodes.cdr), cheaper than rclpy building the message (~27 us)
            self._trajectory_reader = JointTrajectoryReader()
            self.create_subscription(
                JointTrajectory,
                "joint_references",
                self._on_trajectory,
                QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT),
                raw=True,
            )
        else:
            self._velocity_order = velocity_joint_order(params["joints"], self.robot.joint_names)
            self._velocity_joints = list(params["joints"])
            self.create_subscription(
                Float64MultiArray, "joint_velocities", self._on_velocities, command_qos
            )
        if self._wheels:
            self.create_subscription(
                Vector3Stamped, "wheel_torque", self._on_wheel_torque, command_qos
            )
        # Transient local, depth 1: the robot_state_publisher convention, so a subscriber that
        # starts later still receives the model.
        description_qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self._description_pub = self.create_publisher(String, "robot_description", description_qos)
        self._description_pub.publish(String(data=urdf_path.read_text()))
        self.create_service(Trigger, "~/reset", self._on_reset)
        self.add_on_set_parameters_callback(self._on_set_parameters)

        self._thread = threading.Thread(target=self._run, name="rns_simulator_loop", daemon=True)
        self._thread.start()
        self.get_logger().info(
            f"{params['mode']} simulation of {self.robot.name} ({n} joints), dt "
            f"{params['step_size']} s, publishing at {params['publish_rate']} Hz, real-time "
            f"factor {self._real_time_factor or 'max'}"
        )

    # --- commands (executor thread) -----------------------------------------------------------
    def _on_trajectory(self, data: bytes) -> None:
        msg = self._trajectory_reader(data)
        if not msg.points:
            self._reject("JointTrajectory has no points")
            return
        try:
            command = match_named_command(
                msg.names,
                self.robot.joint_names,
                positions=msg.positions,
                velocities=msg.velocities,
                accelerations=msg.accelerations,
                velocity_limits=self.robot.velocity_limits,
            )
            if not self._dynamic and command.velocities is None:
                raise InputError("kinematic mode needs velocities in the trajectory point")
            if command.positions is not None:
                with self._lock:
                    theta = self.simulator.q[7:].copy()
                check_reference_positions(
                    command.positions,
                    theta,
                    self.robot.lower_limits,
                    self.robot.upper_limits,
                    self._max_reference_error,
                    self.robot.joint_names,
                )
        except InputError as exc:
            if not self._ignoring_commands():
                self._reject(str(exc))
            return
        if self._ignoring_commands(command.positions):
            return
        stamp = msg.stamp[0] + 1e-9 * msg.stamp[1]
        self._accept(command.positions, command.velocities, command.accelerations, stamp)

    def _on_velocities(self, msg: Float64MultiArray) -> None:
        if self._ignoring_commands():
            return
        try:
            velocities = np.asarray(msg.data, dtype=float)
            if velocities.shape != (self.robot.n,):
                raise InputError(
                    f"expected {self.robot.n} velocities in joint order "
                    f"{self._velocity_joints} (parameter 'joints'), got {velocities.size}"
                )
            velocities = velocities[self._velocity_order]
            if not np.all(np.isfinite(velocities)):
                raise InputError(f"velocities must be finite, got {velocities.tolist()}")
            check_velocity_limits(velocities, self.robot.velocity_limits, self.robot.joint_names)
        except InputError as exc:
            self._reject(str(exc))
            return
        self._accept(None, velocities, None)

    def _on_wheel_torque(self, msg: Vector3Stamped) -> None:
        frame = msg.header.frame_id
        if frame not in ("", self.robot.base_link):
            self._reject_wheels(
                f"frame_id {frame!r}: wheel torques are about the base axes, frame_id "
                f"{self.robot.base_link!r} or empty"
            )
            return
        v = msg.vector
        torque = np.array([v.x, v.y, v.z])
        if not np.isfinite(torque).all():
            self._reject_wheels(f"torques must be finite, got {torque.tolist()}")
            return
        with self._lock:
            if self._fault or self._reset_requested or self.simulator.time < self._hold_until:
                return
            self.simulator.set_wheel_torque(torque)  # clipped to the limits at every step
            self._last_wheel_command = time.monotonic()
            self._wheel_command_sim_time = self.simulator.time
            self._wheel_stale_logged = False

    def _reject_wheels(self, reason: str) -> None:
        self.get_logger().error(f"rejected wheel torque: {reason}", throttle_duration_sec=1.0)

    def _ignoring_commands(self, positions: np.ndarray | None = None) -> bool:
        """True (logged) while faulted or within ``reset_hold`` after a reset. A reference whose
        ``positions`` start at the reset state (within ``RESET_MATCH_TOLERANCE``) ends the hold:
        it comes from a controller that has seen the reset state and resynchronized, and
        holding it off would only let that controller's reference run ahead of the arm."""
        with self._lock:
            if self._fault:
                self._reject("the simulation diverged and is stopped; call ~/reset")
                return True
            if self._reset_requested or self.simulator.time < self._hold_until:
                if (
                    not self._reset_requested
                    and positions is not None
                    and np.abs(positions - self.simulator.q[7:]).max() <= RESET_MATCH_TOLERANCE
                ):
                    self._hold_until = -math.inf
                    return False
                if not self._hold_logged:
                    self.get_logger().warn(
                        f"ignoring joint commands for reset_hold = {self._reset_hold} s after "
                        "~/reset (simulated time), or until a reference starts at the reset "
                        "state: controllers must see the reset state first"
                    )
                    self._hold_logged = True
                return True
        return False

    def _accept(self, positions, velocities, accelerations, stamp: float | None = None) -> None:
        with self._lock:
            if self._fault or self._reset_requested or self.simulator.time < self._hold_until:
                return  # changed since the check: the command is stale now
            if self._ahead(stamp):
                self._pending = (stamp, positions, velocities, accelerations)
            else:
                self._pending = None  # a newer command replaces one still waiting
                self.simulator.set_reference(
                    positions, velocities, accelerations, since=self._lateness(stamp)
                )
            if self._last_command is None and self._lockstep > 0.0:
                self._reanchor = True  # lockstep starts: leave the real-time pace of the wait
            self._last_command = time.monotonic()
            self._command_sim_time = self._command_anchor(stamp)
            self._stale_logged = False
            self._paused_since = None
            in_callback = self._steps_in_callback()
            if not in_callback:
                self._command_arrived.set()
        if in_callback:
            self._run_to_pause()

    def _ahead(self, stamp: float | None) -> bool:
        """A command stamped ``stamp`` [s] waits for it: /clock is published and the stamp lies
        after the next step's start, by at most ``lockstep_period`` (``MAX_CATCH_UP`` without
        lockstep). Caller holds the lock."""
        if stamp is None or not self._publish_clock:
            return False
        now, dt = self.simulator.time, self.simulator.dt
        lead = self._lockstep if self._lockstep > 0.0 else MAX_CATCH_UP
        return now + 0.5 * dt < stamp <= now + lead + 0.5 * dt

    def _start_pending(self) -> None:
        """The waiting command becomes the reference once the next step starts at its stamp.
        Caller holds the lock."""
        if (
            self._pending is not None
            and self.simulator.time + 0.5 * self.simulator.dt >= self._pending[0]
        ):
            _, positions, velocities, accelerations = self._pending
            self._pending = None
            self.simulator.set_reference(positions, velocities, accelerations)

    def _command_anchor(self, stamp: float | None) -> float:
        """Simulated time [s] a command's lockstep period counts from, on the grid of its
        header ``stamp`` [s] when /clock is published and the stamp is a recent simulated
        time (a controller ticking on this clock stamps the instant it sampled or, with a lead,
        the instant its output starts): the stamp itself when it lies within the period before
        now or waits ahead (:meth:`_ahead`); a later point of its grid, stamp + k
        ``lockstep_period``, the last one not after now, when the command is older (the first
        one reaches a simulation still running in real time a few periods late), so the next
        pause falls on that controller's next tick whatever the latency. Else (no stamp, a
        wall-clock stamp, one older than ``MAX_GRID_AGE``) the simulated time of receipt.
        Caller holds the lock."""
        now, dt = self.simulator.time, self.simulator.dt
        if (
            stamp is None
            or not self._publish_clock
            or self._lockstep <= 0.0
            or not now - MAX_GRID_AGE <= stamp <= now + self._lockstep + 0.5 * dt
        ):
            return now
        behind = math.floor((now + 0.5 * dt - stamp) / self._lockstep)
        return stamp + max(behind, 0) * self._lockstep

    def _reject(self, reason: str) -> None:
        self.get_logger().error(f"rejected joint command: {reason}", throttle_duration_sec=1.0)

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        with self._lock:
            self._reset_requested, self._hold_logged = True, False
        self._command_arrived.set()  # a paused simulation thread resets at once
        response.success = True
        response.message = "simulation reset to its initial state"
        return response

    def _on_set_parameters(self, parameters) -> SetParametersResult:
        for parameter in parameters:
            if parameter.name == "real_time_factor":
                self._real_time_factor = float(parameter.value)
                self._reanchor = True
            elif parameter.name == "command_timeout":
                self._command_timeout = float(parameter.value)
        self._command_arrived.set()  # a paused simulation thread rechecks who steps
        return SetParametersResult(successful=True)

    # --- simulation loop (own thread; in lockstep at real_time_factor 0 the command callback) ---
    def _run(self) -> None:
        wall_anchor = sim_anchor = 0.0
        while not self._stop.is_set():
            if self._fault and not self._reset_requested:
                self._publish_held_state()
                self._stop.wait(self._publish_period)
                self._reanchor = True
                continue
            forced = self._await_command()
            if forced is None:
                self._reanchor = True  # paused for the controller: do not sprint afterwards
                continue
            if self._reanchor:
                wall_anchor, sim_anchor, self._reanchor = (
                    time.monotonic(),
                    self.simulator.time,
                    False,
                )
            factor = self._real_time_factor
            if self._lockstep > 0.0 and self._last_command is None:
                # no controller yet: real time, so it joins before much simulated time passes
                factor = 1.0
            # real time: states are stamped with the instant the pace maps them to
            pace = (wall_anchor, sim_anchor, factor) if factor > 0.0 else None
            self._pace = pace
            with self._stepping:
                # the command callback may have run to the pause since the check
                if not forced and self._paused():
                    continue
                sim_time = self._advance()
            if sim_time is None:
                continue
            if pace is not None:
                delay = pace_lead(pace, sim_time)
                if delay > 0.0:
                    self._stop.wait(delay)
                elif delay < -0.5:
                    self._reanchor = True  # far behind (overloaded machine): do not sprint

    def _advance(self) -> float | None:
        """One step (after a requested reset) and what it publishes; the simulated time after
        it [s], None when it diverged. Caller holds ``_stepping``."""
        with self._lock:
            if self._reset_requested:
                self.simulator.reset()
                self._pending = None
                self._last_command, self._reset_requested, self._reanchor = None, False, True
                self._command_sim_time = 0.0
                self._hold_until = self.simulator.time + self._reset_hold
                self._fault = False
                self._last_wheel_command = None
                self._energy_cost = EnergyCost()
                self._steps = 0
            self._expire_stale_command()
            self._start_pending()
            try:
                self.simulator.step()
            except SimulationDivergedError as exc:
                self._fault = True
                self.get_logger().error(
                    f"{exc}. Stopped: publishing that state with zero velocities until ~/reset"
                )
                return None
            self._steps += 1
            # a lockstep pause also publishes the state there: the controller's tick at the
            # pause samples this instant, not the last grid point (stale by up to a period)
            pauses = self._pauses_here()
            if pauses:
                self._paused_since = time.monotonic()
            publish = self._steps % self._publish_every == 0 or pauses
            snapshot = self.simulator.snapshot() if publish else None
            momentum = self.simulator.centroidal_momentum() if publish else None
            wheels = self._wheel_snapshot() if publish else None
            sim_time = self.simulator.time
        # lockstep: /clock only with the states (so at every pause); without it, every step
        clock = self._clock_pub is not None and (snapshot is not None or self._lockstep <= 0.0)
        if snapshot is not None:
            self._publish_state(snapshot, momentum, wheels, clock=clock)
        elif clock:
            self._send_clock(sim_time)
        return sim_time

    def _state_templates(self) -> _StateTemplates | None:
        """The state messages pre-serialized (:mod:`rns_ros.nodes.cdr`: the conversion of four
        messages was about a third of a lockstep period's CPU here), or None to publish
        messages when a layout cannot be captured."""
        try:
            return _StateTemplates(
                joints=joint_state_template(self.robot.joint_names, effort=self._dynamic),
                odom=odometry_template(self._world_frame, self.robot.base_link),
                momentum=wrench_template(self._world_frame),
                clock=clock_template(),
            )
        except TemplateError as exc:
            self.get_logger().warn(f"{exc}: publishing state messages unserialized")
            return None

    def _send_clock(self, sim_time: float) -> None:
        stamp = stamp_from_seconds(sim_time)
        if self._templates is not None:
            self._clock_pub.publish(self._templates.clock.serialize({}, (stamp.sec, stamp.nanosec)))
            return
        self._clock_msg.clock = stamp
        self._clock_pub.publish(self._clock_msg)

    def _steps_in_callback(self) -> bool:
        """Lockstep as fast as possible once a controller answers: the command callback steps
        to the next pause itself (no hand-off to the simulation thread)."""
        return (
            self._lockstep > 0.0
            and self._real_time_factor == 0.0
            and self._last_command is not None
            and not self._fault
            and not self._reset_requested
        )

    def _run_to_pause(self) -> None:
        """Executor thread, after a command: step until the next lockstep pause (at most
        ``CALLBACK_STEPS`` steps; the simulation thread takes over beyond them)."""
        with self._stepping:
            self._pace = None  # off real time: stamped when published
            for _ in range(CALLBACK_STEPS):
                with self._lock:
                    if self._stop.is_set() or not self._steps_in_callback() or self._pauses_here():
                        break
                if self._advance() is None:
                    break
            paused = self._paused()
        if not paused:  # beyond CALLBACK_STEPS, a reset, a fault: the simulation thread goes on
            self._command_arrived.set()

    def _paused(self) -> bool:
        with self._lock:
            return self._pauses_here()

    def _pauses_here(self) -> bool:
        """Lockstep: the simulation has reached ``lockstep_period`` past the newest command."""
        if self._lockstep <= 0.0 or self._last_command is None:
            return False
        ahead = self.simulator.time + 0.5 * self.simulator.dt - self._command_sim_time
        return ahead >= self._lockstep

    def _await_command(self) -> bool | None:
        """Lockstep: None (after a wait) while the next step would run more than
        ``lockstep_period`` of simulated time past the newest command; else False, or True for
        the one step of a pause that outlasted ``LOCKSTEP_PATIENCE``. Before the first command
        it runs in real time (a controller starts from the published states). A controller that
        stops answering pauses the simulation rather than letting the robot run on under an old
        command: after ``LOCKSTEP_PATIENCE`` it is logged and one step is taken."""
        if self._lockstep <= 0.0:
            return False
        with self._lock:
            wait = self._pause_wait()
        if wait is None:
            return False
        if wait == 0.0:
            return True
        self._command_arrived.wait(wait)
        return None

    def _pause_wait(self) -> float | None:
        """For :meth:`_await_command`: None to step, 0 for the one step after the patience,
        else the wait [s] for the command event. Caller holds the lock."""
        if not self._pauses_here():
            self._paused_since = None
            if not self._steps_in_callback() or self._command_arrived.is_set():
                return None
            # a command callback is stepping to the pause: only wait (racing it for the
            # stepping lock cost both threads a GIL hand-off per period); it sets the event
            # when it hands on
            self._command_arrived.clear()
            return 0.1
        now = time.monotonic()
        if self._paused_since is None:
            self._paused_since = now
        elif now - self._paused_since > LOCKSTEP_PATIENCE:
            # one step: a controller whose timer waits for a later /clock gets it
            self.get_logger().warn(
                f"lockstep: no joint command for {LOCKSTEP_PATIENCE} s at "
                f"t = {self.simulator.time:.3f} s; one step on",
                throttle_duration_sec=5.0,
            )
            self._paused_since = now
            return 0.0
        self._command_arrived.clear()
        # the callback steps at real_time_factor 0: wake for the patience only (and for a
        # reset, a parameter change, the end of a callback's run: they set the event)
        return 0.005 if self._real_time_factor > 0.0 else 0.1

    def _wheel_snapshot(self) -> WheelSnapshot | None:
        if not self._wheels:
            return None
        sim = self.simulator
        return WheelSnapshot(
            sim.wheel_angles.copy(), sim.wheel_speeds.copy(), sim.wheel_torque.copy()
        )

    def _command_age(self, received: float, sim_received: float) -> float:
        """Age of a command [s]: simulated time in lockstep (a paused simulation does not move,
        so a controller busy for a while only pauses it), else wall time."""
        if self._lockstep > 0.0:
            return self.simulator.time - sim_received
        return time.monotonic() - received

    def _expire_stale_command(self) -> None:
        if self._last_wheel_command is not None and (
            self._command_age(self._last_wheel_command, self._wheel_command_sim_time)
            > self._command_timeout
        ):
            self.simulator.set_wheel_torque(np.zeros(3))
            self._last_wheel_command = None
            if not self._wheel_stale_logged:
                self.get_logger().warn(
                    f"no wheel torque for {self._command_timeout} s: wheel motors off"
                )
                self._wheel_stale_logged = True
        if self._last_command is None:
            return
        if self._command_age(self._last_command, self._command_sim_time) > self._command_timeout:
            self.simulator.set_reference(velocities=np.zeros(self.robot.n))
            self._last_command = None
            if not self._stale_logged:
                self.get_logger().warn(
                    f"no joint command for {self._command_timeout} s: stopping the joints"
                )
                self._stale_logged = True

    def _publish_held_state(self) -> None:
        """Faulted: the last finite state, at rest (zero velocities and efforts), and its
        momentum (the conserved value the system had)."""
        with self._lock:
            state = self.simulator.snapshot()
            momentum = self.simulator.centroidal_momentum()
            wheels = self._wheel_snapshot()
        n = self.robot.n
        held = SimulationState(state.time, state.q, np.zeros(6 + n), np.zeros(n))
        if wheels is not None:
            wheels = WheelSnapshot(wheels.angles, np.zeros(3), np.zeros(3))
        self._publish_state(held, momentum, wheels)

    def _stamp(self, state: SimulationState) -> TimeMsg:
        """The instant ``state`` describes: its simulated time on /clock; in real time, the
        wall instant the pace maps it to. A step is computed when it starts, so the state after
        it is published up to one step before that instant: stamping the publication instead
        made every joint state ~1 ms early, and a controller predicting from its stamp (and
        the update grid through it) acted on the wrong configuration."""
        if self._publish_clock:
            return stamp_from_seconds(state.time)
        paced = self._paced_time(state.time)
        return (paced if paced is not None else self.get_clock().now()).to_msg()

    def _paced_time(self, sim_time: float) -> Time | None:
        """The node-clock instant the real-time pace maps ``sim_time`` [s] to, or None off real
        time (no pace: stamps are publication times)."""
        pace = self._pace
        if pace is None:
            return None
        lead = min(max(pace_lead(pace, sim_time), -MAX_STAMP_LAG), self.simulator.dt / pace[2])
        return self.get_clock().now() + Duration(nanoseconds=round(lead * 1e9))

    def _lateness(self, stamp: float | None) -> float:
        """How long before the next step a JointTrajectory stamped ``stamp`` [s] was meant to
        act (kinematic mode, ``catch_up_late_commands``), on the stamp's clock [s]; 0 for none,
        for a stamp ahead of it and for one older than MAX_CATCH_UP (another clock or a stale
        command: it acts on receipt). Caller holds the lock."""
        if stamp is None or self._dynamic or not self._catch_up:
            return 0.0
        if self._publish_clock:
            starts = self.simulator.time
        else:
            paced = self._paced_time(self.simulator.time)
            if paced is None:
                return 0.0
            starts = paced.nanoseconds * 1e-9
        late = starts - stamp
        return late if 0.0 < late <= MAX_CATCH_UP else 0.0

    def _publish_state(
        self,
        state: SimulationState,
        momentum: np.ndarray,
        wheels: WheelSnapshot | None = None,
        clock: bool = False,
    ) -> None:
        """The state topics of ``state``, in the order consumers need them: what controllers
        read (joint_states, base_odom, wheel_states), then /clock at its time (with ``clock``:
        a sim-time timer woken by it finds the state there), then the monitoring topics
        (momentum, energy), which no control loop waits for. They go out as pre-serialized bytes
        (:meth:`_state_templates`), else as reused messages."""
        values = (state.q, state.v, state.effort, momentum)
        if wheels is not None:
            values += tuple(wheels)
        if not all(np.isfinite(value).all() for value in values):
            # the core never keeps a non-finite state; this guards the topics regardless
            self.get_logger().error(
                f"non-finite state at t = {state.time:.6g} s not published",
                throttle_duration_sec=1.0,
            )
            return
        stamp = self._stamp(state)
        if self._templates is not None:
            self._publish_serialized(state, (stamp.sec, stamp.nanosec))
        else:
            self._publish_messages(state, stamp)
        if wheels is not None:
            wheel_states = JointState()
            wheel_states.header.stamp = stamp
            wheel_states.header.frame_id = self.robot.base_link
            wheel_states.name = list(WHEEL_NAMES)
            wheel_states.position = wheels.angles.tolist()
            wheel_states.velocity = wheels.speeds.tolist()
            wheel_states.effort = wheels.torques.tolist()
            self._wheel_pub.publish(wheel_states)
        if clock:
            self._send_clock(state.time)

        self._publish_momentum(momentum, stamp)
        self._state_publications += 1
        if self._energy_every and (self._state_publications - 1) % self._energy_every == 0:
            self._publish_energy(state, wheels)

    def _publish_serialized(self, state: SimulationState, stamp: tuple[int, int]) -> None:
        """joint_states and base_odom of ``state`` through the templates (stamp: sec, nanosec)."""
        values = {"position": state.q[7:], "velocity": state.v[6:]}
        if self._dynamic:
            values["effort"] = state.effort
        self._joint_pub.publish(self._templates.joints.serialize(values, stamp))
        self._odom_pub.publish(
            self._templates.odom.serialize({"pose": state.q[:7], "twist": state.v[:6]}, stamp)
        )

    def _publish_momentum(self, momentum: np.ndarray, stamp: TimeMsg) -> None:
        if self._templates is not None:
            values = {"wrench": momentum}
            self._momentum_pub.publish(
                self._templates.momentum.serialize(values, (stamp.sec, stamp.nanosec))
            )
            return
        wrench = self._momentum_msg
        wrench.header.stamp = stamp
        force, torque = wrench.wrench.force, wrench.wrench.torque
        force.x, force.y, force.z = momentum[:3].tolist()
        torque.x, torque.y, torque.z = momentum[3:].tolist()
        self._momentum_pub.publish(wrench)

    def _publish_messages(self, state: SimulationState, stamp: TimeMsg) -> None:
        """joint_states and base_odom of ``state`` as messages (no templates)."""
        joints = self._joints_msg
        joints.header.stamp = stamp
        joints.position = state.q[7:].tolist()
        joints.velocity = state.v[6:].tolist()
        if self._dynamic:
            joints.effort = state.effort.tolist()
        self._joint_pub.publish(joints)

        odom = self._odom_msg
        odom.header.stamp = stamp
        position, orientation = odom.pose.pose.position, odom.pose.pose.orientation
        position.x, position.y, position.z = state.q[:3].tolist()
        orientation.x, orientation.y, orientation.z, orientation.w = state.q[3:7].tolist()
        linear, angular = odom.twist.twist.linear, odom.twist.twist.angular
        linear.x, linear.y, linear.z = state.v[:3].tolist()
        angular.x, angular.y, angular.z = state.v[3:6].tolist()
        self._odom_pub.publish(odom)

    def _publish_energy(self, state: SimulationState, wheels: WheelSnapshot | None) -> None:
        """The ``energy`` topic (layout: :data:`ENERGY_LABELS`), from the true state."""
        physical = FreeFloatingState.compute(self.robot, state.q)
        twist = base_twist_to_world(physical.base_rotation, state.v[:6])
        theta_dot = state.v[6:]
        terms = kinetic_energy(
            physical,
            twist,
            theta_dot,
            None if wheels is None else wheels.speeds,
            self._wheel_inertia,
        )
        arm, wheel = energy_metric(physical, self._wheel_inertia).energy(theta_dot)
        self._energy_cost.add(state.time, arm + wheel)
        values = [
            *terms,
            arm,
            wheel,
            self._energy_cost.c_max,
            self._energy_cost.c_sum,
            state.time,
        ]
        if not np.isfinite(values).all():
            return
        msg = Float64MultiArray(data=[float(x) for x in values])
        msg.layout.dim = [
            MultiArrayDimension(label=" ".join(ENERGY_LABELS), size=len(values), stride=len(values))
        ]
        self._energy_pub.publish(msg)

    def destroy_node(self) -> None:
        stop_worker(self._thread, self._stop, self._command_arrived)
        super().destroy_node()


def requested_mode(**node_kwargs) -> object:
    """The ``mode`` override (``-p mode:=...``, a params file) of a node named ``rns_simulator``
    built with these rclpy Node keyword arguments, or None. A short-lived probe node reads it from
    rcl's overrides (rclpy has no public getter; see
    :func:`rns_ros.nodes.parameters.warn_unknown_parameters`)."""
    probe = Node(
        NODE_NAME, **{"enable_rosout": False, "start_parameter_services": False, **node_kwargs}
    )
    try:
        override = (getattr(probe, "_parameter_overrides", None) or {}).get("mode")
        return None if override is None else override.value
    finally:
        probe.destroy_node()


def create_simulator_node(**node_kwargs) -> Node:
    """The rns_simulator node for the requested ``mode``: :class:`ContactSimulatorNode`
    (rns_ros.nodes.contact_simulator) for ``contact``, else the free-floating
    :class:`SimulatorNode` (which reports an invalid mode)."""
    if requested_mode(**node_kwargs) == "contact":
        from rns_ros.nodes.contact_simulator import ContactSimulatorNode

        return ContactSimulatorNode(**node_kwargs)
    return SimulatorNode(**node_kwargs)


def simulator_help() -> str:
    """``rns_simulator --help``: the free-floating parameters, then the contact-mode ones."""
    from rns_ros.nodes.contact_simulator import PARAMETERS as CONTACT_PARAMETERS

    contact = parameter_help(
        NODE_NAME,
        "Contact mode (-p mode:=contact, or --params-file config/contact_simulator.yaml): the "
        "fixed-base Part II arm driven by joint torques on joint_efforts, its end effector on a "
        "rigid wall or cylinder; publishes wrist_wrench, contact, joint_states (docs/part2_ros.md)",
        CONTACT_PARAMETERS,
    ).split("\n")
    return "\n".join([parameter_help(NODE_NAME, SUMMARY, PARAMETERS), "", "=" * 79, *contact[2:]])


def _wants_help(argv: list[str]) -> bool:
    try:
        return bool({"-h", "--help"} & set(remove_ros_args(argv)[1:]))
    except ROS_STARTUP_ERRORS:
        return False  # run_node reports the bad ROS arguments


def main(args=None) -> int:
    argv = list(sys.argv if args is None else args)
    if _wants_help(argv):
        print(simulator_help())
        return 0
    return run_node(create_simulator_node, sys.modules[__name__], argv)


if __name__ == "__main__":
    raise SystemExit(main())
