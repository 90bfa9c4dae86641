"""Parameters of rns_force_controller (:mod:`rns_ros.nodes.force_controller`); mirrored in
config/force_controller.yaml."""

from __future__ import annotations

from rns_ros.control.force.settings import (
    CommandFrame,
    ConstrainedFrame,
    ControlMethod,
    ForceMeasurementMode,
    NormalMode,
)
from rns_ros.control.motion_force.osc import OscVariant
from rns_ros.nodes.parameters import (
    CLOCK_TIMEOUT,
    WORLD_FRAME,
    ParameterSpec,
    choices_of,
    specs_by_name,
)

NODE_NAME = "rns_force_controller"
SUMMARY = (
    "Motion/force control of a fixed-base arm in contact (RNS-C or OS-C): twist + force setpoint "
    "in, joint torques out."
)
#: Default model file (config/): the 7-DoF LWR4-class arm of section 6.2.2.
DEFAULT_MODEL = "lwr_7dof.yaml"


def _timeout(name: str, default: float, what: str) -> ParameterSpec:
    return ParameterSpec(name, default, what, "[s]", 1e-3, 60.0)


PARAMETERS = (
    ParameterSpec(
        "model_config",
        "",
        f"Fixed-base model YAML: a path, or a file name in config/; empty: {DEFAULT_MODEL}",
    ),
    ParameterSpec(
        "method",
        ControlMethod.RNS.value,
        "rns: RNS-C closed form (6.17); os: OS-C (6.13)",
        choices=choices_of(ControlMethod),
    ),
    ParameterSpec(
        "os_variant",
        OscVariant.LITERAL.value,
        "OS-C variant [A-4.2]: literal (6.13) with tau_a = 0, or kinematic",
        choices=choices_of(OscVariant),
    ),
    ParameterSpec("k_p", 100.0, "Motion-loop position gain of (6.33)", "[1/s^2]", 0.0, 1e5),
    ParameterSpec("k_d", 10.0, "Motion-loop velocity gain of (6.33)", "[1/s]", 0.0, 1e4),
    ParameterSpec(
        "k_f",
        5.0,
        "Force-loop gain of (6.34) (thesis 5; sampled force measurement needs < 1)",
        "[-]",
        0.0,
        100.0,
    ),
    ParameterSpec(
        "virtual_mass", 1.0e5, "RNS-C virtual link mass m_hat [A-4.9]", "[kg]", 1e-3, 1e12
    ),
    ParameterSpec(
        "virtual_inertia",
        0.0,
        "RNS-C virtual link inertia I_hat (times E); 0: m_hat/12 [A-4.9]",
        "[kg m^2]",
        0.0,
        1e12,
    ),
    ParameterSpec(
        "task_axes",
        ["x", "y", "z", "wx", "wy", "wz"],
        "Task rows of J_e by world axis (x y z wx wy wz); the planar arc: x, y",
    ),
    ParameterSpec(
        "constrained_frame",
        ConstrainedFrame.EE.value,
        "Axes of constrained_axis: ee (taken at activation, then fixed in world) or world",
        choices=choices_of(ConstrainedFrame),
    ),
    ParameterSpec(
        "constrained_axis",
        [0.0, 0.0, 1.0],
        "Contact normal into the environment (normal_mode fixed; the start normal for wrench)",
        "[-]",
        -1.0e3,
        1.0e3,
        length=(3,),
    ),
    ParameterSpec(
        "normal_mode",
        NormalMode.FIXED.value,
        "fixed: n = constrained_axis (a plane); wrench: the measured force direction while "
        "|f| >= contact_threshold",
        choices=choices_of(NormalMode),
    ),
    ParameterSpec(
        "surface_curvature",
        0.0,
        "Normal feed-forward a_n = curvature |v_t|^2 [A-4.8]; > 0: the surface bends toward the "
        "environment; 0: a plane",
        "[1/m]",
        -1e3,
        1e3,
    ),
    ParameterSpec(
        "force_measurement",
        ForceMeasurementMode.PREDICTED.value,
        "f in (6.34): predicted (rigid-contact model, sensor-corrected) or sampled (the "
        "one-step-late wrench; k_f < 1 only)",
        choices=choices_of(ForceMeasurementMode),
    ),
    ParameterSpec(
        "joints",
        [f"joint_{i}" for i in range(1, 8)],
        "Joint order of joint_efforts: a permutation of the model's joints",
    ),
    WORLD_FRAME,
    ParameterSpec(
        "default_twist_frame",
        CommandFrame.EE.value,
        "Axes of a cmd_twist with an empty frame_id: ee or world",
        choices=choices_of(CommandFrame),
    ),
    _timeout(
        "command_timeout",
        0.5,
        "A cmd_twist older than this (receipt) decelerates to rest; await_commands: longest wait "
        "(wall)",
    ),
    _timeout("force_timeout", 0.5, "A force_setpoint older than this: f_des held, status WARN"),
    ParameterSpec(
        "state_timeout",
        0.1,
        "No joint_states for this long (receipt; sim time under use_sim_time): one zero torque, "
        "STALE_STATE",
        "[s]",
        0.005,
        10.0,
    ),
    CLOCK_TIMEOUT,
    ParameterSpec(
        "await_commands",
        False,
        "use_sim_time only: each step waits for the cmd_twist and force_setpoint in force at its "
        "state's stamp",
    ),
    ParameterSpec(
        "max_linear_speed", 0.5, "Twists faster than this are scaled down", "[m/s]", 1e-6, 10.0
    ),
    ParameterSpec(
        "max_angular_speed", 1.0, "Twists faster than this are scaled down", "[rad/s]", 1e-6, 20.0
    ),
    ParameterSpec(
        "max_linear_acceleration",
        5.0,
        "Clip of the twist feed-forward and rate limit of the reference (angular: same ramp time)",
        "[m/s^2]",
        1e-6,
        1e3,
    ),
    ParameterSpec("max_force_setpoint", 30.0, "f_des is clipped to [0, this]", "[N]", 0.0, 1e4),
    ParameterSpec(
        "max_contact_force",
        40.0,
        "Measured |force| over this: WRENCH_LIMIT stop (latched)",
        "[N]",
        1e-6,
        1e5,
    ),
    ParameterSpec(
        "max_contact_torque",
        10.0,
        "Measured |torque| over this: WRENCH_LIMIT stop (latched)",
        "[N m]",
        1e-6,
        1e5,
    ),
    ParameterSpec(
        "contact_threshold",
        1.0,
        "In contact when the measured normal force is at least this",
        "[N]",
        1e-6,
        1e4,
    ),
    ParameterSpec(
        "contact_loss_time",
        0.02,
        "Force below contact_threshold this long while f_des >= 2 thresholds: CONTACT_LOST / "
        "NO_CONTACT stop (latched)",
        "[s]",
        0.0,
        10.0,
    ),
    ParameterSpec(
        "wrench_timeout",
        0.05,
        "No wrist_wrench stamped within this of the state while the force task is on: the push "
        "pauses, WRENCH_STALE",
        "[s]",
        1e-4,
        10.0,
    ),
    ParameterSpec("status_rate", 50.0, "Rate of ~/status", "[Hz]", 0.1, 1000.0),
)
SPECS = specs_by_name(PARAMETERS)


def await_commands_problem(await_commands: bool, use_sim_time: bool) -> str | None:
    """Why ``await_commands`` cannot be on with this ``use_sim_time``, or None when it can.

    The steps wait for commands stamped ahead of the simulated clock (a scripted operator's
    ``lead``), which only a simulation in lockstep can wait for: on the wall clock the arm would
    be left without torques while the operator's next sample is on its way.
    """
    if await_commands and not use_sim_time:
        return (
            "await_commands needs use_sim_time: true (the steps wait for commands stamped ahead "
            "of the simulated clock; on the wall clock commands act on receipt)"
        )
    return None
