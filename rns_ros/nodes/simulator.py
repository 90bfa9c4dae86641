"""rns_simulator: the free-floating satellite + arm, integrated at a fixed step, as a ROS 2 node.

Physics is :class:`rns_ros.sim.free_floating.FreeFloatingSimulator`; this node only converts
messages: commands in (:mod:`rns_ros.nodes.simulator_commands`), state topics out
(:mod:`rns_ros.nodes.simulator_publishing`). It steps from its own monotonic-clock thread
(absolute deadlines, so no drift) or, in lockstep with a controller, as
:class:`rns_ros.nodes.lockstep.LockstepPacer` decides. ``mode: contact`` starts
:mod:`rns_ros.nodes.contact_simulator` instead.

Topics, services, QoS, safety and parameters: docs/nodes/rns_simulator.md.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from rcl_interfaces.msg import SetParametersResult
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.time import Time
from rclpy.utilities import remove_ros_args
from std_msgs.msg import String
from std_srvs.srv import Trigger

from rns_ros.core import FreeFloatingModel
from rns_ros.core.errors import ConfigError, SimulationDivergedError
from rns_ros.nodes import contact_simulator_parameters, simulator_parameters
from rns_ros.nodes.contact_simulator import ContactSimulatorNode
from rns_ros.nodes.lockstep import CALLBACK_POLL, LOCKSTEP_PATIENCE, LockstepPacer
from rns_ros.nodes.parameters import declare_parameters, load_node_model
from rns_ros.nodes.runner import ROS_STARTUP_ERRORS, parameter_help, run_node, stop_worker
from rns_ros.nodes.sim_clock import stamp_from_seconds
from rns_ros.nodes.simulator_commands import CommandIntake, RunState
from rns_ros.nodes.simulator_parameters import (
    CONTACT_MODE,
    NODE_NAME,
    PARAMETERS,
    SPECS,
    SUMMARY,
    check_parameter_changes,
)
from rns_ros.nodes.simulator_publishing import StatePublisher, WheelSnapshot
from rns_ros.sim.free_floating import FreeFloatingSimulator, ServoGains, SimulationState
from rns_ros.sim.reaction_wheels import ReactionWheels

#: Least time [s] between two log lines about a joint standing at a limit.
JOINT_STOP_LOG_PERIOD = 5.0


def _free_floating_simulator(robot: FreeFloatingModel, params: dict) -> FreeFloatingSimulator:
    """The simulator the parameters describe (initial state, servo, wheels)."""
    n = robot.n
    if len(params["initial_joint_positions"]) != n:
        raise ConfigError(
            f"parameter 'initial_joint_positions' needs {n} values for joints "
            f"{list(robot.joint_names)}, got {len(params['initial_joint_positions'])}"
        )
    gains = ServoGains.critically_damped(
        n,
        params["servo_natural_frequency"],
        params["servo_damping_ratio"],
        params["joint_friction"],
    )
    initial_q = robot.configuration(
        params["initial_joint_positions"],
        params["initial_base_position"],
        params["initial_base_orientation"],
    )
    return FreeFloatingSimulator(
        robot,
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


class SimulatorNode(Node):
    """ROS 2 wrapper of :class:`FreeFloatingSimulator` (see the module docstring): the
    :class:`~rns_ros.nodes.lockstep.LockstepPacer` steps it (a
    :class:`~rns_ros.nodes.lockstep.SteppedSimulation`), a
    :class:`~rns_ros.nodes.simulator_commands.CommandIntake` feeds it, a
    :class:`~rns_ros.nodes.simulator_publishing.StatePublisher` publishes its states.

    Args:
        wall_clock: monotonic wall clock [s] of the pace, the lockstep patience and the
            commands' wall-time ages.
        node_kwargs: as for :class:`rclpy.node.Node`.
    """

    def __init__(self, *, wall_clock: Callable[[], float] = time.monotonic, **node_kwargs) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        try:
            self._start(wall_clock)
        except BaseException:
            # a failed start-up leaves nothing registered: its parts reference the node, so it
            # would live on until a garbage collection, and rcl keeps one /rosout publisher per
            # node name (a leaked node would swallow the logs of the next rns_simulator)
            Node.destroy_node(self)
            raise

    def _start(self, wall_clock: Callable[[], float]) -> None:
        params = declare_parameters(self, PARAMETERS)
        # as every node loads it: the same joints, held joints, base
        self.robot = load_node_model(self, params["model_config"])
        self.simulator = _free_floating_simulator(self.robot, params)
        self._wheels = params["reaction_wheels"]
        self._publish_every = max(1, round(1.0 / (params["publish_rate"] * params["step_size"])))
        self._publish_clock = params["publish_clock"]
        # the plant's loop on the real-time pace runs ahead of other work, as hardware would
        self._scheduling = (params["thread_priority"], params["real_time_factor"] > 0.0)
        self._steps = 0  # since the start or the last reset
        self._run_state = RunState()

        # at real_time_factor 0 the command callback steps: the simulation thread only polls
        self._pacer = LockstepPacer.from_parameters(
            self.simulator, params, clock=wall_clock, idle_poll=CALLBACK_POLL
        )
        self._lock, self._stop = self._pacer.lock, self._pacer.stop
        self._command_arrived = self._pacer.wake
        self._publisher = StatePublisher(
            self,
            self.robot,
            world_frame=params["world_frame"],
            dynamic=params["mode"] == "dynamic",
            wheels=self._wheels,
            publish_clock=self._publish_clock,
            # the energy needs one CRBA and a message (~0.4 ms): every k-th state, not every one
            energy_every=0
            if params["energy_rate"] <= 0.0
            else max(1, round(params["publish_rate"] / params["energy_rate"])),
            wheel_inertia=params["wheel_inertia"],
            stamp=self._stamp,
            publish_tf=params["publish_tf"],
        )
        self._commands = CommandIntake(
            self,
            self.simulator,
            self._pacer,
            self._run_state,
            params,
            paced_time=self._paced_time,
            run_to_pause=self._run_to_pause,
        )
        # Transient local, depth 1: the robot_state_publisher convention, so a subscriber that
        # starts later still receives the model.
        description_qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self._description_pub = self.create_publisher(String, "robot_description", description_qos)
        self._description_pub.publish(String(data=self.robot.urdf_xml))
        self.create_service(Trigger, "~/reset", self._on_reset)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)

        self._thread = threading.Thread(
            target=self._pacer.run, args=(self,), name="rns_simulator_loop", daemon=True
        )
        self._thread.start()
        self.get_logger().info(
            f"{params['mode']} simulation of {self.robot.name} ({self.robot.n} joints), dt "
            f"{params['step_size']} s, publishing at {params['publish_rate']} Hz, real-time "
            f"factor {params['real_time_factor'] or 'max'}"
        )

    def realtime_scheduling(self) -> tuple[int, bool]:
        """(thread_priority, whether it applies: real_time_factor > 0 at start-up), for
        :func:`rns_ros.nodes.runner.run_node` (the process, never a host's in-process node)."""
        return self._scheduling

    # --- services and parameters (executor thread) --------------------------------------------
    def _on_reset(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        with self._lock:
            self._run_state.reset_requested, self._commands.hold_logged = True, False
        self._command_arrived.set()  # a paused simulation thread resets at once
        response.success = True
        response.message = "simulation reset to its initial state"
        return response

    def _on_set_parameters(self, parameters) -> SetParametersResult:
        """Accept or reject run-time changes (applied in :meth:`_on_parameters_set`)."""
        return check_parameter_changes(SPECS, parameters)

    def _on_parameters_set(self, parameters) -> None:
        for parameter in parameters:
            if parameter.name == "real_time_factor":
                self._pacer.set_real_time_factor(float(parameter.value))
            elif parameter.name == "command_timeout":
                self._commands.command_timeout = float(parameter.value)
        self._command_arrived.set()  # a paused simulation thread rechecks who steps

    # --- SteppedSimulation (the simulation thread; in lockstep at real_time_factor 0 the ------
    # --- command callback) ------------------------------------------------------------------
    def faulted(self) -> bool:
        return self._run_state.fault and not self._run_state.reset_requested

    def steps_in_callback(self) -> bool:
        return self._commands.steps_in_callback()

    def patience_over(self) -> bool:
        """One step: a controller whose timer waits for a later /clock gets it."""
        self.get_logger().warn(
            f"lockstep: no joint command for {LOCKSTEP_PATIENCE} s at "
            f"t = {self.simulator.time:.3f} s; one step on",
            throttle_duration_sec=5.0,
        )
        return True

    def advance(self) -> float | None:
        """One step (after a requested reset) and what it publishes; the simulated time after
        it [s], None when it diverged. Caller holds the pacer's stepping lock."""
        with self._lock:
            if self._run_state.reset_requested:
                self._reset()
            self._commands.expire_stale()
            self._commands.start_pending()
            self._commands.stop_at_trajectory_end()
            try:
                self.simulator.step()
            except SimulationDivergedError as exc:
                self._run_state.fault = True
                self.get_logger().error(
                    f"{exc}. Stopped: publishing that state with zero velocities until ~/reset"
                )
                return None
            self._steps += 1
            if self.simulator.at_stop.any():
                self._log_joint_stop()
            # a lockstep pause also publishes the state there: the controller's tick at the
            # pause samples this instant, not the last grid point (stale by up to a period)
            pauses = self._pacer.note_pause()
            publish = self._steps % self._publish_every == 0 or pauses
            snapshot = self.simulator.snapshot() if publish else None
            momentum = self.simulator.centroidal_momentum() if publish else None
            wheels = self._wheel_snapshot() if publish else None
            sim_time = self.simulator.time
        # lockstep: /clock only with the states (so at every pause); without it, every step
        clock = self._publish_clock and (snapshot is not None or self._pacer.period <= 0.0)
        if snapshot is not None:
            self._publisher.publish(snapshot, momentum, wheels, clock=clock)
        elif clock:
            self._publisher.send_clock(sim_time)
        return sim_time

    def _log_joint_stop(self) -> None:
        """A joint stands at a position limit (kinematic mode: a mechanical stop): say which,
        where and when, at most every few seconds. Caller holds the lock."""
        joint, side, limit = self.simulator.joint_stop()
        self.get_logger().warn(
            f"{self.robot.joint_names[joint]} stands at its {side} limit {limit:.6g} rad at "
            f"t = {self.simulator.time:.3f} s: the commanded rate past it is not followed "
            "(joint stop)",
            throttle_duration_sec=JOINT_STOP_LOG_PERIOD,
        )

    def _reset(self) -> None:
        """Back to the initial state (a requested ~/reset). Caller holds the lock."""
        self.simulator.reset()
        self._commands.reset()
        self._pacer.reset()
        self._run_state.reset_requested = False
        self._run_state.fault = False
        self._publisher.reset_energy()
        self._steps = 0

    def _run_to_pause(self) -> None:
        self._pacer.run_to_pause(self)

    def publish_held_state(self) -> None:
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
        self._publisher.publish(held, momentum, wheels)

    def _wheel_snapshot(self) -> WheelSnapshot | None:
        if not self._wheels:
            return None
        sim = self.simulator
        return WheelSnapshot(
            sim.wheel_angles.copy(), sim.wheel_speeds.copy(), sim.wheel_torque.copy()
        )

    # --- stamps -------------------------------------------------------------------------------
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
        lead = self._pacer.stamp_lead(sim_time)
        if lead is None:
            return None
        return self.get_clock().now() + Duration(nanoseconds=round(lead * 1e9))

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
    if requested_mode(**node_kwargs) == CONTACT_MODE:
        return ContactSimulatorNode(**node_kwargs)
    return SimulatorNode(**node_kwargs)


def simulator_help() -> str:
    """``rns_simulator --help``: the free-floating parameters, then the contact-mode ones."""
    contact = parameter_help(
        NODE_NAME,
        contact_simulator_parameters.SUMMARY,
        contact_simulator_parameters.PARAMETERS,
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
    return run_node(create_simulator_node, simulator_parameters, argv)


if __name__ == "__main__":
    raise SystemExit(main())
