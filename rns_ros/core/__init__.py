"""ROS-free math core of rns_ros (the ground floor): model, state, momentum/RNS, inverses,
subchains, integration. It imports nothing of rns_ros above it, and never rclpy or rerun.
See docs/symbols.md for the thesis symbol <-> name table.
"""

import importlib

#: public name -> the module that defines it: imported on first use (PEP 562), so a light
#: module of the core (errors, validation, yaml_input) loads without Pinocchio
_HOMES = {
    "load_model": "config",
    "load_model_config": "config",
    "ConfigError": "errors",
    "InputError": "errors",
    "ModelError": "errors",
    "RnsError": "errors",
    "DampedInverse": "inverses",
    "SingularityConsistentInverse": "inverses",
    "damped_least_squares_inverse": "inverses",
    "pseudoinverse": "inverses",
    "singularity_consistent_inverse": "inverses",
    "FreeFloatingModel": "model",
    "ModelSpec": "model",
    "base_twist_from_momentum": "momentum",
    "coupling_angular_momentum": "momentum",
    "generalized_jacobian": "momentum",
    "reactionless_joint_velocity": "momentum",
    "spatial_momentum": "momentum",
    "Determinants": "state",
    "FrameKinematics": "state",
    "FreeFloatingState": "state",
    "SubchainDecomposition": "subchains",
    "subchain_decomposition": "subchains",
}


def __getattr__(name: str):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{home}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_HOMES))


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
