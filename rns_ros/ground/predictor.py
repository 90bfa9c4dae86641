"""The predictive display's arm: where the spacecraft's arm will be when the operator's commands
act, computed on the ground at once, and kept honest by the delayed telemetry.

The operator's commands are time-tagged (:mod:`rns_ros.control.time_tags`): a command stamped
t_c acts on board from t_x = t_c + D. The ground holds its own copy of the on-board loop (the
reactionless controller of eq. 4.5 with the same method, gains, period and command gate, and a
kinematic free-floating integration, :class:`rns_ros.sim.free_floating.FreeFloatingSimulator`)
and runs it on the control period's grid t_k = t_0 + k T ahead of the spacecraft: a command is
shown acting at its t_x, as soon as the operator gives it, D before the spacecraft does it and
D + d_down before its telemetry could show it.

Telemetry stamped tau (on-board time) arrives later; the state predicted for tau is then compared
with it, the prediction error: the angles between the predicted and the measured camera and base
attitudes [deg] and the largest joint difference [rad]. When an attitude error exceeds
``resync_deg`` or a joint's ``resync_rad`` the prediction is re-anchored: the loop restarts at
tau from the measured state (the gate as it was at tau, theta_ref at the measured angles) and
re-runs, through the commands
acting after tau (those still in flight and the ones already acted on but not yet seen), up to
the newest predicted tick. With an exact model the prediction and the telemetry agree to the
integration's rounding and no re-anchoring happens; with a model error the prediction drifts
from the last anchor by at most what the error builds up over D + d_down. A reactionless motion
is forgiving: the base stays still in the model and on board alike, and the camera follows the
commanded rate in both, so a mass error shows only in the joint angles (the reaction null space
depends on the masses); a conventional motion turns the base by what the inertias say, and a
mass error shows in every attitude.
"""

from __future__ import annotations

import copy
import math
from bisect import bisect_right
from collections import deque
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rns_ros.control.camera_goal import CameraGoal, GoalSettings
from rns_ros.control.controller import (
    ControllerSettings,
    ReactionlessController,
    TwistFrame,
    angular_velocity_in_world,
)
from rns_ros.control.teleop import CommandGate, TwistCommand
from rns_ros.control.time_tags import TimeTags
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import as_vector, positive
from rns_ros.sim.free_floating import FreeFloatingSimulator, SimulationMode

#: A telemetry stamp this close to a tick of the grid [s] is compared with that tick.
GRID_TOLERANCE_S = 1e-6
#: Prediction errors kept (the newest): 1000 s of 100 Hz telemetry.
MAX_ERRORS = 100_000


@dataclass(frozen=True)
class GateSettings:
    """The on-board command gate's parameters (rns_controller's of the same names).

    Attributes:
        command_timeout: a command older than this (from its execution time) ramps down [s].
        stop_deceleration: [rad/s^2].
        start_acceleration: [rad/s^2].
    """

    command_timeout: float = 0.5
    stop_deceleration: float = 1.0
    start_acceleration: float = 1.0

    def gate(self) -> CommandGate:
        return CommandGate(
            self.command_timeout,
            self.stop_deceleration,
            TwistFrame.WORLD,
            self.start_acceleration,
        )


