"""Free-floating space robot model: one Pinocchio model with a free-flyer root, zero gravity.

The root body is the satellite base; its frame is the base frame {B} of the thesis (chapter 2).
It is the URDF's root link, or the satellite of the model YAML's ``base`` (the thesis satellite
when the URDF's root has no mass), see :mod:`rns_ros.core.urdf_prep`. The *controlled* joints
are the arm joints theta (Pinocchio's joint order); the others are held at fixed positions, their
mass merged into the body that carries them (:mod:`rns_ros.core.joint_selection`). The
end-effector (``camera``) and wrist-point (``wrist``) frames, and the positioning / wrist
subchains of thesis section 4.1.2, are named in configuration, never hard-coded.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.core.description import read_description
from rns_ros.core.errors import InputError, ModelError
from rns_ros.core.joint_selection import (
    LIMIT_SLACK,
    ONE_DOF_JOINTS,
    REVOLUTE_JOINTS,
    frame_id,
    lock_joints,
    select_joints,
)
from rns_ros.core.urdf_prep import (
    BaseBody,
    check_inertia_matrix,
    check_urdf_inertials,
    prepare_urdf,
)
from rns_ros.core.validation import as_vector

#: Number of wrist joints of the default subchain split (thesis section 4.1.2: a 3-joint wrist).
DEFAULT_WRIST_JOINTS = 3


@dataclass(frozen=True)
class ModelSpec:
    """What rns_ros needs to know about an arm beyond its URDF (the model YAML).

    Attributes:
        camera_frame: end-effector frame whose angular velocity is commanded (eq. 4.5).
        wrist_frame: frame whose origin is the wrist point p_w of eq. (4.5), or None.
        positioning_joints: joint names of the positioning subchain P (section 4.1.2); () for
            no subchains; None for the default: the controlled joints not in the wrist.
        wrist_joints: joint names of the wrist subchain W (section 4.1.2); () for no
            subchains; None for the default: the last :data:`DEFAULT_WRIST_JOINTS` controlled
            joints (or those not in ``positioning_joints``). Both None with fewer than 4
            controlled joints: no subchains.
        controlled_joints: joint names theta is made of, or None for every revolute joint of
            the chain from the root to ``camera_frame``.
        held_joints: positions [rad or m] of joints not controlled (others at 0, a ``<mimic>``
            joint at its leader's rule).
        initial_joint_positions: initial angles [rad] of controlled joints (others 0).
        base: the satellite body, or None (the URDF root, or the thesis satellite when the
            URDF root has no mass).
        xacro_args: ``<xacro:arg>`` values of a xacro description
            (:func:`rns_ros.core.description.read_description`).
        packages: package name -> share folder, for a xacro's ``$(find pkg)``.
    """

    camera_frame: str = "camera"
    wrist_frame: str | None = "wrist"
    positioning_joints: tuple[str, ...] | None = ()
    wrist_joints: tuple[str, ...] | None = ()
    controlled_joints: tuple[str, ...] | None = None
    held_joints: Mapping[str, float] = field(default_factory=dict)
    initial_joint_positions: Mapping[str, float] = field(default_factory=dict)
    base: BaseBody | None = None
    xacro_args: Mapping[str, str] = field(default_factory=dict)
    packages: Mapping[str, Path] = field(default_factory=dict)


@dataclass(frozen=True)
class Subchains:
    """Indices (into theta, shape (n,)) of the positioning and wrist subchains."""

    positioning: np.ndarray = field(repr=False)
    wrist: np.ndarray = field(repr=False)


class FreeFloatingModel:
    """A Pinocchio free-flyer model of a satellite base carrying a serial arm.

    Attributes:
        model: the ``pin.Model`` (nq = 7 + n, nv = 6 + n), gravity zero, held joints locked.
        data: one ``pin.Data`` reused by :class:`rns_ros.core.state.FreeFloatingState`.
        joint_names: controlled joint names in theta order, length n.
        n: number of controlled joints.
        held_joints: held joint name -> locked position [rad or m] (empty when none).
        initial_theta: initial joint angles [rad] from ``initial_joint_positions``, shape (n,).
        base_link: name of the root link (the satellite base frame {B}).
        camera_frame_id, wrist_frame_id: Pinocchio frame ids (wrist may be None).
        subchains: :class:`Subchains` or None when the spec names none.
        velocity_limits: [rad/s] (or [m/s]) per joint from the URDF, shape (n,); +inf where
            the URDF gives none.
        lower_limits, upper_limits: joint position limits [rad], shape (n,); -inf / +inf for a
            continuous joint.
        base_mass: mass of the root body [kg] (satellite plus the links fixed to it).
        total_mass: m_C of eq. (2.9) [kg].
        urdf_xml: the URDF text as loaded (the arm's, before the satellite is added).
        source_path: the URDF file, or None when built from text.
        loading_notes: one line per change loading made to the URDF (satellite added, root
            replaced, continuous joints unbounded); the end of :meth:`describe`.
    """

    def __init__(
        self,
        model: pin.Model,
        spec: ModelSpec,
        *,
        name: str = "robot",
        held_joints: Mapping[str, float] | None = None,
        urdf_xml: str = "",
        source_path: Path | None = None,
        held_rules: Mapping[str, str] | None = None,
        notes: tuple[str, ...] = (),
    ) -> None:
        """Wrap a built free-flyer ``model`` (held joints already locked).

        Args:
            held_joints: locked joint name -> position [rad or m].
            urdf_xml, source_path: the URDF as loaded (attributes of the same names).
            held_rules: held joint name -> its position with unit and origin, for
                :meth:`describe`.
            notes: changes made to the URDF on loading, one line each, for :meth:`describe`.
        """
        self.name = name
        self.spec = spec
        self.model = model
        model.gravity = pin.Motion.Zero()
        self._check_joints()
        self._check_bodies()
        self.n = model.nv - 6
        self.joint_names: tuple[str, ...] = tuple(model.names[2:])
        self.held_joints: dict[str, float] = dict(held_joints or {})
        self.urdf_xml = urdf_xml
        self.source_path = source_path
        self._held_rules = dict(held_rules or {})
        self.loading_notes: tuple[str, ...] = tuple(notes)
        self.camera_frame_id = self._frame_id(spec.camera_frame, "camera_frame")
        self.wrist_frame_id = (
            None if spec.wrist_frame is None else self._frame_id(spec.wrist_frame, "wrist_frame")
        )
        self.subchains = self._subchains(spec)
        velocity = np.array(model.velocityLimit[6:], dtype=float)
        self.velocity_limits = np.where(velocity > 0.0, velocity, np.inf)  # 0: none given
        self.lower_limits = np.array(model.lowerPositionLimit[7:], dtype=float)
        self.upper_limits = np.array(model.upperPositionLimit[7:], dtype=float)
        self.base_link = next(
            frame.name
            for frame in model.frames
            if frame.parentJoint == 1 and frame.type == pin.FrameType.BODY
        )
        self.base_mass = float(model.inertias[1].mass)
        self.total_mass = float(sum(inertia.mass for inertia in model.inertias))
        if not self.total_mass > 0.0:
            raise ModelError(f"{name}: total mass must be > 0 kg, got {self.total_mass}")
        self.initial_theta = self._initial_theta(spec.initial_joint_positions)
        self.data = model.createData()

    # construction ---------------------------------------------------------------------------
    @classmethod
    def from_urdf(cls, path: str | Path, spec: ModelSpec | None = None) -> FreeFloatingModel:
        """Load a URDF (or xacro, expanded with ``spec``'s ``xacro_args`` and ``packages``)
        file with a free-flyer root joint.

        Raises:
            ModelError: the file is missing or unparsable, or the spec names unknown frames/joints.
        """
        path = Path(path)
        spec = spec or ModelSpec()
        xml = read_description(path, spec.xacro_args, spec.packages)
        name = path.name.removesuffix(".xacro").removesuffix(".urdf")
        return cls.from_urdf_string(xml, spec, name=name, source_path=path)

    @classmethod
    def from_urdf_string(
        cls,
        xml: str,
        spec: ModelSpec | None = None,
        *,
        name: str = "robot",
        source_path: Path | None = None,
    ) -> FreeFloatingModel:
        """Build the model from URDF text (see :meth:`from_urdf`).

        Every link's ``<inertial>`` is checked as written (:func:`check_urdf_inertials`) before
        Pinocchio reads the file: its parser turns an unreadable number into zero without failing.
        Continuous joints become revolute joints without position limits and the satellite is
        added (:func:`rns_ros.core.urdf_prep.prepare_urdf`); joints not controlled are locked
        (:mod:`rns_ros.core.joint_selection`).
        """
        spec = spec or ModelSpec()
        check_urdf_inertials(xml, name)
        prepared = prepare_urdf(xml, spec.base, name)
        try:
            full = pin.buildModelFromXML(prepared.xml, pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as exc:
            raise ModelError(f"{name}: URDF could not be parsed: {exc}") from exc
        _check_arm_joints(full, name)
        for joint in prepared.continuous_joints:
            index = full.joints[full.getJointId(joint)].idx_q
            full.lowerPositionLimit[index], full.upperPositionLimit[index] = -np.inf, np.inf
        selection = select_joints(
            full,
            spec.camera_frame,
            spec.controlled_joints,
            spec.held_joints,
            prepared.mimic,
            name,
        )
        held = {}
        for joint, position in selection.held.items():
            kind = full.joints[full.getJointId(joint)].shortname()
            unit = "rad" if kind in REVOLUTE_JOINTS else "m"
            held[joint] = f"{position:.6g} {unit} ({selection.rules[joint]})"
        return cls(
            lock_joints(full, selection.held),
            spec,
            name=name,
            held_joints=selection.held,
            urdf_xml=xml,
            source_path=source_path,
            held_rules=held,
            notes=prepared.notes,
        )

    # validation ------------------------------------------------------------------------------
    def _check_joints(self) -> None:
        _check_arm_joints(self.model, self.name)

    def _check_bodies(self) -> None:
        """Every moving body must be physical (:func:`check_moving_bodies`): a free-flyer's mass
        matrix is singular otherwise."""
        check_moving_bodies(self.model, self.name)

    def _frame_id(self, frame: str, what: str) -> int:
        return frame_id(self.model, frame, what, self.name)

    def _subchains(self, spec: ModelSpec) -> Subchains | None:
        positioning, wrist = spec.positioning_joints, spec.wrist_joints
        if positioning is None and wrist is None and self.n <= DEFAULT_WRIST_JOINTS:
            return None
        if wrist is None:
            wrist = (
                self.joint_names[-DEFAULT_WRIST_JOINTS:]
                if positioning is None
                else tuple(joint for joint in self.joint_names if joint not in positioning)
            )
        if positioning is None:
            positioning = tuple(joint for joint in self.joint_names if joint not in wrist)
        if not positioning and not wrist:
            return None
        indices = []
        for label, names in (("positioning", positioning), ("wrist", wrist)):
            if not names:
                raise ModelError(f"{self.name}: {label}_joints is empty; give both subchains")
            unknown = [joint for joint in names if joint not in self.joint_names]
            if unknown:
                raise ModelError(
                    f"{self.name}: {label}_joints {unknown} are not controlled joints; "
                    f"valid names: {list(self.joint_names)}"
                )
            indices.append(np.array([self.joint_names.index(joint) for joint in names]))
        if set(indices[0]) & set(indices[1]):
            raise ModelError(f"{self.name}: positioning and wrist subchains share joints")
        if len(indices[0]) + len(indices[1]) != self.n:
            raise ModelError(
                f"{self.name}: subchains must cover all {self.n} joints {list(self.joint_names)}"
            )
        return Subchains(positioning=indices[0], wrist=indices[1])

    def _initial_theta(self, positions: Mapping[str, float]) -> np.ndarray:
        theta = np.zeros(self.n)
        for joint, value in positions.items():
            if joint not in self.joint_names:
                hint = "; set held joints in held_joints" if joint in self.held_joints else ""
                raise ModelError(
                    f"{self.name}: initial_joint_positions names '{joint}', not a controlled "
                    f"joint {list(self.joint_names)}{hint}"
                )
            index = self.joint_names.index(joint)
            low, high = self.lower_limits[index], self.upper_limits[index]
            if not (math.isfinite(value) and low - LIMIT_SLACK <= value <= high + LIMIT_SLACK):
                raise ModelError(
                    f"{self.name}: initial_joint_positions '{joint}' = {value} rad is outside "
                    f"its limits [{low:.6g}, {high:.6g}] rad"
                )
            theta[index] = value
        defaulted = [
            f"{joint} [{low:.6g}, {high:.6g}]"
            for joint, low, high in zip(
                self.joint_names, self.lower_limits, self.upper_limits, strict=True
            )
            if joint not in positions and not low - LIMIT_SLACK <= 0.0 <= high + LIMIT_SLACK
        ]
        if defaulted:
            raise ModelError(
                f"{self.name}: initial_joint_positions defaults to 0 rad, outside the limits of "
                f"{', '.join(defaulted)} rad: give those joints an initial angle in the model YAML"
            )
        theta.setflags(write=False)
        return theta

    # summary ---------------------------------------------------------------------------------
    def describe(self) -> list[str]:
        """The start-up summary, one line each: controlled and held joints, the base and the
        total mass [kg], then every change made to the URDF on loading."""
        held = ", ".join(
            f"{joint} = {self._held_rules.get(joint, f'{value:.6g}')}"
            for joint, value in self.held_joints.items()
        )
        arm = self.total_mass - self.base_mass
        return [
            f"{self.name}: {self.n} controlled joints {list(self.joint_names)}",
            f"held joints (locked, mass counted): {held or 'none'}",
            f"base '{self.base_link}': {self.base_mass:.6g} kg (with the links fixed to it)",
            f"total mass {self.total_mass:.6g} kg (arm {arm:.6g} kg, base/arm "
            f"{self.base_mass / arm if arm > 0 else math.inf:.4g})",
            *self.loading_notes,
        ]

    # configurations --------------------------------------------------------------------------
    def configuration(
        self,
        joint_angles,
        base_position=(0.0, 0.0, 0.0),
        base_quaternion=(0.0, 0.0, 0.0, 1.0),
    ) -> np.ndarray:
        """Pinocchio configuration q (7 + n,) from theta [rad] (n,), r_b [m] (3,), quat xyzw (4,).

        The quaternion is normalized; a zero or non-finite one raises :class:`InputError`.
        """
        theta = as_vector(joint_angles, self.n, "joint_angles")
        position = as_vector(base_position, 3, "base_position")
        quaternion = as_vector(base_quaternion, 4, "base_quaternion (x, y, z, w)")
        norm = np.linalg.norm(quaternion)
        if norm < 1e-9:
            raise InputError("base_quaternion must be non-zero")
        return np.concatenate((position, quaternion / norm, theta))

    def neutral(self) -> np.ndarray:
        """Base at the world origin, identity attitude, theta = 0: shape (7 + n,)."""
        return pin.neutral(self.model)

    def joint_angles(self, q: np.ndarray) -> np.ndarray:
        """theta [rad] (n,) from a configuration q (7 + n,)."""
        return np.asarray(q)[7:]

    def skeleton(self, q: np.ndarray) -> np.ndarray:
        """Base origin, every arm joint origin and the camera in world [m], shape (n + 2, 3).

        A stick figure of configuration q (7 + n,) for plots and the rerun ghost arm. Uses its own
        ``pin.Data``: the shared :attr:`data` of the current state is left untouched.
        """
        data = self.model.createData()
        pin.forwardKinematics(self.model, data, np.asarray(q, dtype=float))
        pin.updateFramePlacements(self.model, data)
        points = [data.oMi[j].translation.copy() for j in range(1, self.model.njoints)]
        points.append(data.oMf[self.camera_frame_id].translation.copy())
        return np.array(points)

    def camera_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The camera frame of configuration q (7 + n,) in world: rotation (3, 3) (world <-
        camera) and position [m] (3,). Uses its own ``pin.Data``, like :meth:`skeleton`."""
        data = self.model.createData()
        pin.framesForwardKinematics(self.model, data, np.asarray(q, dtype=float))
        placement = data.oMf[self.camera_frame_id]
        return placement.rotation.copy(), placement.translation.copy()


def check_one_dof_joints(model: pin.Model, name: str, first: int, supported: str) -> None:
    """Every joint from index ``first`` on must have one position and one velocity coordinate
    (revolute or prismatic, :data:`~rns_ros.core.joint_selection.ONE_DOF_JOINTS`).

    Raises:
        ModelError: naming the first other joint, its kind and ``supported`` (what the caller
            accepts).
    """
    for index in range(first, model.njoints):
        kind = model.joints[index].shortname()
        if kind not in ONE_DOF_JOINTS:
            raise ModelError(f"{name}: joint '{model.names[index]}' is {kind}; {supported}")


def check_moving_bodies(model: pin.Model, name: str) -> None:
    """Every moving body (a joint's link plus the fixed links merged into it) must have a finite
    mass > 0 and a finite, symmetric positive definite rotational inertia.

    Raises:
        ModelError: naming the joint, its links and the bad value.
    """
    for index in range(1, model.njoints):
        body = model.inertias[index]
        links = [
            frame.name
            for frame in model.frames
            if frame.parentJoint == index and frame.type == pin.FrameType.BODY
        ]
        where = f"body of joint '{model.names[index]}' (links {links})"
        if not (math.isfinite(body.mass) and body.mass > 0.0):
            raise ModelError(
                f"{name}: {where} has mass {body.mass} kg; must be finite and > 0 "
                "(a moving link needs an <inertial>)"
            )
        check_inertia_matrix(np.array(body.inertia), f"{name}: {where}")


def _check_arm_joints(model: pin.Model, name: str) -> None:
    """A free-flyer root joint, then at least one arm joint, each revolute or prismatic."""
    if model.njoints < 3 or model.joints[1].shortname() != "JointModelFreeFlyer":
        raise ModelError(f"{name}: expected a free-flyer root and at least one arm joint")
    check_one_dof_joints(
        model, name, 2, "rns_ros supports revolute, continuous, prismatic and fixed joints"
    )
