"""One run of an inspection scenario over DDS: a method on a fresh stack of node processes.

For each method (reactionless ``dls``, ``sc``, ``pinv``, ``conventional``, or
``conventional+wheels``) a launch-free stack runs on its own domain, localhost only, each node
as its own process (:class:`rns_ros.harness.ProcessStack`, as ``ros2 run`` starts them):
``rns_simulator`` starting from the scenario's joint angles, ``rns_controller`` with that
method, ``rns_operator`` playing the scenario file, and ``rns_rerun_logger`` recording one
``.rrd`` per run (or a live viewer); this process records the topics
(:class:`rns_ros.harness.Harness`), from which :mod:`rns_ros.analysis.recorded_run` computes
the figures.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rns_ros.analysis.recorded_run import RunFigures, run_figures
from rns_ros.cli import signals_held
from rns_ros.control.scenario import Scenario, check_speed_limit, load_scenario
from rns_ros.core import FreeFloatingModel, RnsError, load_model
from rns_ros.harness import PROBE_NODE, Harness, ProcessStack, TopicLog, header_seconds
from rns_ros.nodes.controller_parameters import NODE_NAME as CONTROLLER_NODE
from rns_ros.nodes.controller_parameters import SPECS as CONTROLLER_SPECS
from rns_ros.nodes.controller_status import TWISTS_RECEIVED
from rns_ros.nodes.link_parameters import NODE_NAME as LINK_NODE
from rns_ros.nodes.predictor_parameters import NODE_NAME as PREDICTOR_NODE
from rns_ros.nodes.rerun_logger_parameters import NODE_NAME as LOGGER_NODE
from rns_ros.resources import default_model_config
from rns_ros.runs.clock import lockstep
from rns_ros.runs.link import (
    GROUND,
    GROUND_TWISTS,
    LinkOptions,
    acting,
    controller_parameters,
    link_options,
    prediction_error_deg,
    start_link_nodes,
)
from rns_ros.runs.logger import rrd_lost, start_logger
from rns_ros.runs.mcap_recording import open_mcap, record_robot_model
from rns_ros.runs.recorded import (
    EnergyFigures,
    InterruptedRun,
    PartialRecordingError,
    energy_figures,
    latest_status_values,
    missed_samples,
    robot_arrays,
)

#: ``conventional+wheels``: the conventional controller with rns_attitude_control holding the
#: base with reaction wheels (thesis chapter 5's comparison); the simulator gets wheels.
WHEELS_SUFFIX = "+wheels"
METHODS = ("dls", "sc", "pinv", "conventional", "conventional+wheels")
DEFAULT_METHODS = ("dls", "sc", "conventional")
#: Settling time after the operator's zeros before the run ends [s], on the run's clock (sim
#: time in lockstep): the figures cover the same stretch of the run at any speed.
SETTLE = 0.3


@dataclass(frozen=True)
class DemoRow:
    """One run of the comparison table.

    Attributes:
        wall_time_s: the whole run, node start-up included [s].
        task_wall_s: wall time from the operator's first command until every state stream
            reached the end of the task [s] (None: not measured).
        task_sim_s: simulated time of that stretch: duration + zero twists + settle [s].
    """

    method: str
    figures: RunFigures
    wall_time_s: float
    recording: str | None
    energy: EnergyFigures | None = None
    task_wall_s: float | None = None
    task_sim_s: float | None = None
    mcap: str | None = None
    #: why the run ended before the task's end (a joint at its limit, Ctrl-C), None when it did not
    ended: str | None = None
    #: a recording of the run that could not be written (the file removed): why, one line each
    unwritten: tuple[str, ...] = ()
    #: behind a space link (--link-delay): its one-way delay [s], and the largest angle between
    #: the predicted and the spacecraft's camera at the same stamp over the task [deg]
    link_delay_s: float | None = None
    prediction_error_deg: float | None = None

    @property
    def real_time_factor(self) -> float | None:
        """Simulated task seconds per wall second (None when not measured)."""
        if self.task_wall_s is None or self.task_sim_s is None or self.task_wall_s <= 0.0:
            return None
        return self.task_sim_s / self.task_wall_s

    @property
    def label(self) -> str:
        """The row's name in messages: its method."""
        return self.method

    def checked_figures(self) -> dict[str, float]:
        """Every figure that must be finite, by name: the run's (those computed), its wall time,
        its energy and, behind a link, its prediction error."""
        values = {k: v for k, v in asdict(self.figures).items() if v is not None}
        values["wall_time_s"] = self.wall_time_s
        if self.prediction_error_deg is not None:
            values["prediction_error_deg"] = self.prediction_error_deg
        if self.energy is not None:
            values |= {k: v for k, v in asdict(self.energy).items() if v is not None}
        return values


