"""rns_rerun_logger over real DDS (loopback, private Context): what it saves, read back."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Twist, TwistStamped, WrenchStamped
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rerun.chunk import RrdReader
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, String

from rns_ros.control.contact_topics import CONTACT_LABELS, ERROR_LABELS
from rns_ros.core import ConfigError
from rns_ros.core.fixed_base import FixedBaseState, load_fixed_base_model
from rns_ros.nodes.controller import ControllerNode
from rns_ros.nodes.ptp import PtpNode, PtpState
from rns_ros.nodes.rerun_logger import RerunLoggerNode
from rns_ros.nodes.simulator import SimulatorNode
from rns_ros.viz import paths
from rns_ros.viz.contact import ContactRecorder
from rns_ros.viz.readback import read_components, read_scalars, read_static, recording_summary

REPO = Path(__file__).resolve().parents[2]


def _node(ros, cls, **overrides):
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(cls(context=ros.context, parameter_overrides=parameters))


def _close(ros, node) -> None:
    """Destroy one node now (as the demo does between runs), not at fixture teardown."""
    ros.executor.remove_node(node)
    ros.nodes.remove(node)
    node.destroy_node()


def test_ptp_goal_becomes_a_ghost_arm_and_the_phases_are_plotted(ros, tmp_path):
    """A partial goal for rns_ptp: the ghost stands at the goal (the unnamed joints at their
    measured angles), and the recording holds the JS-C phase and the progress up to 1."""
    rrd = tmp_path / "ptp.rrd"
    _node(ros, SimulatorNode)
    # a generous state watchdog: this test is not about it (one process, one GIL, 2 cores)
    ptp = _node(ros, PtpNode, method="joint_space", duration=1.0, state_timeout=0.5)
    logger = _node(ros, RerunLoggerNode, sink="save", rrd_path=str(rrd))
    goals = ros.probe().create_publisher(JointState, "ptp_goal", 10)
    assert ros.spin_until(lambda: logger.recorder.state is not None, timeout=10.0)
    assert ros.spin_until(lambda: ptp._theta is not None, timeout=10.0)
    theta = logger.recorder.state.theta.copy()
    goals.publish(JointState(name=["joint_2"], position=[float(theta[1]) + 0.05]))
    assert ros.spin_until(lambda: logger.recorder.counts["ptp_goal"] == 1, timeout=5.0)
    assert ros.spin_until(
        lambda: logger.recorder.counts["ptp_status"] > 0 and ptp.plan is not None, timeout=10.0
    )
    # the 1 s motion and its end, however long the machine takes; then until the logger has
    # taken a DONE status (any later status is not enough: a moving one may still be in flight
    # when rns_ptp finishes)
    assert ros.spin_until(lambda: ptp._mode is PtpState.DONE, timeout=30.0)
    done = (PtpState.DONE.value, "done")
    assert ros.spin_until(lambda: logger.recorder._ptp_step == done, timeout=10.0)
    _close(ros, logger)

    goal = theta.copy()
    goal[1] += 0.05
    (strip,) = [
        row["LineStrips3D:strips"][0]
        for row in read_components(rrd, paths.PTP_GOAL)
        if "LineStrips3D:strips" in row
    ]
    expected = logger.robot.skeleton(logger.robot.configuration(goal))
    # the base has not moved before the goal: the ghost is the goal arm at the origin pose
    np.testing.assert_allclose(np.array(strip), expected, atol=1e-4)
    _, phases = read_scalars(rrd, paths.PTP_PHASE)
    assert paths.PTP_PHASE_CODES["JS-C"] in phases
    assert phases[-1] == paths.PTP_PHASE_CODES["done"]
    _, progress = read_scalars(rrd, paths.PTP_PROGRESS)
    assert progress.max() == pytest.approx(1.0)
    log = [row["TextLog:text"][0] for row in read_components(rrd, paths.PTP_LOG)]
    assert any(line.startswith("phase JS-C") for line in log), log


def test_the_grounds_prediction_error_and_link_state_are_plotted(ros, tmp_path):
    """With ground_namespace: rns_predictor's status (under it) and rns_link's give the
    prediction error and, per direction, the link's delay, messages in flight and lost."""
    rrd = tmp_path / "ground.rrd"
    logger = _node(ros, RerunLoggerNode, sink="save", rrd_path=str(rrd), ground_namespace="ground")
    probe = ros.probe()
    predictor = probe.create_publisher(DiagnosticArray, "/ground/rns_predictor/status", 10)
    link = probe.create_publisher(DiagnosticArray, "/rns_link/status", 10)
    ros.spin_until(lambda: logger.count_publishers("/rns_link/status") > 0, timeout=5.0)

    def status(values):
        message = DiagnosticArray(
            status=[DiagnosticStatus(values=[KeyValue(key=k, value=v) for k, v in values])]
        )
        message.header.stamp.sec = 100
        return message

    counts = logger.recorder.counts

    def both_taken():
        return counts["ground_predictor"] > 0 and counts["ground_link"] > 0

    for _ in range(20):  # best effort: until both were taken
        predictor.publish(status([("prediction_error_camera_deg", "7.2e-10")]))
        link.publish(status([("uplink last delay [s]", "3.0"), ("downlink lost", "4")]))
        if ros.spin_until(both_taken, timeout=0.5):
            break
    _close(ros, logger)
    _, error = read_scalars(rrd, paths.PREDICTION_ERROR_CAMERA)
    assert error[0] == pytest.approx(7.2e-10)
    _, delay = read_scalars(rrd, f"{paths.LINK}/uplink/delay_s")
    assert delay[0] == pytest.approx(3.0)
    _, lost = read_scalars(rrd, f"{paths.LINK}/downlink/lost")
    assert lost[0] == 4.0


