"""rerun visualisation of rns_ros: 3D robot from its URDF, time series, sinks, read-back.

May import rerun and Pinocchio, never rclpy (the node :mod:`rns_ros.nodes.rerun_logger` converts
messages). Entity paths: :mod:`rns_ros.viz.paths`; recording: :class:`TelemetryRecorder`;
read-back of saved ``.rrd`` files: :mod:`rns_ros.viz.readback`.
"""

from rns_ros.viz.recorder import RecorderSettings, TelemetryRecorder
from rns_ros.viz.sinks import SinkError, SinkKind, SinkSettings

__all__ = ["RecorderSettings", "SinkError", "SinkKind", "SinkSettings", "TelemetryRecorder"]
