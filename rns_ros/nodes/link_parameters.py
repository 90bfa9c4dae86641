"""Parameters of rns_link (:mod:`rns_ros.nodes.link`); mirrored in config/link.yaml."""

from __future__ import annotations

from rns_ros.cli import DDS_MAX_DOMAIN_ID
from rns_ros.ground.link import MAX_DELAY_S
from rns_ros.nodes.parameters import ParameterSpec, specs_by_name

NODE_NAME = "rns_link"
SUMMARY = (
    "A simulated space link: carries topics between the ground's namespace and the "
    "spacecraft's with delay, jitter, loss, a bandwidth cap and scheduled outages."
)
#: Most topics per direction.
MAX_TOPICS = 16


def _direction(name: str, topics: list[str], towards: str) -> tuple[ParameterSpec, ...]:
    return (
        ParameterSpec(
            f"{name}_topics",
            topics,
            f"Topics carried {towards}, each 'topic:package/msg/Type' (at most {MAX_TOPICS})",
        ),
        ParameterSpec(f"{name}_delay", 0.0, f"One-way delay {towards}", "[s]", 0.0, MAX_DELAY_S),
        ParameterSpec(
            f"{name}_jitter",
            0.0,
            f"Extra delay {towards}, uniform in [0, jitter) per message (order kept)",
            "[s]",
            0.0,
            MAX_DELAY_S,
        ),
        ParameterSpec(
            f"{name}_loss", 0.0, f"Probability that a message {towards} is lost", "[-]", 0.0, 0.99
        ),
        ParameterSpec(
            f"{name}_bandwidth",
            0.0,
            f"Bytes per second {towards}; 0: no cap",
            "[B/s]",
            0.0,
            1e9,
        ),
    )


PARAMETERS = (
    ParameterSpec(
        "ground_namespace",
        "ground",
        "The ground's side: /<ground_namespace>/<topic>; the spacecraft's: the node's namespace",
    ),
    ParameterSpec(
        "ground_domain_id",
        -1,
        "The ground's side on this ROS domain (its own, as a ground station's network); "
        "-1: the node's domain",
        "[-]",
        -1,
        DDS_MAX_DOMAIN_ID,
    ),
    *_direction(
        "uplink",
        [
            "cmd_twist:geometry_msgs/msg/TwistStamped",
            "rns_controller/camera_goal:geometry_msgs/msg/PoseStamped",
            "ptp_goal:sensor_msgs/msg/JointState",
        ],
        "ground to spacecraft",
    ),
    *_direction(
        "downlink",
        [
            "joint_states:sensor_msgs/msg/JointState",
            "base_odom:nav_msgs/msg/Odometry",
            "rns_controller/status:diagnostic_msgs/msg/DiagnosticArray",
            "rns_controller/camera_goal_reached:geometry_msgs/msg/PoseStamped",
            "rns_ptp/status:diagnostic_msgs/msg/DiagnosticArray",
        ],
        "spacecraft to ground",
    ),
    ParameterSpec(
        "outages",
        "",
        "Loss of contact, both ways: 'start:end' [s] on the node clock, comma separated "
        "(e.g. '10:12,30:31.5')",
    ),
    ParameterSpec("seed", 0, "Seed of the loss and jitter draws", "[-]", 0, 2**31 - 1),
    ParameterSpec(
        "release_period",
        0.002,
        "How often messages that are due are handed on (their delivery is late by up to this)",
        "[s]",
        1e-4,
        0.1,
    ),
    ParameterSpec(
        "max_in_flight",
        100000,
        "Messages in flight per direction; more are refused and counted (a flood)",
        "[-]",
        100,
        10_000_000,
    ),
    ParameterSpec(
        "max_message_size",
        1_000_000,
        "Larger messages are refused and counted",
        "[B]",
        100,
        100_000_000,
    ),
    ParameterSpec("status_period", 1.0, "Period of ~/status", "[s]", 0.01, 60.0),
)
SPECS = specs_by_name(PARAMETERS)
