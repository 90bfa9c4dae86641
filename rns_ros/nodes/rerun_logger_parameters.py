"""Parameters of rns_rerun_logger (:mod:`rns_ros.nodes.rerun_logger`); mirrored in
config/rerun_logger.yaml."""

from __future__ import annotations

from rns_ros.control.controller import TwistFrame
from rns_ros.nodes.parameters import (
    MODEL_CONFIG,
    WORLD_FRAME,
    ParameterSpec,
    choices_of,
    specs_by_name,
)
from rns_ros.viz.sinks import SinkKind

NODE_NAME = "rns_rerun_logger"
SUMMARY = (
    "Logs the running system to rerun: the 3D robot from its URDF, base attitude, momentum, "
    "velocities, singularity measures."
)

PARAMETERS = (
    MODEL_CONFIG,
    WORLD_FRAME,
    ParameterSpec(
        "sink",
        SinkKind.AUTO.value,
        "spawn a viewer, connect to connect_url, serve a web viewer on 127.0.0.1:web_port, save "
        "rrd_path; auto: spawn or save",
        choices=choices_of(SinkKind),
    ),
    ParameterSpec(
        "rrd_path",
        "rns_ros.rrd",
        "Recording file for sink save (relative: to the working directory); overwritten",
    ),
    ParameterSpec(
        "connect_url",
        "rerun+http://127.0.0.1:9876/proxy",
        "Viewer to stream to for sink connect (rerun+http://HOST:PORT/proxy)",
    ),
    ParameterSpec(
        "grpc_port",
        9876,
        "Port of the spawned viewer (spawn) or of the local gRPC server (serve)",
        "[-]",
        1024,
        65535,
    ),
    ParameterSpec("web_port", 9090, "HTTP port of the web viewer (serve)", "[-]", 1024, 65535),
    ParameterSpec(
        "application_id",
        "rns_ros",
        "rerun application id; recordings with the same id share the viewer layout",
    ),
    ParameterSpec(
        "recording_name", "", "Recording name shown in the viewer (e.g. the method); empty: none"
    ),
    ParameterSpec(
        "controller_status_topic",
        "rns_controller/status",
        "DiagnosticArray status of the controller",
    ),
    ParameterSpec(
        "ptp_status_topic",
        "rns_ptp/status",
        "DiagnosticArray status of the point-to-point node",
    ),
    ParameterSpec(
        "ground_namespace",
        "",
        "Ground teleop: draw <ns>/predicted/* at their stamps and <ns>/joint_states as received",
    ),
    ParameterSpec(
        "predictor_status_topic",
        "rns_predictor/status",
        "Ground teleop: rns_predictor's status (prediction error), under ground_namespace "
        "unless absolute",
    ),
    ParameterSpec(
        "link_status_topic",
        "/rns_link/status",
        "Ground teleop: rns_link's status (delay, in flight, lost per direction)",
    ),
    ParameterSpec(
        "default_twist_frame",
        TwistFrame.CAMERA.value,
        "Axes of cmd_twist with an empty header.frame_id (as the controller's parameter)",
        choices=choices_of(TwistFrame),
    ),
    ParameterSpec("trail_length", 300, "Camera trail points kept; 0: no trail", "[-]", 0, 100000),
    ParameterSpec(
        "trail_period", 0.1, "Stamp time between two camera trail points", "[s]", 0.0, 60.0
    ),
    ParameterSpec(
        "max_rate",
        200.0,
        "Highest recorded rate per input topic (by stamp); 0: every message",
        "[Hz]",
        0.0,
        10000.0,
    ),
    ParameterSpec(
        "flush_tick",
        1.0,
        "Longest wall time a sample waits before it is sent to a live viewer (its lag; longer: "
        "bigger chunks)",
        "[s]",
        0.05,
        60.0,
    ),
    ParameterSpec(
        "file_flush_tick",
        10.0,
        "The same for sink save (nobody waits for a file; longer: bigger chunks)",
        "[s]",
        0.05,
        60.0,
    ),
    ParameterSpec(
        "force_errors_topic",
        "/rns_force_controller/errors",
        "Float64MultiArray task errors of the force controller (fixed-base arms only)",
    ),
    ParameterSpec(
        "contact_log_rate",
        50.0,
        "Highest recorded rate of contact, wrist_wrench and the force errors (fixed-base arms "
        "only); 0: every message",
        "[Hz]",
        0.0,
        10000.0,
    ),
    ParameterSpec(
        "force_arrow_scale",
        0.01,
        "Length of the measured and commanded force arrows per newton (fixed-base arms only)",
        "[m/N]",
        1e-6,
        10.0,
    ),
)
SPECS = specs_by_name(PARAMETERS)
