"""The predictive display's arm against an on-board loop behind a delayed link, in process.

The on-board loop here is written out from the parts the spacecraft runs (the command gate on
execution times, the reactionless controller, the kinematic free-floating simulator), apart from
the predictor's own wiring; its telemetry reaches the ground through a :class:`LinkChannel`.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.control.camera_goal import CameraGoal
from rns_ros.control.controller import (
    ControllerSettings,
    ReactionlessController,
    TwistFrame,
    angular_velocity_in_world,
)
from rns_ros.control.teleop import TwistCommand
from rns_ros.control.time_tags import TimeTags
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import FreeFloatingState
from rns_ros.ground.link import LinkChannel, LinkSettings
from rns_ros.ground.predictor import GateSettings, PredictedArm, PredictorSettings
from rns_ros.sim.free_floating import FreeFloatingSimulator, SimulationMode

PERIOD = 0.01  # [s] controller and simulation step
UPLINK_BUDGET = 2.0  # D [s]
DOWNLINK = 1.5  # [s]
AXIS = np.array([1.0, -2.0, 1.5]) / np.linalg.norm([1.0, -2.0, 1.5])
RATE = 0.1  # [rad/s] for TURN seconds, then zeros
TURN = 3.0  # [s]


def _end(turn: float) -> float:
    return turn + UPLINK_BUDGET + DOWNLINK + 1.0


def _settings() -> PredictorSettings:
    return PredictorSettings(
        controller=ControllerSettings(method="dls", period=PERIOD),
        time_tags=TimeTags(execution_delay=UPLINK_BUDGET),
        simulation_step=PERIOD,
    )


class _OnBoard:
    """The spacecraft's loop written out from its parts: the command gate on execution times,
    the reactionless controller, the kinematic free-floating simulator (one step a period)."""

    def __init__(self, robot: FreeFloatingModel, settings: PredictorSettings, q0) -> None:
        self.robot = robot
        self.gate = settings.gate.gate()
        self.controller = ReactionlessController(robot, settings.controller)
        self.state = FreeFloatingState.compute(robot, q0)
        self.controller.reset(self.state)
        self.base_0, self.camera_0 = self.state.base_rotation, self.state.camera.rotation
        self.base = 0.0  # largest base deviation so far [deg]
        self.simulator = FreeFloatingSimulator(
            robot,
            mode=SimulationMode.KINEMATIC,
            dt=PERIOD,
            initial_q=q0,
            initial_momentum=np.zeros(6),
        )

    def step(self, t: float) -> np.ndarray:
        """The period from ``t`` [s] with the commands the gate has; q (7 + n,) at t + T."""
        out = self.gate.update(t, PERIOD)
        if out.stopped:
            theta_dot = np.zeros(self.robot.n)
            self.controller.resync(self.state)
        else:
            omega = angular_velocity_in_world(self.state, out.angular, out.frame)
            theta_dot = self.controller.step(self.state, omega).joint_velocity
        self.simulator.set_reference(velocities=theta_dot)
        self.simulator.step()
        self.state = FreeFloatingState.compute(self.robot, self.simulator.q)
        deviation = math.degrees(attitude_deviation(self.base_0, self.state.base_rotation))
        self.base = max(self.base, deviation)
        return self.simulator.q.copy()


def _run(
    onboard: FreeFloatingModel,
    ground: FreeFloatingModel,
    settings: PredictorSettings,
    turn: float = TURN,
):
    """The operator at 50 Hz on the ground (RATE about AXIS for ``turn`` s, then zeros), the
    spacecraft D later, telemetry d_down later: (predictor, largest base deviation on board
    [deg], on-board camera turn [deg])."""
    q0 = onboard.configuration(onboard.initial_theta)
    tags = settings.time_tags
    board = _OnBoard(onboard, settings, q0)
    uplink = LinkChannel(LinkSettings(delay=1.2, jitter=0.6, seed=1))  # within D
    downlink = LinkChannel(LinkSettings(delay=DOWNLINK))
    arm = PredictedArm(ground, settings, q0, 0.0)
    waiting = []
    for k in range(round(_end(turn) / PERIOD)):
        t = k * PERIOD
        if k % 2 == 0:  # the operator, 50 Hz
            angular = RATE * AXIS if t < turn else np.zeros(3)
            arm.command(t, angular)
            uplink.send(t, (t, angular))
        arm.advance(t + tags.execution_delay)
        # on board: commands taken on arrival, in force from their execution time
        for item in uplink.deliver(t):
            stamp, angular = item.message
            assert tags.refusal(stamp, item.arrival) is None
            waiting.append((tags.execution_time(stamp), angular))
        while waiting and waiting[0][0] <= t + 1e-9:
            acts, angular = waiting.pop(0)
            board.gate.accept(TwistCommand(angular, np.zeros(3), TwistFrame.WORLD, acts))
        downlink.send(t + PERIOD, (t + PERIOD, board.step(t)))
        for item in downlink.deliver(t + PERIOD):
            arm.telemetry(*item.message)
    turned = math.degrees(attitude_deviation(board.camera_0, board.state.camera.rotation))
    return arm, board.base, turned


def _heavier_arm(robot: FreeFloatingModel, factor: float) -> FreeFloatingModel:
    model = robot.model.copy()
    for joint in range(2, model.njoints):  # 1 is the base's free flyer
        body = model.inertias[joint]
        model.inertias[joint] = pin.Inertia(factor * body.mass, body.lever, factor * body.inertia)
    return FreeFloatingModel(model, robot.spec)


def test_with_the_exact_model_the_prediction_is_what_the_telemetry_shows(robot):
    arm, base, turned = _run(robot, robot, _settings())
    errors = np.array([[e.camera_deg, e.base_deg, e.joints_rad] for e in arm.errors])
    # every telemetry sample up to END - d_down compared, none re-anchored
    assert len(arm.errors) == pytest.approx((_end(TURN) - DOWNLINK) / PERIOD, abs=2)
    assert not any(e.resynced for e in arm.errors)
    assert errors.max(axis=0) == pytest.approx(np.zeros(3), abs=1e-9)
    # and the motion was real: a reactionless turn of RATE * TURN about the axis
    assert turned == pytest.approx(math.degrees(RATE * TURN), rel=0.02)
    assert base < 1e-4


def test_a_ten_percent_mass_error_shows_only_in_the_joints_of_a_reactionless_motion(robot):
    # base still and camera at the commanded rate in the model and on board alike; the reaction
    # null space depends on the masses, so the joints differ
    arm, _, _ = _run(robot, _heavier_arm(robot, 1.1), _settings())
    errors = np.array([[e.camera_deg, e.base_deg, e.joints_rad] for e in arm.errors])
    camera, base, joints = errors.max(axis=0)
    assert camera < 1e-6
    assert base < 1e-6
    assert 1e-5 < joints < _settings().resync_rad


def test_a_conventional_motion_with_a_mass_error_is_re_anchored_and_stays_bounded(robot):
    settings = dataclasses.replace(
        _settings(), controller=ControllerSettings(method="conventional", period=PERIOD)
    )
    ground = _heavier_arm(robot, 1.1)
    # a motion of several round trips (3.5 s each)
    arm, base, _ = _run(robot, ground, settings, turn=12.0)
    anchored = max(max(e.camera_deg, e.base_deg) for e in arm.errors)
    assert any(e.resynced for e in arm.errors)
    assert base > 0.1  # the base turns: the 10 % shows in its attitude
    drift, _, _ = _run(robot, ground, dataclasses.replace(settings, resync_deg=1e3), turn=12.0)
    drifted = max(max(e.camera_deg, e.base_deg) for e in drift.errors)
    assert not any(e.resynced for e in drift.errors)
    # re-anchored, the error is what builds up over a round trip, not over the whole motion
    assert anchored < 0.5 * drifted
    assert drifted > 0.01 * base


def test_a_stop_acts_when_its_time_comes_and_the_prediction_shows_it_then(robot):
    settings = _settings()
    q0 = robot.configuration(robot.initial_theta)
    arm = PredictedArm(robot, settings, q0, 0.0)
    arm.command(0.0, RATE * AXIS)
    arm.command(1.0, np.zeros(3))
    before = arm.advance(UPLINK_BUDGET - PERIOD).theta
    assert np.array_equal(before, robot.initial_theta)  # nothing acts before D
    moving = arm.advance(UPLINK_BUDGET + 1.0).theta
    assert np.abs(moving - before).max() > 1e-3
    stopped = arm.advance(UPLINK_BUDGET + 1.0 + 2 * PERIOD).camera.rotation
    later = arm.advance(UPLINK_BUDGET + 3.0).camera.rotation
    # the camera stands (the wrist term may still move the joints in the null space)
    assert attitude_deviation(stopped, later) < 1e-9


def test_bad_inputs_are_named(robot):
    arm = PredictedArm(robot, _settings(), robot.configuration(robot.initial_theta), 0.0)
    with pytest.raises(InputError, match="command stamp must be finite"):
        arm.command(math.nan, np.zeros(3))
    with pytest.raises(InputError, match="angular velocity"):
        arm.command(0.0, [0.0, math.inf, 0.0])
    assert arm.telemetry(0.0043, robot.configuration(robot.initial_theta)) is None  # off grid
    with pytest.raises(ConfigError, match="must be a multiple of simulation_step"):
        PredictorSettings(simulation_step=0.003)
    with pytest.raises(ConfigError, match="resync_deg"):
        PredictorSettings(resync_deg=0.0)
    assert GateSettings().gate().timeout == 0.5


def _run_goal(robot: FreeFloatingModel, settings: PredictorSettings, goal, sent: float, until):
    """The operator sends one camera goal ``goal`` (3, 3) at ``sent`` [s]; it reaches the
    spacecraft D later (an uplink at its budget), where the camera goal law feeds the gate
    every tick, as rns_controller does; telemetry DOWNLINK later. Returns (predictor, on-board
    camera rotation at the end, largest base deviation on board [deg])."""
    q0 = robot.configuration(robot.initial_theta)
    board = _OnBoard(robot, settings, q0)
    uplink = LinkChannel(LinkSettings(delay=settings.time_tags.execution_delay))
    downlink = LinkChannel(LinkSettings(delay=DOWNLINK))
    arm = PredictedArm(robot, settings, q0, 0.0)
    law = CameraGoal(settings.goal)
    for k in range(round(until / PERIOD)):
        t = k * PERIOD
        if abs(t - sent) < 1e-9:
            arm.goal(t, goal)
            uplink.send(t, goal)
        arm.advance(t + settings.time_tags.execution_delay)
        for item in uplink.deliver(t + 1e-9):
            law.set(item.message)
        if law.active:
            step = law.step(board.state.camera.rotation)
            board.gate.accept(TwistCommand(step.omega, np.zeros(3), TwistFrame.WORLD, t))
        downlink.send(t + PERIOD, (t + PERIOD, board.step(t)))
        for item in downlink.deliver(t + PERIOD):
            arm.telemetry(*item.message)
    return arm, board.state.camera.rotation, board.base


def test_a_camera_goal_is_predicted_as_the_spacecraft_turns_to_it(robot):
    """A goal 10 deg away, sent at 0.5 s: the display shows the goal law turning the camera from
    0.5 s + D on, as the spacecraft does once the goal arrives; the telemetry confirms every
    predicted instant (no re-anchoring), the camera ends within the goal tolerance, the base
    still."""
    settings = _settings()
    q0 = robot.configuration(robot.initial_theta)
    camera_0 = FreeFloatingState.compute(robot, q0).camera.rotation
    goal = pin.exp3(math.radians(10.0) * AXIS) @ camera_0
    until = 0.5 + UPLINK_BUDGET + 10.0
    arm, camera, base = _run_goal(robot, settings, goal, 0.5, until)
    assert attitude_deviation(goal, camera) <= settings.goal.tolerance
    assert base < 1e-4
    assert arm.compared > 0.9 * (until - DOWNLINK) / PERIOD
    assert not any(e.resynced for e in arm.errors)
    assert max(e.camera_deg for e in arm.errors) < 1e-9
    # the display got there first: the predicted camera at the end is on the goal too
    assert attitude_deviation(goal, arm.state.camera.rotation) <= settings.goal.tolerance


def test_a_moving_twist_after_a_goal_takes_over_on_the_display(robot):
    settings = _settings()
    q0 = robot.configuration(robot.initial_theta)
    camera_0 = FreeFloatingState.compute(robot, q0).camera.rotation
    arm = PredictedArm(robot, settings, q0, 0.0)
    arm.goal(0.0, pin.exp3(math.radians(10.0) * AXIS) @ camera_0)
    arm.command(1.0, 0.1 * np.array([0.0, 0.0, 1.0]))  # about world z, from 1 s + D on
    arm.command(2.0, np.zeros(3))
    state = arm.advance(2.0 + UPLINK_BUDGET + 2.0)
    # the goal turned the camera for 1 s, then the twist about z took over: the goal is over,
    # the camera stays off it however long the display runs on
    goal = pin.exp3(math.radians(10.0) * AXIS) @ camera_0
    off = attitude_deviation(goal, state.camera.rotation)
    assert off > math.radians(1.0)
    later = arm.advance(2.0 + UPLINK_BUDGET + 7.0)
    assert attitude_deviation(goal, later.camera.rotation) == pytest.approx(off, abs=1e-9)
    assert abs(pin.log3(state.camera.rotation @ camera_0.T)[2]) > 0.05
    with pytest.raises(InputError, match="goal stamp must be finite"):
        arm.goal(math.nan, np.eye(3))