def check_scenarios(files: list[Path]) -> list[Scenario]:
    """Load every scenario file and check it against the controller's ``max_angular_speed``
    (its default, or the scenario's own override) before any node starts.

    Raises:
        ConfigError: a file is invalid, or a scenario's peak angular speed exceeds the limit
            (names the scenario, its peak speed [rad/s] and the limit [rad/s]).
    """
    default_limit = CONTROLLER_SPECS["max_angular_speed"].default
    scenarios = [load_scenario(file) for file in files]
    for scenario in scenarios:
        check_speed_limit(scenario, default_limit)
    return scenarios


#: A scenario's start within this of the model's, joint by joint [deg], is the model's (angles
#: written to a file in degrees and read back differ by rounding).
SAME_START_DEG = 1e-5


def _degrees(theta: np.ndarray) -> str:
    return ", ".join(f"{value:.4g}" for value in np.rad2deg(theta))


def start_configuration(scenario: Scenario, robot: FreeFloatingModel) -> tuple[np.ndarray, str]:
    """The joint angles [rad] (n,) a run of ``scenario`` on ``robot`` starts from, and a note
    ('' when none is due).

    The scenario's ``initial_joint_positions_deg`` when they give one angle per controlled joint
    and lie within the joint limits (the note says so when they differ from the model's own
    ``initial_joint_positions``); otherwise the scenario was written for another arm, and the
    run starts from the model's ``initial_joint_positions`` (zeros for joints the model YAML
    leaves out), which the note says.
    """
    theta = scenario.initial_theta
    own = robot.initial_theta
    if theta.shape != (robot.n,):
        why = (
            f"gives {theta.size} initial angles, the model has {robot.n} controlled joints "
            f"{list(robot.joint_names)}"
        )
    elif np.any(theta < robot.lower_limits) or np.any(theta > robot.upper_limits):
        outside = [
            name
            for name, value, low, high in zip(
                robot.joint_names, theta, robot.lower_limits, robot.upper_limits, strict=True
            )
            if not low <= value <= high
        ]
        why = f"puts joints {outside} outside their limits"
    elif np.allclose(np.rad2deg(theta - own), 0.0, rtol=0.0, atol=SAME_START_DEG):
        return theta, ""
    else:
        return theta, (
            f"starting from scenario {scenario.name!r}'s initial_joint_positions_deg "
            f"[{_degrees(theta)}] deg, not the model's [{_degrees(own)}] deg"
        )
    angles = _degrees(own)
    return own, (
        f"scenario {scenario.name!r} {why}: starting from the model's initial_joint_positions "
        f"[{angles}] deg"
    )


