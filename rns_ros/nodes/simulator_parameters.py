"""Parameters of rns_simulator (the free-floating modes), and the specs its contact mode shares
(:mod:`rns_ros.nodes.contact_simulator_parameters`). Mirrored in config/simulator.yaml."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace

from rcl_interfaces.msg import SetParametersResult
from rclpy.parameter import Parameter

from rns_ros.core.errors import ConfigError
from rns_ros.nodes.parameters import (
    JOINTS,
    MODEL_CONFIG,
    WORLD_FRAME,
    ParameterSpec,
    specs_by_name,
)
from rns_ros.nodes.realtime import thread_priority_spec
from rns_ros.sim.free_floating import SimulationMode

NODE_NAME = "rns_simulator"
SUMMARY = (
    "Free-floating space robot simulator (kinematic or dynamic mode, fixed-step RK4); "
    "contact mode: below."
)
#: ``mode`` of the contact simulator (rns_ros.nodes.contact_simulator).
CONTACT_MODE = "contact"
#: Thesis satellite-observation configuration [-90 -30 0 -70 180 -30 0] deg [rad].
SATELLITE_OBSERVATION_RAD = [math.radians(a) for a in (-90.0, -30.0, 0.0, -70.0, 180.0, -30.0, 0.0)]

# --- specs both modes declare (the contact mode changes defaults and bounds) -------------------
MODE = ParameterSpec(
    "mode",
    SimulationMode.KINEMATIC.value,
    "kinematic: joints follow velocities exactly; dynamic: ABA + joint servo; contact: the Part "
    "II arm (below)",
    choices=(*(mode.value for mode in SimulationMode), CONTACT_MODE),
)
STEP_SIZE = ParameterSpec("step_size", 0.001, "Fixed RK4 integration step", "[s]", 1e-5, 0.1)
PUBLISH_RATE = ParameterSpec(
    "publish_rate", 100.0, "State publishing rate in simulated time", "[Hz]", 1.0, 1000.0
)
REAL_TIME_FACTOR = ParameterSpec(
    "real_time_factor",
    1.0,
    "Simulated seconds per wall-clock second; 0 runs as fast as possible",
    "[-]",
    0.0,
    1000.0,
    read_only=False,
)
INITIAL_JOINT_POSITIONS = ParameterSpec(
    "initial_joint_positions",
    SATELLITE_OBSERVATION_RAD,
    "Initial joint angles in model joint order (default: thesis satellite observation)",
    "[rad]",
    -2 * math.pi,
    2 * math.pi,
)
PUBLISH_CLOCK = ParameterSpec(
    "publish_clock", False, "Publish /clock (sim time) and stamp messages with it"
)
LOCKSTEP_PERIOD = ParameterSpec(
    "lockstep_period",
    0.0,
    "Lockstep: run at most this much simulated time past the newest command; 0: off",
    "[s]",
    0.0,
    10.0,
)

PARAMETERS = (
    MODEL_CONFIG,
    MODE,
    STEP_SIZE,
    PUBLISH_RATE,
    REAL_TIME_FACTOR,
    thread_priority_spec(50, "when real_time_factor > 0 at start-up"),
    INITIAL_JOINT_POSITIONS,
    ParameterSpec(
        "initial_base_position",
        [0.0, 0.0, 0.0],
        "Initial base CoM position in world",
        "[m]",
        -1e6,
        1e6,
        length=(3,),
    ),
    ParameterSpec(
        "initial_base_orientation",
        [0.0, 0.0, 0.0, 1.0],
        "Initial base attitude quaternion x y z w (normalized on use)",
        "[-]",
        -1.0,
        1.0,
        length=(4,),
    ),
    ParameterSpec(
        "initial_momentum",
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        "Conserved momentum [p; l] about the system CoM, world axes",
        "[kg m/s, kg m^2/s]",
        -1e6,
        1e6,
        length=(6,),
    ),
    ParameterSpec(
        "command_interface",
        "trajectory",
        "trajectory: JointTrajectory on joint_references; velocity: Float64MultiArray on "
        "joint_velocities",
        choices=("trajectory", "velocity"),
    ),
    JOINTS,
    ParameterSpec(
        "command_timeout",
        0.5,
        "A command older than this (receipt time; lockstep: sim time, and wall time while "
        "paused) is dropped, joints stop",
        "[s]",
        0.01,
        60.0,
        read_only=False,
    ),
    replace(
        PUBLISH_CLOCK,
        description=f"{PUBLISH_CLOCK.description}: every step; in lockstep with each state only",
    ),
    LOCKSTEP_PERIOD,
    WORLD_FRAME,
    ParameterSpec(
        "publish_tf",
        True,
        "Publish /tf and /tf_static as robot_state_publisher would (false beside one)",
    ),
    ParameterSpec(
        "servo_natural_frequency",
        50.0,
        "Dynamic-mode joint servo bandwidth omega_n",
        "[rad/s]",
        1.0,
        1000.0,
    ),
    ParameterSpec(
        "servo_damping_ratio", 1.0, "Dynamic-mode joint servo damping ratio", "[-]", 0.1, 10.0
    ),
    ParameterSpec(
        "joint_friction",
        0.0,
        "Viscous joint friction in the dynamic plant",
        "[N m s/rad]",
        0.0,
        1e4,
    ),
    ParameterSpec(
        "catch_up_late_commands",
        True,
        "Kinematic mode: a JointTrajectory acts from its header stamp (up to 50 ms late or early); "
        "false: from its receipt",
    ),
    ParameterSpec(
        "max_reference_error",
        0.25,
        "A JointTrajectory position farther than this from the current joint angle is rejected",
        "[rad]",
        0.01,
        10.0,
    ),
    ParameterSpec(
        "energy_rate",
        20.0,
        "Rate of the energy topic and its running C_max / C_sum (sampled with the state); 0: off",
        "[Hz]",
        0.0,
        1000.0,
    ),
    ParameterSpec(
        "reaction_wheels",
        False,
        "Three reaction wheels on the base (spin axes base x, y, z): wheel_torque in, "
        "wheel_states out",
    ),
    ParameterSpec(
        "wheel_inertia",
        0.11,
        "Spin inertia I_r of one wheel (also the I_r of the energy metric Lambda_r)",
        "[kg m^2]",
        1e-6,
        1e3,
    ),
    ParameterSpec(
        "wheel_torque_limit", 0.1, "Motor torque limit per wheel (ETS-VII: 0.1)", "[N m]", 1e-6, 1e3
    ),
    ParameterSpec(
        "wheel_speed_limit",
        200.0 * math.pi,
        "Spin-rate limit per wheel, relative to the base (6000 rpm)",
        "[rad/s]",
        1e-3,
        1e5,
    ),
    ParameterSpec(
        "reset_hold",
        0.2,
        "After ~/reset, joint commands are ignored for this long (simulated time): controllers "
        "see the reset state first",
        "[s]",
        0.0,
        10.0,
    ),
)
SPECS = specs_by_name(PARAMETERS)


def check_parameter_changes(
    specs: Mapping[str, ParameterSpec], parameters: Sequence[Parameter]
) -> SetParametersResult:
    """The on-set verdict on run-time changes: rejected (with the reason) when a spec's check
    fails; rclpy has applied the descriptors (read-only, ranges) before."""
    for parameter in parameters:
        spec = specs.get(parameter.name)
        if spec is None:
            continue
        try:
            spec.check(parameter.value)
        except ConfigError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
    return SetParametersResult(successful=True)
