"""rns_demo: the thesis satellite-observation scenario over real DDS, three ways, compared.

``--scenario ptp_three_phase`` runs the point-to-point task instead (:mod:`rns_ros.demo_ptp`):
rns_ptp with the 3-phase method and the JS-C / IJ-C / TJ-C baselines, in a Table 4.2-style table.

For each method (default: reactionless ``dls``, reactionless ``sc``, ``conventional``) a fresh
launch-free stack runs on its own domain, localhost only, each node as its own process
(:class:`rns_ros.harness.ProcessStack`, as ``ros2 run`` starts them): ``rns_simulator``
starting from the scenario's joint angles, ``rns_controller`` with that method, ``rns_operator``
playing the scenario file, and ``rns_rerun_logger`` recording one ``.rrd`` per run (or a live
viewer with ``--viewer``); this process records the topics (:class:`rns_ros.harness.Harness`).
The point-to-point runs keep their nodes in this process. The recorded topics give a comparison
table (:mod:`rns_ros.analysis.recorded_run`): max base attitude deviation, camera orientation
error at the end, RMS angular-velocity tracking error, max wrist drift, max joint speed,
angular momentum drift, wall time. ``--summary PATH`` writes it as JSON.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rns_ros.analysis.recorded_run import RunFigures, run_figures
from rns_ros.cli import add_domain_id_argument, one_line, run_main, split_ros_args
from rns_ros.control.scenario import Scenario, check_speed_limit, load_scenario
from rns_ros.core import RnsError, load_model
from rns_ros.demo_contact import (
    CONTACT_METHODS,
    CONTACT_SCENARIOS,
    DEFAULT_CONTACT_METHODS,
    contact_epilogue,
    format_contact_table,
    is_contact_scenario,
    non_finite_contact_figures,
    run_contact_method,
    start_logger,
)
from rns_ros.demo_ptp import (
    PTP_METHODS,
    PTP_SCENARIOS,
    PtpScenario,
    format_ptp_table,
    non_finite_ptp_figures,
    run_ptp_method,
)
from rns_ros.harness import Harness, ProcessStack, TopicLog, header_seconds
from rns_ros.nodes.controller_parameters import SPECS as CONTROLLER_SPECS
from rns_ros.resources import default_model_config, scenario_path

#: ``conventional+wheels``: the conventional controller with rns_attitude_control holding the
#: base with reaction wheels (thesis chapter 5's comparison); the simulator gets wheels.
WHEELS_SUFFIX = "+wheels"
METHODS = ("dls", "sc", "pinv", "conventional", "conventional+wheels")
DEFAULT_METHODS = ("dls", "sc", "conventional")
ETS_VII_ALLOWED_DEVIATION_DEG = 0.05  # thesis chapter 4, footnote 1
#: Settling time after the operator's zeros before the run ends [s], on the run's clock (sim
#: time off real time): the figures cover the same stretch of the run at any speed.
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

    @property
    def real_time_factor(self) -> float | None:
        """Simulated task seconds per wall second (None when not measured)."""
        if self.task_wall_s is None or self.task_sim_s is None or self.task_wall_s <= 0.0:
            return None
        return self.task_sim_s / self.task_wall_s


@dataclass(frozen=True)
class EnergyFigures:
    """Energy of one run from rns_simulator's ``energy`` topic (thesis chapter 5).

    Attributes:
        c_max: C_max of eq. (5.12): peak of 1/2 theta_dot^T Lambda theta_dot [J] (the arm's
            motion costed as if wheels cancelled its reaction: zero for the Lambda_r part of a
            reactionless motion).
        c_sum: C_sum of eq. (5.13) [J s].
        peak_wheel_energy: largest kinetic energy of the wheels' spin in the run [J] (0 without
            wheels).
        wheel_saturation_s: time with a wheel at its torque limit per rns_attitude_control [s]
            (None without it).
    """

    c_max: float
    c_sum: float
    peak_wheel_energy: float
    wheel_saturation_s: float | None


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


def non_finite_figures(rows: list[DemoRow]) -> list[str]:
    """One text per run with a NaN or infinite figure ("dls: camera err = nan, ..."); empty
    when every figure is finite."""
    problems = []
    for row in rows:
        values = {**asdict(row.figures), "wall_time_s": row.wall_time_s}
        if row.energy is not None:
            values |= {k: v for k, v in asdict(row.energy).items() if v is not None}
        bad = [f"{name} = {value}" for name, value in values.items() if not np.isfinite(value)]
        if bad:
            problems.append(f"{row.method}: " + ", ".join(bad))
    return problems


def run_method(
    method: str,
    args: argparse.Namespace,
    scenario_file: Path,
) -> DemoRow:
    """One full DDS run of the scenario with ``method``; returns its figures.

    The nodes run as their own processes (:class:`~rns_ros.harness.ProcessStack`: the installed
    ``rns_simulator``, ``rns_controller``, ``rns_operator``, ``rns_rerun_logger`` and, with
    wheels, ``rns_attitude_control``, each on its own executor, as ``ros2 run`` starts them);
    this process only records the topics. In one process the simulation thread and every
    node shared one GIL: outputs came 15-40 ms apart instead of 10 (timer ticks waiting for
    the lock) and reached the simulator 0.4-8 ms after they were published, which turned the
    base by 0.6-1.9e-4 deg (dls) where separate processes give 2.6-2.8e-5 deg.

    Raises:
        RnsError: a node did not start, or the run did not finish in time.
    """
    scenario = load_scenario(scenario_file)
    robot = load_model(default_model_config())
    sim_time = args.real_time_factor != 1.0
    timing = {"use_sim_time": True} if sim_time else {}
    wheels = method.endswith(WHEELS_SUFFIX)
    law = method.removesuffix(WHEELS_SUFFIX)
    controller_parameters = {"method": law, "rate": args.rate, **timing}
    if sim_time:
        # lockstep pauses wait for the controller: a state can come later than the 0.1 s
        # wall-time default while the 2 cores are busy
        controller_parameters["state_timeout"] = 1.0
        if args.output_lead:
            # each output acts one period after its tick: the simulator computes that period
            # while the controller computes the next output (two cores side by side)
            controller_parameters["output_lead"] = 1.0 / args.rate
            # and serves each tick with the operator's sample in force then, published ahead
            # (OPERATOR_LEAD): a run's figures do not depend on when the operator got a core
            controller_parameters["await_commands"] = True
    operator_timing = dict(timing)
    if sim_time and args.output_lead:
        operator_timing.update(lead=OPERATOR_LEAD, start_delay=OPERATOR_LEAD)
    controller_parameters.update(
        {key: value for key, value in scenario.controller.items() if key != "method"}
    )
    ros_args = list(args.ros_args[1:]) if args.ros_args else []
    start = time.perf_counter()
    with (
        ProcessStack(args.domain_id) as processes,
        Harness(args.domain_id, args.ros_args, executor="events") as stack,
    ):
        # serialized, read after the run: this process then costs the stack little CPU
        streams = {
            "joints": stack.record(JointState, "joint_states", raw=True),
            "odom": stack.record(Odometry, "base_odom", raw=True),
            "momentum": stack.record(WrenchStamped, "momentum", raw=True),
            "energy": stack.record(Float64MultiArray, "energy", raw=True),
            "attitude": stack.record(DiagnosticArray, "rns_attitude_control/status", raw=True),
        }
        recording, logger = start_logger(
            processes, method, args, sim_time=sim_time, ros_args=ros_args
        )
        processes.start("rns_controller", controller_parameters, ros_args=ros_args)
        # the operator imports while the others do (started after the robot ran, its start-up
        # competed for the cores with a lockstep run stepping the idle robot as fast as it can:
        # ~2 s of each run's wall time); its profile still waits for this process's cmd_twist
        # subscription, made below once the robot state is recorded
        listeners = [NODE_NAMES["controller"]]
        if logger is not None:
            listeners.append(NODE_NAMES["logger"])
        processes.start(
            "rns_operator",
            {
                "scenario": str(scenario_file),
                "rate": OPERATOR_RATE,
                "start_delay": 0.5,
                "zero_duration": OPERATOR_ZERO_DURATION,
                # the controller, this process and the logger: the first to be matched no
                # longer starts the profile while the controller still misses it
                "min_subscribers": len(listeners) + 1,
                **operator_timing,
            },
            ros_args=ros_args,
        )
        if wheels:
            processes.start(
                "rns_attitude_control", {"rate": args.rate, **timing}, ros_args=ros_args
            )
        processes.start(
            "rns_simulator",
            {
                "initial_joint_positions": scenario.initial_theta.tolist(),
                "mode": args.mode,
                "step_size": simulation_step(args, wheels),
                "real_time_factor": args.real_time_factor,
                "publish_clock": sim_time,
                # off real time, the simulator waits for each control period's output, so the
                # figures do not depend on how fast this machine is
                "lockstep_period": 1.0 / args.rate if sim_time else 0.0,
                "reaction_wheels": wheels,
            },
            ros_args=ros_args,
        )
        # the task only once the robot runs and this process and the logger record it (a
        # recorder matched late would miss the start of the task): the operator counts this
        # subscription among its min_subscribers
        _wait_for_start(stack, processes, streams, listeners, method)
        commands = streams["commands"] = stack.record(TwistStamped, "cmd_twist", raw=True)
        budget = 60.0 + (scenario.duration + 2.0) / max(args.real_time_factor, 1.0)
        if not stack.spin_until(lambda: _moving(commands.latest()), timeout=budget):
            raise RnsError(f"{method}: no moving cmd_twist from rns_operator within {budget:.0f} s")
        # the end on the stamps' clock: off real time a lockstep run goes on at its own pace,
        # so a wall-time settle would let figures depend on this machine's speed
        task = profile_start(commands, scenario, OPERATOR_RATE)
        task_started = time.perf_counter()
        end = task + scenario.duration + OPERATOR_ZERO_DURATION + SETTLE
        states = [streams[name] for name in ("joints", "odom", "momentum")]
        if not stack.spin_until(
            lambda: all(len(log) and log.latest_stamp() >= end for log in states),
            timeout=budget,
            check_every=0.005,  # not after each of the ~4 messages a period brings
        ):
            raise RnsError(
                f"{method}: the scenario did not finish within {budget:.0f} s"
                f"{processes.exit_report()}"
            )
        task_wall = time.perf_counter() - task_started
        # stopped before the recorded messages are read: off real time the stack would go on
        # stepping as fast as it can meanwhile, competing with this process for the cores
        processes.stop()  # the logger writes its summary line as it closes the recording
        # from just before the task: the robot is at rest until the first command, and a
        # recorder (the logger) matched a moment after the first state then has all of it
        data = robot_arrays(streams, until=end, since=task - TASK_MARGIN)
        if data["times"][0] > task:  # the deviations count from the first recorded state
            raise RnsError(
                f"{method}: the robot state was recorded from {data['times'][0]:.3f} s, after "
                f"the operator's profile started at {task:.3f} s"
            )
        energy = energy_figures(
            streams["energy"], streams["attitude"] if wheels else None, until=end
        )
        for line in processes.problems():  # a watchdog that stopped the arm, a rejection
            print(f"  {line}", flush=True)
        if logger is not None:
            closed = [line for line in processes.output(logger).splitlines() if CLOSED in line]
            print("\n".join(closed[-1:]), flush=True)
    figures = run_figures(robot, scenario, **data)
    return DemoRow(
        method,
        figures,
        time.perf_counter() - start,
        recording,
        energy,
        task_wall_s=task_wall,
        task_sim_s=end - task,
    )


#: rns_simulator's default RK4 step [s] and the range --sim-step accepts (its step_size's).
SIM_STEP = 1e-3
MIN_SIM_STEP, MAX_SIM_STEP = 1e-5, 0.1


def simulation_step(args: argparse.Namespace, wheels: bool) -> float:
    """rns_simulator's step [s] for an inspection run: ``--sim-step`` when given; off real time
    in kinematic mode without wheels one control period, since the joint rate is held over the
    period and only the base is integrated (one 10 ms RK4 step gives the 1 ms figures to nine
    digits, dls and conventional: ``test_closed_loop``); else ``SIM_STEP``. Wheels keep 1 ms:
    their torque changes within a period with the attitude loop's."""
    if args.sim_step is not None:
        return args.sim_step
    lockstep = args.real_time_factor != 1.0 and args.mode == "kinematic" and not wheels
    if not lockstep:
        return SIM_STEP
    period = 1.0 / args.rate
    return period / math.ceil(period / MAX_SIM_STEP - 1e-9)