def test_records_the_simulator_at_its_publish_rate_in_sim_time(ros, tmp_path):
    rrd = tmp_path / "sim.rrd"
    simulator = _node(ros, SimulatorNode, publish_clock=True)
    logger = _node(
        ros,
        RerunLoggerNode,
        sink="save",
        rrd_path=str(rrd),
        recording_name="sim",
        use_sim_time=True,
    )
    # 100 states logged (1 s of simulated time at 100 Hz), however long that takes
    assert ros.spin_until(lambda: logger.recorder.counts["joints"] > 100, timeout=60.0)
    # the simulator stops first and its last messages arrive before the recording closes (a
    # close between a state's base_odom and its momentum recorded 100 poses and 99 momenta)
    ros.detach(simulator)
    simulator.destroy_node()
    # each state's pose and momentum are published together: wait until both have arrived
    # (a fixed wait missed the last momentum on a busy machine)
    recorded = logger.recorder.counts
    ros.spin_until(lambda: recorded["odom"] == recorded["momentum"], timeout=10.0)
    ros.spin_for(0.1)
    counts = dict(logger.recorder.counts)
    _close(ros, logger)

    assert RrdReader(rrd).store() is not None  # finalized: footer written
    summary = recording_summary(rrd)
    joints = summary[paths.joint_transform("joint_1")]
    assert joints >= counts["joints"]  # everything received is in the file
    for joint in ("joint_2", "joint_7"):
        assert summary[paths.joint_transform(joint)] == joints
        assert summary[paths.joint_velocity(joint)] == joints
    # the simulator's energy topic (20 Hz, every 5th state), on the joint_states stamps
    assert summary[paths.energy_term("total")] >= counts["energy"] > 0.15 * counts["joints"]
    energy_times, _ = read_scalars(rrd, paths.energy_term("total"))
    joint_times, _ = read_scalars(rrd, paths.joint_velocity("joint_1"))
    assert set(np.round(energy_times, 6)) <= set(np.round(joint_times, 6))
    times, total = read_scalars(rrd, paths.BASE_ATTITUDE_TOTAL)
    assert len(times) >= 80
    # one pose per odometry, plus the identity pose placed before the first one arrived
    assert summary[paths.BASE_POSE] - len(times) in (0, 1)
    assert times[-1] < 60.0  # sim-time stamps: a duration timeline starting near zero
    # one sample per state, on the simulator's 100 Hz grid of simulated time: consecutive
    # samples 10 ms apart, a whole number of periods where the (best-effort) logger missed one
    periods = np.diff(times) / 0.01
    print(f"base attitude samples: {len(times)}, {periods.max():.0f} periods at most apart")
    assert np.allclose(periods, np.round(periods), atol=1e-3)
    assert periods.min() == pytest.approx(1.0, abs=1e-3)
    assert np.abs(total).max() < 1e-9  # no command: the base does not turn
    # every momentum received is in the file (the best-effort logger may miss one of a pair)
    assert summary[paths.MOMENTUM_ANGULAR] >= counts["momentum"] > 0
    for visual in logger.recorder.view.visual_paths()["link_3"]:
        assert visual in summary  # URDF geometry
    assert paths.CAMERA_POINTING in summary


