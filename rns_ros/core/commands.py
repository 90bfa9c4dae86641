"""Joint commands addressed by joint name, checked once at the edge (ROS-free).

A command names its joints; rns_ros matches them to the model's joint order and rejects anything
ambiguous: unknown or missing names, duplicated names, wrong lengths, NaN/Inf, or speeds beyond
the joint velocity limits. A measured joint state (:func:`match_joint_state`) may carry joints
beyond the model's, which are ignored; missing model joints are an error there too. Every
rejection is an :class:`InputError` whose message says what was wrong and what would be valid.
"""

from __future__ import annotations

import functools
from collections import Counter
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from rns_ros.core.errors import InputError
from rns_ros.core.validation import apart

#: Commanded speeds may exceed the URDF velocity limit by this fraction before rejection [-]
#: (controllers that scale exactly to the limit land a rounding error above it).
VELOCITY_LIMIT_TOLERANCE = 0.01
#: Names an error message lists at most [-] (a stranger's command may name thousands).
MAX_LISTED = 10
#: Distinct sets of extra joint_states names a node reports at most [-] (one line each).
MAX_REPORTED_SETS = 16


class NamedJointCommand(NamedTuple):
    """A joint command reordered into the model's theta order; None where the sender gave none.

    Attributes:
        positions: [rad], shape (n,) or None.
        velocities: [rad/s], shape (n,) or None.
        accelerations: [rad/s^2], shape (n,) or None.
    """

    positions: np.ndarray | None
    velocities: np.ndarray | None
    accelerations: np.ndarray | None


def joint_order(names: Sequence[str], model_joints: Sequence[str]) -> np.ndarray:
    """Index array p with command[p[i]] belonging to model joint i; names must be a permutation.

    A stream repeats one name list at every message, so the order of the newest lists is
    cached (the returned array is read-only).

    Raises:
        InputError: more names than the model has joints; unknown, missing or duplicated joint
            names (listed, at most MAX_LISTED of each).
    """
    check_name_count(len(names), model_joints)
    return _cached_order(tuple(names), tuple(model_joints), False)[0]


def check_name_count(count: int, model_joints: Sequence[str]) -> None:
    """A command naming ``count`` joints can address the model at all: at most one name per
    joint (checked first, in constant time: the other checks are linear in the names).

    Raises:
        InputError: more names than joints.
    """
    if count > len(model_joints):
        raise InputError(
            f"the command names {count} joints; the model has {len(model_joints)}: "
            f"{list(model_joints)}"
        )


def listed(items: Sequence[str]) -> str:
    """``items`` as a list, the first MAX_LISTED of them and how many more."""
    items = list(items)
    if len(items) <= MAX_LISTED:
        return str(items)
    return f"{items[:MAX_LISTED]} and {len(items) - MAX_LISTED} more"


def _duplicated(names: Sequence[str]) -> list[str]:
    return sorted(name for name, count in Counter(names).items() if count > 1)


@functools.lru_cache(maxsize=32)
def _cached_order(
    names: tuple[str, ...], model_joints: tuple[str, ...], extras_allowed: bool
) -> tuple[np.ndarray, tuple[str, ...]]:
    """(read-only index array p with values[p[i]] for model joint i, the names that are not
    model joints in message order); those are an error unless ``extras_allowed``.

    Raises:
        InputError: unknown (unless allowed), missing or duplicated joints, all listed.
    """
    model, named = set(model_joints), set(names)
    extras = tuple(dict.fromkeys(name for name in names if name not in model))
    missing = [joint for joint in model_joints if joint not in named]
    duplicated = [name for name in _duplicated(names) if not extras_allowed or name in model]
    problems = []
    if extras and not extras_allowed:
        problems.append(f"unknown joints {listed(sorted(extras))}")
    if missing:
        problems.append(f"missing joints {listed(missing)}")
    if duplicated:
        problems.append(f"duplicated joints {listed(duplicated)}")
    if problems:
        raise InputError("; ".join(problems) + f" (model joints: {list(model_joints)})")
    index = {name: i for i, name in enumerate(names) if name in model}
    order = np.array([index[joint] for joint in model_joints])
    order.flags.writeable = False
    return order, extras


