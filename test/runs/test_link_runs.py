"""rns_ros.runs.link (the demo behind a delayed link): the link options, the twists as they act,
the prediction error measured from the recorded streams."""

from __future__ import annotations

import argparse
import math

import pinocchio as pin
import pytest
from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState

from rns_ros.harness import TopicLog
from rns_ros.nodes.sim_clock import stamp_from_seconds
from rns_ros.runs.link import (
    EXECUTION_MARGIN,
    LinkOptions,
    acting,
    controller_parameters,
    link_options,
    prediction_error_deg,
)


def test_the_execution_delay_covers_the_link_and_a_margin():
    assert link_options(argparse.Namespace(link_delay=None)) is None
    link = link_options(argparse.Namespace(link_delay=3.0, link_jitter=0.2, link_loss=0.01))
    assert link == LinkOptions(3.0, 0.2, 0.01)
    assert link.execution_delay == pytest.approx(3.2 + EXECUTION_MARGIN)
    parameters = controller_parameters(link, lead=0.04)
    assert parameters["execution_delay"] == link.execution_delay
    assert parameters["future_tolerance"] == pytest.approx(0.04 + EXECUTION_MARGIN)


def test_twists_are_stamped_when_they_act():
    log = TopicLog("/ground/cmd_twist", TwistStamped)
    msg = TwistStamped()
    msg.header.stamp = stamp_from_seconds(10.25)
    msg.twist.angular.z = 0.1
    log.messages = [msg]
    moved = acting(log, 3.05).messages[0]
    assert moved.header.stamp.sec + 1e-9 * moved.header.stamp.nanosec == pytest.approx(13.3)
    assert moved.twist.angular.z == 0.1
    assert log.messages[0].header.stamp.sec == 10  # the recording itself is left alone


def _logs(robot, samples) -> dict[str, TopicLog]:
    """joint_states and base_odom logs of (time [s], theta (n,), base quaternion xyzw)."""
    joints, odom = TopicLog("joint_states", JointState), TopicLog("base_odom", Odometry)
    for t, theta, quaternion in samples:
        js = JointState(name=list(robot.joint_names), position=list(theta))
        js.header.stamp = stamp_from_seconds(t)
        pose = Odometry()
        pose.header.stamp = stamp_from_seconds(t)
        o = pose.pose.pose.orientation
        o.x, o.y, o.z, o.w = quaternion
        joints.messages.append(js)
        odom.messages.append(pose)
    return {"joints": joints, "odom": odom}


def test_the_prediction_error_is_the_camera_angle_at_shared_stamps(robot):
    theta = robot.initial_theta
    level = (0.0, 0.0, 0.0, 1.0)
    turned = tuple(pin.Quaternion(pin.utils.rpyToMatrix(0.0, 0.0, math.radians(0.5))).coeffs())
    measured = _logs(robot, [(1.0, theta, level), (1.01, theta, level), (1.02, theta, level)])
    # the prediction sums its periods: 1.0100000000001 is the sample of 1.01
    predicted = _logs(
        robot, [(1.0, theta, level), (1.0100000000001, theta, turned), (5.0, theta, turned)]
    )
    # the base turned 0.5 deg about z in the prediction: the camera with it
    assert prediction_error_deg(robot, predicted, measured, 0.0, 2.0) == pytest.approx(0.5)
    assert prediction_error_deg(robot, predicted, measured, 0.0, 1.005) == pytest.approx(0.0)
    assert math.isnan(prediction_error_deg(robot, predicted, measured, 3.0, 6.0))
