"""The force controller's inputs: operator twist, force setpoint, wrist wrench, joint state;
validated at the edge."""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from rns_ros.control.force.settings import CommandFrame
from rns_ros.core.errors import InputError

#: Frame-id aliases accepted besides the configured names.
WORLD_ALIAS, EE_ALIAS = "world", "ee"


class TwistCommand(NamedTuple):
    """One validated operator twist.

    Attributes:
        linear [m/s], angular [rad/s]: (3,), in ``frame`` axes, finite.
        frame: world or EE axes.
        stamp: header stamp [ns] (0: unstamped: no acceleration feed-forward).
        received: receipt time [s] on the node's input clock (simulated time under
            use_sim_time, else monotonic).
    """

    linear: np.ndarray
    angular: np.ndarray
    frame: CommandFrame
    stamp: int
    received: float


class ForceSetpoint(NamedTuple):
    """One validated force setpoint: force [N] and torque [N m] (3,) in ``frame`` axes (only the
    force along the contact normal is used), receipt time [s] on the node's input clock."""

    force: np.ndarray
    torque: np.ndarray
    frame: CommandFrame
    received: float


class WrenchSample(NamedTuple):
    """The wrist wrench the EE exerts on the environment, EE axes [N, N m] (3,) each, at header
    stamp ``stamp`` [ns] (that of the joint state it belongs to)."""

    stamp: int
    force: np.ndarray
    torque: np.ndarray


class JointMeasurement(NamedTuple):
    """One joint state in model joint order: stamp [ns], q [rad], v [rad/s] (n,), effort [N m]
    (n,) = the torque held over the step that ended here, or None when not reported."""

    stamp: int
    q: np.ndarray
    v: np.ndarray
    effort: np.ndarray | None = None


def command_frames(world_frame: str, ee_frame: str) -> dict[str, CommandFrame]:
    """frame_id -> axes: ``world_frame`` and the alias ``world``; the EE frame's name and the
    alias ``ee``."""
    return {
        WORLD_ALIAS: CommandFrame.WORLD,
        world_frame: CommandFrame.WORLD,
        EE_ALIAS: CommandFrame.EE,
        ee_frame: CommandFrame.EE,
    }


def _finite3(vector, name: str) -> np.ndarray:
    array = np.asarray(vector, dtype=float)
    if array.shape != (3,) or not np.isfinite(array).all():
        raise InputError(f"{name} must be 3 finite numbers, got {array.tolist()}")
    return array


def _frame(frame_id: str, frames: Mapping[str, CommandFrame], default: CommandFrame):
    if frame_id == "":
        return default
    if frame_id not in frames:
        raise InputError(f"frame_id {frame_id!r} is not one of {sorted(frames)}")
    return frames[frame_id]


def validate_twist(
    linear,
    angular,
    frame_id: str,
    frames: Mapping[str, CommandFrame],
    default: CommandFrame,
    stamp: int,
    received: float,
) -> TwistCommand:
    """Check a ``cmd_twist`` message (finite, known frame; empty frame_id -> ``default``).

    Raises:
        InputError: non-finite values or an unknown frame (the message names them).
    """
    return TwistCommand(
        _finite3(linear, "cmd_twist linear velocity"),
        _finite3(angular, "cmd_twist angular velocity"),
        _frame(frame_id, frames, default),
        int(stamp),
        float(received),
    )


def validate_force_setpoint(
    force, torque, frame_id: str, frames: Mapping[str, CommandFrame], received: float
) -> ForceSetpoint:
    """Check a ``force_setpoint`` message (finite, known frame; empty frame_id -> EE).

    Raises:
        InputError: non-finite values or an unknown frame.
    """
    return ForceSetpoint(
        _finite3(force, "force_setpoint force"),
        _finite3(torque, "force_setpoint torque"),
        _frame(frame_id, frames, CommandFrame.EE),
        float(received),
    )


__all__ = [
    "EE_ALIAS",
    "WORLD_ALIAS",
    "ForceSetpoint",
    "JointMeasurement",
    "TwistCommand",
    "WrenchSample",
    "command_frames",
    "validate_force_setpoint",
    "validate_twist",
]
