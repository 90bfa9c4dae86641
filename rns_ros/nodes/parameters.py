"""Declaring node parameters from one table: description, unit, range, choices, read-only.

Every node lists its parameters as :class:`ParameterSpec` rows; :func:`declare_parameters`
declares them with full descriptors (so ``ros2 param describe`` explains each one), reads them
back and checks what rclpy's descriptors cannot (choices, array lengths), raising
:class:`~rns_ros.core.errors.ConfigError` that names the parameter, the bad value and the valid
range. The same table is mirrored in ``config/<node>.yaml`` and a test keeps them in sync.
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.node import Node

from rns_ros.core.commands import joint_order
from rns_ros.core.errors import ConfigError, InputError


@dataclass(frozen=True)
class ParameterSpec:
    """One node parameter.

    Attributes:
        name: parameter name.
        default: default value; its type is the parameter's type (a non-empty list of floats is a
            double array, of strings a string array).
        description: what it does, for ``ros2 param describe``.
        unit: physical unit, e.g. "[s]"; shown in the description.
        low, high: inclusive numeric range (scalars, and every element of a double array).
        choices: allowed strings, for string parameters.
        length: required array length; None = any (0 may mean "use the default").
        read_only: True when the value is only read at start-up.
    """

    name: str
    default: Any
    description: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] = ()
    length: tuple[int, ...] | None = None
    read_only: bool = True

    def descriptor(self) -> ParameterDescriptor:
        text = f"{self.description} {self.unit}".strip()
        constraints = []
        if self.choices:
            constraints.append(f"one of {list(self.choices)}")
        if self.length is not None:
            constraints.append(f"length in {list(self.length)}")
        if self.low is not None and isinstance(self.default, list):
            constraints.append(f"elements in [{self.low}, {self.high}]")
        descriptor = ParameterDescriptor(
            name=self.name,
            description=text,
            additional_constraints="; ".join(constraints),
            read_only=self.read_only,
        )
        if self.low is not None and not isinstance(self.default, list):
            if isinstance(self.default, bool | str):
                raise TypeError(f"{self.name}: ranges are for numbers")
            if isinstance(self.default, int):
                descriptor.integer_range = [
                    IntegerRange(from_value=int(self.low), to_value=int(self.high), step=0)
                ]
            else:
                descriptor.floating_point_range = [
                    FloatingPointRange(
                        from_value=float(self.low), to_value=float(self.high), step=0.0
                    )
                ]
        return descriptor

    def check(self, value: Any) -> Any:
        """Raise ConfigError when ``value`` breaks what the descriptor could not express."""
        if self.choices and value not in self.choices:
            raise ConfigError(
                f"parameter '{self.name}' must be one of {list(self.choices)}, got {value!r}"
            )
        if isinstance(self.default, list):
            value = list(value)
            if self.length is not None and len(value) not in self.length:
                raise ConfigError(
                    f"parameter '{self.name}' must have length in {list(self.length)}, "
                    f"got {len(value)}: {value}"
                )
            if self.low is not None:
                bad = [x for x in value if not (self.low <= x <= self.high)]
                if bad:
                    raise ConfigError(
                        f"parameter '{self.name}' elements must be in [{self.low}, {self.high}] "
                        f"{self.unit}, got {bad}".rstrip()
                    )
        return value


#: Parameters every rns_ros node that loads the robot declares the same way.
MODEL_CONFIG = ParameterSpec(
    "model_config",
    "",
    "Model YAML (URDF, camera/wrist frames, subchains); empty: the default 7-DoF arm",
)
WORLD_FRAME = ParameterSpec("world_frame", "world", "Frame id of the inertial frame")
#: Joint order of Float64MultiArray velocity commands, as ros2_control's forward_command_controller
#: takes it from its ``joints`` parameter. The default is the default model's joints in URDF order;
#: another model needs its own list (checked against the model when the velocity interface is used).
JOINTS = ParameterSpec(
    "joints",
    [f"joint_{i}" for i in range(1, 8)],
    "Joint order of Float64MultiArray velocities (velocity interface), like the 'joints' "
    "parameter of a ros2_control forward_command_controller; a permutation of the model's joints",
)


def velocity_joint_order(joints: Sequence[str], model_joints: Sequence[str]) -> np.ndarray:
    """Index array p, shape (n,): element p[i] of a ``joints``-ordered array is model joint i.

    Raises:
        ConfigError: ``joints`` is not a permutation of the model's joint names (names them).
    """
    try:
        return joint_order(joints, model_joints)
    except InputError as exc:
        raise ConfigError(f"parameter 'joints' {list(joints)}: {exc}") from None


def declare_parameters(node: Node, specs: Sequence[ParameterSpec]) -> dict[str, Any]:
    """Declare every spec on ``node`` and return {name: checked value}.

    Raises:
        ConfigError: a value is out of range, of the wrong type, or not among the choices.
    """
    values = {}
    for spec in specs:
        try:
            parameter = node.declare_parameter(spec.name, spec.default, spec.descriptor())
        except InvalidParameterValueException as exc:
            raise ConfigError(
                f"parameter '{spec.name}' out of range: {_range_text(spec)} ({exc})"
            ) from None
        except InvalidParameterTypeException as exc:
            raise ConfigError(
                f"parameter '{spec.name}' has the wrong type; expected "
                f"{type(spec.default).__name__} like {spec.default!r} ({exc})"
            ) from None
        values[spec.name] = spec.check(parameter.value)
    return values


def warn_unknown_parameters(node: Node) -> list[str]:
    """Warn about parameter overrides for ``node`` that name none of its parameters.

    Call once the node has declared everything. An override (``-p NAME:=VALUE``, or a
    ``--params-file`` entry for this node or ``/**``) of an undeclared name is ignored by rclpy
    without a word; here each one is logged as a warning naming the closest declared name.
    rclpy's own parameters (``use_sim_time``, ...) are declared, so never reported;
    ``qos_overrides.*`` apply to publishers and subscriptions, not to this list.

    Returns:
        The unknown names, sorted.
    """
    # rclpy (Jazzy) has no public getter for the overrides (rclcpp's get_parameter_overrides());
    # Node.__init__ keeps rcl's overrides for this node in this dict, name -> Parameter.
    overrides = getattr(node, "_parameter_overrides", None) or {}
    declared = list(node.list_parameters([], 0).names)
    unknown = sorted(
        name
        for name in overrides
        if not node.has_parameter(name) and not name.startswith("qos_overrides.")
    )
    for name in unknown:
        close = difflib.get_close_matches(name, declared, n=1)
        hint = f"did you mean '{close[0]}'?" if close else f"valid names: {sorted(declared)}"
        node.get_logger().warning(f"unknown parameter '{name}' is ignored; {hint}")
    return unknown


def _range_text(spec: ParameterSpec) -> str:
    if spec.low is None:
        return "see its description"
    return f"valid range [{spec.low}, {spec.high}] {spec.unit}".rstrip()


def specs_by_name(specs: Sequence[ParameterSpec]) -> dict[str, ParameterSpec]:
    return {spec.name: spec for spec in specs}