def run_method(
    method: str,
    args: argparse.Namespace,
    scenario_file: Path,
) -> DemoRow:
    """One full DDS run of the scenario with ``method``; returns its figures.

    The nodes run as their own processes (:class:`~rns_ros.harness.ProcessStack`: the installed
    ``rns_simulator``, ``rns_controller``, ``rns_operator``, ``rns_rerun_logger`` and, with
    wheels, ``rns_attitude_control``, each on its own executor, as ``ros2 run`` starts them);
    this process only records the topics. Separate processes keep the simulation thread and
    the nodes from sharing one GIL, whose waits would delay the controller's outputs
    (docs/controller.md, "Accuracy over DDS").

    Raises:
        RnsError: a node did not start, or the run did not finish in time.
        InterruptedRun: Ctrl-C or SIGTERM; the recordings are closed, its ``row`` holds the
            figures so far (None before the task started).
    """
    scenario = load_scenario(scenario_file)
    model_config = str(getattr(args, "model", None) or default_model_config())
    robot = load_model(model_config)
    theta, _ = start_configuration(scenario, robot)
    scenario = replace(scenario, initial_theta=theta)
    sim_time = lockstep(args)
    wheels = method.endswith(WHEELS_SUFFIX)
    link = link_options(args)
    ros_args = list(args.ros_args[1:]) if args.ros_args else []
    start = time.perf_counter()
    interrupted: KeyboardInterrupt | None = None
    with (
        ProcessStack(args.domain_id) as processes,
        Harness(args.domain_id, args.ros_args, executor="events") as stack,
        open_mcap(args, method, stack) as mcap_file,
    ):
        stack.on_record.append(mcap_file.add)  # each recorded topic, written as it arrives
        record_robot_model(stack, mcap_file)  # what a viewer draws the arm from
        # serialized, read after the run: this process then costs the stack little CPU
        streams = {
            "joints": stack.record(JointState, "joint_states", raw=True),
            "odom": stack.record(Odometry, "base_odom", raw=True),
            "momentum": stack.record(WrenchStamped, "momentum", raw=True),
            "energy": stack.record(Float64MultiArray, "energy", raw=True),
            "attitude": stack.record(DiagnosticArray, "rns_attitude_control/status", raw=True),
        }
        predicted = {}
        if link is not None:  # the ground's predicted arm, compared after the run
            predicted = {
                "joints": stack.record(JointState, "/ground/predicted/joint_states", raw=True),
                "odom": stack.record(Odometry, "/ground/predicted/base_odom", raw=True),
            }
        recording, logger = start_logger(
            processes, method, args, model_config, sim_time=sim_time, ros_args=ros_args
        )
        try:
            listeners = _start_nodes(
                processes,
                method,
                args,
                scenario,
                scenario_file,
                logger is not None,
                ros_args,
                model_config,
            )
            # the task only once the robot runs and this process and the logger record it (a
            # recorder matched late would miss the start of the task): the operator counts
            # this subscription among its min_subscribers
            awaited = None
            if sim_time and args.output_lead:
                awaited = stack.record(DiagnosticArray, f"{CONTROLLER_NODE}/status")
            # behind a link, the predictor too: started from its first telemetry, it knows
            # nothing of a motion already under way
            predicting = None
            if link is not None:
                predicting = stack.record(DiagnosticArray, f"/{GROUND}/{PREDICTOR_NODE}/status")
            _wait_for_start(
                stack, processes, streams, listeners, method, awaited=awaited, predicting=predicting
            )
            task, end, task_wall, limited = _run_task(
                stack, processes, streams, scenario, args, method, link
            )
        except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM: the figures so far, then stop
            interrupted = exc
            task, end, task_wall, limited = _task_so_far(streams, scenario), None, None, False
        with signals_held():  # a second Ctrl-C does not cut the recordings' closing short
            # stopped before the recorded messages are read: in lockstep the stack would go
            # on stepping as fast as it can meanwhile, competing with this process for cores
            processes.stop()  # the logger writes its summary line as it closes the recording
            if link is not None and "commands" in streams:
                streams["commands"] = acting(streams["commands"], link.execution_delay)
            if interrupted is None:
                data = _task_arrays(streams, task, end, method, sim_time)
            else:
                data, end = _arrays_so_far(streams, task)
            energy = None
            if data is not None:
                attitude = streams["attitude"] if wheels else None
                energy = energy_figures(streams["energy"], attitude, until=end)
            for line in processes.problems():  # a watchdog that stopped the arm, a rejection
                print(f"  {line}", flush=True)
            if logger is not None:
                closed = [
                    line
                    for line in processes.output(logger).splitlines()
                    if LOGGER_CLOSED_LINE in line  # a lost recording is among the problems
                ]
                print("\n".join(closed[-1:]), flush=True)
            mcap = mcap_file.close()
    lost = rrd_lost(recording)
    unwritten = [problem for problem in (mcap_file.problem, lost) if problem]
    figures = None
    if data is not None:  # None: interrupted before the task started
        try:
            figures = run_figures(
                robot, scenario, **data, singular_threshold=singular_threshold(scenario)
            )
        except RnsError:
            if interrupted is None:
                raise  # an interrupted run may have too little to show
    if figures is None:
        raise InterruptedRun(interrupted, None, unwritten)
    ended = None
    if interrupted is not None:
        ended = f"interrupted {end - task:.1f} s into the task (its figures so far)"
    elif limited:
        ended = limit_cause(robot, data["joint_positions"][-1], data["times"][-1] - task)
    prediction = None
    if link is not None and task is not None and end is not None:
        measured = {"joints": streams["joints"], "odom": streams["odom"]}
        prediction = prediction_error_deg(robot, predicted, measured, task, end)
    row = DemoRow(
        method,
        figures,
        time.perf_counter() - start,
        None if lost else recording,
        energy,
        task_wall_s=task_wall,
        task_sim_s=end - task,
        mcap=mcap,
        ended=ended,
        unwritten=tuple(unwritten),
        link_delay_s=None if link is None else link.delay,
        prediction_error_deg=prediction,
    )
    if interrupted is not None:
        raise InterruptedRun(interrupted, row, unwritten)
    return row


