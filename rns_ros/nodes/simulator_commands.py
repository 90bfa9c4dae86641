"""Command intake of rns_simulator's free-floating modes: joint_references / joint_velocities
and wheel_torque checked and handed to the simulator, the reset hold, trajectories that end at
rest, stale commands."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from geometry_msgs.msg import Vector3Stamped
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from rns_ros.core import FreeFloatingModel
from rns_ros.core.commands import (
    check_reference_positions,
    check_velocity_limits,
    match_named_command,
)
from rns_ros.core.errors import InputError
from rns_ros.nodes.cdr import JointTrajectoryReader, MalformedMessageError
from rns_ros.nodes.lockstep import LockstepPacer
from rns_ros.nodes.parameters import velocity_joint_order
from rns_ros.nodes.status import CommanderWatch
from rns_ros.sim.free_floating import FreeFloatingSimulator

#: Oldest JointTrajectory stamp [s] the kinematic mode still catches up to, and farthest ahead
#: of the real-time pace one waits for (farther: another clock or a stale command, acted on at
#: receipt).
MAX_CATCH_UP = 0.05
#: Most JointTrajectories stamped ahead that wait for their stamps (a controller's next one or
#: two; a flood keeps the newest).
MAX_PENDING = 8
#: Period [s] (wall clock) of the check for more than one node commanding the joints.
COMMANDER_CHECK_PERIOD = 1.0
#: Lockstep: a command stamped up to this long [s] before the simulated time still puts the
#: pauses on its stamp's grid (older: another clock; the period counts from its receipt).
MAX_GRID_AGE = 1.0
#: After ~/reset, a JointTrajectory starting this close to the reset angles [rad] ends the
#: reset hold (a resynchronized controller); the hold otherwise lasts ``reset_hold``.
RESET_MATCH_TOLERANCE = 0.01
#: A trajectory's velocity ends at the first step that starts no more than this many steps
#: before its end, and a step that starts no more than that after it takes back no motion
#: (simulated times are sums of steps: 20 steps of 1 ms may fall just short of 0.02 s).
END_TOLERANCE_STEPS = 1e-3
#: Wall time [s] between two logs of trajectories that ended at rest with no newer one (each
#: stop is logged at most once; a late controller can cause one every period).
ENDED_LOG_PERIOD = 5.0


@dataclass
class RunState:
    """What gates the commands, shared by the simulation loop and the intake."""

    fault: bool = False  # a step diverged: frozen at the last finite state until ~/reset
    reset_requested: bool = False


class CommandIntake:
    """Subscribes ``node`` to the joint (and wheel) commands and feeds them to ``simulator``.

    Args:
        node: the simulator node (subscriptions, logger).
        simulator: the stepped simulator.
        pacer: the lockstep state; its lock guards the simulator and the command state.
        run_state: fault / reset flags (shared with the loop).
        params: the node's checked parameters.
        paced_time: the node-clock instant the real-time pace maps a simulated time [s] to, or
            None off real time.
        run_to_pause: steps to the next lockstep pause; called after an accepted joint command
            when :meth:`steps_in_callback`, outside the lock.
    """

    def __init__(
        self,
        node: Node,
        simulator: FreeFloatingSimulator,
        pacer: LockstepPacer,
        run_state: RunState,
        params: dict,
        paced_time: Callable[[float], Time | None],
        run_to_pause: Callable[[], None],
    ) -> None:
        self.robot: FreeFloatingModel = simulator.robot
        self.simulator = simulator
        self._pacer = pacer
        self._lock = pacer.lock
        self._run = run_state
        self._logger = node.get_logger()
        self._paced_time = paced_time
        self._run_to_pause = run_to_pause
        self._dynamic = params["mode"] == "dynamic"
        self._publish_clock = params["publish_clock"]
        self._max_reference_error = params["max_reference_error"]
        self._catch_up = params["catch_up_late_commands"]
        self._reset_hold = params["reset_hold"]
        self.command_timeout = params["command_timeout"]
        # JointTrajectories stamped ahead (sim time), in stamp order: (stamp [s], positions,
        # velocities, accelerations, velocity_end [s]), each the reference from the first step
        # at its stamp. A controller ticking side by side can send the next before the
        # simulation reached the stamp of the previous one: both wait.
        self._pending: list[tuple] = []
        # the reference's velocity ends (the joints stop) at this simulated time [s], its
        # trajectory's velocity_end [s] after the instant it started; inf: held until the next
        # command or command_timeout
        self._motion_end = math.inf
        self._velocity_end = math.inf
        self.ended_at_rest = 0  # trajectories that ended at rest with no newer command
        self._stale_logged = False
        self._hold_until = -math.inf  # simulated time [s] before which commands are ignored
        self.hold_logged = False
        self._last_wheel_command: float | None = None  # monotonic receipt time [s]
        self._wheel_command_sim_time = 0.0
        self._wheel_stale_logged = False
        self.malformed = 0  # joint_references that were not a JointTrajectory (rejected)
        self._subscribe(node, params)

    def _subscribe(self, node: Node, params: dict) -> None:
        # Commands: best effort, depth 1 - the newest command is the only one that matters, and
        # a best-effort subscription accepts reliable and best-effort publishers alike.
        command_qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        if params["command_interface"] == "trajectory":
            # depth 10: a trajectory stamped ahead (lockstep side by side) follows the one
            # before it, so none may be dropped while a callback steps; they are taken in order
            # taken serialized: the simulator reads the first point from the bytes
            # (rns_ros.nodes.cdr), cheaper than rclpy building the message (~27 us)
            self._trajectory_reader = JointTrajectoryReader()
            subscription = node.create_subscription(
                JointTrajectory,
                "joint_references",
                self._on_trajectory,
                QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT),
                raw=True,
            )
        else:
            self._velocity_order = velocity_joint_order(params["joints"], self.robot.joint_names)
            self._velocity_joints = list(params["joints"])
            subscription = node.create_subscription(
                Float64MultiArray, "joint_velocities", self._on_velocities, command_qos
            )
        # who commands the joints, read from the graph once a second (wall clock: also while
        # a lockstep pause holds the simulated time)
        self.commanders = CommanderWatch(
            node,
            subscription.topic_name,
            "each command is taken as it comes (the newest wins), so the arm follows them in "
            "turn; run one commander",
            publishes=False,
        )
        node.create_timer(
            COMMANDER_CHECK_PERIOD,
            self.commanders.check,
            clock=Clock(clock_type=ClockType.STEADY_TIME),
        )
        if params["reaction_wheels"]:
            node.create_subscription(
                Vector3Stamped, "wheel_torque", self._on_wheel_torque, command_qos
            )

    # --- executor thread ------------------------------------------------------------------------
    def _on_trajectory(self, data: bytes) -> None:
        try:
            msg = self._trajectory_reader(data)
        except MalformedMessageError as exc:
            self.malformed += 1
            self._reject(f"{exc} ({self.malformed} so far)")
            return
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
        self._accept(
            command.positions,
            command.velocities,
            command.accelerations,
            stamp,
            msg.velocity_end,
        )

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
            if self._blocked():
                return
            self.simulator.set_wheel_torque(torque)  # clipped to the limits at every step
            self._last_wheel_command = self._pacer.clock()
            self._wheel_command_sim_time = self.simulator.time
            self._wheel_stale_logged = False

    def _reject_wheels(self, reason: str) -> None:
        self._logger.error(f"rejected wheel torque: {reason}", throttle_duration_sec=1.0)

    def _reject(self, reason: str) -> None:
        self._logger.error(f"rejected joint command: {reason}", throttle_duration_sec=1.0)

    def _blocked(self) -> bool:
        """Faulted, resetting, or within the reset hold. Caller holds the lock."""
        return (
            self._run.fault or self._run.reset_requested or self.simulator.time < self._hold_until
        )

    def _ignoring_commands(self, positions: np.ndarray | None = None) -> bool:
        """True (logged) while faulted or within ``reset_hold`` after a reset. A reference whose
        ``positions`` start at the reset state (within ``RESET_MATCH_TOLERANCE``) ends the hold:
        it comes from a controller that has seen the reset state and resynchronized, and
        holding it off would only let that controller's reference run ahead of the arm."""
        with self._lock:
            if self._run.fault:
                self._reject("the simulation diverged and is stopped; call ~/reset")
                return True
            if self._run.reset_requested or self.simulator.time < self._hold_until:
                if (
                    not self._run.reset_requested
                    and positions is not None
                    and np.abs(positions - self.simulator.q[7:]).max() <= RESET_MATCH_TOLERANCE
                ):
                    self._hold_until = -math.inf
                    return False
                if not self.hold_logged:
                    self._logger.warn(
                        f"ignoring joint commands for reset_hold = {self._reset_hold} s after "
                        "~/reset (simulated time), or until a reference starts at the reset "
                        "state: controllers must see the reset state first"
                    )
                    self.hold_logged = True
                return True
        return False

    def _accept(
        self,
        positions,
        velocities,
        accelerations,
        stamp: float | None = None,
        velocity_end: float = math.inf,
    ) -> None:
        """Hand a checked command to the simulator: positions [rad], velocities [rad/s],
        accelerations [rad/s^2] (each (n,) or None), header ``stamp`` [s] (None: none) and the
        time [s] after it at which its velocity ends (a trajectory at rest there,
        :class:`rns_ros.nodes.cdr.TrajectoryFields`; inf: held)."""
        with self._lock:
            if self._blocked():
                return  # changed since the check: the command is stale now
            starts = self._waits_until(stamp)
            if starts is not None:
                # a newer command replaces those waiting for its start or a later one
                waiting = [command for command in self._pending if command[0] < starts]
                waiting.append((starts, positions, velocities, accelerations, velocity_end))
                self._pending = waiting[-MAX_PENDING:]
            else:
                self._pending = []  # a newer command replaces those still waiting
                since = self._lateness(stamp)
                self.simulator.set_reference(positions, velocities, accelerations, since=since)
                # a late one started at its stamp: its end counts from there too
                self._started(self.simulator.time - since, velocity_end)
            self._pacer.command_received(self.command_anchor(stamp))
            self._stale_logged = False
            self._pacer.paused_since = None
            in_callback = self.steps_in_callback()
            if not in_callback:
                self._pacer.wake.set()
        if in_callback:
            self._run_to_pause()

    def steps_in_callback(self) -> bool:
        """Lockstep as fast as possible once a controller answers: the command callback steps
        to the next pause itself (no hand-off to the simulation thread). Caller holds the
        lock."""
        pacer = self._pacer
        return (
            pacer.period > 0.0
            and pacer.real_time_factor == 0.0
            and pacer.last_command is not None
            and not self._run.fault
            and not self._run.reset_requested
        )

    # --- stamps (caller holds the lock) -------------------------------------------------------
    def _waits_until(self, stamp: float | None) -> float | None:
        """The simulated time [s] a command stamped ``stamp`` [s] waits for, or None when it
        acts at the next step. With /clock: the stamp, when it lies after the next step's start
        by at most ``lockstep_period`` (``MAX_CATCH_UP`` without lockstep). On the real-time
        pace (kinematic mode, ``catch_up_late_commands``): the simulated time the pace maps
        the stamp to, when it lies after the next step's start by at most ``MAX_CATCH_UP``. A
        simulation that fell behind its pace (a process waiting for a core sprints to catch up)
        then starts a command at its stamp, as it catches up a late one, instead of early at a
        configuration the controller had predicted it past. Caller holds the lock."""
        if stamp is None:
            return None
        now, dt = self.simulator.time, self.simulator.dt
        if self._publish_clock:
            period = self._pacer.period
            lead = period if period > 0.0 else MAX_CATCH_UP
            return stamp if now + 0.5 * dt < stamp <= now + lead + 0.5 * dt else None
        starts = self._next_step_on_stamp_clock() if self._catch_up and not self._dynamic else None
        if starts is None:
            return None
        early = stamp - starts
        return now + early if 0.5 * dt < early <= MAX_CATCH_UP else None

    def command_anchor(self, stamp: float | None) -> float:
        """Simulated time [s] a command's lockstep period counts from, on the grid of its
        header ``stamp`` [s] when /clock is published and the stamp is a recent simulated
        time (a controller ticking on this clock stamps the instant it sampled or, with a lead,
        the instant its output starts): the stamp itself when it lies within the period before
        now or waits ahead (:meth:`_waits_until`); a later point of its grid, stamp + k
        ``lockstep_period``, the last one not after now, when the command is older (one that
        reaches a simulation running in real time after a reset or a dropped command comes a
        few periods late), so the next
        pause falls on that controller's next tick whatever the latency. Else (no stamp, a
        wall-clock stamp, one older than ``MAX_GRID_AGE``) the simulated time of receipt.
        Caller holds the lock."""
        now, dt = self.simulator.time, self.simulator.dt
        period = self._pacer.period
        if (
            stamp is None
            or not self._publish_clock
            or period <= 0.0
            or not now - MAX_GRID_AGE <= stamp <= now + period + 0.5 * dt
        ):
            return now
        behind = math.floor((now + 0.5 * dt - stamp) / period)
        return stamp + max(behind, 0) * period

    def _lateness(self, stamp: float | None) -> float:
        """How long before the next step a JointTrajectory stamped ``stamp`` [s] was meant to
        act (kinematic mode, ``catch_up_late_commands``), on the stamp's clock [s]; 0 for none,
        for a stamp ahead of it and for one older than MAX_CATCH_UP (another clock or a stale
        command: it acts on receipt). Caller holds the lock."""
        if stamp is None or self._dynamic or not self._catch_up:
            return 0.0
        starts = self._next_step_on_stamp_clock()
        if starts is None:
            return 0.0
        late = starts - stamp
        return late if 0.0 < late <= MAX_CATCH_UP else 0.0

    def _next_step_on_stamp_clock(self) -> float | None:
        """When the next step starts on the clock of the commands' stamps [s]: the simulated
        time with /clock, else the node-clock instant the real-time pace maps it to; None off
        real time without /clock. Caller holds the lock."""
        if self._publish_clock:
            return self.simulator.time
        paced = self._paced_time(self.simulator.time)
        return None if paced is None else paced.nanoseconds * 1e-9

    # --- simulation step (caller holds the lock) ----------------------------------------------
    def reset(self) -> None:
        """The simulation was reset: no command, the reset hold starts."""
        self._pending = []
        self._motion_end = math.inf
        self._hold_until = self.simulator.time + self._reset_hold
        self._last_wheel_command = None

    def start_pending(self) -> None:
        """The newest waiting command whose stamp the next step starts at (or past) becomes
        the reference; those before it are over."""
        starts = self.simulator.time + 0.5 * self.simulator.dt
        due = [command for command in self._pending if command[0] <= starts]
        if due:
            self._pending = self._pending[len(due) :]
            _, positions, velocities, accelerations, velocity_end = due[-1]
            self.simulator.set_reference(positions, velocities, accelerations)
            self._started(self.simulator.time, velocity_end)

    def _started(self, start: float, velocity_end: float) -> None:
        """The reference just set acts from simulated time ``start`` [s]; its velocity ends
        ``velocity_end`` [s] later (clipped at 0; inf: held)."""
        self._velocity_end = velocity_end
        self._motion_end = start + max(velocity_end, 0.0)

    def stop_at_trajectory_end(self) -> None:
        """Stop the joints once the simulation reaches the end of the reference's velocity (a
        streamed trajectory's point at rest, 2T after its stamp) with no newer command, as a
        joint_trajectory_controller plays that trajectory: zero velocity, the reference
        positions left where the motion took them. A step that starts after the end (a
        command that came later than its end, caught up) takes back the motion past it
        (kinematic mode: the same catch-up as a late command). Logged (throttled), naming the
        time after the stamp. Called before each step, after :meth:`start_pending`. Caller
        holds the lock."""
        now, tolerance = self.simulator.time, END_TOLERANCE_STEPS * self.simulator.dt
        if now < self._motion_end - tolerance:
            return
        overdue = now - self._motion_end
        overdue = overdue if overdue > tolerance else 0.0  # rounding is no motion to take back
        self._motion_end = math.inf
        reference = self.simulator.reference
        if not reference.velocities.any():
            return  # at rest already
        self.simulator.set_reference(
            reference.positions - overdue * reference.velocities, since=overdue
        )
        self.ended_at_rest += 1
        self._logger.warn(
            f"joint_references ended at rest {self._velocity_end:.3f} s after its stamp with no "
            f"newer one: joints stopped (the controller is late; {self.ended_at_rest} so far)",
            throttle_duration_sec=ENDED_LOG_PERIOD,
        )

    def expire_stale(self) -> None:
        """Commands older than ``command_timeout``: wheel motors off, joints stopped (logged
        once, naming the command's simulated and wall-time ages).

        The age is simulated time in lockstep (a simulation paused for a busy controller does
        not age its command), wall time otherwise. In lockstep a command is stale in wall time
        too while the simulation waits at a pause for a newer joint command: there it takes one
        step per ``LOCKSTEP_PATIENCE`` (5 s) of wall time, so a killed controller's last
        command would act for about 42 min of wall time (1 ms steps, a 0.5 s timeout) before
        its simulated age reached the timeout. Within its lockstep period a joint command
        stays in force however slowly the simulation runs (a slow ``real_time_factor``, a
        process waiting for a core). Caller holds the lock."""
        pacer = self._pacer
        waiting = pacer.pauses_here()  # at a pause: this step is one the patience forced
        if self._last_wheel_command is not None:
            sim_age = self.simulator.time - self._wheel_command_sim_time
            # a wheel torque that answered the paused state is fresh: its controller waits
            # for the simulation too
            ages = self._stale_ages(
                self._last_wheel_command,
                self._wheel_command_sim_time,
                waiting and sim_age > 0.5 * self.simulator.dt,
            )
            if ages is not None:
                self.simulator.set_wheel_torque(np.zeros(3))
                self._last_wheel_command = None
                if not self._wheel_stale_logged:
                    self._logger.warn(f"wheel torque {self._ages_text(*ages)}: wheel motors off")
                    self._wheel_stale_logged = True
        if pacer.last_command is None:
            return
        ages = self._stale_ages(pacer.last_command, pacer.command_sim_time, waiting)
        if ages is not None:
            self.simulator.set_reference(velocities=np.zeros(self.robot.n))
            self._motion_end = math.inf
            pacer.last_command = None
            if not self._stale_logged:
                self._logger.warn(f"joint command {self._ages_text(*ages)}: stopping the joints")
                self._stale_logged = True

    def _stale_ages(
        self, received: float, sim_received: float, judged_on_wall: bool
    ) -> tuple[float, float] | None:
        """(simulated, wall) age [s] of a command received at wall time ``received`` [s] and
        simulated time ``sim_received`` [s] when it is older than ``command_timeout`` by the
        pacer's age (:meth:`LockstepPacer.command_age`) or, ``judged_on_wall``, in wall time;
        None while it is in force. Caller holds the lock."""
        pacer = self._pacer
        sim_age = self.simulator.time - sim_received
        wall_age = pacer.clock() - received
        if pacer.command_age(received, sim_received) > self.command_timeout or (
            judged_on_wall and wall_age > self.command_timeout
        ):
            return sim_age, wall_age
        return None

    def _ages_text(self, sim_age: float, wall_age: float) -> str:
        return (
            f"{sim_age:.3f} s old in simulated time, {wall_age:.3f} s in wall time "
            f"(command_timeout {self.command_timeout} s)"
        )
