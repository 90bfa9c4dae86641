"""Messages of every type a session records (the simulator's, the controller's, the robot
model's), and a field-by-field comparison with what another library decoded from their bytes."""

from __future__ import annotations

import math

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import TransformStamped, TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, String
from tf2_msgs.msg import TFMessage


def _stamped(msg, k: int):
    msg.header.stamp.sec, msg.header.stamp.nanosec = 1000 + k, 7 * k
    return msg


def joint_state(names: list[str], k: int = 0) -> JointState:
    n = len(names)
    msg = JointState(
        name=names,
        position=[0.1 * k + i for i in range(n)],
        velocity=[-0.5 * i for i in range(n)],
        effort=[] if k % 2 else [1e-3 * i for i in range(n)],
    )
    msg.header.frame_id = "world"[: k % 6]
    return _stamped(msg, k)


def sample_messages() -> dict[str, list]:
    """topic -> messages, each topic's of one type; names and strings of many lengths, so the
    CDR padding before the float64 sequences takes every value."""
    joint_names = [[f"joint_{i}" for i in range(1, 8)], ["a"], ["ab", "abc"], [], ["wheel_x"] * 3]
    odom = Odometry(child_frame_id="base_link")
    odom.header.frame_id = "world"
    odom.pose.pose.orientation.z, odom.pose.pose.orientation.w = 0.6, 0.8
    odom.pose.covariance[7] = 0.25
    odom.twist.twist.angular.x = -0.125
    transforms = [
        TransformStamped(child_frame_id=name)
        for name in ("link_1", "link_22", "camera_optical_frame")
    ]
    for i, transform in enumerate(transforms):
        transform.header.frame_id = "base_link"
        transform.transform.translation.x = 0.5 * i
        transform.transform.rotation.w = 1.0
    status = DiagnosticArray(
        status=[
            DiagnosticStatus(
                level=b"\x01", name="rns_controller", message="ok",
                values=[KeyValue(key="state", value="RUNNING"),
                        KeyValue(key="sigma_min", value="0.28")],
            ),
            DiagnosticStatus(name="x"),
        ]
    )  # fmt: skip
    twist = TwistStamped()
    twist.twist.angular.z = -0.1
    wrench = WrenchStamped()
    wrench.wrench.force.y = 3.5
    energy = Float64MultiArray(data=[0.5, 1.5, 2.5])
    energy.layout.dim = [MultiArrayDimension(label="terms", size=3, stride=3)]
    return {
        "/joint_states": [joint_state(names, k) for k, names in enumerate(joint_names * 2)],
        "/base_odom": [_stamped(odom, k) for k in range(3)],
        "/tf": [TFMessage(transforms=transforms[: k + 1]) for k in range(3)],
        "/tf_static": [TFMessage(transforms=transforms), TFMessage()],
        "/robot_description": [String(data="<robot name='rns'/>"), String(data="")],
        "/rns_controller/status": [status, DiagnosticArray()],
        "/cmd_twist": [_stamped(twist, k) for k in range(2)],
        "/momentum": [_stamped(wrench, 0)],
        "/energy": [energy, Float64MultiArray()],
    }


def type_name(msg) -> str:
    return f"{type(msg).__module__.split('.')[0]}/msg/{type(msg).__name__}"


def same_fields(ours, theirs, where: str = "") -> None:
    """Assert that ``theirs`` (another library's decoded message: attributes, numpy arrays,
    lists) holds every field value of the rclpy message ``ours``."""
    if hasattr(ours, "get_fields_and_field_types"):
        for name in ours.get_fields_and_field_types():
            same_fields(getattr(ours, name), getattr(theirs, name), f"{where}.{name}")
        return
    if isinstance(ours, bytes | bytearray) and len(ours) == 1:  # a byte field
        ours = ours[0]
    if isinstance(ours, str | int | float | bool):
        if isinstance(theirs, bytes | bytearray) and len(theirs) == 1:
            theirs = theirs[0]
        if isinstance(ours, float):
            assert math.isclose(ours, float(theirs), rel_tol=0, abs_tol=0), where
        else:
            assert ours == theirs, f"{where}: {ours!r} != {theirs!r}"
        return
    ours, theirs = list(ours), list(theirs)
    assert len(ours) == len(theirs), f"{where}: {len(ours)} != {len(theirs)} elements"
    for index, (a, b) in enumerate(zip(ours, theirs, strict=True)):
        same_fields(a, b, f"{where}[{index}]")
