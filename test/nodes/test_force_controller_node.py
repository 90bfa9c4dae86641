"""rns_force_controller over DDS without a simulator: a probe publishes joint_states and
wrist_wrench itself and checks the node's torques, errors and status (docs/part2_ros.md)."""

from __future__ import annotations

import itertools
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rns_testing import SimClock, status_values
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rns_ros.control.contact_topics import ERROR_LABELS
from rns_ros.control.force.commands import JointMeasurement, WrenchSample
from rns_ros.control.force.controller import ForceTeleopController
from rns_ros.control.force.settings import ForceControlSettings
from rns_ros.core.fixed_base import load_fixed_base_model
from rns_ros.nodes.force_controller import ForceControllerNode
from rns_ros.resources import config_dir

REPO = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
JOINTS = [f"joint_{i}" for i in range(1, 8)]
START = np.radians([20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0])
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
ZERO7 = np.zeros(7)
PUSH = np.array([0.0, 0.0, 3.0])  # the wrench the EE exerts, EE axes [N]
#: Wall-clock bound [s] of a wait that only a hang exceeds.
HANG_TIMEOUT = 30.0


class _Arm:
    """Publishes joint_states (names shuffled) and the wrist wrench of the same stamp."""

    def __init__(self, ros):
        self.ros = ros
        self.probe = ros.probe()
        self.states = self.probe.create_publisher(JointState, "joint_states", RELIABLE)
        self.wrench = self.probe.create_publisher(WrenchStamped, "wrist_wrench", RELIABLE)
        self.sent = 0

    def publish(self, q=START, v=ZERO7, effort=ZERO7):
        stamp = self.probe.get_clock().now().to_msg()
        wrench = WrenchStamped()
        wrench.header.stamp, wrench.header.frame_id = stamp, "ee"
        wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z = PUSH
        self.wrench.publish(wrench)
        self.ros.spin_for(0.02)  # the wrench first (two topics: no order guaranteed)
        order = [6, 0, 5, 1, 4, 2, 3]
        state = JointState(
            name=[JOINTS[i] for i in order],
            position=[float(q[i]) for i in order],
            velocity=[float(v[i]) for i in order],
            effort=[float(effort[i]) for i in order],
        )
        state.header.stamp = stamp
        self.states.publish(state)
        self.sent += 1
        return stamp


def _start(ros, **overrides):
    # not about the watchdog: longer than this process waits for a core on a loaded machine
    overrides.setdefault("state_timeout", 10.0)
    node = ros.add(ForceControllerNode, overrides)
    torques = ros.record(Float64MultiArray, "joint_efforts")
    errors = ros.record(Float64MultiArray, "rns_force_controller/errors")
    status = ros.record(DiagnosticArray, "rns_force_controller/status")
    arm = _Arm(ros)
    assert ros.spin_until(
        lambda: arm.states.get_subscription_count() and arm.wrench.get_subscription_count(), 10.0
    )
    return node, arm, torques, errors, status


def test_one_finite_torque_per_state_in_joints_order(ros):
    reversed_joints = list(reversed(JOINTS))
    node, arm, torques, errors, status = _start(ros, joints=reversed_joints)
    for _ in range(20):
        arm.publish()
        ros.spin_for(0.01)
    assert ros.spin_until(lambda: len(errors) >= 20, 5.0)
    assert len(torques) == 20
    data = torques.array(lambda m: m.data)
    assert data.shape == (20, 7)
    assert np.isfinite(data).all()
    # the first torque equals the pure step at the same inputs, reordered to `joints`
    robot = load_fixed_base_model(config_dir() / "lwr_7dof.yaml")
    controller = ForceTeleopController(robot, ForceControlSettings())
    controller.add_wrench(WrenchSample(5, PUSH, np.zeros(3)))
    expected = controller.step(JointMeasurement(5, START, np.zeros(7), np.zeros(7)), 0.0).torque
    np.testing.assert_allclose(data[0], expected[::-1], rtol=1e-9, atol=1e-9)
    # ~/errors layout; force measured = the pushed 3 N along the EE z axis (the default normal)
    sample = errors.latest()
    assert sample.layout.dim[0].label == " ".join(ERROR_LABELS)
    row = dict(zip(ERROR_LABELS, sample.data, strict=True))
    assert row["force_measured"] == pytest.approx(3.0)
    assert row["force_active"] == 0.0  # no force setpoint yet
    assert ros.spin_until(lambda: len(status) > 0, 2.0)
    values = status_values(status.latest())
    assert values["state"] == "HOLDING"
    assert values["contact"] == "in_contact"
    assert float(values["step_time_us"]) > 0.0
    assert node.controller.normal is not None


