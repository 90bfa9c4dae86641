"""Free-floating space robot model: one Pinocchio model with a free-flyer root, zero gravity.

The URDF root link is the satellite base; its frame is the base frame {B} of the thesis (chapter 2).
Every actuated joint of the file becomes an arm joint (theta, in Pinocchio's joint order). The
end-effector (``camera``) and wrist-point (``wrist``) frames, and the positioning / wrist subchains
of thesis section 4.1.2, are named in configuration, never hard-coded.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import InputError, ModelError
from rns_ros.core.validation import as_vector

#: Joint kinds (Pinocchio short names) that have one position and one velocity coordinate.
_ONE_DOF_JOINTS = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
_ONE_DOF_JOINTS += ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")

#: Relative tolerance of the triangle inequality on principal moments (I1 + I2 >= I3): URDFs
#: exported from CAD round their moments, and a thin disk (I, I, 2I) sits exactly on the bound.
TRIANGLE_RTOL = 1e-4
_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


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
        self._check_bodies()
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
        """Build the model from URDF text (see :meth:`from_urdf`).

        Every link's ``<inertial>`` is checked as written (:func:`check_urdf_inertials`) before
        Pinocchio reads the file: its parser turns an unreadable number into zero without failing.
        """
        check_urdf_inertials(xml, name)
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
        check_one_dof_joints(
            model,
            self.name,
            2,
            "rns_ros supports revolute and prismatic joints (continuous joints: give them limits)",
        )

    def _check_bodies(self) -> None:
        """Every moving body must be physical (:func:`check_moving_bodies`): a free-flyer's mass
        matrix is singular otherwise."""
        check_moving_bodies(self.model, self.name)

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


def check_one_dof_joints(model: pin.Model, name: str, first: int, supported: str) -> None:
    """Every joint from index ``first`` on must have one position and one velocity coordinate
    (revolute or prismatic, :data:`_ONE_DOF_JOINTS`).

    Raises:
        ModelError: naming the first other joint, its kind and ``supported`` (what the caller
            accepts).
    """
    for index in range(first, model.njoints):
        kind = model.joints[index].shortname()
        if kind not in _ONE_DOF_JOINTS:
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
        _check_inertia_matrix(np.array(body.inertia), f"{name}: {where}")


# URDF inertial checks ---------------------------------------------------------------------------
def check_urdf_inertials(xml: str, name: str = "robot") -> None:
    """Check every ``<link>``'s ``<inertial>`` as the URDF text writes it.

    Links without ``<inertial>`` (frames such as ``camera``) are accepted. For the others: mass
    [kg] finite and > 0; the six moments ``ixx ixy ixz iyy iyz izz`` [kg m^2] present and finite;
    the inertia matrix positive definite; its principal moments obey the triangle inequality
    I1 + I2 >= I3 (relative tolerance :data:`TRIANGLE_RTOL`).

    Raises:
        ModelError: one line naming the link and the bad value; or the text is not XML.
    """
    try:
        root = ET.fromstring(xml.encode())
    except ET.ParseError as exc:
        raise ModelError(f"{name}: URDF could not be parsed: {exc}") from None
    for link in root.iter("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        where = f"{name}: link '{link.get('name')}'"
        mass = _number(inertial.find("mass"), "value", f"{where} <mass>")
        if not mass > 0.0:
            raise ModelError(f"{where}: mass must be finite and > 0 kg, got {mass}")
        element = inertial.find("inertia")
        values = {key: _number(element, key, f"{where} <inertia>") for key in _INERTIA_KEYS}
        matrix = np.array(
            [
                [values["ixx"], values["ixy"], values["ixz"]],
                [values["ixy"], values["iyy"], values["iyz"]],
                [values["ixz"], values["iyz"], values["izz"]],
            ]
        )
        _check_inertia_matrix(matrix, where)


def _number(element: ET.Element | None, key: str, where: str) -> float:
    """The finite float in attribute ``key`` of ``element``, else ModelError naming it."""
    if element is None:
        raise ModelError(f"{where} is missing")
    text = element.get(key)
    if text is None:
        raise ModelError(f"{where}: attribute {key} is missing")
    try:
        value = float(text)
    except ValueError:
        raise ModelError(f"{where}: {key}={text!r} is not a number") from None
    if not math.isfinite(value):
        raise ModelError(f"{where}: {key}={text!r} must be finite")
    return value


def _check_inertia_matrix(matrix: np.ndarray, where: str) -> None:
    """Rotational inertia [kg m^2] (3, 3): finite, symmetric, positive definite, triangle."""
    if not np.all(np.isfinite(matrix)):
        raise ModelError(f"{where}: inertia must be finite, got {matrix.tolist()}")
    if not np.allclose(matrix, matrix.T, rtol=1e-9, atol=0.0):
        raise ModelError(f"{where}: inertia must be symmetric, got {matrix.tolist()}")
    moments = np.linalg.eigvalsh(matrix)  # ascending
    if not moments[0] > 0.0:
        raise ModelError(
            f"{where}: inertia must be positive definite, got principal moments "
            f"{_fmt(moments)} kg m^2 from {_fmt(matrix)}"
        )
    if moments[0] + moments[1] < moments[2] * (1.0 - TRIANGLE_RTOL):
        raise ModelError(
            f"{where}: principal moments {_fmt(moments)} kg m^2 break the triangle inequality "
            f"I1 + I2 >= I3 ({moments[0] + moments[1]:.6g} < {moments[2]:.6g}); no rigid body "
            "has them"
        )


def _fmt(values: np.ndarray) -> str:
    return np.array2string(np.asarray(values), precision=6, separator=", ").replace("\n", "")
