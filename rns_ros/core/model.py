"""Free-floating space robot model: one Pinocchio model with a free-flyer root, zero gravity.

The URDF root link is the satellite base; its frame is the base frame {B} of the thesis (chapter 2).
Every actuated joint of the file becomes an arm joint (theta, in Pinocchio's joint order). The
end-effector (``camera``) and wrist-point (``wrist``) frames, and the positioning / wrist subchains
of thesis section 4.1.2, are named in configuration, never hard-coded.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import InputError, ModelError
from rns_ros.core.validation import as_vector

#: Joint kinds (Pinocchio short names) that have one position and one velocity coordinate.
_ONE_DOF_JOINTS = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
_ONE_DOF_JOINTS += ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")


@dataclass(frozen=True)
class ModelSpec:
    """What rns_ros needs to know about an arm beyond its URDF.

    Attributes:
        camera_frame: end-effector frame whose angular velocity is commanded (eq. 4.5).
        wrist_frame: frame whose origin is the wrist point p_w of eq. (4.5), or None.
        positioning_joints: joint names of the positioning subchain P (section 4.1.2), may be empty.
        wrist_joints: joint names of the wrist subchain W (section 4.1.2), may be empty.
    """

    camera_frame: str = "camera"
    wrist_frame: str | None = "wrist"
    positioning_joints: tuple[str, ...] = ()
    wrist_joints: tuple[str, ...] = ()


@dataclass(frozen=True)
class Subchains:
    """Indices (into theta, shape (n,)) of the positioning and wrist subchains."""

    positioning: np.ndarray = field(repr=False)
    wrist: np.ndarray = field(repr=False)


class FreeFloatingModel:
    """A Pinocchio free-flyer model of a satellite base carrying a serial arm.

    Attributes:
        model: the ``pin.Model`` (nq = 7 + n, nv = 6 + n), gravity zero.
        data: one ``pin.Data`` reused by :class:`rns_ros.core.state.FreeFloatingState`.
        joint_names: arm joint names in theta order, length n.
        n: number of arm joints.
        base_link: name of the URDF root link (the satellite base frame {B}).
        camera_frame_id, wrist_frame_id: Pinocchio frame ids (wrist may be None).
        subchains: :class:`Subchains` or None when the spec names none.
        velocity_limits: [rad/s] (or [m/s]) per joint from the URDF, shape (n,).
        lower_limits, upper_limits: joint position limits [rad], shape (n,).
        total_mass: m_C of eq. (2.9) [kg].
    """

    def __init__(self, model: pin.Model, spec: ModelSpec, *, name: str = "robot") -> None:
        self.name = name
        self.spec = spec
        self.model = model
        model.gravity = pin.Motion.Zero()
        self._check_joints()
        self.n = model.nv - 6
        self.joint_names: tuple[str, ...] = tuple(model.names[2:])
        self.camera_frame_id = self._frame_id(spec.camera_frame, "camera_frame")
        self.wrist_frame_id = (
            None if spec.wrist_frame is None else self._frame_id(spec.wrist_frame, "wrist_frame")
        )
        self.subchains = self._subchains(spec)
        self.velocity_limits = np.array(model.velocityLimit[6:], dtype=float)
        self.lower_limits = np.array(model.lowerPositionLimit[7:], dtype=float)
        self.upper_limits = np.array(model.upperPositionLimit[7:], dtype=float)
        self.base_link = next(
            frame.name
            for frame in model.frames
            if frame.parentJoint == 1 and frame.type == pin.FrameType.BODY
        )
        self.total_mass = float(sum(inertia.mass for inertia in model.inertias))
        if not self.total_mass > 0.0:
            raise ModelError(f"{name}: total mass must be > 0 kg, got {self.total_mass}")
        self.data = model.createData()

    # construction ---------------------------------------------------------------------------
    @classmethod
    def from_urdf(cls, path: str | Path, spec: ModelSpec | None = None) -> FreeFloatingModel:
        """Load a URDF file with a free-flyer root joint.

        Raises:
            ModelError: the file is missing or unparsable, or the spec names unknown frames/joints.
        """
        path = Path(path)
        if not path.is_file():
            raise ModelError(f"URDF file not found: {path}")
        return cls.from_urdf_string(path.read_text(), spec, name=path.stem)

    @classmethod
    def from_urdf_string(
        cls, xml: str, spec: ModelSpec | None = None, *, name: str = "robot"
    ) -> FreeFloatingModel:
        """Build the model from URDF text (see :meth:`from_urdf`)."""
        try:
            model = pin.buildModelFromXML(xml, pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as exc:
            raise ModelError(f"{name}: URDF could not be parsed: {exc}") from exc
        return cls(model, spec or ModelSpec(), name=name)

    # validation ------------------------------------------------------------------------------
    def _check_joints(self) -> None:
        model = self.model
        if model.njoints < 3 or model.joints[1].shortname() != "JointModelFreeFlyer":
            raise ModelError(f"{self.name}: expected a free-flyer root and at least one arm joint")
        for index in range(2, model.njoints):
            kind = model.joints[index].shortname()
            if kind not in _ONE_DOF_JOINTS:
                raise ModelError(
                    f"{self.name}: joint '{model.names[index]}' is {kind}; rns_ros supports "
                    "revolute and prismatic joints (continuous joints: give them limits)"
                )

    def _frame_id(self, frame: str, what: str) -> int:
        if not self.model.existFrame(frame):
            names = sorted({f.name for f in self.model.frames} - {"universe", "root_joint"})
            raise ModelError(
                f"{self.name}: {what} '{frame}' is not a frame of the URDF; have {names}"
            )
        return self.model.getFrameId(frame)

    def _subchains(self, spec: ModelSpec) -> Subchains | None:
        if not spec.positioning_joints and not spec.wrist_joints:
            return None
        indices = []
        for label, names in (
            ("positioning", spec.positioning_joints),
            ("wrist", spec.wrist_joints),
        ):
            if not names:
                raise ModelError(f"{self.name}: {label}_joints is empty; give both subchains")
            unknown = [joint for joint in names if joint not in self.joint_names]
            if unknown:
                raise ModelError(
                    f"{self.name}: {label}_joints {unknown} are not joints of the URDF; "
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