def test_stale_state_publishes_one_zero_torque(ros):
    """Each state gets its torque; once the newest is state_timeout old, one zero torque, and
    no more while it stays stale. (On a loaded machine a state may come more than 0.1 s after
    the one before: that gap gets its one zero too.)"""
    _, arm, torques, _, status = _start(ros, state_timeout=0.1)
    for _ in range(5):
        arm.publish()
        ros.spin_for(0.01)
    assert ros.spin_until(lambda: len(torques) >= 5, 5.0)
    assert ros.spin_until(
        lambda: (
            status.latest() is not None and status_values(status.latest())["state"] == "STALE_STATE"
        ),
        5.0,
    )
    ros.spin_for(0.3)
    zero = [not np.any(row) for row in torques.array(lambda m: m.data)]
    assert zero.count(False) == 5  # one torque per state
    assert zero[-1]  # stale: the arm's torque is zero
    assert not any(a and b for a, b in itertools.pairwise(zero))  # one zero per stale episode
    assert "state_timeout 0.1 s" in status.latest().status[0].message


def test_shutdown_publishes_zero_torque(ros):
    node, arm, torques, _, _ = _start(ros)
    arm.publish(effort=np.ones(7))
    assert ros.spin_until(lambda: len(torques) >= 1, 5.0)
    ros.detach(node)
    node.destroy_node()
    assert ros.spin_until(lambda: len(torques) >= 2, 5.0)
    assert torques.latest().data.tolist() == [0.0] * 7


def test_config_files_load_through_rcl(ros):
    default = ros.add(ForceControllerNode, params_file=REPO / "config" / "force_controller.yaml")
    assert default.settings.rows == (0, 1, 2, 3, 4, 5)
    node = ros.add(
        ForceControllerNode,
        params_file=REPO / "config" / "force_controller_arc.yaml",
        name="arc_controller",
    )
    assert node.robot.n == 3
    assert node.settings.rows == (0, 1)
    assert node.settings.surface_curvature == pytest.approx(1 / 0.707)


@pytest.mark.parametrize(
    ("args", "pattern"),
    [
        (["-p", "method:=pid"], r"'method' must be one of \['rns', 'os'\]"),
        (
            ["-p", "force_measurement:=sampled"],
            r"needs k_f < 1, got k_f = 5: .*diverges",
        ),
        (["-p", "task_axes:=[x, q]"], r"task_axes must be distinct names"),
        (["-p", "await_commands:=true"], r"await_commands needs use_sim_time: true"),
    ],
)
def test_startup_errors_are_one_line_and_exit_2(args, pattern, tmp_path):
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    result = subprocess.run(
        [str(BIN / "rns_force_controller"), "--ros-args", *args],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=30,
        check=False,
    )
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.returncode == 2, result.stderr[-2000:]
    assert len(lines) == 1, result.stderr[-2000:]
    assert lines[0].startswith("rns_force_controller: ")
    assert re.search(pattern, lines[0]), lines[0]


# --- simulated time: the test publishes /clock, the wrench and joint_states itself --------------

#: Simulated time per step of the test's /clock [s].
STEP = 0.01


class _SimArm(_Arm):
    """:class:`_Arm` on a /clock the test publishes: each step advances it by STEP and sends the
    wrench and the state stamped then."""

    def __init__(self, ros):
        super().__init__(ros)
        self.clock = SimClock(self.probe)

    def step(self, state: bool = True) -> None:
        """One STEP of simulated time, with a wrench and a state at its stamp unless ``state``
        is False, then the callbacks of 10 ms of wall time."""
        stamp = self.clock.advance(STEP)
        if state:
            wrench = WrenchStamped()
            wrench.header.stamp, wrench.header.frame_id = stamp, "ee"
            wrench.wrench.force.x, wrench.wrench.force.y, wrench.wrench.force.z = PUSH
            self.wrench.publish(wrench)
            msg = JointState(
                name=JOINTS, position=START.tolist(), velocity=ZERO7.tolist(), effort=ZERO7.tolist()
            )
            msg.header.stamp = stamp
            self.states.publish(msg)
            self.sent += 1
        self.ros.spin_for(0.01)

    def steps(self, count: int, torques) -> None:
        """``count`` steps, each once the torque of the one before came (a simulator in lockstep
        waits so): no state waits in the controller's queue (depth 10: the oldest would be
        dropped, its torque never sent) however slowly a busy machine runs the controller."""
        for _ in range(count):
            expected = len(torques) + 1
            self.step()
            assert self.ros.spin_until(lambda n=expected: len(torques) >= n, HANG_TIMEOUT)


