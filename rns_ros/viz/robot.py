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

Any arm is drawn (:mod:`rns_ros.viz.robot_shapes`): the loader gets a copy of the URDF with the
meshes that resolve on this machine (``package://`` through the ament index) made absolute and
the others left out, and every link left without a visual gets its ellipsoid of equivalent
inertia and its skeleton under ``world/robot/shapes/<link>``, so the 3D view is never empty.
Held joints (not driven, :attr:`FreeFloatingModel.held_joints`) are posed once, statically, at
their held positions. A base body that is not a link of the URDF (the satellite of a model YAML's
``base``) is drawn as its ellipsoid of equivalent inertia, the URDF's root placed on it where the
model mounts it.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pinocchio as pin
import rerun as rr
import rerun.urdf as rru

from rns_ros.core.description import read_description
from rns_ros.core.errors import ModelError
from rns_ros.core.fixed_base import FixedBaseModel
from rns_ros.core.joint_selection import frame_id
from rns_ros.core.model import FreeFloatingModel
from rns_ros.viz import paths
from rns_ros.viz.robot_shapes import (
    LinkShape,
    equivalent_ellipsoid,
    resolve_description,
)

#: Length of the camera pointing arrow [m].
CAMERA_ARROW_LENGTH = 0.6
#: Length of the camera frame axes [m].
CAMERA_AXES_LENGTH = 0.25
CAMERA_COLOR = (250, 200, 40)
_MOVING_JOINTS = ("revolute", "continuous", "prismatic")
SHAPE_COLOR = (150, 160, 175)
SKELETON_COLOR = (90, 90, 100)


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
        self.source_path = Path(urdf_path)
        try:
            spec = getattr(robot, "spec", None)
            text = read_description(
                self.source_path,
                getattr(spec, "xacro_args", None),
                getattr(spec, "packages", None),
            )
            self.description = resolve_description(text, self.source_path.parent)
        except (OSError, ModelError) as exc:
            raise ModelError(f"cannot read the URDF {self.source_path}: {exc}") from exc
        # the loader reads a file: the resolved copy lives as long as this view
        self._folder = tempfile.TemporaryDirectory(prefix="rns_ros_urdf_")
        #: The URDF rerun's loader reads (meshes resolved, see the module docstring).
        self.urdf_path = Path(self._folder.name) / self.source_path.name
        self.urdf_path.write_text(self.description.xml)
        try:
            self.tree = rru.UrdfTree.from_file_path(self.urdf_path)
        except Exception as exc:  # rerun raises plain exceptions from its Rust parser
            raise ModelError(f"rerun cannot read the URDF {self.source_path}: {exc}") from exc
        moving = {j.name: j for j in self.tree.joints() if j.joint_type in _MOVING_JOINTS}
        missing = [name for name in robot.joint_names if name not in moving]
        if missing:
            raise ModelError(
                f"{self.urdf_path}: joints {missing} are not moving joints of the URDF; it has "
                f"{sorted(moving)}"
            )
        #: (URDF joint, entity path) in theta order.
        self.joints = [(moving[name], paths.joint_transform(name)) for name in robot.joint_names]
        held = getattr(robot, "held_joints", {}) or {}
        #: (URDF joint, entity path, held position [rad or m]) of the joints not driven.
        self.held = [
            (moving[name], paths.joint_transform(name), float(value))
            for name, value in held.items()
            if name in moving
        ]
        #: The URDF's root link; the base pose is logged for the model's base frame.
        self.root_link = self.tree.root_link().name
        self.base_link = getattr(robot, "base_link", self.root_link)
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
            link = self.root_link if joint is None else joint.child_link
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
        self.log_shapes(rec)
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

    def shapes(self) -> list[LinkShape]:
        """The simple shapes drawn: the URDF's bare links, and a base body the URDF lacks."""
        shapes = list(self.description.shapes)
        if self.base_link != self.root_link and isinstance(self.robot, FreeFloatingModel):
            body = self.robot.model.inertias[1]  # the free-flyer's body: the satellite
            half_sizes, axes = equivalent_ellipsoid(body.mass, body.inertia)
            quaternion = np.array(pin.Quaternion(axes).normalized().coeffs())
            shapes.append(LinkShape(self.base_link, np.array(body.lever), half_sizes, quaternion))
        return shapes

    def log_shapes(self, rec: rr.RecordingStream) -> None:
        """The simple shapes (static), the mount of the URDF's root on a base body it lacks and
        the held joints at their positions."""
        for shape in self.shapes():
            entity = f"{paths.ROBOT_SHAPES}/{shape.link}"
            if shape.center is not None:
                rec.log(
                    entity,
                    rr.CoordinateFrame(shape.link),
                    rr.Ellipsoids3D(
                        centers=[shape.center],
                        half_sizes=[shape.half_sizes],
                        quaternions=[rr.Quaternion(xyzw=shape.quaternion_xyzw)],
                        colors=[SHAPE_COLOR],
                        fill_mode="solid",
                    ),
                    static=True,
                )
            if len(shape.segments):
                rec.log(
                    f"{entity}/skeleton",
                    rr.CoordinateFrame(shape.link),
                    rr.LineStrips3D(shape.segments, colors=[SKELETON_COLOR], radii=[0.01]),
                    static=True,
                )
        mount = self.mount()
        if mount is not None:
            rec.log(
                paths.ROBOT_MOUNT,
                rr.Transform3D(
                    translation=mount.translation,
                    mat3x3=mount.rotation,
                    parent_frame=self.base_link,
                    child_frame=self.root_link,
                ),
                static=True,
            )
        for joint, path, value in self.held:
            rec.log(path, joint.compute_transform(value, clamp=False), static=True)

    def mount(self) -> pin.SE3 | None:
        """Placement of the URDF's root link in the model's base frame, when the two differ
        (a base body added by the model YAML); else None."""
        if self.base_link == self.root_link or not isinstance(self.robot, FreeFloatingModel):
            return None
        model = self.robot.model
        if not model.existFrame(self.root_link):
            return None
        frame = model.frames[frame_id(model, self.root_link, "root link", self.robot.name)]
        return frame.placement if frame.parentJoint == 1 else None

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