def _task_arrays(
    streams: dict[str, TopicLog], task: float, end: float, method: str, sim_time: bool
) -> dict[str, np.ndarray]:
    """The robot's recorded samples of a finished task (from just before its start: the robot
    is at rest until the first command, and a recorder matched a moment after the first state
    then has all of it).

    Raises:
        PartialRecordingError: this process matched late or missed samples (the run itself is
            repeatable).
    """
    data = robot_arrays(streams, until=end, since=task - TASK_MARGIN)
    if data["times"][0] > task:  # the deviations count from the first recorded state
        # this process matched late (the operator may count a subscriber of a run just ended)
        raise PartialRecordingError(
            f"{method}: the robot state was recorded from {data['times'][0]:.3f} s, after "
            f"the operator's profile started at {task:.3f} s"
        )
    _check_at_rest_before(data, task, method)
    _check_complete(data, method, sim_time)
    return data


#: Largest joint speed [rad/s] of an arm at rest: before the first command acts nothing moves
#: (the controller's output is exactly zero), so anything above is a command already acting.
AT_REST = 1e-3


def _check_at_rest_before(data: dict[str, np.ndarray], task: float, method: str) -> None:
    """The arm stands still up to the task's start: the start is the first moving twist this
    process recorded, so an arm already moving then means the twists before it were lost to
    this process (on the wall clock a starved recorder drops best-effort samples, and the
    figures would start mid-task: the camera's target counted from where it had turned to).

    Raises:
        PartialRecordingError: it moved.
    """
    before = data["times"] <= task
    speed = float(np.abs(data["joint_velocities"][before]).max(initial=0.0))
    if speed > AT_REST:
        raise PartialRecordingError(
            f"{method}: the arm moved at {speed:.3g} rad/s before the first moving cmd_twist "
            f"this process recorded ({task:.3f} s): it missed the start of the operator's "
            "profile; no figures from a partial recording"
        )


def _task_so_far(streams: dict[str, TopicLog], scenario: Scenario) -> float | None:
    """When the operator's profile started [s], or None when no moving twist was recorded."""
    commands = streams.get("commands")
    if commands is None:
        return None
    try:
        return profile_start(commands, scenario, OPERATOR_RATE)
    except RnsError:
        return None


def _arrays_so_far(
    streams: dict[str, TopicLog], task: float | None
) -> tuple[dict[str, np.ndarray] | None, float | None]:
    """The robot's samples from the task's start to the newest state every stream reached,
    and that end [s]; (None, None) before the task started or with too few samples."""
    if task is None:
        return None, None
    stamps = [streams[name].latest_stamp() for name in ("joints", "odom", "momentum")]
    if any(stamp is None for stamp in stamps) or min(stamps) <= task:
        return None, None
    end = min(stamps)
    try:
        return robot_arrays(streams, until=end, since=task - TASK_MARGIN), end
    except RnsError:
        return None, None


def singular_threshold(scenario: Scenario) -> float:
    """The singular-region threshold of ``scenario``'s controller: its ``epsilon`` (section
    4.3.2), rns_controller's default when the scenario sets none."""
    return float(scenario.controller.get("epsilon", CONTROLLER_SPECS["epsilon"].default))