def _field(
    values: Sequence[float], order: np.ndarray, label: str, count: int | None = None
) -> np.ndarray | None:
    """``values`` (one per name, ``count`` names; default one per model joint) picked by
    ``order`` into model order, None when empty.

    Raises:
        InputError: a length other than ``count``, or a picked value that is not finite.
    """
    if len(values) == 0:
        return None
    count = order.size if count is None else count
    if len(values) != count:
        raise InputError(f"{label} has {len(values)} values for {count} joints")
    array = np.asarray(values, dtype=float)[order]
    if not np.isfinite(array).all():
        raise InputError(f"{label} must be finite, got {array.tolist()}")
    return array


def match_named_command(
    names: Sequence[str],
    model_joints: Sequence[str],
    *,
    positions: Sequence[float] = (),
    velocities: Sequence[float] = (),
    accelerations: Sequence[float] = (),
    velocity_limits: np.ndarray | None = None,
) -> NamedJointCommand:
    """Validate a named joint command and reorder it into the model's joint order.

    Args:
        names: joint names of the command.
        model_joints: the model's joint names (theta order).
        positions, velocities, accelerations: per-name values, each empty or len(names).
        velocity_limits: |theta_dot| limits [rad/s] in model order, shape (n,); None = no check.

    Raises:
        InputError: see the module docstring; also when every field is empty.
    """
    order = joint_order(names, model_joints)
    command = NamedJointCommand(
        positions=_field(positions, order, "positions"),
        velocities=_field(velocities, order, "velocities"),
        accelerations=_field(accelerations, order, "accelerations"),
    )
    if command.positions is None and command.velocities is None:
        raise InputError("the command has neither positions nor velocities")
    if command.velocities is not None and velocity_limits is not None:
        check_velocity_limits(command.velocities, velocity_limits, model_joints)
    return command


def joint_state_order(
    names: Sequence[str], model_joints: Sequence[str]
) -> tuple[np.ndarray, tuple[str, ...]]:
    """Index array p with state[p[i]] belonging to model joint i, and the names that are not
    model joints (in message order): a measured state may carry more joints than the model
    (a gripper's fingers beside the arm's, from joint_state_broadcaster), which are ignored.

    A stream repeats one name list at every message, so the newest lists are cached (the
    returned array is read-only).

    Raises:
        InputError: missing model joints, or a model joint named twice (listed, at most
            MAX_LISTED of each).
    """
    return _cached_order(tuple(names), tuple(model_joints), True)


def match_joint_state(
    names: Sequence[str],
    model_joints: Sequence[str],
    *,
    positions: Sequence[float] = (),
    velocities: Sequence[float] = (),
) -> tuple[NamedJointCommand, tuple[str, ...]]:
    """A measured joint state (sensor_msgs/JointState) in the model's joint order, and the
    names it carries beyond the model's joints (ignored; see :func:`joint_state_order`).

    Args:
        names: joint names of the message.
        model_joints: the model's joint names (theta order), shape (n,).
        positions: [rad], empty or len(names).
        velocities: [rad/s], empty or len(names).

    Returns:
        (positions (n,) and velocities (n,), each None when empty; accelerations None), and
        the extra names in message order (each once).

    Raises:
        InputError: missing or duplicated model joints, a length other than len(names), a
            model joint's value that is not finite (the extras' values are not checked), or
            neither positions nor velocities.
    """
    order, extras = joint_state_order(names, model_joints)
    count = len(names)
    state = NamedJointCommand(
        positions=_field(positions, order, "positions", count),
        velocities=_field(velocities, order, "velocities", count),
        accelerations=None,
    )
    if state.positions is None and state.velocities is None:
        raise InputError("the joint state has neither positions nor velocities")
    return state, extras


