"""Three ways to operate the arm from the ground through a delayed link, on one task.

The task: turn the camera to an attitude R_goal (a held-out oblique turn) and know it is there,
with one-way delay D both ways (a round trip of 2 D). On board runs the reactionless loop
(eq. 4.5 with the command gate, kinematic integration: :class:`rns_ros.ground.predictor.
PredictedArm` with an exact model *is* that loop); the ground sees the telemetry of on-board time
t - D at t. Each mode is a scripted operator (its parameters are inputs of this comparison, not
results):

* **move and wait** (what an operator without a prediction does): from the newest telemetry,
  command the rate omega_max e / |e| for |e| / omega_max seconds (one burst meant to close the
  error e = log(R_goal R_seen^T)), then wait a round trip and ``settle`` for the telemetry to
  show the arm at rest, and repeat until the telemetry is within ``tolerance``;
* **predictive rate teleop**: stream omega = k e_pred (capped at omega_max) from the predicted
  display, the ground's copy of the loop ahead to t + D, where the command given now acts; stop
  streaming once e_pred is below ``stop_tolerance``;
* **supervisory goal**: send R_goal once; on board the camera goal (:class:`rns_ros.control.
  camera_goal.CameraGoal`, the same omega_max) turns the camera once it arrives, D later.

Each mode's task time is the ground time at which the telemetry first shows the camera within
``tolerance`` of the goal and the joints at rest: what the operator waits for. The figures also
give the on-board camera error at the end, the base's largest deviation [deg] and the commands
sent. ``python -m rns_ros.ground.modes`` prints the table of docs/ground_teleop.md.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.control.camera_goal import CameraGoal, GoalSettings
from rns_ros.control.controller import ControllerSettings, TwistFrame
from rns_ros.control.time_tags import TimeTags
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.core.validation import positive
from rns_ros.ground.predictor import PredictedArm, PredictorSettings

#: The modes, in the order of the table.
MODES = ("move_and_wait", "predictive_rate", "supervisory_goal")
#: Joints slower than this [rad/s] in two consecutive telemetry samples count as at rest.
AT_REST = 1e-3


@dataclass(frozen=True)
class GroundTask:
    """The task and the scripted operators' parameters (inputs of the comparison).

    Attributes:
        delay: one-way link delay D [s], >= 0.
        axis: turn axis in world axes (3,), normalised here.
        angle: turn angle [rad], > 0.
        max_speed: omega_max, the operator's (and the goal's) largest camera rate [rad/s], > 0.
        tolerance: the camera counts as on the goal within this [rad], > 0.
        stop_tolerance: the predictive operator stops streaming below this [rad], > 0.
        gain: k, the predictive operator's gain on e_pred [1/s], > 0.
        settle: move and wait: extra wait after the round trip for the arm to come to rest [s].
        operator_period: how often the operator acts and streams [s], a multiple of the period.
        period: the on-board control period T [s].
        timeout: give up after this ground time [s].
    """

    delay: float = 3.0
    axis: tuple[float, float, float] = (0.6, 0.0, 0.8)
    angle: float = math.radians(30.0)
    max_speed: float = 0.1
    tolerance: float = math.radians(0.1)
    stop_tolerance: float = math.radians(0.02)
    gain: float = 2.0
    settle: float = 0.5
    operator_period: float = 0.02
    period: float = 0.01
    timeout: float = 300.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.delay) and self.delay >= 0.0):
            raise ValueError(f"delay must be a finite number >= 0 s, got {self.delay!r}")
        for name, unit in (
            ("angle", "rad"),
            ("max_speed", "rad/s"),
            ("tolerance", "rad"),
            ("stop_tolerance", "rad"),
            ("gain", "1/s"),
            ("period", "s"),
            ("operator_period", "s"),
            ("timeout", "s"),
        ):
            positive(getattr(self, name), name, unit)


@dataclass(frozen=True)
class ModeResult:
    """One mode on the task.

    Attributes:
        mode: one of :data:`MODES`.
        task_time: ground time when the telemetry first showed the camera on the goal, at rest
            [s] (NaN: not within the timeout).
        commands: operator messages sent (twists or the goal).
        bursts: move and wait: bursts commanded (others: 1).
        final_camera_error_deg: on-board camera vs R_goal at the end [deg].
        max_base_deviation_deg: largest on-board base attitude change [deg].
    """

    mode: str
    task_time: float
    commands: int
    bursts: int
    final_camera_error_deg: float
    max_base_deviation_deg: float


class _Run:
    """The on-board loop, the ground's view of it and the clock of one mode."""

    def __init__(self, robot: FreeFloatingModel, task: GroundTask, q0: np.ndarray) -> None:
        self.robot, self.task = robot, task
        settings = PredictorSettings(
            controller=ControllerSettings(period=task.period),
            time_tags=TimeTags(execution_delay=task.delay),
            history=task.timeout + 4.0 * task.delay + 10.0,
            simulation_step=task.period,
        )
        self.board = PredictedArm(robot, settings, q0, 0.0)
        self.display = PredictedArm(robot, settings, q0, 0.0)
        first = FreeFloatingState.compute(robot, q0)
        self.base_0 = first.base_rotation
        axis = np.asarray(task.axis, dtype=float)
        self.goal = pin.exp3(task.angle * axis / np.linalg.norm(axis)) @ first.camera.rotation
        self.commands = 0
        self.base = 0.0
        self.q0 = q0
        self._seen: tuple[float, np.ndarray] | None = None  # (stamp [s], q) of the last look

    def send(self, t: float, omega) -> None:
        """The operator's twist at ground time ``t`` [s]: on board and on the display it acts
        from t + D."""
        self.board.command(t, omega, TwistFrame.WORLD)
        self.display.command(t, omega, TwistFrame.WORLD)
        self.commands += 1

    def step(self, t: float) -> None:
        """On board up to t + T; the base's deviation so far."""
        state = self.board.advance(t + self.task.period)
        self.base = max(self.base, attitude_deviation(self.base_0, state.base_rotation))

    def seen(self, t: float) -> tuple[float, bool, np.ndarray]:
        """What the ground sees at ``t`` [s], from the telemetry of t - D (before on-board time
        0: the arm at rest at q0): camera error to the goal [rad], whether the joints moved
        slower than :data:`AT_REST` since the previous call, the configuration (7 + n,)."""
        stamp = t - self.task.delay
        q = self.q0 if stamp < 0.0 else self.board.predicted_q(stamp)
        previous, self._seen = self._seen, (stamp, q)
        camera = FreeFloatingState.compute(self.robot, q).camera.rotation
        rest = stamp < 0.0 or (
            previous is not None
            and np.abs(q[7:] - previous[1][7:]).max() <= AT_REST * (stamp - previous[0])
        )
        return attitude_deviation(self.goal, camera), rest, q

    def error_of(self, state: FreeFloatingState) -> np.ndarray:
        """e = log(R_goal R_c^T) [rad] (3,), world axes."""
        return pin.log3(self.goal @ state.camera.rotation.T)

    def result(self, mode: str, task_time: float, bursts: int) -> ModeResult:
        final = FreeFloatingState.compute(self.robot, self.board.q)
        return ModeResult(
            mode,
            task_time,
            self.commands,
            bursts,
            math.degrees(attitude_deviation(self.goal, final.camera.rotation)),
            math.degrees(self.base),
        )


