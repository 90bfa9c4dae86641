"""One run of a motion/force scenario over DDS (``rns_demo --scenario wall_contact``): RNS-C, OS-C.

Section 6.2.2 (Figs. 6.7-6.8; docs/part2.md, "Chapter 6 runs"): the LWR4-class arm pushes 10 N
into a wall through its start flange point and strokes back and forth along it. For each
controller a fresh in-process stack (:class:`rns_ros.harness.Harness`, its own domain, localhost
only) runs ``rns_simulator`` in contact mode (wall through the start flange, normal along the
flange z axis), ``rns_force_controller`` with that method, ``rns_operator`` playing
``config/scenarios/wall_contact.yaml`` (twist and force setpoint) and ``rns_rerun_logger`` (one
``.rrd`` per run). The simulator runs in lockstep with the controller (``lockstep_period`` = the
1 ms step): every torque is computed from the state it acts on, as in the in-process loop of
``rns_reproduce``, at whatever speed the machine allows. The operator is in the lockstep too: it
publishes each sample ahead of simulated time (``lead``), stamped with its instant, and the
controller's step of each state waits for the twist and force setpoint in force at its stamp
(``await_commands``), so the figures do not depend on when the operator's process got a core.

The table gives, from the topics recorded up to the end of the task (the operator's first force
setpoint, which marks the profile's start, plus the scenario's duration and twice ``SETTLE``;
:mod:`rns_ros.analysis.recorded_contact`), the largest in-plane position error, the largest force
error (whole run, and once the 10 N are reached), the peak joint speed next to the in-process run
of the same task (``run_closed_loop``), the residual joint speed at the end, the torque-loop rate
reached (control steps per wall second) and the controller's step time (median / p99).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped, WrenchStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rns_ros.analysis.motion_force_runs import run_closed_loop
from rns_ros.analysis.recorded_contact import ContactRunFigures, contact_run_figures
from rns_ros.control.contact_scenarios import (
    ScenarioKind,
    Task,
    load_motion_force_scenario,
    scenario_kind,
)
from rns_ros.core import ConfigError, RnsError
from rns_ros.core.contact_geometry import ArcConstraint
from rns_ros.harness import Harness, ProcessStack, TopicLog
from rns_ros.resources import config_dir, scenario_path
from rns_ros.runs.logger import rrd_lost, start_logger
from rns_ros.runs.mcap_recording import open_mcap, record_robot_model
from rns_ros.runs.recorded import latest_status_values

#: rns_demo method -> (rns_force_controller method, os_variant, label of rns_reproduce).
CONTACT_METHODS = {
    "rns": ("rns", "literal", "RNS-C"),
    "os": ("os", "literal", "OS-C"),
    "os_kinematic": ("os", "kinematic", "OS-C-kinematic"),
}
DEFAULT_CONTACT_METHODS = ("rns", "os")
#: Shipped motion/force scenarios (any ``kind: motion_force`` file works too).
CONTACT_SCENARIOS = ("wall_contact", "planar_arc")
#: Per task: the params files of rns_simulator (contact mode) and rns_force_controller.
TASK_PARAMS = {
    Task.WALL: ("contact_simulator.yaml", "force_controller.yaml"),
    Task.ARC: ("contact_arc.yaml", "force_controller_arc.yaml"),
}
#: Simulator step = control period [s], operator rate [Hz].
CONTACT_STEP = 1e-3
OPERATOR_RATE = 500.0
#: How far ahead of its instant [s] the operator publishes each sample (two samples, as the
#: inspection demo's operator), and the simulated time [s] from its start condition to the
#: profile: zero twists the controller awaits meanwhile, so the profile starts in the lockstep.
OPERATOR_LEAD = 2.0 / OPERATOR_RATE
OPERATOR_START_DELAY = 0.5
#: Subscribers of cmd_twist and force_setpoint the operator waits for: the controller and this
#: process (the logger's cmd_twist subscription is not waited for).
OPERATOR_SUBSCRIBERS = 2
#: Simulated time after the operator finished, before the run ends [s].
SETTLE = 0.3
ERRORS_TOPIC = "rns_force_controller/errors"
#: rns_force_controller states that end a demo run as failed (safety stops, lost state, ...).
FAILED_STATES = (
    "unknown",
    "WAITING_FOR_STATE",
    "INVALID_COMMAND",
    "WRENCH_LIMIT",
    "CONTACT_LOST",
    "NO_CONTACT",
    "STALE_STATE",
    "NON_FINITE",
    "CONTROL_ERROR",
)
STATUS_TOPIC = "rns_force_controller/status"


@dataclass(frozen=True)
class ContactDemoRow:
    """One DDS run of a motion/force controller.

    Attributes:
        method: rns_demo method (``rns``, ``os``, ``os_kinematic``); label: RNS-C, OS-C, ...
        figures: what the recorded topics show (:class:`ContactRunFigures`).
        core_peak_joint_speed: peak |theta_dot| of the in-process run of the same task and
            controller (``run_closed_loop``) [rad/s].
        loop_rate_hz: control steps per wall-clock second over the run [Hz].
        step_time_median_us, step_time_p99_us: the controller's own step time [us], from its
            newest status.
        final_state: the controller's state at the end (OK unless a safety stop happened).
        wall_time_s: wall time of the run [s]; recording: the .rrd written, or None.
    """

    method: str
    label: str
    figures: ContactRunFigures
    core_peak_joint_speed: float
    loop_rate_hz: float
    step_time_median_us: float
    step_time_p99_us: float
    final_state: str
    wall_time_s: float
    recording: str | None
    mcap: str | None = None
    #: a recording of the run that could not be written (the file removed): why, one line each
    unwritten: tuple[str, ...] = ()

    def checked_figures(self) -> dict[str, float]:
        """Every figure that must be finite, by name: the recorded run's and the loop's."""
        return {
            **{name: getattr(self.figures, name) for name in self.figures.__dataclass_fields__},
            "core_peak_joint_speed": self.core_peak_joint_speed,
            "loop_rate_hz": self.loop_rate_hz,
        }


def _error_columns(log: TopicLog) -> dict[str, np.ndarray]:
    if len(log) < 2:
        raise RnsError("fewer than two force-controller samples were recorded; is DDS working?")
    labels = log.latest().layout.dim[0].label.split()
    data = np.array([msg.data for msg in log.messages if len(msg.data) == len(labels)])
    return {label: data[:, i] for i, label in enumerate(labels)}


def is_contact_scenario(name_or_path: str) -> bool:
    """True when ``name_or_path`` names a ``kind: motion_force`` scenario file."""
    try:
        return scenario_kind(scenario_path(name_or_path)) is ScenarioKind.MOTION_FORCE
    except ConfigError:
        return False


def _environment(constraint) -> dict:
    """rns_simulator environment parameters of the scenario's surface (world axes)."""
    if isinstance(constraint, ArcConstraint):
        return {
            "environment": "arc",
            "arc_center": constraint.center.tolist(),
            "arc_radius": float(constraint.radius),
            "arc_axis": constraint.axis.tolist(),
        }
    return {
        "environment": "wall",
        "wall_point": constraint.point.tolist(),
        "wall_normal": constraint.normal.tolist(),
    }


