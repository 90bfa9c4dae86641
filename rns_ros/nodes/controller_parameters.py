"""Parameters of rns_controller (mirrored in config/controller.yaml), and the control objects
they configure."""

from __future__ import annotations

from rns_ros.control.camera_law import ControlGains, Method
from rns_ros.control.command_tracking import TrackingSettings
from rns_ros.control.controller import ControllerSettings, HoldCorrection, TwistFrame
from rns_ros.control.teleop import CommandGate, resolve_twist_frame
from rns_ros.control.time_tags import MAX_EXECUTION_DELAY_S, TimeTags
from rns_ros.core.validation import Choice
from rns_ros.nodes.parameters import (
    CLOCK_TIMEOUT,
    JOINTS,
    MAX_CLOCK_JUMP,
    MAX_REFERENCE_ERROR,
    MODEL_CONFIG,
    OUTPUT_INTERFACE,
    WORLD_FRAME,
    ParameterSpec,
    specs_by_name,
)
from rns_ros.nodes.realtime import thread_priority_spec

NODE_NAME = "rns_controller"
SUMMARY = "Reactionless camera-pointing controller: twist in, joint references out (DLS / SC)."
#: Output timing [s] of a plant that acts on a JointTrajectory from its stamp (rns_simulator, a
#: joint trajectory controller): neither latency nor update grid. A plant acting on receipt
#: (the velocity interface) needs its DDS latency and its update period (rns_simulator: step).
DEFAULT_OUTPUT_LATENCY = 0.0
DEFAULT_PLANT_PERIOD = 0.0


def _choices(enum: type[Choice], default: Choice) -> tuple[str, ...]:
    """The values of ``enum``, ``default`` first (as ``--help`` and error messages list them)."""
    return (default.value, *(member.value for member in enum if member is not default))


PARAMETERS = (
    MODEL_CONFIG,
    thread_priority_spec(40, "on the wall clock (use_sim_time false)"),
    ParameterSpec(
        "method",
        Method.DLS.value,
        "Singularity handling: dls (4.10-4.12), sc (4.13-4.15), pinv (4.9), conventional "
        "(4.7-4.8, disturbs the base)",
        choices=_choices(Method, Method.DLS),
        read_only=False,
    ),
    ParameterSpec(
        "epsilon",
        0.2,
        "DLS singular region: damping starts below this sigma_min of J-bar",
        "[-]",
        1e-6,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "lambda2_max",
        2.0,
        "DLS maximum damping lambda^2_max",
        "[-]",
        1e-6,
        100.0,
        read_only=False,
    ),
    ParameterSpec(
        "sc_gain",
        1.7,
        "Singularity-Consistent gain b of eq. (4.13)",
        "[-]",
        1e-3,
        100.0,
        read_only=False,
    ),
    ParameterSpec(
        "wrist_gain",
        100.0,
        "Wrist-position stabilization gain k_g of eq. (4.5); 0 disables",
        "[1/(m s)]",
        0.0,
        1e4,
        read_only=False,
    ),
    ParameterSpec("rate", 100.0, "Control rate (output period)", "[Hz]", 1.0, 1000.0),
    ParameterSpec(
        "hold_correction",
        HoldCorrection.MIDPOINT.value,
        "midpoint: law at the predicted mid-period configuration (reactionless over the hold); "
        "naive: at the sample",
        choices=_choices(HoldCorrection, HoldCorrection.MIDPOINT),
        read_only=False,
    ),
    ParameterSpec(
        "hold_iterations", 1, "Midpoint predictions per period", "[-]", 1, 5, read_only=False
    ),
    ParameterSpec(
        "max_angular_speed",
        1.0,
        "A command with a larger |angular| is scaled down to it, axis kept (SPEED_LIMITED); "
        "NaN/Inf are rejected",
        "[rad/s]",
        1e-3,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "command_timeout",
        0.5,
        "A command older than this (by receipt time) decelerates to zero",
        "[s]",
        0.01,
        60.0,
        read_only=False,
    ),
    ParameterSpec(
        "stop_deceleration",
        1.0,
        "Angular deceleration of the command when stale or rejected",
        "[rad/s^2]",
        1e-3,
        1000.0,
        read_only=False,
    ),
    ParameterSpec(
        "start_acceleration",
        1.0,
        "Angular acceleration of the command from rest (first command, after a stop, a state "
        "fault or a restart)",
        "[rad/s^2]",
        1e-3,
        1000.0,
        read_only=False,
    ),
    ParameterSpec(
        "state_hold_age",
        0.1,
        "joint_states or base_odom older than this hold the arm (STATE_GAP); also the "
        "longest own stall ridden",
        "[s]",
        0.005,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "state_timeout",
        0.25,
        "joint_states or base_odom older than this: STALE_STATE (error), the arm held",
        "[s]",
        0.005,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "state_jump_tolerance",
        0.05,
        "A joint angle this far from its prediction is a discontinuity: the reference restarts "
        "there, the command ramps up",
        "[rad]",
        1e-4,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "immediate_reaction",
        True,
        "Serve a changed command at once and restart the period, not at the next tick (wall "
        "clock only)",
    ),
    ParameterSpec(
        "predict_state",
        True,
        "Extrapolate joint_states to when the output takes effect, held until the next tick; "
        "false: the sample as it is",
    ),
    ParameterSpec(
        "output_latency",
        DEFAULT_OUTPUT_LATENCY,
        "Publish-to-receipt time at a plant acting on receipt (velocity interface), for "
        "predict_state; wall clock only",
        "[s]",
        0.0,
        0.05,
        read_only=False,
    ),
    ParameterSpec(
        "output_lead",
        0.0,
        "Under use_sim_time: stamp each output this long after its tick (lockstep side by side); "
        "0: acts from its tick",
        "[s]",
        0.0,
        0.1,
    ),
    ParameterSpec(
        "plant_period",
        DEFAULT_PLANT_PERIOD,
        "Update period of a plant acting on receipt, on a grid through the joint_states stamps; "
        "0: acts at once",
        "[s]",
        0.0,
        0.1,
        read_only=False,
    ),
    ParameterSpec(
        "await_commands",
        False,
        "With use_sim_time, output_lead and twist_stamped: twists act at their stamps, ticks wait "
        "for the twist in force",
    ),
    ParameterSpec(
        "await_timeout",
        0.5,
        "With await_commands: wall time a tick waits for the next twist after a moving one, "
        "then served with the newest",
        "[s]",
        0.01,
        60.0,
    ),
    ParameterSpec("twist_stamped", True, "cmd_twist is TwistStamped (false: plain Twist)"),
    ParameterSpec(
        "execution_delay",
        0.0,
        "Time-tagged twists (a delayed link): a twist stamped t acts at t + this; 0: on arrival",
        "[s]",
        0.0,
        MAX_EXECUTION_DELAY_S,
    ),
    ParameterSpec(
        "late_tolerance",
        0.5,
        "execution_delay > 0: a twist received more than this after t + execution_delay is refused",
        "[s]",
        1e-3,
        60.0,
    ),
    ParameterSpec(
        "future_tolerance",
        0.05,
        "execution_delay > 0: a twist stamped more than this ahead of the node clock is refused",
        "[s]",
        1e-3,
        60.0,
    ),
    ParameterSpec(
        "default_twist_frame",
        TwistFrame.CAMERA.value,
        "Axes of unstamped or frame-less commands: world, base, camera, or the world_frame, "
        "base link or camera frame name",
    ),
    ParameterSpec(
        "goal_gain",
        2.0,
        "~/camera_goal: orientation error feedback gain k (omega = k e, the error decays as "
        "exp(-k t))",
        "[1/s]",
        0.01,
        50.0,
        read_only=False,
    ),
    ParameterSpec(
        "goal_max_speed",
        0.3,
        "~/camera_goal: largest camera speed commanded toward a goal (also <= max_angular_speed)",
        "[rad/s]",
        1e-3,
        10.0,
        read_only=False,
    ),
    ParameterSpec(
        "goal_tolerance",
        1e-3,
        "~/camera_goal: the goal is reached once the camera is within this angle of it",
        "[rad]",
        1e-6,
        0.5,
        read_only=False,
    ),
    ParameterSpec(
        "tracking_gain",
        TrackingSettings.gain,
        "The camera follows the integral of the commanded rate over the command stamps: "
        "correction k e toward it; 0: off",
        "[1/s]",
        0.0,
        20.0,
        read_only=False,
    ),
    ParameterSpec(
        "tracking_max_correction",
        TrackingSettings.max_correction,
        "Largest correction rate toward the commanded camera attitude",
        "[rad/s]",
        1e-4,
        1.0,
        read_only=False,
    ),
    ParameterSpec(
        "tracking_max_error",
        TrackingSettings.max_error,
        "A larger gap to the commanded attitude (joint limit, singular region) restarts it at "
        "the camera",
        "[rad]",
        1e-3,
        3.14,
        read_only=False,
    ),
    CLOCK_TIMEOUT,
    MAX_CLOCK_JUMP,
    MAX_REFERENCE_ERROR,
    OUTPUT_INTERFACE,
    JOINTS,
    WORLD_FRAME,
)
SPECS = specs_by_name(PARAMETERS)