#: What rns_rerun_logger's summary line on closing its recording contains.
CLOSED = "recording closed"
#: Robot states before the first command that the figures include [s].
TASK_MARGIN = 0.2
#: Zero twists the operator sends after the profile [s] (its default).
OPERATOR_ZERO_DURATION = 1.0
#: The operator's rate [Hz] (its default) and, in lockstep side by side, how far ahead [s] it
#: publishes each sample (two samples), the first at the start condition (its start_delay).
OPERATOR_RATE = 50.0
OPERATOR_LEAD = 0.04


def _moving(twist: TwistStamped | None) -> bool:
    if twist is None:
        return False
    w = twist.twist.angular
    return (w.x, w.y, w.z) != (0.0, 0.0, 0.0)


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


#: Node names of the processes whose subscriptions the demo waits for.
NODE_NAMES = {"controller": "rns_controller", "logger": "rns_rerun_logger"}


def _wait_for_start(
    stack: Harness,
    processes: ProcessStack,
    streams: dict[str, TopicLog],
    listeners: list[str],
    method: str,
    timeout: float = 60.0,
) -> None:
    """Until this process records the robot state and ``listeners`` subscribe to it."""
    probe = stack.probe()

    def ready() -> bool:
        if not all(len(streams[name]) for name in ("joints", "odom", "momentum")):
            return False
        nodes = {info.node_name for info in probe.get_subscriptions_info_by_topic("/base_odom")}
        return all(name in nodes for name in listeners)

    if not stack.spin_until(ready, timeout=timeout):
        raise RnsError(
            f"{method}: the robot state or its listeners ({', '.join(listeners)}) did not come "
            f"up within {timeout:.0f} s{processes.exit_report()}"
        )