def run_contact_method(method: str, scenario_name: str, args: argparse.Namespace):
    """One DDS run of the motion/force scenario ``scenario_name`` with ``method``.

    The nodes run as their own processes (:class:`~rns_ros.harness.ProcessStack`: the installed
    ``rns_simulator``, ``rns_force_controller``, ``rns_operator`` and ``rns_rerun_logger``, each
    on its own executor, as ``ros2 run`` starts them); this process only records the topics.
    Sharing one process (one GIL) halves the 1 kHz torque loop's rate.

    Raises:
        RnsError: bad scenario, the controller stopped the task, or the run did not finish.
    """
    label = CONTACT_METHODS[method][2]
    path = scenario_path(scenario_name)
    scenario = load_motion_force_scenario(path)
    core = run_closed_loop(scenario.setup, label, dt=CONTACT_STEP)
    model_config = str(config_dir() / scenario.spec.model)
    timing = {"use_sim_time": True}
    ros_args = list(args.ros_args[1:]) if args.ros_args else []
    start = time.perf_counter()
    with (
        ProcessStack(args.domain_id) as processes,
        Harness(args.domain_id, args.ros_args) as stack,
        open_mcap(args, f"{scenario.name}_{method}", stack) as mcap_file,
    ):
        stack.on_record.append(mcap_file.add)  # each recorded topic, written as it arrives
        record_robot_model(stack, mcap_file)  # what a viewer draws the arm from
        joints = stack.record(JointState, "joint_states")
        errors = stack.record(Float64MultiArray, ERRORS_TOPIC)
        status = stack.record(DiagnosticArray, STATUS_TOPIC)
        setpoints = stack.record(WrenchStamped, "force_setpoint")
        # the operator starts once the controller and this process subscribe to both of its
        # topics (OPERATOR_SUBSCRIBERS): its first force setpoint is the task's start
        stack.record(TwistStamped, "cmd_twist", raw=True)
        recording, _ = start_logger(
            processes, f"{scenario.name}_{method}", args, model_config, ros_args=ros_args
        )
        _start_plant(processes, method, scenario, model_config, args, ros_args)
        budget = 60.0 + 20.0 * scenario.duration
        # the operator only once this process records the running loop: a recorder matched
        # seconds late (discovery on a busy machine) would miss the start of the task
        if not stack.spin_until(lambda: len(errors) > 0 and len(joints) > 0, timeout=budget):
            raise RnsError(
                f"{label}: no joint_states and {ERRORS_TOPIC} within {budget:.0f} s; is DDS "
                "working?"
            )
        processes.start(
            "rns_operator",
            {
                "scenario": str(path),
                "rate": OPERATOR_RATE,
                "zero_duration": SETTLE,
                "lead": OPERATOR_LEAD,
                "start_delay": OPERATOR_START_DELAY,
                "min_subscribers": OPERATOR_SUBSCRIBERS,
                **timing,
            },
            ros_args=ros_args,
        )

        done = stack.spin_until(
            lambda: _finished(setpoints, errors, joints, scenario.duration), timeout=budget
        )
        wall = time.perf_counter() - start
        values = latest_status_values(status)
        states = {_state(msg) for msg in status.messages}
        if not done:
            raise RnsError(
                f"{label}: the scenario did not finish within {budget:.0f} s (controller state "
                f"{values.get('state')}){processes.exit_report()}"
            )
        mcap = mcap_file.close()
    lost = rrd_lost(recording)
    _check_states(label, states, values)
    figures = _figures(label, errors, joints, setpoints, scenario)
    return ContactDemoRow(
        method=method,
        label=label,
        figures=figures,
        core_peak_joint_speed=core.peak_joint_speed,
        loop_rate_hz=figures.samples / wall,
        step_time_median_us=float(values.get("step_time_us", "nan")),
        step_time_p99_us=float(values.get("step_time_p99_us", "nan")),
        final_state=values.get("state", "unknown"),
        wall_time_s=wall,
        recording=None if lost else recording,
        mcap=mcap,
        unwritten=tuple(problem for problem in (mcap_file.problem, lost) if problem),
    )


