r"""Fixed-base redundant arms of thesis Part II (chapters 6-7): model, state, model files.

Part II controls the end effector of a *fixed-base* arm in contact with its environment. The
model is the same URDF + YAML pair as the free-floating arm (``config/planar_3dof.yaml``,
``config/lwr_7dof.yaml``), loaded without a free-flyer root and validated the same way (every
moving body physical, SPD inertia, only one-DoF revolute joints).

One :class:`FixedBaseState` per step holds what the controllers and the contact simulation need,
computed once (like :class:`rns_ros.core.state.FreeFloatingState`): M_l(q), the Coriolis and
gravity torques c_l, g_l of eq. (6.2), the end-effector Jacobian J_e (6.3) and the drift
J_e_dot q_dot of its classical acceleration, all with the end-effector twist V_e = [v; omega] in
world axes at the end-effector frame origin (Pinocchio's LOCAL_WORLD_ALIGNED).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.core.config import read_yaml_mapping
from rns_ros.core.description import read_description
from rns_ros.core.errors import ConfigError, ModelError
from rns_ros.core.joint_selection import frame_id
from rns_ros.core.model import check_moving_bodies, check_one_dof_joints
from rns_ros.core.urdf_prep import check_urdf_inertials
from rns_ros.core.validation import as_vector, short_repr

#: Standard gravity [m/s^2], along -z of world when ``gravity`` is on.
STANDARD_GRAVITY = 9.80665
_KEYS = {"urdf", "ee_frame", "description"}


class FixedBaseModel:
    """A fixed-base serial arm: Pinocchio model (nq = nv = n), end-effector frame, limits.

    Attributes:
        model, data: ``pin.Model`` and one ``pin.Data`` reused by :class:`FixedBaseState`.
        name: URDF robot name (file stem).
        n: number of joints; joint_names in q order.
        ee_frame_id: Pinocchio frame id of the end effector (contact point / tool).
        lower_limits, upper_limits [rad], velocity_limits [rad/s], effort_limits [N m]: (n,).
        gravity: gravity is on (thesis Part II: off).
    """

    def __init__(
        self, model: pin.Model, ee_frame: str, *, name: str = "robot", gravity: bool = False
    ) -> None:
        self.name = name
        self.model = model
        self.gravity = bool(gravity)
        model.gravity = (
            pin.Motion(np.array([0.0, 0.0, -STANDARD_GRAVITY]), np.zeros(3))
            if self.gravity
            else pin.Motion.Zero()
        )
        if model.njoints < 2:
            raise ModelError(f"{name}: the URDF has no moving joint")
        check_one_dof_joints(model, name, 1, "Part II arms need revolute joints with limits")
        check_moving_bodies(model, name)
        self.ee_frame_id = frame_id(model, ee_frame, "ee_frame", name)
        self.n = model.nv
        self.joint_names: tuple[str, ...] = tuple(model.names[1:])
        self.lower_limits = np.array(model.lowerPositionLimit, dtype=float)
        self.upper_limits = np.array(model.upperPositionLimit, dtype=float)
        self.velocity_limits = np.array(model.velocityLimit, dtype=float)
        self.effort_limits = np.array(model.effortLimit, dtype=float)
        self.data = model.createData()

    @classmethod
    def from_urdf(cls, path: str | Path, ee_frame: str, *, gravity: bool = False):
        """Load a URDF file with a fixed base (its root link is welded to ``world``).

        Raises:
            ModelError: the file is missing, unparsable or over the limits of
                :mod:`rns_ros.core.urdf_tree`, a body is not physical, or the end-effector
                frame is unknown.
        """
        path = Path(path)
        xml = read_description(path)
        check_urdf_inertials(xml, path.stem)
        try:
            model = pin.buildModelFromXML(xml)
        except (RuntimeError, ValueError) as exc:
            raise ModelError(f"{path.stem}: URDF could not be parsed: {exc}") from exc
        return cls(model, ee_frame, name=path.stem, gravity=gravity)

    def frame_position(self, q, frame: str) -> np.ndarray:
        """Position of a named frame in world [m], shape (3,) (own Data: the shared one is kept)."""
        index = frame_id(self.model, frame, "frame", self.name)
        data = self.model.createData()
        pin.framesForwardKinematics(self.model, data, as_vector(q, self.n, "q"))
        return data.oMf[index].translation.copy()


def load_fixed_base_model(path: str | Path, *, gravity: bool = False) -> FixedBaseModel:
    """The :class:`FixedBaseModel` of a model YAML file (keys: ``urdf`` relative to the file,
    ``ee_frame``, optional ``description``).

    Raises:
        ConfigError: missing file, unknown key or wrong type. ModelError: see
            :meth:`FixedBaseModel.from_urdf`.
    """
    path, content = read_yaml_mapping(path, _KEYS, "fixed-base model config")
    for key in ("urdf", "ee_frame"):
        if not isinstance(content.get(key), str):
            raise ConfigError(
                f"{path}: '{key}' must be a string, got {short_repr(content.get(key))}"
            )
    urdf = (path.parent / content["urdf"]).resolve()
    return FixedBaseModel.from_urdf(urdf, content["ee_frame"], gravity=gravity)


@dataclass(frozen=True)
class FixedBaseState:
    """Dynamics and end-effector kinematics at one (q, q_dot), eq. (6.2)-(6.3).

    Attributes (n joints):
        q [rad], v [rad/s]: (n,).
        mass_matrix: M_l [kg m^2], (n, n), symmetric.
        coriolis: c_l = C(q, q_dot) q_dot [N m], (n,).
        gravity: g_l [N m], (n,) (zero with gravity off).
        jacobian: J_e mapping q_dot to V_e = [v_e; omega_e] (world axes, at the EE origin),
            (6, n).
        jacobian_dot_v: J_e_dot q_dot, the EE's classical acceleration at q_ddot = 0, (6,)
            [m/s^2, rad/s^2].
        ee_position: [m], (3,). ee_rotation: world <- EE, (3, 3).
    """

    q: np.ndarray
    v: np.ndarray
    mass_matrix: np.ndarray
    coriolis: np.ndarray
    gravity: np.ndarray
    jacobian: np.ndarray
    jacobian_dot_v: np.ndarray
    ee_position: np.ndarray
    ee_rotation: np.ndarray
    robot: FixedBaseModel = field(repr=False, compare=False)

    @classmethod
    def compute(cls, robot: FixedBaseModel, q, v) -> FixedBaseState:
        """One pass of Pinocchio (CRBA, RNEA terms, Jacobian, classical drift).

        Raises:
            InputError: q or v of the wrong length or not finite.
        """
        model, data = robot.model, robot.data
        q = as_vector(q, robot.n, "q").copy()
        v = as_vector(v, robot.n, "v").copy()
        frame = robot.ee_frame_id
        mass = pin.crba(model, data, q)
        mass = np.triu(mass) + np.triu(mass, 1).T  # crba fills the upper triangle
        nonlinear = pin.rnea(model, data, q, v, np.zeros(robot.n))
        gravity = pin.computeGeneralizedGravity(model, data, q).copy()
        pin.forwardKinematics(model, data, q, v, np.zeros(robot.n))
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        frame_ref = pin.LOCAL_WORLD_ALIGNED
        jacobian = pin.getFrameJacobian(model, data, frame, frame_ref).copy()
        drift = pin.getFrameClassicalAcceleration(model, data, frame, frame_ref).vector.copy()
        placement = data.oMf[frame]
        return cls(
            q=q,
            v=v,
            mass_matrix=mass,
            coriolis=nonlinear - gravity,
            gravity=gravity,
            jacobian=jacobian,
            jacobian_dot_v=drift,
            ee_position=placement.translation.copy(),
            ee_rotation=placement.rotation.copy(),
            robot=robot,
        )

    @property
    def n(self) -> int:
        return self.q.shape[0]