class _MoveAndWait:
    """Move and wait: a burst from the newest telemetry, then a round trip and ``settle``."""

    def __init__(self, task: GroundTask) -> None:
        self.task, self.bursts = task, 0
        self._burst_end, self._next_plan, self._omega = -math.inf, 0.0, np.zeros(3)

    def act(self, run: _Run, t: float, seen: tuple | None) -> None:
        if seen is None:
            return
        task = self.task
        if t >= self._next_plan:
            error, _, q = seen
            e = run.error_of(FreeFloatingState.compute(run.robot, q))
            self._omega, self._burst_end = task.max_speed * e / error, t + error / task.max_speed
            self._next_plan = self._burst_end + 2.0 * task.delay + task.settle
            self.bursts += 1
        if t < self._burst_end:
            run.send(t, self._omega)
        elif t < self._burst_end + task.settle:
            run.send(t, np.zeros(3))  # a clean stop, not a stale command ramping down


class _PredictiveRate:
    """Predictive rate teleop: omega = k e_pred from the display, until e_pred is small."""

    def __init__(self, task: GroundTask) -> None:
        self.task, self.bursts = task, 1
        self._stopped_at, self._streaming = math.inf, True

    def act(self, run: _Run, t: float, seen: tuple | None) -> None:
        task = self.task
        if seen is None or not self._streaming:
            return  # not the operator's tick, or done streaming
        e = run.error_of(run.display.advance(t + task.delay))
        error = float(np.linalg.norm(e))
        if error <= task.stop_tolerance and self._stopped_at == math.inf:
            self._stopped_at = t
        if self._stopped_at < math.inf:
            run.send(t, np.zeros(3))
            self._streaming = t < self._stopped_at + task.settle
        else:
            run.send(t, min(task.gain * error, task.max_speed) * e / error)