def energy_figures(
    energy: TopicLog, attitude: TopicLog | None, until: float = np.inf
) -> EnergyFigures | None:
    """C_max, C_sum, peak wheel energy from the ``energy`` topic (labels from its layout; samples
    up to simulated time ``until`` [s]), and the saturation time from the newest
    rns_attitude_control status; None without samples."""
    if not len(energy):
        return None
    labels = energy.latest().layout.dim[0].label.split()
    rows = [dict(zip(labels, msg.data, strict=True)) for msg in energy.messages]
    rows = [row for row in rows if row.get("time", -np.inf) <= until]
    if not rows:
        return None
    saturation = None
    if attitude is not None and len(attitude):
        values = {kv.key: kv.value for kv in attitude.latest().status[0].values}
        saturation = float(values.get("saturated_time_s", "nan"))
    return EnergyFigures(
        c_max=rows[-1]["c_max"],
        c_sum=rows[-1]["c_sum"],
        peak_wheel_energy=max(row["wheels"] for row in rows),
        wheel_saturation_s=saturation,
    )


def _add_logger(stack: Harness, method: str, args, timing: dict) -> str | None:
    from rns_ros.nodes.rerun_logger import RerunLoggerNode

    args.output.mkdir(parents=True, exist_ok=True)
    path = args.output / f"{method}.rrd"
    sink = "spawn" if args.viewer else "save"
    stack.add(
        RerunLoggerNode,
        {"sink": sink, "rrd_path": str(path), "recording_name": method, **timing},
    )
    return str(path) if sink == "save" else None


