"""rns_ros: reactionless (Reaction Null-Space) teleoperation of free-floating space manipulators.

The math lives in :mod:`rns_ros.core` (numpy + Pinocchio, no ROS imports); ROS 2 nodes wrap it.
"""

__version__ = "0.1.0"

# Before numpy / Pinocchio / rclpy load (~0.4 s): Ctrl-C while an rns_ros executable is still
# importing must end it with exit code 0, not a traceback. A no-op when imported as a library.
from rns_ros.cli import install_startup_handler as _install_startup_handler

_install_startup_handler()
