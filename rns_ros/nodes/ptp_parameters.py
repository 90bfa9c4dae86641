"""Parameters of rns_ptp (:mod:`rns_ros.nodes.ptp`); mirrored in config/ptp.yaml."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace

from rns_ros.control.ptp import PtpMethod
from rns_ros.core.errors import ConfigError
from rns_ros.nodes.parameters import (
    CLOCK_TIMEOUT,
    JOINTS,
    MAX_CLOCK_JUMP,
    MAX_REFERENCE_ERROR,
    MODEL_CONFIG,
    OUTPUT_INTERFACE,
    WORLD_FRAME,
    ParameterSpec,
    choices_of,
    specs_by_name,
)
from rns_ros.nodes.realtime import thread_priority_spec

NODE_NAME = "rns_ptp"
SUMMARY = "Reactionless point-to-point motion: joint goal in, planned joint references out."

PARAMETERS = (
    MODEL_CONFIG,
    thread_priority_spec(40, "on the wall clock (use_sim_time false)"),
    ParameterSpec(
        "method",
        PtpMethod.THREE_PHASE.value,
        "Planner of joint goals: three_phase, joint_space (JS-C), inverse_jacobian (IJ-C), "
        "transposed_jacobian (TJ-C)",
        choices=choices_of(PtpMethod, without=(PtpMethod.DEPLOY,)),  # DEPLOY: goal ['deploy']
    ),
    ParameterSpec(
        "duration",
        30.0,
        "Planned duration of a joint_space / inverse_jacobian / transposed_jacobian motion "
        "(stretched to the velocity limits)",
        "[s]",
        0.1,
        3600.0,
    ),
    ParameterSpec(
        "phase_durations",
        [5.0, 20.0, 5.0],
        "Planned durations of the three_phase phases I, II, III (the planner may stretch them)",
        "[s]",
        0.01,
        3600.0,
        length=(3,),
    ),
    ParameterSpec(
        "deploy_duration",
        30.0,
        "Planned duration of the full deployment (goal ['deploy'])",
        "[s]",
        0.1,
        3600.0,
    ),
    ParameterSpec("rate", 100.0, "Output rate (playback period)", "[Hz]", 1.0, 1000.0),
    ParameterSpec(
        "state_timeout",
        0.25,
        "joint_states (base_odom once arrived) older than this by receipt time: zero velocity, "
        "plan held (HOLDING)",
        "[s]",
        0.005,
        10.0,
    ),
    ParameterSpec(
        "state_loss_timeout",
        3.0,
        "No fresh joint_states / base_odom this long: the input is lost, STALE_STATE, the plan "
        "abandoned (>= state_timeout)",
        "[s]",
        0.005,
        600.0,
    ),
    ParameterSpec(
        "resume_tolerance",
        0.005,
        "After a hold the plan resumes if every joint is this close to the plan's sample "
        "nearest the arm, else replanned",
        "[rad]",
        1e-6,
        1.0,
    ),
    ParameterSpec(
        "resume_acceleration",
        2.0,
        "After a hold the playback rate rises from 0 to 1 at this rate: the arm resumes on its "
        "path",
        "[1/s]",
        0.01,
        1000.0,
    ),
    replace(
        CLOCK_TIMEOUT,
        description="use_sim_time: /clock standing still this long (wall time) with no "
        "joint_states holds the arm (HOLDING)",
    ),
    replace(
        MAX_CLOCK_JUMP,
        description="use_sim_time: a /clock reading this far forward, any back, or two /clock "
        "publishers hold the arm (CLOCK_FAULT)",
    ),
    MAX_REFERENCE_ERROR,
    ParameterSpec(
        "goal_tolerance",
        0.01,
        "DONE once every measured joint is this close to the plan's last sample; else "
        "GOAL_MISSED after settle_timeout",
        "[rad]",
        1e-6,
        1.0,
    ),
    ParameterSpec(
        "settle_timeout",
        1.0,
        "Time after the plan's end for the measured joints to come within goal_tolerance "
        "(node clock)",
        "[s]",
        0.01,
        60.0,
    ),
    ParameterSpec(
        "cancel_deceleration",
        2.0,
        "On ~/cancel the playback rate (1 while moving) falls to 0 at this rate: the arm stops on "
        "its path",
        "[1/s]",
        0.01,
        1000.0,
    ),
    ParameterSpec(
        "plan_output",
        "tick",
        "tick: one JointTrajectory per period; whole: the plan as one JointTrajectory at its start "
        "(trajectory interface)",
        choices=("tick", "whole"),
    ),
    ParameterSpec(
        "plan_sample_period",
        0.25,
        "plan_output whole: longest interval between samples (equal within a phase, its ends "
        "included)",
        "[s]",
        0.01,
        10.0,
    ),
    OUTPUT_INTERFACE,
    JOINTS,
    WORLD_FRAME,
)
SPECS = specs_by_name(PARAMETERS)


def refused(parameters: Iterable) -> str | None:
    """Why a run-time change of ``parameters`` (an on-set callback's list) is refused: the
    first value its spec refuses (ConfigError's text); None when every one passes."""
    for parameter in parameters:
        spec = SPECS.get(parameter.name)
        if spec is not None:
            try:
                spec.check(parameter.value)
            except ConfigError as exc:
                return str(exc)
    return None
