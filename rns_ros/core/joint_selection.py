"""Controlled and held joints: which arm joints theta holds, and where the others are locked.

The operator drives the *controlled* joints (theta, shape (n,)); every other moving joint of the
URDF (a gripper's fingers, a joint the user names) is *held* at a fixed position. A held joint is
locked with ``pin.buildReducedModel``: its child links merge into the parent body, so their mass
and inertia still count in the momentum, but it has no velocity coordinate and takes no part in
the reactionless solution. A ``<mimic>`` joint is held at multiplier * leader + offset, its
leader held too.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ModelError
from rns_ros.core.urdf_prep import MimicRule

#: Joint kinds (Pinocchio short names) that turn about an axis: controlled by default on the chain.
REVOLUTE_JOINTS = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
#: Joint kinds with one position and one velocity coordinate (revolute or prismatic).
ONE_DOF_JOINTS = (
    *REVOLUTE_JOINTS,
    "JointModelPX",
    "JointModelPY",
    "JointModelPZ",
    "JointModelPrismaticUnaligned",
)
#: Slack [rad or m] on a held position's limits (a value written at the bound in decimal).
LIMIT_SLACK = 1e-9


class JointSelection(NamedTuple):
    """Result of :func:`select_joints`.

    Attributes:
        controlled: controlled joint names in the model's joint order (theta order).
        held: held joint name -> locked position [rad or m], in the model's joint order.
        rules: held joint name -> how its position was chosen (for the start-up summary).
    """

    controlled: tuple[str, ...]
    held: dict[str, float]
    rules: dict[str, str]


def frame_id(model: pin.Model, frame: str, what: str, name: str) -> int:
    """Pinocchio id of the frame named ``frame`` (``what`` and ``name`` label errors).

    A URDF may give a link and a joint the same name (a fixed ``right_hand`` joint whose child
    is the link ``right_hand``); the name then means the link, whose frame is the one a
    tool, a camera or /tf refers to. A joint's frame is taken when no link has the name.

    Raises:
        ModelError: no frame has the name (the message lists the frames of the URDF).
    """
    matches = [index for index, f in enumerate(model.frames) if f.name == frame]
    if not matches:
        names = sorted({f.name for f in model.frames} - {"universe", "root_joint"})
        raise ModelError(f"{name}: {what} '{frame}' is not a frame of the URDF; have {names}")
    links = [index for index in matches if model.frames[index].type == pin.FrameType.BODY]
    return (links or matches)[0]


def chain_joints(model: pin.Model, frame: int) -> list[str]:
    """Names of the moving joints from the root to ``frame`` (root first), the free flyer
    excluded."""
    joints, joint = [], model.frames[frame].parentJoint
    while joint > 1:
        joints.append(model.names[joint])
        joint = model.parents[joint]
    return joints[::-1]


def select_joints(
    model: pin.Model,
    camera_frame: str,
    controlled: Sequence[str] | None,
    held: Mapping[str, float],
    mimic: Mapping[str, MimicRule],
    name: str,
) -> JointSelection:
    """Split the moving joints of ``model`` (free-flyer root, one-DoF joints) into controlled and
    held ones.

    Args:
        camera_frame: the end-effector frame; the default controlled joints are the revolute
            joints of the chain from the root to it (``<mimic>`` followers and ``held`` excluded).
        controlled: joint names to control, or None for the default.
        held: explicit held positions [rad or m]; a held joint not named here sits at 0, or at
            its ``<mimic>`` rule.
        mimic: ``<mimic>`` rules of the URDF (:func:`rns_ros.core.urdf_prep.prepare_urdf`).

    Raises:
        ModelError: one line naming the joint: unknown, both controlled and held, a controlled
            joint that is or leads a ``<mimic>`` joint, a held position that breaks its rule or
            its limits, or nothing left to control.
    """
    movable = list(model.names[2:])
    for label, names in (("controlled_joints", controlled or ()), ("held_joints", held)):
        unknown = [joint for joint in names if joint not in movable]
        if unknown:
            raise ModelError(
                f"{name}: {label} {unknown} are not moving joints of the URDF; valid: {movable}"
            )
    if controlled is None:
        chain = chain_joints(model, frame_id(model, camera_frame, "camera_frame", name))
        kinds = {joint: model.joints[model.getJointId(joint)].shortname() for joint in chain}
        chosen = {j for j in chain if kinds[j] in REVOLUTE_JOINTS and j not in mimic}
        chosen -= set(held)
    else:
        chosen = set(controlled)
        both = [joint for joint in movable if joint in chosen and joint in held]
        if both:
            raise ModelError(f"{name}: joints {both} are both in controlled_joints and held_joints")
    if not chosen:
        raise ModelError(
            f"{name}: no joint to control; the chain to '{camera_frame}' has no revolute joint "
            "(name them in controlled_joints)"
        )
    for follower, rule in mimic.items():
        if follower in chosen:
            raise ModelError(
                f"{name}: joint '{follower}' is a <mimic> of '{rule.leader}' and cannot be "
                "controlled; control neither, or remove the <mimic>"
            )
        if rule.leader in chosen:
            raise ModelError(
                f"{name}: controlled joint '{rule.leader}' leads <mimic> joint '{follower}'; "
                "rns_ros controls independent joints only: hold it (held_joints) or remove the "
                "<mimic>"
            )
    positions, rules = {}, {}
    for joint in movable:
        if joint not in chosen:
            positions[joint], rules[joint] = _held_position(joint, held, mimic, movable, name)
            _check_limits(model, joint, positions[joint], name)
    return JointSelection(tuple(j for j in movable if j in chosen), positions, rules)


def _held_position(
    joint: str,
    held: Mapping[str, float],
    mimic: Mapping[str, MimicRule],
    movable: list[str],
    name: str,
    seen: tuple[str, ...] = (),
) -> tuple[float, str]:
    """(position, how it was chosen) of a held joint."""
    if joint in seen:
        raise ModelError(f"{name}: <mimic> joints {list(seen)} lead each other in a loop")
    rule = mimic.get(joint)
    if rule is None:
        if joint in held:
            return float(held[joint]), "held_joints"
        return 0.0, "default 0"
    if rule.leader not in movable:
        raise ModelError(
            f"{name}: joint '{joint}' is a <mimic> of '{rule.leader}', not a moving joint"
        )
    leader, _ = _held_position(rule.leader, held, mimic, movable, name, (*seen, joint))
    position = rule.multiplier * leader + rule.offset
    if joint in held and abs(float(held[joint]) - position) > LIMIT_SLACK:
        raise ModelError(
            f"{name}: held_joints gives '{joint}' {held[joint]}, but its <mimic> rule "
            f"{rule.multiplier:g} * {rule.leader} + {rule.offset:g} gives {position:.9g}"
        )
    return position, f"<mimic> {rule.multiplier:g} * {rule.leader} + {rule.offset:g}"


def _check_limits(model: pin.Model, joint: str, position: float, name: str) -> None:
    index = model.joints[model.getJointId(joint)].idx_q
    lower, upper = model.lowerPositionLimit[index], model.upperPositionLimit[index]
    if not (np.isfinite(position) and lower - LIMIT_SLACK <= position <= upper + LIMIT_SLACK):
        raise ModelError(
            f"{name}: held joint '{joint}' at {position:.6g} is outside its limits "
            f"[{lower:.6g}, {upper:.6g}]; give its position in held_joints"
        )


def lock_joints(model: pin.Model, held: Mapping[str, float]) -> pin.Model:
    """``model`` with the ``held`` joints locked at their positions [rad or m] (a new model;
    the same one when nothing is held)."""
    if not held:
        return model
    q = pin.neutral(model)
    ids = []
    for joint, position in held.items():
        index = model.getJointId(joint)
        q[model.joints[index].idx_q] = position
        ids.append(index)
    return pin.buildReducedModel(model, ids, q)