@dataclass(frozen=True)
class PredictorSettings:
    """Settings of :class:`PredictedArm`.

    Attributes:
        controller: the on-board controller's method, gains and period T.
        gate: the on-board command gate.
        goal: the on-board camera goal's law (rns_controller's goal_* parameters).
        time_tags: D, the execution delay, as the spacecraft applies it.
        resync_deg: re-anchor when the camera's or the base's attitude error exceeds this
            [deg], > 0.
        resync_rad: re-anchor when a joint's error exceeds this [rad], > 0.
        history: how long predicted ticks are kept for comparison [s], >= the round trip.
        simulation_step: integration step [s]; T must be a multiple of it.
    """

    controller: ControllerSettings = field(default_factory=ControllerSettings)
    gate: GateSettings = field(default_factory=GateSettings)
    goal: GoalSettings = field(default_factory=GoalSettings)
    time_tags: TimeTags = field(default_factory=TimeTags)
    resync_deg: float = 0.01
    resync_rad: float = 1e-3
    history: float = 120.0
    simulation_step: float = 0.01

    def __post_init__(self) -> None:
        positive(self.resync_deg, "resync_deg", "deg")
        positive(self.resync_rad, "resync_rad", "rad")
        positive(self.history, "history", "s")
        period = self.controller.period
        substeps = round(period / positive(self.simulation_step, "simulation_step", "s"))
        if substeps < 1 or abs(substeps * self.simulation_step - period) > 1e-9 * period:
            raise ConfigError(
                f"the control period {period} s must be a multiple of simulation_step "
                f"{self.simulation_step} s"
            )

    @property
    def substeps(self) -> int:
        return round(self.controller.period / self.simulation_step)


class PredictionError(NamedTuple):
    """Predicted minus measured at one telemetry stamp.

    Attributes:
        stamp: the telemetry's on-board time [s].
        camera_deg: angle between the predicted and the measured camera attitude [deg].
        base_deg: angle between the predicted and the measured base attitude [deg].
        joints_rad: largest |theta_predicted - theta_measured| [rad].
        resynced: whether the prediction was re-anchored on this telemetry.
    """

    stamp: float
    camera_deg: float
    base_deg: float
    joints_rad: float
    resynced: bool


class _Goal(NamedTuple):
    """A camera goal among the commands: R_goal (world <- camera) (3, 3)."""

    rotation: np.ndarray


class _Tick(NamedTuple):
    """The loop at the start of one tick: time [s], configuration q (7 + n,), the gate, and
    the newest camera goal (its execution time [s] and R_goal (3, 3), None once reached), if
    one is in force."""

    time: float
    q: np.ndarray
    gate: CommandGate
    goal: tuple[float, np.ndarray | None] | None = None