#: How close [rad] a joint must be to a limit to be named as the one that stopped a run.
LIMIT_NEAR = 0.05


def limit_cause(robot: FreeFloatingModel, theta: np.ndarray, t: float) -> str:
    """Why a run stopped at ``t`` [s] of task time with the joints at ``theta`` [rad] (n,): the
    joint nearest one of its limits, named with the limit (e.g. ``g7_joint5 reached its upper
    limit 2.9 rad at t = 11.68 s``)."""
    lower = np.abs(theta - robot.lower_limits)
    upper = np.abs(theta - robot.upper_limits)
    gaps = np.minimum(lower, upper)
    joint = int(np.argmin(gaps))
    side, limit = (
        ("upper", robot.upper_limits[joint])
        if upper[joint] <= lower[joint]
        else ("lower", robot.lower_limits[joint])
    )
    if gaps[joint] > LIMIT_NEAR:
        return f"the controller stopped at a joint limit at t = {t:.2f} s"
    return f"{robot.joint_names[joint]} reached its {side} limit {limit:.6g} rad at t = {t:.2f} s"


def _controller_parameters(
    method: str, args: argparse.Namespace, scenario: Scenario
) -> dict[str, object]:
    """rns_controller's parameters for ``method`` (its control law, without ``+wheels``) at
    ``--rate``; in lockstep on sim time, waiting for the lockstep simulator; the scenario's
    own controller settings (its method aside) last."""
    sim_time = lockstep(args)
    parameters = {
        "method": method.removesuffix(WHEELS_SUFFIX),
        "rate": args.rate,
        # in lockstep the thesis' law, open in the rate: the figures are the law's, not a
        # feedback's; on the wall clock the controller as a lab runs it, whose camera catches
        # up with the commanded turn after a stall (tracking_gain at its default)
        **({"use_sim_time": True, "tracking_gain": 0.0} if sim_time else {}),
    }
    if sim_time and args.output_lead:
        # each output acts one period after its tick: the simulator computes that period
        # while the controller computes the next output (two cores side by side)
        parameters["output_lead"] = 1.0 / args.rate
        # and serves each tick with the operator's sample in force then, published ahead
        # (OPERATOR_LEAD): a run's figures do not depend on when the operator got a core
        parameters["await_commands"] = True
        parameters["await_timeout"] = AWAIT_TIMEOUT
    link = link_options(args)
    if link is not None:
        parameters.update(controller_parameters(link, OPERATOR_LEAD))
    parameters.update({key: value for key, value in scenario.controller.items() if key != "method"})
    return parameters


