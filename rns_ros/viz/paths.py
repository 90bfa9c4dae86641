"""Every rerun entity path rns_ros logs, in one place, with its archetype, unit and source topic.

Paths carry no leading slash (rerun adds it; :func:`rns_ros.viz.readback.recording_summary` strips
it again). All vectors are in world axes unless a name says otherwise. Angles in plots are
degrees, rates rad/s.

3D scene (``world`` is right-handed, z up; metres):

=====================================  ================  =====================================
path                                   archetype         content (source topic)
=====================================  ================  =====================================
``world/robot/<urdf name>/             URDF loader       link geometry from the URDF's
visual_geometries/<link>/visual_<k>``                    ``<visual>`` elements, static; each
                                                         entity sits in its link's frame
``tf_static``                          Transform3D       the URDF's joint origins (loader,
                                                         static, outside ``world``)
``world/robot/base_pose``              Transform3D       base link pose in ``tf#/world``
                                                         (``base_odom``)
``world/robot/joints/<joint>``         Transform3D       parent link -> child link at the
                                                         measured angle (``joint_states``)
``world/camera/frame``                 TransformAxes3D   axes of the URDF camera frame, static
``world/camera/pointing``              Arrows3D          camera optical axis +z, from Pinocchio
                                                         forward kinematics [m] (``joint_states``)
``world/camera/trail``                 LineStrips3D      recent camera positions [m]
``world/ptp/goal``                     LineStrips3D      ghost arm of the newest ``ptp_goal``:
                                                         base, joint origins, camera [m] at the
                                                         goal angles and the base pose of the
                                                         moment it arrived; cleared by a
                                                         ``["deploy"]`` goal (no fixed goal)
``world/ptp/goal/joints``              Points3D          the same points as spheres
=====================================  ================  =====================================

Time series (``Scalars``, one entity per series, one row per logged message):

* ``plots/base_attitude/{roll,pitch,yaw,total}`` [deg]: R_0^T R of the base relative to the first
  ``base_odom`` (roll-pitch-yaw with R = Rz(yaw) Ry(pitch) Rx(roll); total = rotation angle).
* ``plots/coupling_momentum/{x,y,z,norm}`` [kg m^2/s]: the controller's predicted base disturbance
  M~_omega_m theta_dot (``rns_controller/status`` key ``coupling_momentum``).
* ``plots/angular_velocity/commanded/{x,y,z}`` [rad/s]: ``cmd_twist`` angular part in world axes.
* ``plots/angular_velocity/achieved/{x,y,z}`` [rad/s]: camera angular velocity from
  ``joint_states`` velocities and the ``base_odom`` twist.
* ``plots/joint_velocity/<joint>`` [rad/s]: ``joint_states`` velocities.
* ``plots/singularity/{sigma_min,det_kinematic,det_algorithmic}`` [-] and
  ``plots/singularity/det_coupling`` [(kg m^2)^6]: section 4.3.1 measures (controller status).
* ``plots/controller/state`` [-]: numeric state code (:data:`CONTROLLER_STATE_CODES`);
  ``plots/controller/damping`` [-] (DLS lambda^2); ``plots/controller/speed_scale`` [-].
* ``plots/momentum/{linear,angular}``: |p| [kg m/s] and |l| [kg m^2/s] (``momentum``).
* ``plots/ptp/phase`` [-]: numeric phase code of rns_ptp (:data:`PTP_PHASE_CODES`: 0 at rest,
  1-3 the 3-phase method's phases I-III, ...); ``plots/ptp/progress`` [-] from 0 to 1; the
  predicted |M~_omega_m theta_dot| of rns_ptp goes to ``plots/coupling_momentum/norm`` (the two
  commanders never run together).

* ``plots/energy/{base,arm,coupling,wheels,total}`` [J]: eq. (5.1) terms of the true state
  (rns_simulator ``energy``); ``plots/energy/lambda/{arm,wheels}`` [J]: the joint motion costed
  with Lambda_m and Lambda_r (eq. 5.3); ``plots/energy/cost/c_max`` [J] and
  ``plots/energy/cost/c_sum`` [J s] (eqs. 5.12-5.13, running).
* ``plots/wheels/speed/{x,y,z}`` [rad/s] and ``plots/wheels/torque/{x,y,z}`` [N m]: reaction
  wheel rates relative to the base and applied motor torques (``wheel_states``).

Part II contact tasks (fixed-base arms, :mod:`rns_ros.viz.contact`; docs/part2_ros.md):

=====================================  ================  =====================================
path                                   archetype         content (source topic)
=====================================  ================  =====================================
``world/robot/base_pose``              Transform3D       static identity: the arm's base link
                                                         at the world origin
``world/environment/wall``             Boxes3D           static: translucent 0.6 m x 0.6 m x
                                                         2 mm plate centred at the wall point,
                                                         its thin axis along the normal
                                                         (``environment``)
``world/environment/arc``              Cylinders3D       static: translucent cylinder of the
                                                         arc radius, 0.4 m long along the axis,
                                                         centred at the arc centre
``world/environment/normal``           Arrows3D          static: the wall normal (into the
                                                         wall), 0.1 m, at the wall point
``world/contact/point``                Points3D          contact point [m] (``contact``),
                                                         green pushing, grey no load, red
                                                         pulling
``world/contact/force_measured``       Arrows3D          R_ee f_wrist * force_arrow_scale at
                                                         the EE point (``wrist_wrench``)
``world/contact/force_desired``        Arrows3D          f_des n * force_arrow_scale at the EE
                                                         point (force controller ``errors``)
=====================================  ================  =====================================

* ``plots/contact/{normal_force,gap}``: lambda [N] and phi [m] (> 0 penetration) (``contact``).
* ``plots/force/{desired,measured,error,reference}`` [N]: f_des, f, f_des - f, f_ref of (6.34)
  (force controller ``errors``).
* ``plots/position_error/{x,y,z}`` [m]: p_des - p in world axes; ``plots/position_error/
  orientation`` [rad]: |log(R_des R^T)| (force controller ``errors``).

Text: ``log/controller`` (TextLog): one line whenever the controller state changes;
``log/ptp``: one line whenever the rns_ptp state or phase changes.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The one timeline set from message header stamps (sim time when the simulator publishes /clock).
#: Stamps before 2001-09-09 (< 1e9 s) are taken as simulated time and logged as a duration since
#: zero; later ones as absolute timestamps.
TIMELINE = "ros_time"

# --- 3D scene -------------------------------------------------------------------------------------
WORLD = "world"
#: Implicit transform frame of the ``world`` entity: the parent of the base link's frame.
WORLD_FRAME_ID = "tf#/world"
#: Prefix under which the URDF loader logs the model: ``ROBOT/<urdf robot name>/...``.
ROBOT = "world/robot"
BASE_POSE = "world/robot/base_pose"
JOINTS = "world/robot/joints"
CAMERA = "world/camera"
CAMERA_FRAME = "world/camera/frame"
CAMERA_POINTING = "world/camera/pointing"
CAMERA_TRAIL = "world/camera/trail"

# --- time series ----------------------------------------------------------------------------------
PLOTS = "plots"
AXES = ("x", "y", "z")

BASE_ATTITUDE = "plots/base_attitude"
BASE_ATTITUDE_ROLL = "plots/base_attitude/roll"
BASE_ATTITUDE_PITCH = "plots/base_attitude/pitch"
BASE_ATTITUDE_YAW = "plots/base_attitude/yaw"
BASE_ATTITUDE_TOTAL = "plots/base_attitude/total"

COUPLING_MOMENTUM = "plots/coupling_momentum"
COUPLING_MOMENTUM_NORM = "plots/coupling_momentum/norm"

ANGULAR_VELOCITY = "plots/angular_velocity"
COMMANDED_ANGULAR_VELOCITY = "plots/angular_velocity/commanded"
ACHIEVED_ANGULAR_VELOCITY = "plots/angular_velocity/achieved"

JOINT_VELOCITY = "plots/joint_velocity"

SINGULARITY = "plots/singularity"
SIGMA_MIN = "plots/singularity/sigma_min"
DET_KINEMATIC = "plots/singularity/det_kinematic"
DET_COUPLING = "plots/singularity/det_coupling"
DET_ALGORITHMIC = "plots/singularity/det_algorithmic"

CONTROLLER = "plots/controller"
CONTROLLER_STATE = "plots/controller/state"
CONTROLLER_DAMPING = "plots/controller/damping"
CONTROLLER_SPEED_SCALE = "plots/controller/speed_scale"

MOMENTUM = "plots/momentum"
MOMENTUM_LINEAR = "plots/momentum/linear"
MOMENTUM_ANGULAR = "plots/momentum/angular"

ENERGY = "plots/energy"
ENERGY_TERMS = ("base", "arm", "coupling", "wheels", "total")
ENERGY_LAMBDA = ("arm", "wheels")
ENERGY_COSTS = ("c_max", "c_sum")
WHEELS = "plots/wheels"
WHEEL_SPEED = "plots/wheels/speed"
WHEEL_TORQUE = "plots/wheels/torque"

PTP = "plots/ptp"
PTP_PHASE = "plots/ptp/phase"
PTP_PROGRESS = "plots/ptp/progress"
PTP_GOAL = "world/ptp/goal"
PTP_GOAL_JOINTS = "world/ptp/goal/joints"

# --- Part II: contact tasks ----------------------------------------------------------------------
ENVIRONMENT = "world/environment"
ENVIRONMENT_WALL = "world/environment/wall"
ENVIRONMENT_ARC = "world/environment/arc"
ENVIRONMENT_NORMAL = "world/environment/normal"
CONTACT = "world/contact"
CONTACT_POINT = "world/contact/point"
FORCE_MEASURED_ARROW = "world/contact/force_measured"
FORCE_DESIRED_ARROW = "world/contact/force_desired"

CONTACT_PLOTS = "plots/contact"
CONTACT_NORMAL_FORCE = "plots/contact/normal_force"
CONTACT_GAP = "plots/contact/gap"
FORCE = "plots/force"
FORCE_DESIRED = "plots/force/desired"
FORCE_MEASURED = "plots/force/measured"
FORCE_ERROR = "plots/force/error"
FORCE_REFERENCE = "plots/force/reference"
POSITION_ERROR = "plots/position_error"
POSITION_ERROR_ORIENTATION = "plots/position_error/orientation"

CONTROLLER_LOG = "log/controller"
PTP_LOG = "log/ptp"


def axis_paths(group: str) -> tuple[str, str, str]:
    """``(group/x, group/y, group/z)`` for a vector series."""
    return tuple(f"{group}/{axis}" for axis in AXES)


def energy_term(term: str) -> str:
    """Time series of one eq. (5.1) term [J] (``ENERGY_TERMS``)."""
    return f"{ENERGY}/{term}"


def energy_lambda(part: str) -> str:
    """Time series of the Lambda_m / Lambda_r cost of the joint motion [J] (``ENERGY_LAMBDA``)."""
    return f"{ENERGY}/lambda/{part}"


def energy_cost(name: str) -> str:
    """Running C_max [J] or C_sum [J s] (``ENERGY_COSTS``)."""
    return f"{ENERGY}/cost/{name}"


COUPLING_MOMENTUM_AXES = axis_paths(COUPLING_MOMENTUM)
POSITION_ERROR_AXES = axis_paths(POSITION_ERROR)
WHEEL_SPEED_AXES = axis_paths(WHEEL_SPEED)
WHEEL_TORQUE_AXES = axis_paths(WHEEL_TORQUE)
COMMANDED_ANGULAR_VELOCITY_AXES = axis_paths(COMMANDED_ANGULAR_VELOCITY)
ACHIEVED_ANGULAR_VELOCITY_AXES = axis_paths(ACHIEVED_ANGULAR_VELOCITY)
BASE_ATTITUDE_SERIES = (
    BASE_ATTITUDE_ROLL,
    BASE_ATTITUDE_PITCH,
    BASE_ATTITUDE_YAW,
    BASE_ATTITUDE_TOTAL,
)


def joint_transform(joint: str) -> str:
    """Entity of the Transform3D of URDF joint ``joint``."""
    return f"{JOINTS}/{joint}"


def joint_velocity(joint: str) -> str:
    """Time series of the velocity of ``joint`` [rad/s]."""
    return f"{JOINT_VELOCITY}/{joint}"


#: Numeric code of each controller state on ``plots/controller/state`` (teleop.ControllerState).
CONTROLLER_STATE_CODES = {
    "OK": 0,
    "DECELERATING": 1,
    "SINGULAR_REGION": 2,
    "JOINT_LIMIT": 3,
    "IDLE": 4,
    "INVALID_COMMAND": 5,
    "RAMPING": 6,
    "SPEED_LIMITED": 7,
    "WAITING_FOR_STATE": 8,
    "STALE_STATE": 9,
    "CONFLICTING_STATE": 10,
}


#: Numeric code of each rns_ptp phase on ``plots/ptp/phase`` (control.ptp.PhaseInfo names).
PTP_PHASE_CODES = {
    "done": 0,
    "I": 1,
    "II": 2,
    "III": 3,
    "JS-C": 4,
    "IJ-C": 5,
    "TJ-C": 6,
    "deploy": 7,
}


@dataclass(frozen=True)
class Series:
    """Legend entry of one time series: label with unit, and RGB colour."""

    label: str
    color: tuple[int, int, int]


_RGB = ((230, 60, 60), (60, 170, 60), (60, 110, 230))  # x, y, z
_PALE_RGB = ((245, 160, 160), (150, 215, 150), (160, 185, 245))  # commanded x, y, z
_GREY = (90, 90, 90)
_JOINT_RGB = (
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
)


def series_table(joint_names: tuple[str, ...] | list[str]) -> dict[str, Series]:
    """Legend label and colour of every time series, for a robot with ``joint_names``."""
    table = {
        BASE_ATTITUDE_ROLL: Series("roll [deg]", _RGB[0]),
        BASE_ATTITUDE_PITCH: Series("pitch [deg]", _RGB[1]),
        BASE_ATTITUDE_YAW: Series("yaw [deg]", _RGB[2]),
        BASE_ATTITUDE_TOTAL: Series("total angle [deg]", _GREY),
        COUPLING_MOMENTUM_NORM: Series("|M~ θ̇| [kg m²/s]", _GREY),
        SIGMA_MIN: Series("σ_min(J̄) [-]", _RGB[0]),
        DET_KINEMATIC: Series("det(J_ωe J_ωeᵀ) [-]", _RGB[1]),
        DET_ALGORITHMIC: Series("det(J̄ J̄ᵀ) [-]", _RGB[2]),
        DET_COUPLING: Series("det(M~ M~ᵀ) [(kg m²)⁶]", _GREY),
        CONTROLLER_STATE: Series("state code [-]", _GREY),
        CONTROLLER_DAMPING: Series("DLS λ² [-]", _RGB[0]),
        CONTROLLER_SPEED_SCALE: Series("speed scale [-]", _RGB[2]),
        MOMENTUM_LINEAR: Series("|p| [kg m/s]", _RGB[0]),
        MOMENTUM_ANGULAR: Series("|l| [kg m²/s]", _RGB[2]),
        PTP_PHASE: Series("rns_ptp phase code [-]", _GREY),
        PTP_PROGRESS: Series("rns_ptp progress [-]", _RGB[2]),
    }
    for index, term in enumerate(ENERGY_TERMS):
        color = _GREY if term == "total" else _JOINT_RGB[index]
        table[energy_term(term)] = Series(f"{term} [J]", color)
    table[energy_lambda("arm")] = Series("Λ_m part [J]", _RGB[1])
    table[energy_lambda("wheels")] = Series("Λ_r part [J]", _RGB[0])
    table[energy_cost("c_max")] = Series("C_max [J]", _RGB[0])
    table[energy_cost("c_sum")] = Series("C_sum [J s]", _RGB[2])
    for index, axis in enumerate(AXES):
        table[WHEEL_SPEED_AXES[index]] = Series(f"wheel {axis} [rad/s]", _RGB[index])
        table[WHEEL_TORQUE_AXES[index]] = Series(f"wheel {axis} [N m]", _RGB[index])
        table[COUPLING_MOMENTUM_AXES[index]] = Series(f"{axis} [kg m²/s]", _RGB[index])
        table[COMMANDED_ANGULAR_VELOCITY_AXES[index]] = Series(
            f"commanded {axis} [rad/s]", _PALE_RGB[index]
        )
        table[ACHIEVED_ANGULAR_VELOCITY_AXES[index]] = Series(
            f"achieved {axis} [rad/s]", _RGB[index]
        )
    for index, joint in enumerate(joint_names):
        table[joint_velocity(joint)] = Series(
            f"{joint} [rad/s]", _JOINT_RGB[index % len(_JOINT_RGB)]
        )
    return table


def contact_series_table(joint_names: tuple[str, ...] | list[str]) -> dict[str, Series]:
    """Legend label and colour of every time series of a fixed-base arm in contact (Part II):
    joint velocities, contact, force and position-error series."""
    table = {
        CONTACT_NORMAL_FORCE: Series("normal force λ [N]", _RGB[2]),
        CONTACT_GAP: Series("gap φ [m] (> 0 penetration)", _RGB[0]),
        FORCE_DESIRED: Series("desired f_des [N]", _PALE_RGB[2]),
        FORCE_MEASURED: Series("measured f [N]", _RGB[2]),
        FORCE_ERROR: Series("error f_des - f [N]", _RGB[0]),
        FORCE_REFERENCE: Series("reference f_ref (6.34) [N]", _GREY),
        POSITION_ERROR_ORIENTATION: Series("orientation |log(R_des Rᵀ)| [rad]", _GREY),
    }
    for index, axis in enumerate(AXES):
        table[POSITION_ERROR_AXES[index]] = Series(f"{axis} [m]", _RGB[index])
    for index, joint in enumerate(joint_names):
        table[joint_velocity(joint)] = Series(
            f"{joint} [rad/s]", _JOINT_RGB[index % len(_JOINT_RGB)]
        )
    return table
