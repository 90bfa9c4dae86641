"""Every rerun entity path rns_ros logs, in one place, with its archetype, unit and source topic.

Paths carry no leading slash (rerun adds it). All vectors are in world axes unless a name says
otherwise; angles in plots are degrees, rates rad/s. The table of every path, its archetype and
source topic: docs/rerun_entities.md.
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
#: Simple shapes of the links without a resolvable visual: ``ROBOT_SHAPES/<link>``.
ROBOT_SHAPES = f"{ROBOT}/shapes"
#: Static transform from the model's base frame to the URDF's root link (a base the URDF lacks).
ROBOT_MOUNT = f"{ROBOT}/mount"
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
#: Teleoperation from the ground (rns_predictor, rns_link): the arm predicted for each on-board
#: instant, logged at that instant, and the telemetry arm as the ground receives it, logged at
#: its receipt.
PREDICTED_ARM = "world/ground/predicted"
PREDICTED_ARM_JOINTS = "world/ground/predicted/joints"
TELEMETRY_ARM = "world/ground/telemetry"
TELEMETRY_ARM_JOINTS = "world/ground/telemetry/joints"
#: The predicted camera's frustum (a pinhole at the predicted camera pose, +z forward).
PREDICTED_CAMERA = "world/ground/predicted/camera"
#: rns_predictor's prediction error (predicted at t vs the telemetry of t, once it arrived).
PREDICTION_ERROR = "plots/ground/prediction_error"
PREDICTION_ERROR_CAMERA = "plots/ground/prediction_error/camera_deg"
PREDICTION_ERROR_BASE = "plots/ground/prediction_error/base_deg"
#: rns_link's state, per direction (uplink, downlink): one-way delay of the newest message
#: delivered [s], messages in flight, messages lost so far.
LINK = "plots/ground/link"
LINK_FIGURES = ("delay_s", "in_flight", "lost")

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
    "PAUSED": 11,
    "GOAL_ACTIVE": 12,
    "GOAL_REACHED": 13,
    "CLOCK_FAULT": 14,
    "STATE_GAP": 15,
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