def _start_nodes(
    processes: ProcessStack,
    method: str,
    args: argparse.Namespace,
    scenario: Scenario,
    scenario_file: Path,
    logger: bool,
    ros_args: list[str],
    model_config: str,
) -> list[str]:
    """Start rns_controller, rns_operator, (with wheels) rns_attitude_control and rns_simulator
    for ``scenario`` (read from ``scenario_file``; the simulator starts from its
    ``initial_theta``), each on the robot of ``model_config``; return the nodes whose
    subscriptions the task waits for (``logger``: one is running)."""
    sim_time = lockstep(args)
    timing = {"use_sim_time": True} if sim_time else {}
    model = {"model_config": model_config}
    wheels = method.endswith(WHEELS_SUFFIX)
    link = link_options(args)
    controller = {**_controller_parameters(method, args, scenario), **model}
    processes.start("rns_controller", controller, ros_args=ros_args)
    if link is not None:
        start_link_nodes(processes, link, controller, timing, ros_args)
    # the operator imports while the others do (started after the robot ran, its start-up
    # competed for the cores with a lockstep run stepping the idle robot as fast as it can:
    # ~2 s of each run's wall time); its profile still waits for this process's cmd_twist
    # subscription, made once the robot state is recorded
    listeners = [CONTROLLER_NODE]
    if logger:
        listeners.append(LOGGER_NODE)
    # the operator's twists go to the ground's topic: the link and the predictor take them
    twist_takers = [LINK_NODE, PREDICTOR_NODE] if link is not None else list(listeners)
    operator_subscribers = len(twist_takers)
    if link is not None:
        listeners.append(LINK_NODE)
    operator_timing = dict(timing)
    if sim_time and args.output_lead:
        # the profile on the controller's period grid: the same samples in each tick, however
        # late the operator's start condition was met
        # zeros before it, at least one sample even when every subscriber is there at the
        # operator's first tick: a first recorded twist that moves then means a late recorder
        # (a constant-rate profile moves from its first sample)
        operator_timing.update(
            lead=OPERATOR_LEAD,
            start_delay=OPERATOR_LEAD + 1.0 / OPERATOR_RATE,
            start_grid=1.0 / args.rate,
        )
    processes.start(
        "rns_operator",
        {
            "scenario": str(scenario_file),
            "rate": OPERATOR_RATE,
            "start_delay": 0.5,
            "zero_duration": OPERATOR_ZERO_DURATION,
            # the controller, this process and the logger: the first to be matched no
            # longer starts the profile while the controller still misses it; named, so a
            # stranger's subscriber (a plot, an echo) does not stand in for one of them
            "min_subscribers": operator_subscribers + 1,
            "subscriber_nodes": ",".join([*twist_takers, PROBE_NODE]),
            **operator_timing,
            **model,  # the operator's base and camera frame ids
        },
        remappings={"cmd_twist": GROUND_TWISTS} if link is not None else None,
        ros_args=ros_args,
    )
    if wheels:
        processes.start(
            "rns_attitude_control", {"rate": args.rate, **timing, **model}, ros_args=ros_args
        )
    processes.start(
        "rns_simulator",
        {
            "initial_joint_positions": scenario.initial_theta.tolist(),
            "mode": args.mode,
            "step_size": simulation_step(args, wheels),
            "real_time_factor": args.real_time_factor,
            "publish_clock": sim_time,
            # in lockstep, the simulator waits for each control period's output, so the
            # figures do not depend on how fast this machine is
            "lockstep_period": 1.0 / args.rate if sim_time else 0.0,
            "reaction_wheels": wheels,
            **model,
        },
        ros_args=ros_args,
    )
    return listeners


def _run_task(
    stack: Harness,
    processes: ProcessStack,
    streams: dict[str, TopicLog],
    scenario: Scenario,
    args: argparse.Namespace,
    method: str,
    link: LinkOptions | None = None,
) -> tuple[float, float, float, bool]:
    """Record ``cmd_twist`` (into ``streams``) until every state stream reached the task's end,
    or until rns_controller reports JOINT_LIMIT (a joint at its limit: the task cannot be done;
    the run ends there, its figures so far kept); return the task's start and end [s] (stamps'
    clock), its wall time [s] and whether a joint limit ended it. Behind a ``link`` the
    operator's twists are recorded on the ground and the task starts when they act on board,
    the execution delay after their stamps."""
    # the operator's profile waits for this subscription (one of its min_subscribers): made
    # only now, once the robot runs and is recorded, it holds the profile until then
    topic = "cmd_twist" if link is None else GROUND_TWISTS
    commands = streams["commands"] = stack.record(TwistStamped, topic, raw=True)
    # serialized: only the newest is read (JointLimitWatch); deserializing each status in the
    # executor would cost it the time it needs to record every cmd_twist
    status = stack.record(DiagnosticArray, f"{CONTROLLER_NODE}/status", raw=True)
    shift = 0.0 if link is None else link.execution_delay  # when a twist acts on board
    budget = 60.0 + (scenario.duration + 2.0 + 2 * shift) / max(args.real_time_factor, 1.0)
    if not stack.spin_until(lambda: _moving(commands.latest()), timeout=budget):
        raise RnsError(f"{method}: no moving cmd_twist from rns_operator within {budget:.0f} s")
    # the end on the stamps' clock: a lockstep run goes on at its own pace,
    # so a wall-time settle would let figures depend on this machine's speed
    _check_recorded_from_the_start(commands.messages[0], args, method)
    task = profile_start(commands, scenario, OPERATOR_RATE) + shift
    task_started = time.perf_counter()
    end = task + scenario.duration + OPERATOR_ZERO_DURATION + SETTLE
    states = [streams[name] for name in ("joints", "odom", "momentum")]
    stop = JointLimitWatch(status)
    if not stack.spin_until(
        lambda: all(len(log) and log.latest_stamp() >= min(end, stop.at) for log in states),
        timeout=budget,
        check_every=0.005,  # not after each of the ~4 messages a period brings
    ):
        raise RnsError(
            f"{method}: the scenario did not finish within {budget:.0f} s{processes.exit_report()}"
        )
    return task, min(end, stop.at), time.perf_counter() - task_started, stop.at < end


