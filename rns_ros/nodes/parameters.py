"""Declaring node parameters from one table: description, unit, range, choices, read-only.

Every node lists its parameters as :class:`ParameterSpec` rows; :func:`declare_parameters`
declares them with full descriptors (so ``ros2 param describe`` explains each one), reads them
back and checks what rclpy's descriptors cannot (choices, array lengths), raising
:class:`~rns_ros.core.errors.ConfigError` that names the parameter, the bad value and the valid
range. The same table is mirrored in ``config/<node>.yaml`` and a test keeps them in sync.
"""

from __future__ import annotations

import difflib
import inspect
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import Enum
from typing import Any

import numpy as np
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.node import Node

from rns_ros.control.command_bounds import DEFAULT_MAX_REFERENCE_ERROR
from rns_ros.control.controller import TwistFrame
from rns_ros.control.watchdog import DEFAULT_MAX_CLOCK_JUMP
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
#: Where the nodes that command the joints (rns_controller, rns_ptp) send them: a
#: JointTrajectory for a trajectory controller or rns_simulator, or Float64MultiArray velocities
#: in the ``joints`` order for a ros2_control forward_command_controller.
OUTPUT_INTERFACE = ParameterSpec(
    "output_interface",
    "trajectory",
    "JointTrajectory on joint_references, or Float64MultiArray on joint_velocities / "
    "joint_positions (docs/ros2_control.md)",
    choices=("trajectory", "velocity", "position"),
)
#: Joint order of Float64MultiArray commands, as ros2_control's forward_command_controller takes
#: it from its ``joints`` parameter. The default is the default model's joints in URDF order;
#: another model needs its own list (checked against the model when an array interface is used).
JOINTS = ParameterSpec(
    "joints",
    [f"joint_{i}" for i in range(1, 8)],
    "Joint order of Float64MultiArray commands: a permutation of the model's joints",
)
#: Under use_sim_time, the wall-clock check that /clock moves (rns_ros.nodes.input_clock): the
#: nodes that command the robot stop it when their simulated clock stands still this long.
CLOCK_TIMEOUT = ParameterSpec(
    "clock_timeout",
    1.0,
    "use_sim_time: /clock standing still this long (wall time) stops the arm (STALE_STATE)",
    "[s]",
    0.05,
    60.0,
    read_only=False,
)
#: Under use_sim_time, what a /clock that cannot be trusted is (rns_ros.nodes.input_clock,
#: ClockJumps): a reading this far forward, any reading back, or two publishers.
MAX_CLOCK_JUMP = ParameterSpec(
    "max_clock_jump",
    DEFAULT_MAX_CLOCK_JUMP,
    "use_sim_time: a /clock reading this far forward, or any back, stops the arm (CLOCK_FAULT)",
    "[s]",
    1e-3,
    3600.0,
)
#: Joint command bound of the nodes that command the joints (rns_ros.control.command_bounds).
MAX_REFERENCE_ERROR = ParameterSpec(
    "max_reference_error",
    DEFAULT_MAX_REFERENCE_ERROR,
    "Commanded positions stay within this of the measured angles (and within the URDF limits)",
    "[rad]",
    0.01,
    10.0,
)
#: frame_id of twists in the base and camera frames (nodes that send TwistStamped); empty: the
#: frames of ``model_config``'s model (its base link and camera frame).
BASE_FRAME = ParameterSpec(
    "base_frame", "", "frame_id of base-frame twists; empty: the base link of model_config"
)
CAMERA_FRAME = ParameterSpec(
    "camera_frame", "", "frame_id of camera-frame twists; empty: the camera frame of model_config"
)


#: rclpy's own parameter that puts a node on /clock (declared by rclpy, not read-only).
USE_SIM_TIME = "use_sim_time"


def sim_time_change_refused(node: Node, parameters: Iterable) -> str | None:
    """Why ``parameters`` (the list an on-set-parameters callback gets) cannot be set on the
    running ``node``: one of them changes ``use_sim_time``; None when none does.

    rclpy declares use_sim_time itself and switches the node's clock when it is set, but an
    rns_ros node reads it once at start-up (its input watchdogs, ticks and stamps), so a switch
    would leave it on neither clock. Call it first in the node's on-set callback and refuse
    with the reason (``SetParametersResult(successful=False, reason=...)``). The callback must
    be added after ``Node.__init__``: rclpy's TimeSource applies use_sim_time in an on-set
    callback of its own, and callbacks added later run first.
    """
    current = node.get_parameter(USE_SIM_TIME).value
    for parameter in parameters:
        if parameter.name == USE_SIM_TIME and parameter.value != current:
            return (
                f"use_sim_time cannot change on a running node (it is {_yaml_text(current)}, "
                f"asked {_yaml_text(parameter.value)}): restart it with "
                f"-p use_sim_time:={_yaml_text(parameter.value)}"
            )
    return None