def robot_arrays(
    streams: dict[str, TopicLog], until: float = np.inf, since: float = -np.inf
) -> dict[str, np.ndarray]:
    """Robot samples where joint_states and base_odom share a stamp (the simulator publishes
    both per step), plus momentum and commands; only messages stamped in [``since``,
    ``until``] [s]."""
    streams = {name: _within(log, since, until) for name, log in streams.items()}
    joints, odom = streams["joints"], streams["odom"]
    poses = {}
    for msg in odom.messages:
        stamp = (msg.header.stamp.sec, msg.header.stamp.nanosec)
        p, o = msg.pose.pose.position, msg.pose.pose.orientation
        w = msg.twist.twist.angular
        poses[stamp] = ([p.x, p.y, p.z], [o.x, o.y, o.z, o.w], [w.x, w.y, w.z])
    rows = [
        (msg, poses[key])
        for msg in joints.messages
        if (key := (msg.header.stamp.sec, msg.header.stamp.nanosec)) in poses
    ]
    if len(rows) < 2:
        raise RnsError("fewer than two robot states were recorded; is DDS working on loopback?")
    commands = streams["commands"]
    return {
        "times": np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m, _ in rows]),
        "joint_positions": np.array([m.position for m, _ in rows]),
        "joint_velocities": np.array([m.velocity for m, _ in rows]),
        "base_positions": np.array([pose[0] for _, pose in rows]),
        "base_orientations": np.array([pose[1] for _, pose in rows]),
        "base_angular_velocities": np.array([pose[2] for _, pose in rows]),
        "angular_momentum": streams["momentum"].array(
            lambda m: [m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z]
        ),
        "command_times": commands.stamps() if len(commands) else np.zeros(0),
        "commands": commands.array(
            lambda m: [m.twist.angular.x, m.twist.angular.y, m.twist.angular.z]
        ).reshape(-1, 3),
    }