def test_closed_loop_achieved_follows_commanded_and_the_base_stays(ros, tmp_path):
    """The controller's closed loop recorded: achieved follows commanded, the base stays.

    On simulated time in lockstep (as rns_demo runs): the simulator runs at most one period past
    the newest joint command, the controller's outputs act one period after their ticks, and
    the operator answers each joint state with the twist stamped then. A process that a busy
    machine delays stops the simulated world instead of losing motion, so the achieved rate
    does not depend on the load."""
    rrd = tmp_path / "loop.rrd"
    period = 0.01  # the controller's 100 Hz
    _node(
        ros,
        SimulatorNode,
        real_time_factor=0.0,
        publish_clock=True,
        lockstep_period=period,
    )
    # a paused simulation is not a dead one on however loaded a machine
    _node(ros, ControllerNode, use_sim_time=True, output_lead=period, clock_timeout=30.0)
    logger = _node(ros, RerunLoggerNode, sink="save", rrd_path=str(rrd), use_sim_time=True)
    probe = ros.probe()
    twist_pub = probe.create_publisher(
        TwistStamped, "cmd_twist", QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
    )

    def operator(state: JointState) -> None:
        msg = TwistStamped(twist=Twist())
        msg.header.frame_id = "world"
        msg.header.stamp = state.header.stamp
        msg.twist.angular.x = 0.1
        twist_pub.publish(msg)

    probe.create_subscription(JointState, "joint_states", operator, 10)
    # 150 controller statuses and 80 twists logged (100 Hz of simulated time each), however
    # long that takes
    counts = logger.recorder.counts
    assert ros.spin_until(lambda: counts["status"] > 150 and counts["twist"] > 80, timeout=60.0)
    _close(ros, logger)

    summary = recording_summary(rrd)
    for path in (paths.SIGMA_MIN, paths.DET_ALGORITHMIC, paths.COUPLING_MOMENTUM_NORM):
        assert summary[path] > 100, path
    assert summary[paths.COMMANDED_ANGULAR_VELOCITY_AXES[0]] > 50
    _, commanded_x = read_scalars(rrd, paths.COMMANDED_ANGULAR_VELOCITY_AXES[0])
    assert np.all(commanded_x == 0.1)
    achieved_t, achieved_x = read_scalars(rrd, paths.ACHIEVED_ANGULAR_VELOCITY_AXES[0])
    _, achieved_y = read_scalars(rrd, paths.ACHIEVED_ANGULAR_VELOCITY_AXES[1])
    late = achieved_t > achieved_t[-1] - 1.0  # settled: the last second
    print(f"achieved x over the last second: {achieved_x[late].mean():.4f} rad/s")
    assert achieved_x[late].mean() == pytest.approx(0.1, rel=0.05)
    assert np.abs(achieved_y[late]).max() < 0.02
    _, total = read_scalars(rrd, paths.BASE_ATTITUDE_TOTAL)
    assert total.max() < 1e-3  # deg: reactionless
    _, coupling = read_scalars(rrd, paths.COUPLING_MOMENTUM_NORM)
    assert coupling.max() < 1e-9


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"sink": "viewer"}, "'sink' must be one of"),
        ({"grpc_port": 80}, "'grpc_port' out of range"),
        ({"sink": "save", "rrd_path": "/no/such/folder/x.rrd"}, "does not exist"),
        ({"connect_url": "localhost:9876"}, "connect_url must look like"),
    ],
)
def test_bad_parameters_fail_with_a_clear_error(ros, overrides, message):
    with pytest.raises(ConfigError, match=message):
        RerunLoggerNode(
            context=ros.context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )


def test_ctrl_c_leaves_a_complete_file(ros, tmp_path):
    """The installed-style executable, interrupted like a terminal user would."""
    rrd = tmp_path / "ctrl_c.rrd"
    probe = ros.probe()
    publisher = probe.create_publisher(JointState, "joint_states", 10)
    names = [f"joint_{i}" for i in range(1, 8)]
    state = JointState(name=names, position=[0.3] * 7, velocity=[0.0] * 7)
    # zero stamps: the logger stamps them with its own clock
    probe.create_timer(0.02, lambda: publisher.publish(state))
    command = [sys.executable, "-m", "rns_ros.nodes.rerun_logger", "--ros-args"]
    started = time.time()
    process = subprocess.Popen(
        [*command, "-p", "sink:=save", "-p", f"rrd_path:={rrd}"],
        env=os.environ.copy(),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(process.stdout), daemon=True)
    reader.start()
    try:
        # the logger has recorded a first joint state (discovery done both ways), then 1.5 s of
        # data: matching on our side alone once left only 6 samples on a busy 2-core CI machine
        assert ros.spin_until(
            lambda: any("receiving joint_states" in line for line in lines), timeout=20.0
        ), "".join(lines)
        ros.spin_for(1.5)
        process.send_signal(signal.SIGINT)
        assert ros.spin_until(lambda: process.poll() is not None, timeout=10.0)
        reader.join(timeout=5.0)
        assert process.returncode == 0, "".join(lines)
        (closed,) = [line for line in lines if "recording closed" in line]
        assert "joints 0," not in closed
    finally:
        if process.poll() is None:
            process.kill()
        process.wait(timeout=5)
    assert RrdReader(rrd).store() is not None  # finalized: footer written
    assert recording_summary(rrd)[paths.joint_transform("joint_4")] > 10
    times, _ = read_scalars(rrd, paths.ACHIEVED_ANGULAR_VELOCITY_AXES[0])
    # wall-clock stamps (an absolute timestamp timeline): the instants of this run
    assert started <= times[0] <= times[-1] <= time.time()