def _task_end(setpoints: TopicLog, duration: float) -> float:
    """The end of the task on the stamps' clock [s]: the operator's first force setpoint (its
    profile's start; before it only zero twists go out) plus ``duration`` [s] and twice the
    settling time (the operator's zeros, then as long again)."""
    return _seconds(setpoints.messages[0].header.stamp) + duration + 2 * SETTLE


def _finished(setpoints: TopicLog, errors: TopicLog, joints: TopicLog, duration: float) -> bool:
    """The controller's errors and the joint states reached the end of the task
    (:func:`_task_end`)."""
    if not len(setpoints) or not len(errors) or not len(joints):
        return False
    end = _task_end(setpoints, duration)
    return _latest_time(errors) >= end and joints.latest_stamp() >= end


def _check_states(label: str, states: set[str], values: dict[str, str]) -> None:
    """Raises RnsError when rns_force_controller reported a failed state during the run
    (``states``; ``values``: its newest status)."""
    failed = sorted(states & set(FAILED_STATES) - {"WAITING_FOR_STATE"})
    if failed:
        raise RnsError(
            f"{label}: rns_force_controller reported {failed} during the run "
            f"(last: {values.get('state')}, {values.get('detail')})"
        )


def _start_plant(
    processes: ProcessStack,
    method: str,
    scenario,
    model_config: str,
    args: argparse.Namespace,
    ros_args: list[str],
) -> None:
    """Start rns_force_controller with ``method`` (awaiting the operator's commands) and
    rns_simulator in contact mode, in lockstep on sim time, with the params files of
    ``scenario``'s task."""
    controller, variant, _ = CONTACT_METHODS[method]
    setup = scenario.setup
    simulator_file, controller_file = (config_dir() / name for name in TASK_PARAMS[scenario.task])
    # the controller first: it is listening when the first state comes
    processes.start(
        "rns_force_controller",
        {
            "model_config": model_config,
            "method": controller,
            "os_variant": variant,
            "use_sim_time": True,
            # each step waits for the operator's commands in force at its state's stamp
            "await_commands": True,
        },
        params_file=controller_file,
        ros_args=ros_args,
    )
    processes.start(
        "rns_simulator",
        {
            "model_config": model_config,
            **_environment(setup.constraint),
            "initial_joint_positions": setup.initial_q.tolist(),
            "step_size": CONTACT_STEP,
            "publish_rate": 1.0 / CONTACT_STEP,
            "real_time_factor": args.real_time_factor,
            "publish_clock": True,
            "lockstep_period": CONTACT_STEP,
        },
        params_file=simulator_file,
        ros_args=ros_args,
    )


