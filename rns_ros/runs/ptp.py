"""One run of the thesis' point-to-point motion over DDS (``rns_demo --scenario ptp_three_phase``).

The §4.4 task (Table 4.2): the arm moves from [-20 -40 0 -60 180 180 0] deg to
[-120 50 0 -60 180 180 0] deg. For each planner of ``rns_ptp`` (``three_phase``, ``joint_space``
= JS-C, ``inverse_jacobian`` = IJ-C, ``transposed_jacobian`` = TJ-C) a fresh in-process stack
(:class:`rns_ros.harness.Harness`, its own domain, localhost only) runs ``rns_simulator`` from the
start angles, ``rns_ptp`` with that method, and ``rns_rerun_logger`` (one ``.rrd`` per run, with the
goal as a ghost arm and the phases plotted). The goal is published once on ``ptp_goal``; the run
ends when ``rns_ptp`` reports DONE. The table gives, per method, the largest base attitude
deviation from ``base_odom`` (geodesic angle of R_b(0)^T R_b(t), A-0.1), its ratio to the 3-phase
method, the thesis' values (its arm geometry differs: compare the ranking, not the degrees), the
final joint error, the planned duration and the folds the reactionless phases reached
(:func:`rns_ros.runs.report.format_ptp_table`).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState

from rns_ros.analysis.reproduce.chapter4_ptp import FINAL_DEG, INITIAL_DEG
from rns_ros.core import RnsError
from rns_ros.core.conventions import rotation_from_quaternion
from rns_ros.core.integration import attitude_deviation
from rns_ros.core.state import FreeFloatingState
from rns_ros.harness import Harness, TopicLog
from rns_ros.nodes.ptp import PtpNode
from rns_ros.nodes.simulator import SimulatorNode
from rns_ros.runs.clock import lockstep
from rns_ros.runs.logger import add_logger, rrd_lost
from rns_ros.runs.mcap_recording import open_mcap, record_robot_model

#: rns_ptp methods in Table 4.2 order, with the thesis' labels.
PTP_METHODS = {
    "three_phase": "3-phase",
    "joint_space": "JS-C",
    "inverse_jacobian": "IJ-C",
    "transposed_jacobian": "TJ-C",
}
#: States of rns_ptp that end a demo run without reaching the goal.
FAILED_STATES = ("INVALID_GOAL", "GOAL_MISSED", "STALE_STATE", "CONFLICTING_STATE")
#: Wall-time allowance for planning (IJ-C/TJ-C integrate the 3-phase plan first) [s].
PLANNING_ALLOWANCE = 60.0
SETTLE = 0.3


@dataclass(frozen=True)
class PtpScenario:
    """A point-to-point task: start and goal joint angles [rad], shape (n,) each."""

    name: str
    description: str
    start: tuple[float, ...]
    goal: tuple[float, ...]


PTP_SCENARIOS = {
    "ptp_three_phase": PtpScenario(
        "ptp_three_phase",
        "thesis section 4.4 point-to-point motion (Table 4.2): 3-phase vs JS-C, IJ-C, TJ-C",
        tuple(math.radians(x) for x in INITIAL_DEG),
        tuple(math.radians(x) for x in FINAL_DEG),
    )
}


@dataclass(frozen=True)
class PtpDemoRow:
    """One DDS run of a point-to-point method.

    Attributes:
        method: rns_ptp method; label: the thesis' name (3-phase, JS-C, ...).
        max_base_deviation_deg: largest base attitude deviation over the run [deg].
        final_joint_error_deg: max |theta - goal| over the joints at the end [deg].
        final_camera_error_m: for IJ-C / TJ-C, which steer the camera rather than the joints:
            distance of the camera at the end (measured angles and base pose) from the plan's
            camera target [m]; None for the joint-space methods.
        duration_s: planned duration (after any stretching to the velocity limits) [s].
        fold_reached: theta_4 at the folded end of each reactionless phase, as rns_ptp reports.
        max_joint_speed: largest |theta_dot| of joint_states [rad/s].
        wall_time_s: wall time of the run [s].
        recording: the .rrd written, or None.
    """

    method: str
    label: str
    max_base_deviation_deg: float
    final_joint_error_deg: float
    final_camera_error_m: float | None
    duration_s: float
    fold_reached: str
    max_joint_speed: float
    wall_time_s: float
    recording: str | None
    mcap: str | None = None
    #: a recording of the run that could not be written (the file removed): why, one line each
    unwritten: tuple[str, ...] = ()

    def checked_figures(self) -> dict[str, float]:
        """Every figure that must be finite, by name (no camera error: 0)."""
        return {
            "max_base_deviation_deg": self.max_base_deviation_deg,
            "final_joint_error_deg": self.final_joint_error_deg,
            "max_joint_speed": self.max_joint_speed,
            "duration_s": self.duration_s,
            "final_camera_error_m": self.final_camera_error_m or 0.0,
        }


def _values(msg: DiagnosticArray) -> dict[str, str]:
    return {kv.key: kv.value for kv in msg.status[0].values} if msg.status else {}


def run_ptp_method(method: str, scenario: PtpScenario, args: argparse.Namespace) -> PtpDemoRow:
    """One DDS run: simulator at ``scenario.start``, rns_ptp with ``method``, goal once, until
    DONE; with the rerun logger unless ``--no-record``.

    Raises:
        RnsError: rns_ptp rejected the goal, lost the state, or did not finish in time.
    """
    sim_time = lockstep(args)
    timing = {"use_sim_time": True} if sim_time else {}
    start = time.perf_counter()
    with (
        Harness(args.domain_id, args.ros_args) as stack,
        open_mcap(args, method, stack) as mcap_file,
    ):
        stack.on_record.append(mcap_file.add)  # each recorded topic, written as it arrives
        record_robot_model(stack, mcap_file)  # what a viewer draws the arm from
        joints = stack.record(JointState, "joint_states")
        odom = stack.record(Odometry, "base_odom")
        status = stack.record(DiagnosticArray, "rns_ptp/status")
        recording = None if args.no_record else add_logger(stack, method, args, timing)
        stack.add(
            SimulatorNode,
            {
                "initial_joint_positions": list(scenario.start),
                "mode": args.mode,
                "real_time_factor": args.real_time_factor,
                "publish_clock": sim_time,
                "lockstep_period": 1.0 / args.rate if sim_time else 0.0,
            },
        )
        # on the wall clock all nodes share this process (one GIL): a joint state can arrive
        # after the 0.1 s default; in lockstep inputs age in simulated time
        watchdog = {} if sim_time else {"state_timeout": 0.3}
        ptp = stack.add(PtpNode, {"method": method, "rate": args.rate, **timing, **watchdog})
        goal_publisher = stack.probe().create_publisher(JointState, "ptp_goal", 10)

        def state() -> str | None:
            latest = status.latest()
            return _values(latest).get("state") if latest is not None else None

        if not stack.spin_until(lambda: state() == "IDLE", timeout=20.0):
            raise RnsError(f"{method}: rns_ptp did not become IDLE (state {state()})")
        names = list(ptp.robot.joint_names)
        goal_publisher.publish(JointState(name=names, position=list(scenario.goal)))
        if not stack.spin_until(
            lambda: state() in ("MOVING", *FAILED_STATES), timeout=PLANNING_ALLOWANCE
        ):
            raise RnsError(f"{method}: no plan within {PLANNING_ALLOWANCE:.0f} s")
        duration = float(_values(status.latest()).get("duration", "nan"))
        budget = 30.0 + duration / max(args.real_time_factor, 1.0)
        finished = stack.spin_until(lambda: state() in ("DONE", *FAILED_STATES), timeout=budget)
        final = _values(status.latest())
        if not finished or final["state"] != "DONE":
            raise RnsError(
                f"{method}: rns_ptp ended in {final['state']} ({status.latest().status[0].message})"
            )
        target = ptp.plan.details.get("camera_target") if ptp.plan is not None else None
        stack.spin_for(SETTLE)
        robot = ptp.robot
        mcap = mcap_file.close()
    lost = rrd_lost(recording)
    deviation, error, speed = _figures(joints, odom, np.array(scenario.goal))
    camera_error = (
        None if target is None else _camera_error(robot, joints, odom, np.asarray(target))
    )
    return PtpDemoRow(
        method=method,
        label=PTP_METHODS[method],
        max_base_deviation_deg=deviation,
        final_joint_error_deg=error,
        final_camera_error_m=camera_error,
        duration_s=duration,
        fold_reached=final.get("fold_reached", "none"),
        max_joint_speed=speed,
        wall_time_s=time.perf_counter() - start,
        recording=None if lost else recording,
        mcap=mcap,
        unwritten=tuple(problem for problem in (mcap_file.problem, lost) if problem),
    )


def _figures(joints: TopicLog, odom: TopicLog, goal: np.ndarray) -> tuple[float, float, float]:
    """(max base deviation [deg], final joint error [deg], max joint speed [rad/s])."""
    if len(joints) < 2 or len(odom) < 2:
        raise RnsError("fewer than two robot states were recorded; is DDS working on loopback?")
    quaternions = odom.array(
        lambda m: [getattr(m.pose.pose.orientation, axis) for axis in ("x", "y", "z", "w")]
    )
    rotations = [rotation_from_quaternion(quaternion) for quaternion in quaternions]
    deviation = max(attitude_deviation(rotations[0], rotation) for rotation in rotations)
    positions = joints.array(lambda m: m.position)
    velocities = joints.array(lambda m: m.velocity)
    error = float(np.degrees(np.abs(positions[-1] - goal)).max())
    return math.degrees(deviation), error, float(np.abs(velocities).max())


def _camera_error(robot, joints: TopicLog, odom: TopicLog, target: np.ndarray) -> float:
    """Distance of the camera at the end (last joint angles and base pose) from ``target`` [m]."""
    pose = odom.latest().pose.pose
    q = robot.configuration(
        joints.latest().position,
        [pose.position.x, pose.position.y, pose.position.z],
        [pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w],
    )
    camera = FreeFloatingState.compute(robot, q).camera.position
    return float(np.linalg.norm(camera - target))
