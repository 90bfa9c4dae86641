"""rns_demo's motion/force runs over DDS: the 7-DoF wall task (thesis section 6.2.2) with the
contact simulator, rns_force_controller and the scripted operator, against the in-process loop;
and what the simulator does when the torque controller dies mid-push.
"""

from __future__ import annotations

import argparse

import numpy as np
import pytest
import yaml
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
from rns_testing import status_values
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rns_ros.control.contact_topics import CONTACT_LABELS
from rns_ros.harness import Harness, ProcessStack
from rns_ros.nodes.lockstep import LOCKSTEP_PATIENCE
from rns_ros.runs.contact import run_contact_method
from rns_ros.runs.report import format_contact_table

DOMAIN = 47
#: One stroke of the wall task (2.5 s, 10 N): the shipped file with strokes = 1.
ONE_STROKE = {
    "kind": "motion_force",
    "task": "wall",
    "name": "wall_one_stroke",
    "description": "one stroke of the thesis wall task",
    "strokes": 1,
}


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    path = tmp_path_factory.mktemp("scenario") / "wall_one_stroke.yaml"
    path.write_text(yaml.safe_dump(ONE_STROKE))
    args = argparse.Namespace(
        domain_id=DOMAIN, ros_args=[], no_record=True, viewer=False, real_time_factor=0.0
    )
    result = {method: run_contact_method(method, str(path), args) for method in ("rns", "os")}
    print(format_contact_table(list(result.values())))
    return result


def test_the_wall_task_holds_the_force_and_tracks_the_stroke(rows):
    """Over DDS, in lockstep with the simulator and the operator: the 10 N are held within 0.1 N
    once reached (measured 0.015 / 0.005 N), never off by more than 0.5 N on the ramp
    (0.038 N), and the flange follows the stroke within 1 mm in the wall plane (0.021 /
    0.017 mm; the in-process loop: 0.008 mm)."""
    for row in rows.values():
        figures = row.figures
        assert figures.held_force_error_n < 0.1, row.label
        assert figures.max_force_error_n < 0.5, row.label
        assert figures.max_position_error_m < 1e-3, row.label
        assert figures.max_orientation_error_rad < 1e-3, row.label
        assert figures.duration_s > 2.5  # the whole stroke was recorded


def test_rns_c_moves_the_joints_more_calmly_than_os_c_as_in_process(rows):
    """The thesis' claim on the first stroke (in process: 1.043 vs 1.542 rad/s); each DDS peak
    within 20 % of its in-process value (measured within 0.3 %)."""
    rns, os_ = rows["rns"], rows["os"]
    assert rns.figures.peak_joint_speed < os_.figures.peak_joint_speed
    for row in (rns, os_):
        assert row.figures.peak_joint_speed == pytest.approx(row.core_peak_joint_speed, rel=0.2)
        assert row.loop_rate_hz > 0.0


def _contact(msg: Float64MultiArray) -> dict[str, float]:
    return dict(zip(CONTACT_LABELS, msg.data, strict=True))


def test_a_killed_controller_makes_the_simulator_release_the_push():
    """rns_force_controller (a process) pushes 10 N with rns_simulator at its contact-mode
    defaults (lockstep), then is killed (SIGKILL: no last word). The paused simulator waits
    LOCKSTEP_PATIENCE (wall clock) for the next torque, then brakes the joints and runs on
    in real time: the push ends (normal force < 0.5 N) and the arm comes to rest; nothing
    non-finite is published."""
    with ProcessStack(DOMAIN + 1) as processes, Harness(DOMAIN + 1) as stack:
        contact = stack.record(Float64MultiArray, "contact")
        joints = stack.record(JointState, "joint_states")
        status = stack.record(DiagnosticArray, "rns_force_controller/status")
        controller = processes.start("rns_force_controller", {"use_sim_time": True})
        processes.start("rns_simulator", {"mode": "contact"})
        push = stack.probe().create_publisher(WrenchStamped, "force_setpoint", 10)

        def pushing() -> bool:
            msg = WrenchStamped()
            msg.header.frame_id = "ee"
            msg.wrench.force.z = 10.0
            push.publish(msg)
            return len(contact) > 0 and abs(_contact(contact.latest())["normal_force"] - 10.0) < 0.5

        assert stack.spin_until(pushing, timeout=30.0), (
            "the controller never pushed 10 N",
            _contact(contact.latest()) if len(contact) else None,
            status_values(status.latest()) if len(status) else None,
        )
        controller.kill()
        stack.spin_for(LOCKSTEP_PATIENCE + 1.5)
        latest = _contact(contact.latest())
        assert abs(latest["normal_force"]) < 0.5
        assert latest["contact_state"] == 0.0
        assert np.abs(joints.latest().velocity).max() < 1e-2
        assert np.isfinite(contact.array(lambda m: m.data)).all()
        assert np.isfinite(joints.array(lambda m: m.velocity)).all()
