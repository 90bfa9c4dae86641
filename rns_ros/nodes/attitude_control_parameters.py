"""Parameters of rns_attitude_control (:mod:`rns_ros.nodes.attitude_control`); mirrored in
config/attitude_control.yaml."""

from __future__ import annotations

from rns_ros.nodes.parameters import CLOCK_TIMEOUT, MODEL_CONFIG, ParameterSpec, specs_by_name

NODE_NAME = "rns_attitude_control"
SUMMARY = "Holds the base attitude with three reaction wheels (eq. 5.14 feed-forward + PD)."

PARAMETERS = (
    MODEL_CONFIG,
    ParameterSpec("rate", 100.0, "Control rate", "[Hz]", 1.0, 1000.0),
    ParameterSpec(
        "natural_frequency",
        0.1,
        "Attitude loop natural frequency omega_n (gains scale with the base inertia)",
        "[rad/s]",
        1e-4,
        100.0,
    ),
    ParameterSpec("damping_ratio", 1.0, "Attitude loop damping ratio", "[-]", 0.05, 10.0),
    ParameterSpec(
        "torque_limit", 0.1, "Motor torque limit per wheel (ETS-VII: 0.1)", "[N m]", 1e-6, 1e3
    ),
    ParameterSpec(
        "feedforward", True, "Use the eq. (5.14) feed-forward -d/dt(M~_wm theta_dot_ref)"
    ),
    ParameterSpec("wheel_inertia", 0.11, "Spin inertia I_r of one wheel", "[kg m^2]", 1e-6, 1e3),
    ParameterSpec(
        "state_timeout",
        0.1,
        "joint_states, base_odom or wheel_states older than this (sim time under use_sim_time): "
        "zero torque, STALE_STATE",
        "[s]",
        0.005,
        10.0,
    ),
    ParameterSpec(
        "reference_timeout",
        0.1,
        "joint_references older than this: the feed-forward uses the measured joint rates",
        "[s]",
        0.005,
        10.0,
    ),
    CLOCK_TIMEOUT,
)
SPECS = specs_by_name(PARAMETERS)
