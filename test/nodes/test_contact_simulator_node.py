"""rns_simulator, contact mode, over real DDS (loopback, private Context): physics of the static
push, saturation, bad inputs, the stale-command brake, lockstep, the free arm, start-up errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import Log
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rns_testing import Recorder
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, String

from rns_ros.control.contact_tasks import ArcScenario
from rns_ros.control.contact_topics import CONTACT_LABELS
from rns_ros.core import ConfigError
from rns_ros.core.contact_geometry import ArcConstraint, PlaneConstraint
from rns_ros.core.fixed_base import FixedBaseState, load_fixed_base_model
from rns_ros.nodes.contact_simulator import ContactSimulatorNode
from rns_ros.nodes.contact_simulator_parameters import WALL_TASK_RAD
from rns_ros.nodes.lockstep import MAX_STAMP_LAG
from rns_ros.nodes.simulator import SimulatorNode, create_simulator_node
from rns_ros.sim.contact import ContactSimulator

REPO = Path(__file__).resolve().parents[2]
COMMAND_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
LWR = load_fixed_base_model(REPO / "config" / "lwr_7dof.yaml")
LABEL = {name: k for k, name in enumerate(CONTACT_LABELS)}
PUSH = 10.0  # N


def _node(ros, **overrides) -> ContactSimulatorNode:
    overrides.setdefault("command_timeout", 0.3)  # generous: 2 shared cores
    # free-running on the wall clock unless a test is about lockstep or sim time (the contact
    # mode's defaults are lockstep at the step and /clock)
    overrides.setdefault("lockstep_period", 0.0)
    overrides.setdefault("publish_clock", False)
    parameters = [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(ContactSimulatorNode(context=ros.context, parameter_overrides=parameters))


def _wall_push_torque(f: float = PUSH) -> np.ndarray:
    """tau = J_c^T f [N m] (7,) at the wall-task start, from the core."""
    start = FixedBaseState.compute(LWR, WALL_TASK_RAD, np.zeros(7))
    wall = PlaneConstraint(start.ee_position, start.ee_rotation[:, 2])
    return ContactSimulator(LWR, wall, initial_q=WALL_TASK_RAD).constraint_jacobian() * f


def _recorders(probe):
    return (
        Recorder(probe, JointState, "joint_states", qos=200),
        Recorder(probe, WrenchStamped, "wrist_wrench", qos=200),
        Recorder(probe, Float64MultiArray, "contact", qos=200),
    )


def _errors(probe, level=Log.ERROR):
    """Log lines of at least ``level`` on /rosout (transient local, as rcl publishes it: lines
    logged before the subscription matched arrive too)."""
    errors = []
    qos = QoSProfile(depth=1000, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    probe.create_subscription(
        Log, "/rosout", lambda m: errors.append(m.msg) if m.level >= level else None, qos
    )
    return errors


def _all_finite(joints, wrenches, contacts) -> bool:
    values = [np.concatenate([m.position, m.velocity, m.effort]) for m in joints.messages]
    for m in wrenches.messages:
        f, t = m.wrench.force, m.wrench.torque
        values.append(np.array([f.x, f.y, f.z, t.x, t.y, t.z]))
    values += [np.array(m.data) for m in contacts.messages]
    return all(np.isfinite(v).all() for v in values)


def test_static_push_reads_the_force_on_the_wrist_and_in_the_contact_sample(ros):
    tau = _wall_push_torque()
    _node(ros, publish_clock=True)
    probe = ros.probe()
    joints, wrenches, contacts = _recorders(probe)
    command = probe.create_publisher(Float64MultiArray, "joint_efforts", COMMAND_QOS)

    def pushing():
        command.publish(Float64MultiArray(data=tau.tolist()))
        return len(joints.messages) > 300 and np.allclose(joints.messages[-1].effort, tau)

    assert ros.spin_until(pushing, timeout=20.0)
    ros.spin_for(0.05)
    stamped = joints.by_stamp()
    checked = 0
    for wrench in wrenches.messages[-100:]:
        state = stamped.get((wrench.header.stamp.sec, wrench.header.stamp.nanosec))
        if state is None or not np.array_equal(state.effort, tau):
            continue
        f = wrench.wrench.force
        assert wrench.header.frame_id == "ee"
        assert np.allclose([f.x, f.y, f.z], [0.0, 0.0, PUSH], atol=1e-3)  # EE z = wall normal
        checked += 1
    assert checked > 20
    sample = contacts.messages[-1]
    assert sample.layout.dim[0].label == " ".join(CONTACT_LABELS)
    assert sample.data[LABEL["normal_force"]] == pytest.approx(PUSH, abs=1e-3)
    assert sample.data[LABEL["contact_state"]] == 1.0
    assert abs(sample.data[LABEL["gap"]]) < 1e-9
    assert sample.data[LABEL["saturated_joints"]] == 0.0
    assert np.allclose(joints.messages[-1].position, WALL_TASK_RAD, atol=1e-9)  # static
    assert _all_finite(joints, wrenches, contacts)


def test_saturated_torque_is_clipped_and_counted(ros):
    node = _node(ros, lockstep_period=0.001)
    probe = ros.probe()
    joints, _, contacts = _recorders(probe)
    command = probe.create_publisher(Float64MultiArray, "joint_efforts", COMMAND_QOS)
    warnings = _errors(probe, level=Log.WARN)
    tau = _wall_push_torque()
    tau[0] = 500.0  # limit 176 N m
    tau[6] = -50.0  # limit 30 N m
    assert ros.spin_until(lambda: len(joints.messages) > 5)

    def clipped():
        command.publish(Float64MultiArray(data=tau.tolist()))
        return joints.messages[-1].effort[0] == 176.0

    assert ros.spin_until(clipped, timeout=60.0)
    expected = np.clip(tau, -node.robot.effort_limits, node.robot.effort_limits)
    assert np.array_equal(joints.messages[-1].effort, expected)
    assert ros.spin_until(lambda: contacts.messages[-1].data[LABEL["saturated_joints"]] == 2.0)
    assert ros.spin_until(lambda: any("joint_1" in w and "joint_7" in w for w in warnings))


@pytest.mark.parametrize(
    ("data", "reason"),
    [([0.0] * 6 + [float("nan")], "must be finite"), ([1.0] * 3, "expected 7 torques")],
    ids=["nan", "length"],
)
def test_bad_torques_are_rejected_and_the_brake_takes_over(ros, data, reason):
    tau = _wall_push_torque()
    _node(ros)
    probe = ros.probe()
    errors = _errors(probe)
    joints, wrenches, contacts = _recorders(probe)
    command = probe.create_publisher(Float64MultiArray, "joint_efforts", COMMAND_QOS)

    def pushing():
        command.publish(Float64MultiArray(data=tau.tolist()))
        return joints.messages and np.array_equal(joints.messages[-1].effort, tau)

    assert ros.spin_until(pushing, timeout=60.0)

    def bad():
        command.publish(Float64MultiArray(data=data))
        return any(reason in e for e in errors) and np.abs(joints.messages[-1].effort).max() < 1e-9

    # bad messages never reach the arm and do not feed the watchdog: after command_timeout the
    # brake holds (zero torque at rest without gravity)
    assert ros.spin_until(bad, timeout=60.0), errors
    count = len(joints.messages)
    assert ros.spin_until(lambda: len(joints.messages) > count + 50)  # still running
    assert contacts.messages[-1].data[LABEL["normal_force"]] == pytest.approx(0.0, abs=1e-6)
    assert _all_finite(joints, wrenches, contacts)


def test_killed_controller_mid_push_releases_within_the_timeout(ros):
    """The issue's safety case: a controller pushing 10 N while sliding stops publishing; within
    command_timeout + 1 s of simulated time (the contact samples' time; plus the real-time
    pace's catch-up after a lag, at most MAX_STAMP_LAG) the push has ended (< 0.5 N) and the
    joints have stopped. A slow machine slows the simulation, not the release per simulated
    second."""
    timeout = 0.1
    node = _node(ros, command_timeout=timeout)
    probe = ros.probe()
    warnings = _errors(probe, level=Log.WARN)
    joints, wrenches, contacts = _recorders(probe)
    command = probe.create_publisher(Float64MultiArray, "joint_efforts", COMMAND_QOS)
    tau = _wall_push_torque() + np.array([0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])

    def sliding():
        command.publish(Float64MultiArray(data=tau.tolist()))
        return (
            contacts.messages  # (its subscription may match later than the joints')
            and contacts.messages[-1].data[LABEL["normal_force"]] > 5.0  # (and lag behind them)
            and joints.messages
            and np.abs(joints.messages[-1].velocity).max() > 0.05
        )

    assert ros.spin_until(sliding, timeout=60.0), "the controller never pushed and slid"
    killed = node.simulator.time  # the last command went out before this instant
    assert ros.spin_until(
        lambda: (
            abs(contacts.messages[-1].data[LABEL["normal_force"]]) < 0.5
            and np.abs(joints.messages[-1].velocity).max() < 1e-3
        ),
        timeout=60.0,
    )
    released = contacts.messages[-1].data[LABEL["time"]] - killed
    print(f"released {released:.3f} s of simulated time after the last command ({timeout} s)")
    assert released < timeout + 1.0 + MAX_STAMP_LAG
    assert _all_finite(joints, wrenches, contacts)
    # once per stale event (a late test publish on a loaded machine may make one more)
    assert any("joint brakes on" in w for w in warnings), warnings


def test_lockstep_advances_one_step_per_command(ros):
    step = 0.001
    node = _node(ros, lockstep_period=step, real_time_factor=0.0)
    probe = ros.probe()
    joints, _, _ = _recorders(probe)
    command = probe.create_publisher(Float64MultiArray, "joint_efforts", COMMAND_QOS)
    assert ros.spin_until(lambda: len(joints.messages) > 5)
    for _ in range(3):
        before = node._pacer.command_sim_time
        command.publish(Float64MultiArray(data=[0.0] * 7))
        assert ros.spin_until(lambda b=before: node._pacer.command_sim_time != b, timeout=2.0)
        received_at = node._pacer.command_sim_time
        ros.spin_for(0.2)  # no command: the simulation waits
        assert node.simulator.time == pytest.approx(received_at + step)


def test_free_arm_accelerates_as_the_core_says(ros):
    node = _node(ros, environment="none", lockstep_period=0.001, publish_clock=True)
    probe = ros.probe()
    joints, wrenches, contacts = _recorders(probe)
    command = probe.create_publisher(Float64MultiArray, "joint_efforts", COMMAND_QOS)
    tau = np.array([2.0, -3.0, 1.0, 1.5, 0.01, -0.01, 0.002])
    assert ros.spin_until(lambda: len(joints.messages) > 5)
    count = len(joints.messages)

    def two_steps():
        command.publish(Float64MultiArray(data=tau.tolist()))
        return sum(np.array_equal(m.effort, tau) for m in joints.messages[count:]) >= 2

    assert ros.spin_until(two_steps, timeout=60.0)
    first, second = [m for m in joints.messages[count:] if np.array_equal(m.effort, tau)][:2]
    dt = (second.header.stamp.nanosec - first.header.stamp.nanosec) * 1e-9 % 1.0
    assert dt == pytest.approx(0.001, abs=1e-9)
    state = FixedBaseState.compute(node.robot, first.position, first.velocity)
    expected = np.linalg.solve(state.mass_matrix, tau - state.coriolis - state.gravity)
    measured = (np.array(second.velocity) - first.velocity) / dt
    assert np.allclose(measured, expected, rtol=2e-2, atol=1e-3 * np.abs(expected).max())
    assert not np.any([m.wrench.force.z for m in wrenches.messages])
    assert contacts.messages[-1].data[LABEL["normal_force"]] == 0.0
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    environment = Recorder(probe, String, "environment", qos=latched)
    assert ros.spin_until(lambda: environment.messages)
    assert json.loads(environment.messages[0].data) == {"type": "none", "frame": "world"}


def test_the_arc_params_file_starts_the_planar_arm_on_the_cylinder(ros):
    node = ros.add(create_simulator_node, params_file=REPO / "config" / "contact_arc.yaml")
    assert isinstance(node, ContactSimulatorNode)
    probe = ros.probe()
    joints, _, contacts = _recorders(probe)
    assert ros.spin_until(lambda: len(contacts.messages) > 5)
    assert abs(contacts.messages[-1].data[LABEL["gap"]]) < 1e-9
    robot = node.robot
    arc = ArcConstraint([1.91, 1.91, 0.0], 0.707)
    p = FixedBaseState.compute(robot, joints.messages[-1].position, np.zeros(3)).ee_position
    assert abs(arc.phi(p)) < 1e-9
    assert np.allclose(node.initial_q, ArcScenario().setup().initial_q, atol=1e-12)


def test_other_modes_still_build_the_free_floating_node(ros):
    node = ros.add(create_simulator_node, {"mode": "dynamic"})
    assert isinstance(node, SimulatorNode)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"wall_normal": [0.0, 0.0, 0.0]}, "plane normal must be a non-zero direction"),
        ({"environment": "arc", "arc_radius": -0.5}, "arc radius must be a finite number > 0"),
        ({"environment": "arc", "project_start": False}, "m outside the arc"),
        ({"joints": ["joint_1", "elbow"]}, "must be a permutation of the model's joints"),
        ({"initial_joint_positions": [0.1, 0.2]}, "needs 7 values"),
        ({"model_config": "nowhere.yaml"}, "'model_config' 'nowhere.yaml' is neither"),
    ],
)
def test_bad_parameters_fail_with_a_clear_error(ros, overrides, message):
    with pytest.raises(ConfigError) as caught:
        ContactSimulatorNode(
            context=ros.context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()],
        )
    assert message in str(caught.value)
    assert "\n" not in str(caught.value)
    if "joints" in overrides:
        assert "model joints: ['joint_1'" in str(caught.value)  # both lists named


def test_an_unknown_environment_is_one_line_and_exit_2(tmp_path):
    env = {
        **__import__("os").environ,
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "AMENT_PREFIX_PATH": str(Path(sys.executable).parent.parent),
    }
    result = subprocess.run(
        [
            str(Path(sys.executable).parent / "rns_simulator"),
            "--ros-args",
            "-p",
            "mode:=contact",
            "-p",
            "environment:=cube",
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=30,
        check=False,
    )
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.returncode == 2, result.stderr
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rns_simulator: parameter 'environment' must be one of")
    assert "cube" in lines[0]


def _sim_seconds(msg) -> float:
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec


def test_a_diverged_step_holds_the_last_state_until_reset(ros):
    """A step that diverges (forced here once) is logged once; the node then publishes the last
    finite state at rest, never a NaN, and ~/reset starts it again from the start state."""
    from std_srvs.srv import Trigger

    from rns_ros.core.errors import SimulationDivergedError

    node = _node(ros, publish_clock=True, publish_rate=100.0)
    probe = ros.probe()
    errors = _errors(probe)
    joints, wrenches, contacts = _recorders(probe)
    client = probe.create_client(Trigger, "/rns_simulator/reset")
    assert ros.spin_until(lambda: len(joints.messages) > 5)
    healthy = node.simulator.step

    def diverge():
        node.simulator.step = healthy
        raise SimulationDivergedError("contact simulation diverged (forced): non-finite v")

    node.simulator.step = diverge
    assert ros.spin_until(lambda: node._fault, timeout=30.0)
    count = len(joints.messages)
    assert ros.spin_until(lambda: len(joints.messages) > count + 10, timeout=30.0)
    held = joints.messages[-5:]
    assert len({_sim_seconds(m) for m in held}) == 1  # simulated time stopped
    assert not np.any([m.velocity for m in held])
    assert not np.any([m.effort for m in held])
    assert ros.spin_until(lambda: any("diverged" in e for e in errors), timeout=30.0), errors
    assert sum("diverged" in e for e in errors) == 1, errors
    assert _all_finite(joints, wrenches, contacts)

    assert client.wait_for_service(timeout_sec=5.0)
    future = client.call_async(Trigger.Request())
    assert ros.spin_until(future.done, timeout=30.0)
    assert future.result().success
    assert ros.spin_until(lambda: not node._fault and node.simulator.time > 0.1, timeout=30.0)
    assert np.allclose(joints.messages[-1].position, WALL_TASK_RAD, atol=1e-12)
