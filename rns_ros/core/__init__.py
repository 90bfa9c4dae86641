"""ROS-free math core of rns_ros (the ground floor): model, state, momentum/RNS, inverses,
subchains, integration. It imports nothing of rns_ros above it, and never rclpy or rerun.
See docs/symbols.md for the thesis symbol <-> name table.
"""

from rns_ros.core.config import load_model, load_model_config
from rns_ros.core.errors import ConfigError, InputError, ModelError, RnsError
from rns_ros.core.inverses import (
    DampedInverse,
    SingularityConsistentInverse,
    damped_least_squares_inverse,
    pseudoinverse,
    singularity_consistent_inverse,
)
from rns_ros.core.model import FreeFloatingModel, ModelSpec
from rns_ros.core.momentum import (
    base_twist_from_momentum,
    coupling_angular_momentum,
    generalized_jacobian,
    reactionless_joint_velocity,
    spatial_momentum,
)
from rns_ros.core.state import Determinants, FrameKinematics, FreeFloatingState
from rns_ros.core.subchains import SubchainDecomposition, subchain_decomposition

__all__ = [
    "ConfigError",
    "DampedInverse",
    "Determinants",
    "FrameKinematics",
    "FreeFloatingModel",
    "FreeFloatingState",
    "InputError",
    "ModelError",
    "ModelSpec",
    "RnsError",
    "SingularityConsistentInverse",
    "SubchainDecomposition",
    "base_twist_from_momentum",
    "coupling_angular_momentum",
    "damped_least_squares_inverse",
    "generalized_jacobian",
    "load_model",
    "load_model_config",
    "pseudoinverse",
    "reactionless_joint_velocity",
    "singularity_consistent_inverse",
    "spatial_momentum",
    "subchain_decomposition",
]
