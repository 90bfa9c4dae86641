r"""The robot in rerun's 3D view: URDF geometry from rerun's URDF loader, posed by transform frames.

rerun 0.41 loads a URDF itself (``RecordingStream.log_file_from_path``): every link's ``<visual>``
becomes a static entity under ``world/robot/<urdf name>/visual_geometries/<link>/visual_<k>``
placed in a *named transform frame* equal to the link name, and the joint origins at zero angle
go to ``/tf_static`` as ``Transform3D(parent_frame=<parent link>, child_frame=<child link>)``.
Moving the robot therefore means logging, per joint state, one Transform3D per moving joint
between the same two frames (:meth:`RobotView.joint_columns`, computed by rerun's own
``UrdfJoint.compute_transform_columns`` so origin, rpy and axis conventions are the loader's), and
one from ``tf#/world`` (the implicit frame of the ``world`` entity) to the base link
(:meth:`RobotView.base_pose_columns`), which also connects the robot's frame tree to the scene.
Samples are sent as columns (``send_columns``), a batch at a time: one ``log`` call per sample and
entity costs 40-140 µs.

``UrdfTree.log_urdf_to_recording`` would log the same model, but in 0.41 its ``entity_path_prefix``
is taken as one path part (``world/robot`` becomes ``world\/robot``), so the model is logged with
``log_file_from_path`` and ``UrdfTree`` is only used for the joint kinematics.

The camera's optical axis (+z of the camera frame) is drawn from Pinocchio forward kinematics as an
independent check: it must leave the black camera box the URDF frame tree draws.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
import rerun.urdf as rru

from rns_ros.core.errors import ModelError
from rns_ros.core.fixed_base import FixedBaseModel
from rns_ros.core.model import FreeFloatingModel
from rns_ros.viz import paths

#: Length of the camera pointing arrow [m].
CAMERA_ARROW_LENGTH = 0.6
#: Length of the camera frame axes [m].
CAMERA_AXES_LENGTH = 0.25
CAMERA_COLOR = (250, 200, 40)
_MOVING_JOINTS = ("revolute", "continuous", "prismatic")


class RobotView:
    """Logs one robot: static URDF model, then base pose and joint transforms.

    A free-floating robot also gets its camera frame axes, pointing arrow and trail; a fixed-base
    arm (Part II, no camera frame: :attr:`camera_link` is None) only the URDF model.

    Args:
        robot: the Pinocchio model (joint order = theta order).
        urdf_path: the URDF ``robot`` was built from.

    Raises:
        ModelError: the URDF cannot be parsed by rerun, or a model joint is not one of its moving
            joints.
    """

    def __init__(self, robot: FreeFloatingModel | FixedBaseModel, urdf_path: str | Path) -> None:
        self.robot = robot
        self.urdf_path = Path(urdf_path)
        try:
            self.tree = rru.UrdfTree.from_file_path(self.urdf_path)
        except Exception as exc:  # rerun raises plain exceptions from its Rust parser
            raise ModelError(f"rerun cannot read the URDF {self.urdf_path}: {exc}") from exc
        moving = {j.name: j for j in self.tree.joints() if j.joint_type in _MOVING_JOINTS}
        missing = [name for name in robot.joint_names if name not in moving]
        if missing:
            raise ModelError(
                f"{self.urdf_path}: joints {missing} are not moving joints of the URDF; it has "
                f"{sorted(moving)}"
            )
        #: (URDF joint, entity path) in theta order.
        self.joints = [(moving[name], paths.joint_transform(name)) for name in robot.joint_names]
        self.base_link = self.tree.root_link().name
        camera = getattr(robot, "camera_frame_id", None)
        #: Link of the camera frame; None for a fixed-base arm.
        self.camera_link = None if camera is None else robot.model.frames[camera].name

    @property
    def model_path(self) -> str:
        """Entity under which the URDF loader puts the model, ``world/robot/<urdf name>``."""
        return f"{paths.ROBOT}/{self.tree.name}"

    def visual_paths(self) -> dict[str, list[str]]:
        """{link name: entity paths of its visual geometries} as the loader logs them."""
        prefix = f"{paths.ROBOT}/"
        result = {}
        for joint in [None, *self.tree.joints()]:
            link = self.base_link if joint is None else joint.child_link
            # Paths from a prefix-less tree start at "/<urdf name>/...".
            result[link] = [
                prefix + p.lstrip("/") for p in self.tree.get_visual_geometry_paths(link)
            ]
        return result

    def log_static(self, rec: rr.RecordingStream) -> None:
        """World axes, the URDF model (geometry + fixed joint origins) and the camera frame axes
        (free-floating robots only)."""
        rec.log("/", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        rec.log_file_from_path(self.urdf_path, entity_path_prefix=paths.ROBOT, static=True)
        if self.camera_link is None:
            return
        rec.log(
            paths.CAMERA_FRAME,
            rr.CoordinateFrame(self.camera_link),
            rr.TransformAxes3D(CAMERA_AXES_LENGTH, show_frame=True),
            static=True,
        )
        # Styles are static; the per-sample rows only carry geometry.
        rec.log(
            paths.CAMERA_POINTING,
            rr.Arrows3D.from_fields(colors=[CAMERA_COLOR], radii=[0.01]),
            static=True,
        )
        rec.log(
            paths.CAMERA_TRAIL,
            rr.LineStrips3D.from_fields(colors=[CAMERA_COLOR], radii=[0.004]),
            static=True,
        )

    def log_fixed_base(self, rec: rr.RecordingStream) -> None:
        """A fixed-base arm: its base link at the world origin, static (world -> base link)."""
        rec.log(
            paths.BASE_POSE,
            rr.Transform3D(
                translation=[0.0, 0.0, 0.0],
                quaternion=rr.Quaternion(xyzw=[0.0, 0.0, 0.0, 1.0]),
                parent_frame=paths.WORLD_FRAME_ID,
                child_frame=self.base_link,
            ),
            static=True,
        )

    def base_pose_columns(self, positions: np.ndarray, quaternions_xyzw: np.ndarray):
        """Transform3D columns world -> base link: positions [m] (k, 3), unit quaternions
        x y z w (k, 4), one row each (for ``send_columns``)."""
        count = len(positions)
        return rr.Transform3D.columns(
            translation=np.asarray(positions, dtype=float).reshape(count, 3),
            quaternion=np.asarray(quaternions_xyzw, dtype=float).reshape(count, 4),
            parent_frame=[paths.WORLD_FRAME_ID] * count,
            child_frame=[self.base_link] * count,
        )

    def joint_columns(self, theta: np.ndarray):
        """[(entity path, Transform3D columns)] per joint for angles ``theta`` [rad] (k, n)."""
        theta = np.asarray(theta, dtype=float).reshape(-1, len(self.joints))
        # rerun's own joint kinematics (origin, rpy, axis) so the loader's frames line up; no
        # clamping: show where the arm really is, even past a URDF limit.
        return [
            (path, joint.compute_transform_columns(theta[:, index].tolist(), clamp=False))
            for index, (joint, path) in enumerate(self.joints)
        ]

    @staticmethod
    def camera_columns(origins: np.ndarray, axes: np.ndarray):
        """Arrows3D columns of the camera optical axis: camera origins [m] (k, 3) and unit +z
        axes (k, 3) in world."""
        origins = np.asarray(origins, dtype=float).reshape(-1, 3)
        vectors = np.asarray(axes, dtype=float).reshape(-1, 3) * CAMERA_ARROW_LENGTH
        return rr.Arrows3D.columns(origins=origins, vectors=vectors)

    @staticmethod
    def log_trail(rec: rr.RecordingStream, strip: np.ndarray) -> None:
        """Recent camera positions [m], shape (k, 3), as one line strip."""
        rec.log(paths.CAMERA_TRAIL, rr.LineStrips3D([strip]))