class _SupervisoryGoal:
    """A supervisory goal: sent once; on board the goal law turns the camera from D on."""

    def __init__(self, task: GroundTask) -> None:
        self.task, self.bursts = task, 1
        self._goal = CameraGoal(
            GoalSettings(max_speed=task.max_speed, tolerance=task.stop_tolerance)
        )
        self._sent = False

    def act(self, run: _Run, t: float, seen: tuple | None) -> None:
        if not self._sent:
            run.commands += 1  # the goal, on its way up
            self._sent = True
        if t < self.task.delay - 1e-9:
            return
        goal = self._goal
        if not goal.active and goal.error is None:
            goal.set(run.goal)
        if goal.active:
            step = goal.step(FreeFloatingState.compute(run.robot, run.board.q).camera.rotation)
            # acts on board now: issued D earlier in the time-tag sense
            run.board.command(t - self.task.delay, step.omega, TwistFrame.WORLD)


#: The scripted operator of each mode.
_OPERATORS = {
    "move_and_wait": _MoveAndWait,
    "predictive_rate": _PredictiveRate,
    "supervisory_goal": _SupervisoryGoal,
}


def run_mode(robot: FreeFloatingModel, mode: str, task: GroundTask, q0) -> ModeResult:
    """``mode`` (one of :data:`MODES`) on ``task`` from configuration ``q0`` (7 + n,)."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {list(MODES)}, got {mode!r}")
    run = _Run(robot, task, np.asarray(q0, dtype=float))
    operator = _OPERATORS[mode](task)
    every = round(task.operator_period / task.period)
    for k in range(round(task.timeout / task.period)):
        t = k * task.period
        seen = run.seen(t) if k % every == 0 else None  # what the operator sees on its tick
        if seen is not None and seen[0] <= task.tolerance and seen[1]:
            return run.result(mode, t, operator.bursts)
        operator.act(run, t, seen)
        run.step(t)
    return run.result(mode, math.nan, operator.bursts)


def compare(robot: FreeFloatingModel, task: GroundTask, q0) -> list[ModeResult]:
    """Every mode of :data:`MODES` on ``task``."""
    return [run_mode(robot, mode, task, q0) for mode in MODES]


def format_table(results: list[ModeResult], task: GroundTask) -> str:
    head = (
        f"{'mode':<18} {'task [s]':>9} {'commands':>9} {'bursts':>7} "
        f"{'camera err [deg]':>17} {'max base dev [deg]':>19}"
    )
    lines = [f"one-way delay {task.delay:g} s, {math.degrees(task.angle):g} deg turn", head]
    for r in results:
        lines.append(
            f"{r.mode:<18} {r.task_time:>9.2f} {r.commands:>9d} {r.bursts:>7d} "
            f"{r.final_camera_error_deg:>17.3g} {r.max_base_deviation_deg:>19.3g}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    from rns_ros.core import load_model
    from rns_ros.resources import default_model_config

    parser = argparse.ArgumentParser(prog="python -m rns_ros.ground.modes")
    parser.add_argument("--delays", default="1,3,6", help="one-way delays [s], comma-separated")
    args = parser.parse_args(argv)
    robot = load_model(default_model_config())
    q0 = robot.configuration(robot.initial_theta)
    for delay in (float(d) for d in args.delays.split(",")):
        task = GroundTask(delay=delay)
        print(format_table(compare(robot, task, q0), task))
        print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