def controller_settings(params: dict) -> ControllerSettings:
    """The law's settings from the parameter values ``params`` (name -> value).

    Raises:
        ConfigError: a value the settings reject.
    """
    return ControllerSettings(
        method=params["method"],
        gains=ControlGains(
            epsilon=params["epsilon"],
            lambda2_max=params["lambda2_max"],
            sc_gain=params["sc_gain"],
            wrist_gain=params["wrist_gain"],
        ),
        period=1.0 / params["rate"],
        hold_correction=params["hold_correction"],
        hold_iterations=params["hold_iterations"],
    )


def time_tags(params: dict) -> TimeTags | None:
    """The time tags of ``execution_delay`` > 0 (None: twists act on arrival)."""
    if params["execution_delay"] == 0.0:
        return None
    return TimeTags(params["execution_delay"], params["late_tolerance"], params["future_tolerance"])


def command_gate(params: dict, frames: dict[str, TwistFrame]) -> CommandGate:
    """The command gate from the parameter values ``params``; ``frames``: frame id -> axes.

    Raises:
        ConfigError: a value the gate rejects, or an unknown default_twist_frame.
    """
    return CommandGate(
        params["command_timeout"],
        params["stop_deceleration"],
        resolve_twist_frame(params["default_twist_frame"], frames, "default_twist_frame"),
        acceleration=params["start_acceleration"],
    )


def tracking_settings(params: dict) -> TrackingSettings:
    """The commanded-attitude tracking from the parameter values ``params``; a command counts
    for at most ``command_timeout``.

    Raises:
        ConfigError: a value the settings reject.
    """
    return TrackingSettings(
        gain=params["tracking_gain"],
        max_correction=params["tracking_max_correction"],
        max_error=params["tracking_max_error"],
        max_interval=params["command_timeout"],
    )


__all__ = [
    "NODE_NAME",
    "PARAMETERS",
    "SPECS",
    "SUMMARY",
    "command_gate",
    "controller_settings",
    "time_tags",
    "tracking_settings",
]
