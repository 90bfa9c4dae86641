"""Parameters of rns_simulator's contact mode (:mod:`rns_ros.nodes.contact_simulator`); the specs
it shares with the free-floating modes come from :mod:`rns_ros.nodes.simulator_parameters`.
Mirrored in config/contact_simulator.yaml."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from rns_ros.core.errors import ConfigError
from rns_ros.nodes.parameters import JOINTS, WORLD_FRAME, ParameterSpec, specs_by_name
from rns_ros.nodes.simulator_parameters import (
    CONTACT_MODE,
    INITIAL_JOINT_POSITIONS,
    LOCKSTEP_PERIOD,
    MODE,
    PUBLISH_CLOCK,
    PUBLISH_RATE,
    REAL_TIME_FACTOR,
    STEP_SIZE,
)
from rns_ros.nodes.simulator_parameters import NODE_NAME as SIMULATOR_NODE_NAME

NODE_NAME = SIMULATOR_NODE_NAME  # one node, selected by its mode parameter
SUMMARY = (
    "Contact mode (-p mode:=contact): the fixed-base Part II arm on joint torques against a "
    "rigid wall or cylinder"
)
#: Wall-task start configuration of thesis section 6.2.2 [rad] (LWR [20, -20, 0, 100, 0, 10, 0]
#: deg).
WALL_TASK_RAD = [math.radians(a) for a in (20.0, -20.0, 0.0, 100.0, 0.0, 10.0, 0.0)]
ENVIRONMENTS = ("wall", "arc", "none")


@dataclass(frozen=True)
class OptionalVectorSpec(ParameterSpec):
    """A double-array parameter whose default is empty ("derive it"): declared with dynamic
    typing, because rclpy types an empty default as a byte array (so [0.0, 0.0, 1.0] would be
    refused) and a params file's ``[]`` arrives unset. The checked value is a list of floats,
    [] when unset."""

    def descriptor(self):
        descriptor = super().descriptor()
        descriptor.dynamic_typing = True
        return descriptor

    def check(self, value):
        if value is None:
            value = []
        if isinstance(value, str | bool | int | float) or not all(
            isinstance(x, int | float) and not isinstance(x, bool) for x in value
        ):
            raise ConfigError(
                f"parameter '{self.name}' must be a list of numbers {self.unit} (or [] for the "
                f"default), got {value!r}"
            )
        return super().check([float(x) for x in value])


PARAMETERS = (
    ParameterSpec(
        "model_config",
        "",
        "Part II fixed-base model YAML, a path or a file of the package's config/; empty: "
        "lwr_7dof.yaml",
    ),
    replace(MODE, default=CONTACT_MODE, choices=(CONTACT_MODE,)),
    replace(STEP_SIZE, high=0.01),
    replace(PUBLISH_RATE, default=1000.0),
    REAL_TIME_FACTOR,
    replace(PUBLISH_CLOCK, default=True),
    replace(LOCKSTEP_PERIOD, default=0.001),
    WORLD_FRAME,
    replace(
        INITIAL_JOINT_POSITIONS,
        default=WALL_TASK_RAD,
        description="Initial joint angles in model joint order (default: the thesis wall task "
        "[20, -20, 0, 100, 0, 10, 0] deg)",
    ),
    replace(
        JOINTS,
        description="Joint order of the Float64MultiArray torques on joint_efforts; a "
        "permutation of the model's joints",
    ),
    ParameterSpec(
        "command_timeout",
        0.05,
        "No valid torque for this long (wall time; simulated time in lockstep): the joint "
        "brakes take over",
        "[s]",
        0.001,
        60.0,
        read_only=False,
    ),
    ParameterSpec(
        "brake_damping",
        20.0,
        "Joint brake damping d of tau = g(q) - B q_dot, B = d M (M + dt d I)^-1 (stable for any d)",
        "[N m s/rad]",
        1e-3,
        1e4,
    ),
    ParameterSpec(
        "environment",
        "wall",
        "wall: a plane (wall_point, wall_normal); arc: a cylinder (arc_center, arc_radius, "
        "arc_axis); none: the free arm",
        choices=ENVIRONMENTS,
    ),
    OptionalVectorSpec(
        "wall_point",
        [],
        "A point of the wall surface in world; empty: the start EE point",
        "[m]",
        -1e3,
        1e3,
        length=(0, 3),
    ),
    OptionalVectorSpec(
        "wall_normal",
        [],
        "Wall normal into the wall (world, normalized, non-zero); empty: the start EE frame z axis",
        "[-]",
        -1e3,
        1e3,
        length=(0, 3),
    ),
    ParameterSpec(
        "arc_center",
        [1.91, 1.91, 0.0],
        "A point of the cylinder axis in world (thesis section 6.2.1: (1.91, 1.91) m)",
        "[m]",
        -1e3,
        1e3,
        length=(3,),
    ),
    ParameterSpec(
        "arc_radius", 0.707, "Cylinder radius (thesis: 0.707 m); must be > 0", "[m]", -1e3, 1e3
    ),
    ParameterSpec(
        "arc_axis",
        [0.0, 0.0, 1.0],
        "Cylinder axis direction in world (normalized, non-zero)",
        "[-]",
        -1e3,
        1e3,
        length=(3,),
    ),
    ParameterSpec("gravity", False, "Gravity along -z of world (thesis Part II: off)"),
    ParameterSpec(
        "contact_threshold",
        0.1,
        "|normal force| above which the contact sample reports pushing (+1) or pulling (-1)",
        "[N]",
        0.0,
        1e4,
    ),
    ParameterSpec(
        "project_start",
        True,
        "Move the initial joints onto the surface (minimum-norm, logged); false: a start off "
        "the surface is an error",
    ),
    ParameterSpec(
        "saturate_torque",
        True,
        "Clip commanded torques to the URDF effort limits (saturated joints are reported)",
    ),
)
SPECS = specs_by_name(PARAMETERS)