class JointLimitWatch:
    """The stamp [s] of the first rns_controller status in JOINT_LIMIT (:attr:`at`; inf until
    one is seen). Each look reads the statuses received since the last one, as bytes: only one
    naming JOINT_LIMIT is decoded, so the watch costs a byte search per status, and the stamp
    does not depend on how often this process looked (on simulated time the figures end at the
    same instant on a busy machine as on a quiet one)."""

    def __init__(self, status: TopicLog) -> None:
        self._status = status
        self._looked = 0
        self._at = math.inf

    @property
    def at(self) -> float:
        if math.isfinite(self._at):
            return self._at
        new = self._status.serialized(self._looked)
        self._looked += len(new)
        for data in new:
            if JOINT_LIMIT_STATE not in data:
                continue
            msg = self._status.decode(data)
            if msg is None:
                continue
            states = {kv.value for entry in msg.status for kv in entry.values if kv.key == "state"}
            if "JOINT_LIMIT" in states:
                self._at = header_seconds(msg)
                break
        return self._at


#: The controller state's text as it appears in a serialized status.
JOINT_LIMIT_STATE = b"JOINT_LIMIT"


#: rns_simulator's default RK4 step [s] and the range --sim-step accepts (its step_size's).
SIM_STEP = 1e-3
MIN_SIM_STEP, MAX_SIM_STEP = 1e-5, 0.1


def simulation_step(args: argparse.Namespace, wheels: bool) -> float:
    """rns_simulator's step [s] for an inspection run: ``--sim-step`` when given; in lockstep
    in kinematic mode without wheels one control period, since the joint rate is held over the
    period and only the base is integrated (one 10 ms RK4 step gives the 1 ms figures to nine
    digits, dls and conventional: ``test_closed_loop``); else ``SIM_STEP``. Wheels keep 1 ms:
    their torque changes within a period with the attitude loop's."""
    if args.sim_step is not None:
        return args.sim_step
    lockstep_run = lockstep(args) and args.mode == "kinematic" and not wheels
    if not lockstep_run:
        return SIM_STEP
    period = 1.0 / args.rate
    return period / math.ceil(period / MAX_SIM_STEP - 1e-9)


#: What rns_rerun_logger's summary line on closing its recording contains.
LOGGER_CLOSED_LINE = "recording closed"
#: Robot states before the first command that the figures include [s].
TASK_MARGIN = 0.2
#: Zero twists the operator sends after the profile [s] (its default).
OPERATOR_ZERO_DURATION = 1.0
#: How long [s, wall clock] a lockstep tick waits for the operator's next sample after a moving
#: one: a tick served without it runs a period off the operator's plan (and off rns_predictor's
#: prediction), so a process starved on a loaded machine for longer than rns_controller's
#: default (0.5 s) is waited for.
AWAIT_TIMEOUT = 5.0
#: The operator's rate [Hz] (its default) and, in lockstep side by side, how far ahead [s] it
#: publishes each sample (two samples), the first at the start condition (its start_delay).
OPERATOR_RATE = 50.0
OPERATOR_LEAD = 0.04


def _check_recorded_from_the_start(
    first: TwistStamped, args: argparse.Namespace, method: str
) -> None:
    """Leading on simulated time, the operator sends zeros before its profile: a ``first``
    recorded twist that moves means this process's recorder matched after the profile started
    (the operator counted a subscriber that was not this one, e.g. one of a run just ended).

    Raises:
        PartialRecordingError: it did.
    """
    if lockstep(args) and args.output_lead and _moving(first):
        raise PartialRecordingError(
            f"{method}: this process recorded cmd_twist only from {header_seconds(first):.3f} "
            "s, after the operator's profile started"
        )