def _within(log: TopicLog, since: float, until: float) -> TopicLog:
    """``log`` without the messages stamped after ``until`` or before ``since`` [s] (messages
    without a header are kept)."""
    unbounded = until == np.inf and since == -np.inf
    if unbounded or not log.messages or not hasattr(log.messages[0], "header"):
        return log
    kept = TopicLog(log.topic)
    for msg, received in zip(log.messages, log.received, strict=True):
        if since <= header_seconds(msg) <= until:
            kept.messages.append(msg)
            kept.received.append(received)
    return kept


def format_table(rows: list[DemoRow]) -> str:
    columns = (
        ("method", max(14, 2 + max((len(row.method) for row in rows), default=0))),
        ("max base dev [deg]", 20),
        ("camera err [deg]", 18),
        ("RMS ω err [rad/s]", 19),
        ("wrist drift [m]", 17),
        ("max |θ̇| [rad/s]", 17),
        ("Δl [kg m²/s]", 14),
        ("C_max [J]", 11),
        ("C_sum [J s]", 13),
        ("wheel KE [J]", 14),
        ("wheel sat [s]", 15),
        ("wall [s]", 10),
        ("task [s]", 10),
        ("× real time", 13),
    )
    header = "".join(
        f"{title:<{width}}" if i == 0 else f"{title:>{width}}"
        for i, (title, width) in enumerate(columns)
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        f = row.figures
        lines.append(
            f"{row.method:<{columns[0][1]}}{f.max_base_deviation_deg:>20.3e}{f.final_camera_error_deg:>18.4g}"
            f"{f.rms_tracking_error:>19.3e}{f.max_wrist_drift_m:>17.3f}{f.max_joint_speed:>17.3f}"
            f"{f.angular_momentum_drift:>14.2e}{_energy_columns(row.energy)}"
            f"{row.wall_time_s:>10.1f}{_task_columns(row)}"
        )
    return "\n".join(lines)


def _task_columns(row: DemoRow) -> str:
    """Wall time of the task [s] and its real-time factor, or dashes."""
    factor = row.real_time_factor
    if factor is None:
        return f"{'-':>10}{'-':>13}"
    return f"{row.task_wall_s:>10.2f}{factor:>13.2f}"


def _energy_columns(energy: EnergyFigures | None) -> str:
    if energy is None:
        return f"{'-':>11}{'-':>13}{'-':>14}{'-':>15}"
    saturation = "-" if energy.wheel_saturation_s is None else f"{energy.wheel_saturation_s:.2f}"
    return (
        f"{energy.c_max:>11.3g}{energy.c_sum:>13.3g}{energy.peak_wheel_energy:>14.3g}"
        f"{saturation:>15}"
    )


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    argv, ros_args = split_ros_args(sys.argv[1:] if argv is None else list(argv))
    parser = argparse.ArgumentParser(
        prog="rns_demo",
        usage="%(prog)s [options] [--ros-args -p NAME:=VALUE --params-file FILE -r FROM:=TO]",
        epilog="--ros-args apply to every node of every run (e.g. -p wrist_gain:=10.0, "
        "-r joint_states:=arm/joint_states); the demo's own settings (method, rate, scenario "
        "angles) win where they overlap.",
        description="Thesis satellite-observation scenario over DDS (simulator + controller + "
        "scripted operator + rerun recording): reactionless DLS and SC vs the conventional "
        "baseline, compared in one table.",
    )
    parser.add_argument(
        "--scenario",
        default="satellite_observation",
        help="inspection scenario name or YAML file, a point-to-point scenario "
        f"({', '.join(PTP_SCENARIOS)}: rns_ptp instead of rns_controller), or a motion/force "
        f"scenario ({', '.join(CONTACT_SCENARIOS)}: contact simulator + rns_force_controller)",
    )
    parser.add_argument(
        "--methods",
        default=None,
        help=f"comma-separated; inspection: from {list(METHODS)} (default "
        f"{','.join(DEFAULT_METHODS)}); point-to-point: from {list(PTP_METHODS)} (default all); "
        f"motion/force: from {list(CONTACT_METHODS)} (default "
        f"{','.join(DEFAULT_CONTACT_METHODS)})",
    )
    parser.add_argument("--mode", choices=("kinematic", "dynamic"), default="kinematic")
    parser.add_argument("--rate", type=float, default=100.0, help="controller rate [Hz]")
    parser.add_argument(
        "--real-time-factor",
        type=float,
        default=1.0,
        help="simulated s per wall s; other than 1 runs on sim time (/clock); 0 = as fast as "
        "possible",
    )
    parser.add_argument(
        "--output-lead",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="off real time: the controller stamps each output one period after its tick, so "
        "simulator and controller compute side by side on two cores (default; about 1.6x "
        "faster than in turn; a twist acts one period later); --no-output-lead: in turn",
    )
    parser.add_argument(
        "--sim-step",
        type=float,
        default=None,
        help="inspection: rns_simulator's RK4 step [s], a divisor of the control period in "
        f"[{MIN_SIM_STEP:g}, {MAX_SIM_STEP:g}]; default 1 ms, but one control period off real "
        "time in kinematic mode without wheels (the joint rate is held over the period, so one "
        "RK4 step gives the same figures, ten times cheaper)",
    )
    parser.add_argument(
        "--output", type=Path, default=Path("rns_demo_recordings"), help="folder for .rrd files"
    )
    parser.add_argument("--no-record", action="store_true", help="no rerun recording")
    parser.add_argument("--viewer", action="store_true", help="live rerun viewer (needs display)")
    parser.add_argument("--summary", type=Path, default=None, help="also write the table as JSON")
    parser.add_argument(
        "--runs",
        type=int,
        default=1,
        help="inspection scenarios: run every method this many times and add the min / median "
        "/ max of the base deviation (in --summary too); [1, 100]",
    )
    add_domain_id_argument(parser, 42, "of the runs")
    args = parser.parse_args(argv)
    args.ros_args = ros_args
    if args.scenario in PTP_SCENARIOS:
        allowed, default = list(PTP_METHODS), list(PTP_METHODS)
    elif is_contact_scenario(args.scenario):
        allowed, default = list(CONTACT_METHODS), list(DEFAULT_CONTACT_METHODS)
    else:
        allowed, default = METHODS, DEFAULT_METHODS
    text = ",".join(default) if args.methods is None else args.methods
    args.methods = [m.strip() for m in text.split(",") if m.strip()]
    unknown = [m for m in args.methods if m not in allowed]
    if unknown or not args.methods:
        parser.error(f"--methods for {args.scenario} must be a comma-separated subset of {allowed}")
    if not 1.0 <= args.rate <= 1000.0:
        parser.error(f"--rate must be in [1, 1000] Hz, got {args.rate}")
    if not 0.0 <= args.real_time_factor <= 1000.0:
        parser.error(f"--real-time-factor must be in [0, 1000], got {args.real_time_factor}")
    if not 1 <= args.runs <= 100:
        parser.error(f"--runs must be in [1, 100], got {args.runs}")
    if args.sim_step is not None:
        substeps = 1.0 / (args.rate * args.sim_step)
        if (
            not MIN_SIM_STEP <= args.sim_step <= MAX_SIM_STEP
            or abs(substeps - round(substeps)) > 1e-6
        ):
            parser.error(
                f"--sim-step must divide the control period 1/rate = {1.0 / args.rate:g} s and lie "
                f"in [{MIN_SIM_STEP:g}, {MAX_SIM_STEP:g}] s, got {args.sim_step:g}"
            )
    if args.runs > 1 and (args.scenario in PTP_SCENARIOS or is_contact_scenario(args.scenario)):
        parser.error("--runs is for the inspection scenarios")
    return args


def main(argv: list[str] | None = None) -> int:
    """Exit code 2 with one line on stderr for bad options or configuration; 0 after Ctrl-C."""
    return run_main("rns_demo", lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    args = parse_args(argv)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    if args.scenario in PTP_SCENARIOS:
        return _main_ptp(args, PTP_SCENARIOS[args.scenario])
    if is_contact_scenario(args.scenario):
        return _main_contact(args)
    try:
        scenario_file = scenario_path(args.scenario)
        (scenario,) = check_scenarios([scenario_file])
        print(f"scenario: {scenario_file} ({scenario.description})")
        print(
            f"model: {default_model_config()}; {args.mode} simulation, controller at "
            f"{args.rate:g} Hz, real-time factor {args.real_time_factor:g}, "
            f"ROS domain {args.domain_id} (localhost only)\n",
            flush=True,
        )
        runs: list[list[DemoRow]] = []
        for run in range(args.runs):
            rows = []
            for method in args.methods:
                label = f" (run {run + 1} of {args.runs})" if args.runs > 1 else ""
                print(f"running {method}{label} ...", flush=True)
                rows.append(run_method(method, args, scenario_file))
            runs.append(rows)
    except RnsError as exc:
        print(f"rns_demo: {one_line(exc)}", file=sys.stderr)
        return 2
    summary = [
        {"method": row.method, **asdict(row.figures), "wall_time_s": row.wall_time_s}
        | {"task_wall_s": row.task_wall_s, "task_sim_s": row.task_sim_s}
        | {"recording": row.recording}
        | {"energy": None if row.energy is None else asdict(row.energy)}
        | (
            {
                "runs": spread(runs, row.method)._asdict(),
                "task_wall_runs": spread(runs, row.method, _task_wall)._asdict(),
            }
            if args.runs > 1
            else {}
        )
        for row in runs[-1]
    ]
    table = format_table(runs[-1])
    if args.runs > 1:
        table += "\n\n" + format_spread(runs)
    return _report(
        args,
        runs[-1],
        table,
        [problem for rows in runs for problem in non_finite_figures(rows)],
        f"ETS-VII allowed base attitude deviation: ±{ETS_VII_ALLOWED_DEVIATION_DEG} deg.",
        summary,
    )


class Spread(NamedTuple):
    """One figure of one method over the runs: min, median, max, and each run."""

    min: float
    median: float
    max: float
    values: list[float]


def _base_deviation(row: DemoRow) -> float:
    return row.figures.max_base_deviation_deg


def spread(
    runs: list[list[DemoRow]],
    method: str,
    figure: Callable[[DemoRow], float | None] = _base_deviation,
) -> Spread:
    """:class:`Spread` of ``figure(row)`` (default: the max base deviation [deg]) of
    ``method``'s rows over ``runs`` (rows per run); runs without the figure are left out."""
    values = [
        value
        for rows in runs
        for row in rows
        if row.method == method and (value := figure(row)) is not None
    ]
    if not values:
        return Spread(np.nan, np.nan, np.nan, [])
    return Spread(min(values), float(np.median(values)), max(values), values)


def _task_wall(row: DemoRow) -> float | None:
    return row.task_wall_s


def format_spread(runs: list[list[DemoRow]]) -> str:
    """The max base deviation and the task's wall time of each method over the runs (the table
    above is the last run)."""
    lines = [
        f"over {len(runs)} runs (the table: the last run)",
        f"{'method':<22}{'max base dev [deg]: min':>26}{'median':>12}{'max':>12}"
        f"{'task [s]: min':>16}{'median':>10}{'max':>10}",
    ]
    for row in runs[-1]:
        base, task = spread(runs, row.method), spread(runs, row.method, _task_wall)
        lines.append(
            f"{row.method:<22}{base.min:>26.3e}{base.median:>12.3e}{base.max:>12.3e}"
            f"{task.min:>16.2f}{task.median:>10.2f}{task.max:>10.2f}"
        )
    return "\n".join(lines)


def _report(args, rows, table: str, problems: list[str], epilogue: str, summary: list) -> int:
    """The end of every demo: the table; exit 1 on non-finite figures (a run that produced NaN
    / inf failed, whatever the table shows); else the epilogue, the recordings and the JSON
    ``summary`` to ``--summary``."""
    print()
    print(table)
    if problems:
        print(f"rns_demo: non-finite figures: {'; '.join(problems)}", file=sys.stderr)
        return 1
    print(f"\n{epilogue}")
    recordings = [row.recording for row in rows if row.recording]
    if recordings:
        print("rerun recordings (open with `rerun <file>`): " + ", ".join(recordings))
    if args.summary:
        args.summary.write_text(json.dumps(summary, indent=2) + "\n")
        print(f"summary written to {args.summary}")
    return 0


def _main_ptp(args: argparse.Namespace, scenario: PtpScenario) -> int:
    print(f"scenario: {scenario.name} ({scenario.description})")
    print(
        f"model: {default_model_config()}; {args.mode} simulation, rns_ptp at {args.rate:g} Hz, "
        f"real-time factor {args.real_time_factor:g}, ROS domain {args.domain_id} "
        "(localhost only)\n",
        flush=True,
    )
    rows = []
    try:
        for method in args.methods:
            print(f"running {method} ...", flush=True)
            rows.append(
                run_ptp_method(
                    method,
                    scenario,
                    args,
                    lambda stack, name, timing: _add_logger(stack, name, args, timing),
                )
            )
    except RnsError as exc:
        print(f"rns_demo: {one_line(exc)}", file=sys.stderr)
        return 2
    return _report(
        args,
        rows,
        format_ptp_table(rows),
        non_finite_ptp_figures(rows),
        "ratio: max base deviation / that of the 3-phase method. The thesis' arm geometry is "
        "not printed (ours is identified, docs/arm_identification.md): compare the ranking.",
        [asdict(row) for row in rows],
    )


def _main_contact(args: argparse.Namespace) -> int:
    print(f"scenario: {scenario_path(args.scenario)} (thesis Part II, chapter 6)")
    print(
        "contact simulation at 1 kHz in lockstep with "
        f"rns_force_controller, real-time factor {args.real_time_factor:g}, ROS domain "
        f"{args.domain_id} (localhost only)\n",
        flush=True,
    )
    rows = []
    try:
        for method in args.methods:
            print(f"running {method} ...", flush=True)
            rows.append(run_contact_method(method, args.scenario, args))
    except RnsError as exc:
        print(f"rns_demo: {one_line(exc)}", file=sys.stderr)
        return 2
    return _report(
        args,
        rows,
        format_contact_table(rows),
        non_finite_contact_figures(rows),
        contact_epilogue(args.scenario),
        [
            {
                "method": row.method,
                "label": row.label,
                **asdict(row.figures),
                "core_peak_joint_speed": row.core_peak_joint_speed,
                "loop_rate_hz": row.loop_rate_hz,
                "step_time_median_us": row.step_time_median_us,
                "step_time_p99_us": row.step_time_p99_us,
                "final_state": row.final_state,
                "wall_time_s": row.wall_time_s,
                "recording": row.recording,
            }
            for row in rows
        ],
    )


if __name__ == "__main__":
    sys.exit(main())