class PredictedArm:
    """The ground's copy of the on-board loop (module docstring).

    Usage::

        arm = PredictedArm(robot, settings, q0, t0)
        arm.command(stamp, angular, TwistFrame.WORLD)   # each operator command, at once
        state = arm.advance(now + D)                    # what the display shows now
        error = arm.telemetry(tau, q_measured)          # each telemetry sample, when it arrives

    Args:
        robot: the ground's model of the spacecraft (exact or not).
        settings: :class:`PredictorSettings`.
        q0: the on-board configuration at ``t0`` (7 + n,) (pinocchio layout).
        t0: on-board time of ``q0`` [s], the first tick.
    """

    def __init__(
        self, robot: FreeFloatingModel, settings: PredictorSettings, q0, t0: float
    ) -> None:
        self.robot = robot
        self.settings = settings
        self.period = settings.controller.period
        self._controller = ReactionlessController(robot, settings.controller)
        # the commands and their execution times [s], in execution order
        self._acts: list[float] = []
        self._commands: list[TwistCommand | _Goal] = []
        self._ticks: deque[_Tick] = deque()
        #: the newest prediction errors (at most MAX_ERRORS kept); their worst so far
        self.errors: deque[PredictionError] = deque(maxlen=MAX_ERRORS)
        self.worst = PredictionError(math.nan, 0.0, 0.0, 0.0, False)
        self.compared = 0  # telemetry samples compared
        self.resyncs = 0  # re-anchorings
        self._origin = float(t0)  # the first tick [s]
        self._anchor(self._origin, as_vector(q0, robot.model.nq, "q0"), settings.gate.gate(), True)

    # --- inputs --------------------------------------------------------------------------------
    def command(self, stamp: float, angular, frame: TwistFrame = TwistFrame.WORLD) -> None:
        """The operator's command stamped ``stamp`` [s]: ``angular`` [rad/s] (3,) in ``frame``
        axes, acting from stamp + D. Commands come in stamp order; one acting before the newest
        predicted tick re-runs the prediction from there."""
        if not math.isfinite(stamp):
            raise InputError(f"command stamp must be finite, got {stamp!r}")
        angular = as_vector(angular, 3, "angular velocity")
        acts = self.settings.time_tags.execution_time(stamp)
        self._insert(acts, TwistCommand(angular, np.zeros(3), TwistFrame.parse(frame), acts))

    def _insert(self, acts: float, command: TwistCommand | _Goal) -> None:
        """``command`` acting from ``acts`` [s], in execution order; one acting before the
        newest predicted tick re-runs the prediction from there."""
        position = bisect_right(self._acts, acts)
        self._acts.insert(position, acts)
        self._commands.insert(position, command)
        self._forget_commands()
        if acts < self.time - GRID_TOLERANCE_S:
            tick = self._ticks[max(0, math.floor((acts - self._ticks[0].time) / self.period))]
            self._restart(tick.time, tick.q)

    def goal(self, stamp: float, rotation) -> None:
        """The operator's camera goal R_goal (world <- camera, (3, 3)) sent at ``stamp`` [s]:
        turned to on board from stamp + D with the goal law (goals carry no time tag: they act
        on arrival, which D bounds; the telemetry corrects the difference). A moving twist
        acting later takes over, as on board."""
        if not math.isfinite(stamp):
            raise InputError(f"goal stamp must be finite, got {stamp!r}")
        rotation = np.array(rotation, dtype=float).reshape(3, 3)
        if not np.isfinite(rotation).all():
            raise InputError("goal rotation must be finite")
        self._insert(self.settings.time_tags.execution_time(stamp), _Goal(rotation))

    def advance(self, t: float) -> FreeFloatingState:
        """Predict up to on-board time ``t`` [s] (every tick t_k <= t); the newest predicted
        state."""
        while self._ticks[-1].time + self.period <= t + GRID_TOLERANCE_S:
            self._tick()
        return self.state

    @property
    def time(self) -> float:
        """On-board time of the newest predicted state [s]."""
        return self._ticks[-1].time

    @property
    def q(self) -> np.ndarray:
        """The newest predicted configuration (7 + n,)."""
        return self._ticks[-1].q.copy()

    @property
    def state(self) -> FreeFloatingState:
        """The newest predicted state."""
        return FreeFloatingState.compute(self.robot, self._ticks[-1].q)

    def predicted_q(self, t: float) -> np.ndarray | None:
        """The predicted configuration (7 + n,) at the tick at time ``t`` [s], if kept."""
        tick = self._tick_at(t)
        return None if tick is None else tick.q.copy()

    def telemetry(self, stamp: float, q) -> PredictionError | None:
        """The measured configuration ``q`` (7 + n,) stamped ``stamp`` [s] (on-board time):
        the prediction error at that stamp (also appended to :attr:`errors` and counted in
        :attr:`worst`, :attr:`compared`, :attr:`resyncs`), or None when the
        stamp is off the grid or outside the kept history. Re-anchors past ``resync_deg``."""
        q = as_vector(q, self.robot.model.nq, "telemetry q")
        tick = self._tick_at(stamp)
        if tick is None:
            return None
        predicted = FreeFloatingState.compute(self.robot, tick.q)
        measured = FreeFloatingState.compute(self.robot, q)
        camera = math.degrees(
            attitude_deviation(predicted.camera.rotation, measured.camera.rotation)
        )
        base = math.degrees(attitude_deviation(predicted.base_rotation, measured.base_rotation))
        joints = float(np.abs(predicted.theta - measured.theta).max(initial=0.0))
        limits = self.settings
        resync = max(camera, base) > limits.resync_deg or joints > limits.resync_rad
        if resync:
            self._restart(tick.time, q)
        error = PredictionError(stamp, camera, base, joints, resync)
        self.errors.append(error)
        worst = self.worst
        self.worst = PredictionError(
            stamp,
            max(worst.camera_deg, camera),
            max(worst.base_deg, base),
            max(worst.joints_rad, joints),
            worst.resynced or resync,
        )
        self.compared += 1
        self.resyncs += resync
        return error

    # --- the loop ------------------------------------------------------------------------------
    def _anchor(
        self,
        t: float,
        q: np.ndarray,
        gate: CommandGate,
        reset: bool,
        goal: tuple[float, np.ndarray | None] | None = None,
    ) -> None:
        q = pin.normalize(self.robot.model, q.copy())
        state = FreeFloatingState.compute(self.robot, q)
        if reset:
            self._controller.reset(state)
        else:
            self._controller.resync(state)
        self._simulator = FreeFloatingSimulator(
            self.robot,
            mode=SimulationMode.KINEMATIC,
            dt=self.settings.simulation_step,
            initial_q=q,
            initial_momentum=np.zeros(6),
        )
        self._ticks.append(_Tick(t, q, gate, goal))

    def _tick(self) -> None:
        """One period from the newest tick: gate, law, kinematic integration."""
        t, q, gate, goal = self._ticks[-1]
        gate = copy.deepcopy(gate)  # the kept tick stays as it was
        state = FreeFloatingState.compute(self.robot, q)
        # the newest command acting by t is in force, as the on-board gate's newest accepted;
        # a goal feeds the gate its law's rate every tick until reached, a moving twist ends it
        due = bisect_right(self._acts, t + GRID_TOLERANCE_S)
        # the inputs that came into force since the previous tick (all of them at the first)
        since = (
            0 if t <= self._origin else bisect_right(self._acts, t - self.period + GRID_TOLERANCE_S)
        )
        for acts, command in zip(self._acts[since:due], self._commands[since:due], strict=True):
            if isinstance(command, _Goal):
                goal = (acts, command.rotation)
            elif np.any(command.angular) or np.any(command.linear):
                goal = None  # a moving twist takes over from the goal
        newest = next(
            (c for c in reversed(self._commands[:due]) if isinstance(c, TwistCommand)), None
        )
        if newest is not None:
            gate.accept(newest)
        if goal is not None and goal[1] is not None:
            law = CameraGoal(self.settings.goal)
            law.set(goal[1])
            step = law.step(state.camera.rotation)
            gate.accept(TwistCommand(step.omega, np.zeros(3), TwistFrame.WORLD, t))
            if step.reached:
                goal = (goal[0], None)  # reached: this goal is done, the next one may come
        out = gate.update(t, self.period)
        if out.stopped:
            theta_dot = np.zeros(self.robot.n)
            self._controller.resync(state)
        else:
            omega = angular_velocity_in_world(state, out.angular, out.frame)
            theta_dot = self._controller.step(state, omega).joint_velocity
        simulator = self._simulator
        simulator.set_reference(velocities=theta_dot)
        for _ in range(self.settings.substeps):
            simulator.step()
        self._ticks.append(_Tick(t + self.period, simulator.q.copy(), gate, goal))
        while self._ticks[-1].time - self._ticks[0].time > self.settings.history:
            self._ticks.popleft()

    def _tick_at(self, t: float) -> _Tick | None:
        if not self._ticks:
            return None
        k = round((t - self._ticks[0].time) / self.period)
        if not 0 <= k < len(self._ticks):
            return None
        tick = self._ticks[k]
        return tick if abs(tick.time - t) <= GRID_TOLERANCE_S else None

    def _restart(self, t: float, q: np.ndarray) -> None:
        """Re-run the loop from the kept tick at ``t`` [s], its configuration replaced by ``q``
        (telemetry, or the tick's own), up to the newest predicted tick."""
        newest = self.time
        while len(self._ticks) > 1 and self._ticks[-1].time > t + GRID_TOLERANCE_S:
            self._ticks.pop()
        start = self._ticks.pop()
        self._anchor(start.time, q, start.gate, False, start.goal)
        self.advance(newest)

    def _forget_commands(self) -> None:
        """Drop the commands superseded before the oldest kept tick (the newest one acting by
        then stays: it may still be in force)."""
        stale = bisect_right(self._acts, self._ticks[0].time) - 1
        if stale > 0:
            del self._acts[:stale], self._commands[:stale]