def _moving(twist: TwistStamped | None) -> bool:
    if twist is None:
        return False
    w = twist.twist.angular
    return (w.x, w.y, w.z) != (0.0, 0.0, 0.0)


def _check_complete(data: dict[str, np.ndarray], method: str, sim_time: bool) -> None:
    """Figures only from a complete recording: this process missed no robot state in the task
    (nor, on simulated time, where the operator's stamps are on a fixed grid, any twist).

    Raises:
        PartialRecordingError: samples are missing: the figures would come from a part of the run.
    """
    missing = [(missed_samples(data["times"]), "robot states")]
    if sim_time:
        missing.append((missed_samples(data["command_times"]), "cmd_twist samples"))
    lost = [f"{count} {what}" for count, what in missing if count]
    if lost:
        raise PartialRecordingError(
            f"{method}: this process missed {' and '.join(lost)} of the task (it waited for a "
            "core longer than DDS holds them); no figures from a partial recording"
        )


def profile_start(commands: TopicLog, scenario: Scenario, rate: float) -> float:
    """When the operator's profile started [s], on the stamps' clock: the first moving twist's
    stamp less its time in the profile, which rns_operator samples every 1/``rate`` s from its
    start. The first twist recorded is not always the start: an operator that waited for a
    core before its first motion (lockstep, ``lead``) starts its profile that much later.

    Raises:
        RnsError: no twist asked for motion, or the scenario never moves on that grid.
    """
    first = next((msg for msg in commands.messages if _moving(msg)), None)
    if first is None:
        raise RnsError("no recorded cmd_twist asks for motion")
    steps = math.floor(scenario.duration * rate) + 1
    for k in range(steps):
        if np.any(scenario.angular_velocity(k / rate) != 0.0):
            return header_seconds(first) - k / rate
    raise RnsError(f"scenario {scenario.name!r} never moves at {rate:g} Hz")


def _has_twist(status: TopicLog | None) -> bool:
    """rns_controller's newest ``status`` counts a received twist (True without a log)."""
    if status is None:
        return True
    return int(latest_status_values(status).get(TWISTS_RECEIVED, "0")) > 0


def _predicts(status: TopicLog | None) -> bool:
    """rns_predictor's newest status (``status``) says it predicts; True without a predictor."""
    if status is None:
        return True
    return bool(status.messages) and status.messages[-1].status[0].message == "PREDICTING"


def _wait_for_start(
    stack: Harness,
    processes: ProcessStack,
    streams: dict[str, TopicLog],
    listeners: list[str],
    method: str,
    timeout: float = 60.0,
    awaited: TopicLog | None = None,
    predicting: TopicLog | None = None,
) -> None:
    """Until this process records the robot state and ``listeners`` subscribe to it; with
    ``awaited`` (rns_controller's status, when it awaits the operator's twists), until the
    controller has received a twist: from then on its every tick waits for the twist in force,
    so the profile (released by this process's cmd_twist subscription, made after this) cannot
    start on ticks served without it; with ``predicting`` (rns_predictor's status), until the
    predictor has its first telemetry and predicts."""
    probe = stack.probe()
    state_streams = ("joints", "odom", "momentum")

    def missing() -> list[str]:
        """What is not up yet: unrecorded state streams, listeners not subscribed, no twist at
        the controller."""
        nodes = {info.node_name for info in probe.get_subscriptions_info_by_topic("/base_odom")}
        return [
            *(f"no {streams[name].topic} recorded" for name in state_streams if not streams[name]),
            *(f"{name} not subscribed to base_odom" for name in listeners if name not in nodes),
            *(["rns_controller has received no cmd_twist"] if not _has_twist(awaited) else []),
            *(["rns_predictor has no telemetry yet"] if not _predicts(predicting) else []),
        ]

    if not stack.spin_until(lambda: processes.exited() or not missing(), timeout=timeout):
        raise RnsError(
            f"{method}: not ready within {timeout:.0f} s: {'; '.join(missing())}"
            f"{processes.exit_report()}"
        )
    if processes.exited():  # a node failed at start-up: no use waiting for it
        raise RnsError(f"{method}: a node did not start{processes.exit_report()}")
