"""rns_ros: reactionless (Reaction Null-Space) teleoperation of free-floating space manipulators.

The math lives in :mod:`rns_ros.core` (numpy + Pinocchio, no ROS imports); ROS 2 nodes wrap it.
"""

__version__ = "0.1.0"
