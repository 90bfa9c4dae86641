"""Typed exceptions of rns_ros: everything the package raises on bad input derives from RnsError."""


class RnsError(Exception):
    """Base class of every error rns_ros raises on purpose."""


class ModelError(RnsError, ValueError):
    """A robot description (URDF, frames, joint names, subchains) is unusable."""


class ConfigError(RnsError, ValueError):
    """A configuration file or parameter has an unknown key or an out-of-range value."""


class InputError(RnsError, ValueError):
    """A numeric input (configuration, velocity, matrix) has the wrong shape or is not finite."""


class SimulationDivergedError(RnsError, ArithmeticError):
    """A simulation step produced a non-finite state; the simulator kept the last finite one."""