def _sim_time_start(ros, **overrides):
    """rns_force_controller under use_sim_time, stepped 20 times on the test's /clock."""
    node = ros.add(ForceControllerNode, {"use_sim_time": True, **overrides})
    torques = ros.record(Float64MultiArray, "joint_efforts")
    status = ros.record(DiagnosticArray, "rns_force_controller/status")
    arm = _SimArm(ros)
    assert ros.spin_until(
        lambda: arm.states.get_subscription_count() and arm.wrench.get_subscription_count(), 10.0
    )
    arm.steps(20, torques)
    assert len(torques) == 20
    return node, arm, torques, status


def _last_state(status) -> str | None:
    return None if status.latest() is None else status_values(status.latest())["state"]


def test_sim_time_a_wall_clock_pause_of_the_simulation_does_not_stop_the_motors(ros):
    """Under use_sim_time the state's age is simulated time: /clock and the state paused for 1 s
    of wall time (4 state_timeouts, below clock_timeout) age nothing: no zero torque."""
    node, arm, torques, status = _sim_time_start(ros, state_timeout=0.25, clock_timeout=10.0)
    ros.spin_for(1.0)  # the simulation pauses: no /clock, no joint_states
    arm.steps(20, torques)
    ros.spin_for(0.1)
    assert len(torques) == 40  # one per state, no zero torque of a stale state between them
    assert not node._stale
    assert "STALE_STATE" not in {status_values(m)["state"] for m in status.messages}


def test_sim_time_a_stopped_clock_turns_the_motors_off(ros):
    """/clock and the state stop (a dead simulator): no simulated time passes, yet after
    clock_timeout of wall time (set at run time) one zero torque goes out and the status says
    STALE_STATE; a state on a moving clock again resumes the torques."""
    node, arm, torques, status = _sim_time_start(ros, state_timeout=0.25, clock_timeout=30.0)
    result = node.set_parameters([Parameter("clock_timeout", value=1.0)])
    assert result[0].successful
    # the watch must see /clock move between two of its new checks (clock_timeout / 4 apart,
    # from the change): steps for three such periods of wall time at least
    changed = time.monotonic()
    arm.steps(50, torques)
    while time.monotonic() - changed < 0.75:
        arm.steps(1, torques)
    assert ros.spin_until(
        lambda: (
            status.latest() is not None
            and "/clock stood still" in status.latest().status[0].message
        ),
        HANG_TIMEOUT,
    )
    assert _last_state(status) == "STALE_STATE"
    assert "(clock_timeout 1.0 s wall time)" in status.latest().status[0].message
    assert len(torques) == arm.sent + 1  # the torques of the states, then exactly one zero
    assert torques.latest().data.tolist() == [0.0] * 7
    arm.step()  # a state on a moving clock: its torque after the zero
    assert ros.spin_until(lambda: len(torques) >= arm.sent + 1, HANG_TIMEOUT)
    assert torques.latest().data.tolist() != [0.0] * 7
    assert ros.spin_until(lambda: _last_state(status) != "STALE_STATE", HANG_TIMEOUT)


def test_sim_time_a_state_stale_in_simulated_time_turns_the_motors_off(ros):
    """/clock goes on without joint_states: after state_timeout of simulated time, one zero
    torque and STALE_STATE."""
    _, arm, torques, status = _sim_time_start(ros, state_timeout=0.25, clock_timeout=30.0)
    deadline = time.monotonic() + 10.0
    while _last_state(status) != "STALE_STATE" and time.monotonic() < deadline:
        arm.step(state=False)
    assert _last_state(status) == "STALE_STATE"
    message = status.latest().status[0].message
    assert "joint_states" in message
    assert "(state_timeout 0.25 s)" in message
    assert len(torques) == 21
    assert torques.latest().data.tolist() == [0.0] * 7