def twist_frame_names(
    params: Mapping[str, Any], model_frames: Callable[[], tuple[str, str]] | None = None
) -> dict[TwistFrame, str]:
    """frame_id of each twist frame from the world_frame, base_frame and camera_frame values.

    An empty base_frame or camera_frame is the model's (``model_frames()``: (base link, camera
    frame), called only then; default :func:`model_frame_names` of ``params["model_config"]``).
    """
    names = {
        TwistFrame.WORLD: params["world_frame"],
        TwistFrame.BASE: params["base_frame"],
        TwistFrame.CAMERA: params["camera_frame"],
    }
    if not names[TwistFrame.BASE] or not names[TwistFrame.CAMERA]:
        base, camera = (model_frames or (lambda: model_frame_names(params["model_config"])))()
        names[TwistFrame.BASE] = names[TwistFrame.BASE] or base
        names[TwistFrame.CAMERA] = names[TwistFrame.CAMERA] or camera
    return names


def model_frame_names(model_config: str) -> tuple[str, str]:
    """(base link, camera frame) of the model YAML ``model_config`` ('' = the default model).

    Raises:
        ConfigError, ModelError: the model does not load (one line naming the problem).
    """
    from rns_ros.core import load_model
    from rns_ros.resources import default_model_config

    robot = load_model(model_config or default_model_config())
    return robot.base_link, robot.model.frames[robot.camera_frame_id].name


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


def choices_of(enum: Iterable[Enum], without: Iterable[Enum] = ()) -> tuple[str, ...]:
    """The values of a string enum but ``without``, in declaration order: the choices of its
    parameter."""
    excluded = set(without)
    return tuple(member.value for member in enum if member not in excluded)


def from_parameters(factory: Callable[..., Any], params: Mapping[str, Any], **overrides) -> Any:
    """``factory(**kwargs)`` with every keyword argument of ``factory`` that names a parameter
    taken from ``params`` (lists as tuples), and ``overrides`` on top."""
    names = inspect.signature(factory).parameters
    kwargs = {
        name: tuple(value) if isinstance(value, list) else value
        for name, value in params.items()
        if name in names
    }
    return factory(**{**kwargs, **overrides})


# --- documentation ------------------------------------------------------------------------------
#: Columns of :func:`markdown_table`.
TABLE_HEADER = ("Name", "Type", "Default", "Unit", "Range / choices", "Read-only", "Description")


def type_name(default: Any) -> str:
    """The ROS parameter type of ``default``: bool, integer, double, string or an array."""
    if isinstance(default, list):
        return f"{type_name(default[0]) if default else 'double'}[]"
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, int):
        return "integer"
    if isinstance(default, float):
        return "double"
    return "string"


def _limits_text(spec: ParameterSpec) -> str:
    parts = []
    if spec.choices:
        parts.append(", ".join(f"`{choice}`" for choice in spec.choices))
    if spec.low is not None:
        parts.append(f"[{spec.low:g}, {spec.high:g}]")
    if spec.length is not None:
        parts.append(f"length {' or '.join(str(n) for n in spec.length)}")
    return "; ".join(parts)


def _yaml_text(value: Any) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(_yaml_text(item) for item in value) + "]"
    if isinstance(value, bool):
        return str(value).lower()
    return "''" if value == "" else str(value)


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def markdown_table(specs: Sequence[ParameterSpec]) -> str:
    """The parameters as a Markdown table, one row each: name, type, default, unit,
    range/choices, read-only (no: changes apply while the node runs) and description."""
    lines = ["| " + " | ".join(TABLE_HEADER) + " |", "|" + "---|" * len(TABLE_HEADER)]
    for spec in specs:
        row = (
            f"`{spec.name}`",
            type_name(spec.default),
            f"`{_yaml_text(spec.default)}`",
            spec.unit.strip("[]"),
            _limits_text(spec),
            "yes" if spec.read_only else "no",
            spec.description,
        )
        lines.append("| " + " | ".join(_cell(cell) for cell in row) + " |")
    return "\n".join(lines)


def load_node_model(node: Node, model_config: str):
    """The node's robot model (``model_config``, or the package's default when empty), with
    its start-up summary logged once: controlled and held joints, masses, what loading changed
    (:meth:`rns_ros.core.FreeFloatingModel.describe`)."""
    from rns_ros.core import load_model
    from rns_ros.resources import default_model_config

    robot = load_model(model_config or default_model_config())
    for line in robot.describe():
        node.get_logger().info(line)
    return robot