# --- Part II: a fixed-base arm in contact ---------------------------------------------------------
LWR = REPO / "config" / "lwr_7dof.yaml"


def _labelled(labels, values) -> Float64MultiArray:
    """A Float64MultiArray laid out like the contact simulator's / force controller's."""
    msg = Float64MultiArray(data=[float(v) for v in values])
    msg.layout.dim = [MultiArrayDimension(label=" ".join(labels), size=len(values), stride=1)]
    return msg


def _stamp(msg, seconds: float):
    msg.header.stamp.sec = int(seconds)
    msg.header.stamp.nanosec = round((seconds - int(seconds)) * 1e9)
    return msg


def _contact_row(k: int, start: float) -> list[float]:
    """contact sample k of a 1 kHz stream: pushing 10 + k N at a point moving along y."""
    point = [0.5, 0.2 + 1e-3 * k, 0.4]
    return [start + 1e-3 * k, 1.0, 10.0 + k, 1e-7 * k, 0.0, *point, 0.0, 0.0, -1.0, 0.0]


def test_fixed_base_arm_wall_contact_and_forces(ros, tmp_path):
    """rns_rerun_logger with the LWR model: a latched wall, joint states, contact, the wrist
    wrench and the force controller's errors, as the contract lays them out; read back."""
    rrd = tmp_path / "contact.rrd"
    scale = 0.02
    logger = _node(
        ros,
        RerunLoggerNode,
        model_config=str(LWR),
        sink="save",
        rrd_path=str(rrd),
        contact_log_rate=50.0,
        force_arrow_scale=scale,
    )
    assert logger.fixed_base
    assert isinstance(logger.recorder, ContactRecorder)
    probe = ros.probe()
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    environment = probe.create_publisher(String, "environment", latched)
    states = probe.create_publisher(JointState, "joint_states", 10)
    contact = probe.create_publisher(Float64MultiArray, "contact", 100)
    wrench = probe.create_publisher(WrenchStamped, "wrist_wrench", 10)
    errors = probe.create_publisher(Float64MultiArray, "/rns_force_controller/errors", 10)
    recorder = logger.recorder

    wall = {"type": "wall", "frame": "world", "point": [0.5, 0.2, 0.4], "normal": [0, 0, -2]}
    environment.publish(String(data=json.dumps(wall)))
    assert ros.spin_until(lambda: recorder.counts["environment"] == 1, timeout=10.0)

    theta = np.radians([20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0])
    start = 2.0  # [s], a sim-time stamp
    names = [f"joint_{i}" for i in range(1, 8)]
    states.publish(_stamp(JointState(name=names, position=theta.tolist()), start))
    assert ros.spin_until(lambda: recorder.counts["joints"] == 1, timeout=10.0)

    force_ee = np.array([0.5, -1.0, 12.0])
    msg = WrenchStamped()
    msg.header.frame_id = "ee"
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = force_ee.tolist()
    wrench.publish(_stamp(msg, start))
    error = dict.fromkeys(ERROR_LABELS, 0.0)
    error |= {"time": start, "position_error_x": 1e-4, "position_error_y": -2e-4}
    error |= {"position_error_z": 3e-5, "orientation_error": 1e-3, "force_desired": 12.0}
    error |= {"force_measured": 11.5, "force_error": 0.5, "force_reference": 12.2}
    error |= {"normal_z": -1.0, "force_active": 1.0}
    errors.publish(_labelled(ERROR_LABELS, error.values()))
    assert ros.spin_until(
        lambda: recorder.counts["wrench"] == 1 and recorder.counts["errors"] == 1, timeout=10.0
    )

    # malformed contact samples first (skipped, no traceback), then 41 at 1 kHz: at 50 Hz the
    # logger keeps the ones 20 ms apart
    contact.publish(_labelled(CONTACT_LABELS, _contact_row(0, start)[:-1]))  # 11 values
    contact.publish(_labelled(CONTACT_LABELS, [math.nan, *_contact_row(0, start)[1:]]))
    for k in range(41):
        contact.publish(_labelled(CONTACT_LABELS, _contact_row(k, start)))
    assert ros.spin_until(lambda: recorder.counts["contact"] == 3, timeout=10.0)
    ros.spin_for(0.5)
    counts = dict(recorder.counts)
    _close(ros, logger)
    assert counts == {"joints": 1, "environment": 1, "contact": 3, "wrench": 1, "errors": 1}

    # the wall: a plate centred at its point, its thin axis along the (normalized) normal
    box = read_static(rrd, paths.ENVIRONMENT_WALL)
    np.testing.assert_allclose(box["Boxes3D:centers"][0], wall["point"], atol=1e-6)
    x, y, z, w = box["Boxes3D:quaternions"][0]
    np.testing.assert_allclose(
        pin.Quaternion(w, x, y, z).toRotationMatrix()[:, 2], [0, 0, -1], atol=1e-6
    )
    # the measured force: R_ee f_wrist * scale at the EE point of the core forward kinematics
    core = FixedBaseState.compute(load_fixed_base_model(LWR), theta, np.zeros(7))
    (measured,) = [
        row
        for row in read_components(rrd, paths.FORCE_MEASURED_ARROW)
        if row.get("Arrows3D:vectors")
    ]
    np.testing.assert_allclose(measured["Arrows3D:origins"][0], core.ee_position, atol=1e-6)
    np.testing.assert_allclose(
        measured["Arrows3D:vectors"][0], core.ee_rotation @ force_ee * scale, atol=1e-6
    )
    (desired,) = [
        row
        for row in read_components(rrd, paths.FORCE_DESIRED_ARROW)
        if row.get("Arrows3D:vectors")
    ]
    np.testing.assert_allclose(desired["Arrows3D:origins"][0], core.ee_position, atol=1e-6)
    np.testing.assert_allclose(desired["Arrows3D:vectors"][0], [0, 0, -12.0 * scale], atol=1e-6)
    # contact: the samples 0, 20 and 40 ms, at the joint state's stamp
    times, force = read_scalars(rrd, paths.CONTACT_NORMAL_FORCE)
    np.testing.assert_allclose(times, [start] * 3)
    np.testing.assert_allclose(force, [10.0, 30.0, 50.0])
    np.testing.assert_allclose(read_scalars(rrd, paths.CONTACT_GAP)[1], [0.0, 2e-6, 4e-6])
    points = [
        row["Points3D:positions"][0]
        for row in read_components(rrd, paths.CONTACT_POINT)
        if row.get("Points3D:positions")
    ]
    np.testing.assert_allclose(points, [_contact_row(k, start)[5:8] for k in (0, 20, 40)], 1e-6)
    # the errors' series are the sample's values
    for label, path in (
        ("force_desired", paths.FORCE_DESIRED),
        ("force_measured", paths.FORCE_MEASURED),
        ("force_error", paths.FORCE_ERROR),
        ("force_reference", paths.FORCE_REFERENCE),
        ("position_error_x", paths.POSITION_ERROR_AXES[0]),
        ("position_error_y", paths.POSITION_ERROR_AXES[1]),
        ("position_error_z", paths.POSITION_ERROR_AXES[2]),
        ("orientation_error", paths.POSITION_ERROR_ORIENTATION),
    ):
        np.testing.assert_allclose(read_scalars(rrd, path)[1], [error[label]], err_msg=label)
    # the arm: one pose per joint state, the base static at the origin
    summary = recording_summary(rrd)
    assert summary[paths.joint_transform("joint_7")] == 1
    assert summary[paths.BASE_POSE] == 0
    assert paths.BASE_ATTITUDE_TOTAL not in summary  # no free-floating series


def test_config_yaml_fixed_base_parameters_have_their_documented_defaults():
    values = yaml.safe_load((REPO / "config" / "rerun_logger.yaml").read_text())
    values = values["/**"]["ros__parameters"]
    assert values["force_errors_topic"] == "/rns_force_controller/errors"
    assert values["contact_log_rate"] == 50.0
    assert values["force_arrow_scale"] == 0.01