def _figures(
    label: str, errors: TopicLog, joints: TopicLog, setpoints: TopicLog, scenario
) -> ContactRunFigures:
    """The run's figures from the recorded topics, up to the end of the task
    (:func:`_task_end`): the same stretch of simulated time however long the recording ran on.

    Raises:
        RnsError: the recording starts after the task, or missed its first force setpoint.
    """
    first = setpoints.messages[0]
    force = first.wrench.force
    size = float(np.linalg.norm([force.x, force.y, force.z]))
    if abs(size - scenario.setup.force(0.0)) > 1e-9:
        raise RnsError(
            f"{label}: the recording missed the operator's first force setpoint (the task's "
            f"start): the first recorded, at {_seconds(first.header.stamp):.3f} s, is "
            f"{size:.6g} N, not f_des(0) = {scenario.setup.force(0.0):g} N"
        )
    columns = _error_columns(errors)
    task_start = _seconds(setpoints.messages[0].header.stamp)
    if columns["time"][0] > task_start:
        raise RnsError(
            f"{label}: the recording starts {columns['time'][0] - task_start:.3f} s after the "
            "task; its figures would miss the start"
        )
    end = _task_end(setpoints, scenario.duration)
    within = columns["time"] <= end + 1e-9
    columns = {name: column[within] for name, column in columns.items()}
    times = joints.stamps()
    states = times <= end + 1e-9
    velocities = joints.array(lambda m: m.velocity)[states]
    return contact_run_figures(columns, times[states], velocities, tail=SETTLE)


def _seconds(stamp) -> float:
    return stamp.sec + 1e-9 * stamp.nanosec


#: What the thesis reports for each task (compare with the peak |theta_dot| columns).
THESIS_NOTES = {
    Task.WALL: "The thesis prints no numbers for the wall task (Figs. 6.7-6.8); it shows RNS-C "
    "moving the joints more calmly than OS-C.",
    Task.ARC: "Thesis Fig. 6.4: peak |θ̇| 0.73 rad/s for RNS-C against 4.22 for OS-C (our "
    "half-cycle time is tuned to the 0.73, docs/part2.md [A-4.7]).",
}


def contact_epilogue(scenario_name: str) -> str:
    """The text under the table: what the columns are and what the thesis reports."""
    task = load_motion_force_scenario(scenario_path(scenario_name)).task
    return (
        "pos err: in-plane p_des - p; held: |f_des - f| once the desired force is reached; "
        "in-process: the same task in rns_reproduce's loop (docs/part2.md); final |θ̇|: over "
        f"the last {SETTLE} s, after the task. " + THESIS_NOTES[task]
    )


def _state(msg: DiagnosticArray) -> str:
    if not msg.status:
        return "unknown"
    return next((kv.value for kv in msg.status[0].values if kv.key == "state"), "unknown")


def _latest_time(errors: TopicLog) -> float:
    latest = errors.latest()
    return latest.data[0] if latest is not None and latest.data else -math.inf