class ExtraJointsReport:
    """Which sets of extra joint names (:func:`match_joint_state`) a node has reported: each
    distinct set once, the first ``MAX_REPORTED_SETS`` of them."""

    def __init__(self) -> None:
        self._reported: set[tuple[str, ...]] = set()

    def note(self, extras: Sequence[str], topic: str = "joint_states") -> str | None:
        """The line to log for ``extras`` received on ``topic``, or None (no extras, or this
        set was reported already)."""
        extras = tuple(extras)
        if not extras or extras in self._reported or len(self._reported) >= MAX_REPORTED_SETS:
            return None
        self._reported.add(extras)
        more = len(extras) - MAX_LISTED
        return f"{topic}: ignoring joints not in the model: {', '.join(extras[:MAX_LISTED])}" + (
            f" and {more} more" if more > 0 else ""
        )


def check_velocity_limits(
    velocities: np.ndarray, velocity_limits: np.ndarray, model_joints: Sequence[str]
) -> None:
    """Raise :class:`InputError` naming the first joint whose |speed| exceeds its limit."""
    too_fast = np.flatnonzero(np.abs(velocities) > velocity_limits * (1 + VELOCITY_LIMIT_TOLERANCE))
    if too_fast.size:
        joint = too_fast[0]
        raise InputError(
            f"velocity {velocities[joint]:.4g} rad/s on {model_joints[joint]} exceeds its limit "
            f"{velocity_limits[joint]:.4g} rad/s"
        )


#: Rounding allowed past ``max_reference_error`` [rad]: a sender that bounds its command to
#: the same distance from the angle it measured lands on the edge, one rounding either side.
REFERENCE_SLACK = 1e-6


def check_reference_positions(
    positions: np.ndarray,
    current: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    max_error: float,
    model_joints: Sequence[str],
) -> None:
    """Raise :class:`InputError` naming the first joint whose reference position [rad] is outside
    its URDF limits [lower, upper] or farther than ``max_error`` [rad] (plus
    :data:`REFERENCE_SLACK`) from its current angle (all arrays shape (n,), model order)."""
    outside = np.flatnonzero((positions < lower) | (positions > upper))
    if outside.size:
        joint = outside[0]
        value, low, high = apart(positions[joint], lower[joint], upper[joint])
        raise InputError(
            f"position {value} rad on {model_joints[joint]} is outside its limits "
            f"[{low}, {high}] rad"
        )
    far = np.flatnonzero(np.abs(positions - current) > max_error + REFERENCE_SLACK)
    if far.size:
        joint = far[0]
        raise InputError(
            f"position {positions[joint]:.4g} rad on {model_joints[joint]} is "
            f"{abs(positions[joint] - current[joint]):.3g} rad from its current angle "
            f"{current[joint]:.4g} rad; allowed [{current[joint] - max_error:.4g}, "
            f"{current[joint] + max_error:.4g}] rad (max_reference_error {max_error} rad)"
        )


def partial_joint_goal(
    names: Sequence[str],
    positions: Sequence[float],
    model_joints: Sequence[str],
    current: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> np.ndarray:
    """A goal configuration [rad], shape (n,): the named joints at ``positions``, the others at
    their ``current`` angle (model order, like ``lower`` and ``upper`` [rad]).

    Raises:
        InputError: no names, unknown or duplicated names, a length mismatch, non-finite values,
            or a goal outside the URDF limits (the message names the joint and the range).
    """
    model = list(model_joints)
    if not len(names):
        raise InputError("goal names no joint")
    check_name_count(len(names), model)
    names, positions = list(names), list(positions)
    if len(positions) != len(names):
        raise InputError(f"goal has {len(positions)} positions for {len(names)} names")
    unknown = sorted(set(names) - set(model))
    if unknown:
        raise InputError(f"unknown joints {listed(unknown)} (model joints: {model})")
    duplicated = _duplicated(names)
    if duplicated:
        raise InputError(f"duplicated joints {listed(duplicated)}")
    index = {name: i for i, name in enumerate(model)}
    goal = np.array(current, dtype=float)
    for name, value in zip(names, positions, strict=True):
        if not np.isfinite(value):
            raise InputError(f"goal position of {name} must be finite, got {value}")
        goal[index[name]] = value
    for i, name in enumerate(model):
        if not lower[i] <= goal[i] <= upper[i]:
            value, low, high = apart(goal[i], lower[i], upper[i])
            raise InputError(f"goal {name} = {value} rad is outside its limits [{low}, {high}] rad")
    return goal
