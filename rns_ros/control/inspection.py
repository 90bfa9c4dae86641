"""Reactionless camera-orientation control, thesis section 4.2-4.3 (continuous-time law).

theta_dot_ref = J-bar^inv omega_ref - k_g P J_vw^T dp_w                      eq. (4.5)
    J-bar = J_omega_e P_RNS (restricted Jacobian), P = P_RNS (E - J-bar^+ J-bar),
    J-bar^inv: pseudoinverse (4.9), DLS with numerical filtering (4.10-4.12) or the
    Singularity-Consistent inverse (4.13-4.14; its null term is scaled by det(J-bar J-bar^T), 4.15).
Conventional baseline, eq. (4.7)-(4.8): theta_dot_W = J_W_omega_e^-1 omega_ref, theta_dot_P = 0.

Sign of the wrist term: (4.5) prints +k_g P J_vw^T dp_w, but V = |dp_w|^2 / 2 (4.6) decreases only
along -J_vw^T dp_w, so the descent sign is used (a test shows the drift shrinking). dp_w is the
wrist position relative to the base origin (world axes) minus its initial value: under reactionless
motion the base does not turn, and J_vw theta_dot is exactly the rate of that relative position.

Joint-speed limits scale the whole theta_dot uniformly, which keeps it in the reaction null space
and keeps its direction (per-joint clipping would not).

This module is the continuous-time law; holding its output over a control period (the ROS
controller) needs the hold-interval correction of the controller issue.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from rns_ros.core.errors import ConfigError, ModelError
from rns_ros.core.fastmath import (
    gram_determinant,
    inverse_small,
    solve_small,
    svd_small,
    symmetric_eigenvalues,
)
from rns_ros.core.inverses import (
    THESIS_EPSILON,
    THESIS_LAMBDA2_MAX,
    THESIS_SC_GAIN,
    TINY,
    WideSvd,
    dls_from_svd,
    pseudoinverse_from_svd,
    sc_from_svd,
)
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.state import (
    GRAM_CONDITION_LIMIT,
    ArmKinematics,
    Determinants,
    FreeFloatingState,
)
from rns_ros.core.validation import Choice, as_vector, positive

#: Singular values of J-bar below this fraction of sigma_max count as lost for P [-].
_RANK_RCOND = 1e-12
#: SC and pinv take the closed form of :func:`law_rates` while sigma_min(J-bar) exceeds this [-]
#: (S = J-bar J-bar^T then has a condition number below ~1e7); closer, the SVD.
_CLOSED_FORM_SIGMA = 1e-3

#: Thesis wrist-stabilization gain k_g of eq. (4.5) [1/(m s)] (section 4.2.2 prints "kg/m s").
THESIS_WRIST_GAIN = 100.0


class Method(Choice):
    """How omega_ref is mapped to joint velocities."""

    __label__ = "method"

    DLS = "dls"
    SC = "sc"
    PINV = "pinv"
    CONVENTIONAL = "conventional"


@dataclass(frozen=True)
class ControlGains:
    """Gains of eq. (4.5)-(4.15), thesis values by default.

    Attributes:
        epsilon: DLS singular region on sigma_min [-].
        lambda2_max: DLS maximum damping lambda_max^2 [-].
        sc_gain: b of the SC inverse [-].
        wrist_gain: k_g [1/(m s)], >= 0 (0 disables wrist stabilization).
    """

    epsilon: float = THESIS_EPSILON
    lambda2_max: float = THESIS_LAMBDA2_MAX
    sc_gain: float = THESIS_SC_GAIN
    wrist_gain: float = THESIS_WRIST_GAIN

    def __post_init__(self) -> None:
        positive(self.epsilon, "epsilon")
        positive(self.lambda2_max, "lambda2_max")
        positive(self.sc_gain, "sc_gain")
        if not (np.isfinite(self.wrist_gain) and self.wrist_gain >= 0.0):
            raise ConfigError(
                f"wrist_gain must be finite and >= 0 1/(m s), got {self.wrist_gain!r}"
            )


@dataclass(frozen=True)
class ControlOutput:
    """One evaluation of the control law.

    Attributes:
        joint_velocity: theta_dot_ref after speed scaling [rad/s], shape (n,).
        sigma_min: smallest singular value of J-bar (of J_W_omega_e for the baseline) [-].
        determinants: the three determinants of section 4.3.1.
        damping: DLS lambda^2 applied [-] (0 for other methods).
        speed_scale: overall speed factor applied: SC's b prod(sigma) times the joint-limit
            scale [-] (1 means the command is met at full speed).
        limit_scale: the joint-limit part of ``speed_scale`` alone, in [0, 1] (0 when a joint
            sits at a position limit and the command pushes into it).
        position_limited: True when a joint position limit reduced ``limit_scale``.
        angular_residual: omega_ref - J_omega_e theta_dot, the part of the command not achieved
            [rad/s], shape (3,).
        coupling_momentum: predicted base disturbance M~_omega_m theta_dot [kg m^2/s], shape (3,).
    """

    joint_velocity: np.ndarray
    sigma_min: float
    determinants: Determinants
    damping: float
    speed_scale: float
    limit_scale: float
    position_limited: bool
    angular_residual: np.ndarray
    coupling_momentum: np.ndarray


def wrist_offset(state: FreeFloatingState) -> np.ndarray:
    """Wrist position relative to the base origin, world axes [m], shape (3,)."""
    if state.wrist is None:
        raise ModelError("the model has no wrist frame; wrist stabilization needs one")
    return state.wrist.position - state.base_position


def uniform_speed_scale(theta_dot: np.ndarray, velocity_limits: np.ndarray) -> float:
    """Largest s in (0, 1] with |s theta_dot_i| <= limit_i for every joint."""
    ratios = np.abs(theta_dot) / velocity_limits
    worst = float(ratios.max(initial=0.0))
    return 1.0 if worst <= 1.0 else 1.0 / worst


def position_limit_scale(
    theta: np.ndarray,
    theta_dot: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    horizon: float,
) -> float:
    """Largest s in [0, 1] such that theta + s theta_dot horizon stays within [lower, upper].

    Joints moving away from their limit never restrict s; a joint at (or past) its limit and
    moving into it gives s = 0, i.e. the whole motion halts (uniformly, so it stays reactionless).

    Args:
        theta, theta_dot, lower, upper: [rad], [rad/s], [rad], [rad], shape (n,).
        horizon: look-ahead time [s], > 0 (one control period).
    """
    step = theta_dot * horizon
    room = np.maximum(np.where(step > 0.0, upper - theta, theta - lower), 0.0)
    moving = np.abs(step)
    # s = room / |step| for moving joints; scale only where the step would use up the room
    binding = moving > room
    if not binding.any():
        return 1.0
    return float((room[binding] / moving[binding]).min())


class LawRates(NamedTuple):
    """The joint velocity of one evaluation of the law and what it was made with.

    Attributes:
        joint_velocity: theta_dot_ref after speed and position-limit scaling [rad/s], (n,).
        sigma_min: smallest singular value of J-bar (of J_W_omega_e for the baseline) [-].
        algorithmic: det(J-bar J-bar^T) [-].
        damping: DLS lambda^2 applied [-] (0 for other methods).
        sc_scale: SC's b prod(sigma) [-] (1 for other methods).
        limit_scale: joint-limit scale in [0, 1] [-].
        position_limited: True when a joint position limit reduced ``limit_scale``.
    """

    joint_velocity: np.ndarray
    sigma_min: float
    algorithmic: float
    damping: float
    sc_scale: float
    limit_scale: float
    position_limited: bool


def reactionless_camera_control(
    robot: FreeFloatingModel,
    state: FreeFloatingState,
    omega_ref,
    *,
    method: Method | str = Method.DLS,
    gains: ControlGains | None = None,
    wrist_reference: np.ndarray | None = None,
    limit_horizon: float | None = None,
) -> ControlOutput:
    """Evaluate eq. (4.5)/(4.15) (or the baseline 4.7-4.8) at ``state``.

    Args:
        omega_ref: commanded camera angular velocity, world axes [rad/s], shape (3,).
        method: :class:`Method` or its value.
        gains: :class:`ControlGains` (thesis values by default).
        wrist_reference: initial wrist offset p_w^init (see :func:`wrist_offset`) [m], shape (3,);
            None disables the wrist term.
        limit_horizon: look-ahead [s] for joint position limits (one control period); None
            ignores position limits. Velocity limits always apply.
    """
    omega_ref = as_vector(omega_ref, 3, "omega_ref")
    if wrist_reference is not None:
        wrist_reference = as_vector(wrist_reference, 3, "wrist_reference")
    rates = law_rates(
        robot,
        state,
        omega_ref,
        Method.parse(method),
        gains or ControlGains(),
        wrist_reference,
        limit_horizon,
    )
    return control_output(state, omega_ref, rates)


def control_output(
    state: FreeFloatingState, omega_ref: np.ndarray, rates: LawRates
) -> ControlOutput:
    """The :class:`ControlOutput` of ``rates`` (the law evaluated at ``state``)."""
    theta_dot = rates.joint_velocity
    j_omega = state.camera.jacobian[3:]
    sigma = state.coupling_singular_values.tolist()
    return ControlOutput(
        joint_velocity=theta_dot,
        sigma_min=rates.sigma_min,
        determinants=Determinants(
            kinematic=gram_determinant(j_omega),
            coupling=math.prod(value * value for value in sigma),
            algorithmic=rates.algorithmic,
        ),
        damping=rates.damping,
        speed_scale=rates.sc_scale * rates.limit_scale,
        limit_scale=rates.limit_scale,
        position_limited=rates.position_limited,
        angular_residual=omega_ref - j_omega @ theta_dot,
        coupling_momentum=state.coupling_angular_momentum_matrix @ theta_dot,
    )


def arm_law_rates(
    robot: FreeFloatingModel,
    arm: ArmKinematics,
    omega_ref: np.ndarray,
    method: Method,
    gains: ControlGains,
    wrist_reference: np.ndarray | None,
    limit_horizon: float | None,
    coupling_scale: float,
) -> tuple[LawRates, ControlOutput] | None:
    """The law of :func:`law_rates` on :class:`ArmKinematics`, without P_RNS or an SVD, and its
    :class:`ControlOutput`.

    With A = [J_omega_e; M~_omega_m / s] (6, n) (s = ``coupling_scale`` [kg m^2], e.g.
    sigma_max of M~, only balances the rows) and Y = (A A^T)^-1 (6 x 6), the reactionless
    minimum-norm solutions are A^+ = A^T Y: J-bar^+ omega = A^+ [omega; 0] (J-bar = J_omega_e
    P_RNS, eq. 4.5), the projector of the wrist term P = P_RNS (E - J-bar^+ J-bar) = E - A^+ A,
    and Y's upper-left 3 x 3 block is S^-1 with S = J-bar J-bar^T (the Schur complement of
    M~ M~^T in A A^T), whose eigenvalues give sigma(J-bar). So, as in :func:`law_rates`,

        theta_dot = A^T Y ([c omega_ref; 0] + k A g) - k g,  g = J_vw^T dp_w,

    one 6 x 6 inverse; A A^T also holds J_omega_e J_omega_e^T and M~ M~^T for the determinants,
    and A theta_dot the achieved rate and the coupling momentum. Returns None where this form
    does not apply: DLS inside its singular region (sigma_min(J-bar) <= epsilon), SC and pinv
    with sigma_min <= _CLOSED_FORM_SIGMA, M~ closer to a coupling singularity than
    GRAM_CONDITION_LIMIT, the conventional baseline; the caller then evaluates
    :func:`law_rates` on the full state.
    """
    if method is Method.CONVENTIONAL:
        return None
    stacked = np.concatenate((arm.camera_angular_jacobian, arm.coupling_angular_momentum_matrix))
    stacked[3:] *= 1.0 / coupling_scale
    gram = stacked @ stacked.T
    coupling_gram = gram[3:, 3:].tolist()
    coupling_determinant = _determinant_3x3(coupling_gram)  # of M~ M~^T / s^6
    trace = coupling_gram[0][0] + coupling_gram[1][1] + coupling_gram[2][2]
    # lambda_min / lambda_max >= det / trace^3: enough to show M~ far from a coupling singularity
    if coupling_determinant <= GRAM_CONDITION_LIMIT**2 * trace**3:
        eigenvalues = symmetric_eigenvalues(gram[3:, 3:])
        if eigenvalues[0] <= GRAM_CONDITION_LIMIT**2 * eigenvalues[-1]:
            return None
    inverse = inverse_small(gram)
    inverse_eigenvalues = symmetric_eigenvalues(inverse[:3, :3]).tolist()  # 1 / sigma_i^2
    sigma_min = 1.0 / math.sqrt(inverse_eigenvalues[-1])
    if sigma_min <= (gains.epsilon if method is Method.DLS else _CLOSED_FORM_SIGMA):
        return None
    algorithmic = 1.0 / math.prod(inverse_eigenvalues)
    sc_scale = gains.sc_gain * math.sqrt(algorithmic) if method is Method.SC else 1.0
    command = sc_scale * omega_ref if method is Method.SC else omega_ref
    if wrist_reference is not None and gains.wrist_gain > 0.0:
        gain = gains.wrist_gain * (algorithmic if method is Method.SC else 1.0)
        gradient = arm.wrist_linear_jacobian.T @ (arm.wrist_offset - wrist_reference)
        gradient *= gain
        rhs = stacked @ gradient
        rhs[:3] += command
    else:
        gradient = None
        rhs = np.zeros(6)
        rhs[:3] = command
    # y = (A A^T)^-1 rhs with one step of iterative refinement: cond(A A^T) reaches 1e4-1e6 near
    # the singular region, and M~ theta_dot = 0 rests on (A A^T) y = rhs (1e-9 kg m^2/s without,
    # 1e-11 with, as P_RNS gives)
    multipliers = inverse @ rhs
    multipliers += inverse @ (rhs - gram @ multipliers)
    theta_dot = stacked.T @ multipliers
    if gradient is not None:
        theta_dot -= gradient
    theta_dot, limit_scale, position_limited = _limited(robot, arm.theta, theta_dot, limit_horizon)
    rates = LawRates(
        theta_dot, sigma_min, algorithmic, 0.0, sc_scale, limit_scale, position_limited
    )
    achieved = stacked @ theta_dot  # [J_omega_e theta_dot; M~ theta_dot / s]
    camera_gram = gram[:3, :3].tolist()
    output = ControlOutput(
        joint_velocity=theta_dot,
        sigma_min=sigma_min,
        determinants=Determinants(
            kinematic=_determinant_3x3(camera_gram),
            coupling=coupling_determinant * coupling_scale**6,
            algorithmic=algorithmic,
        ),
        damping=0.0,
        speed_scale=sc_scale * limit_scale,
        limit_scale=limit_scale,
        position_limited=position_limited,
        angular_residual=omega_ref - achieved[:3],
        coupling_momentum=coupling_scale * achieved[3:],
    )
    return rates, output


def _determinant_3x3(matrix: list) -> float:
    """det of a symmetric 3 x 3 matrix given as nested lists (closed form)."""
    (a, b, c), (_, e, f), (_, _, i) = matrix
    return a * (e * i - f * f) - b * (b * i - f * c) + c * (b * f - e * c)


def _limited(robot, theta, theta_dot, limit_horizon):
    """(theta_dot, limit scale, position limited) after the uniform speed and position-limit
    scaling of :func:`law_rates`."""
    limit_scale = uniform_speed_scale(theta_dot, robot.velocity_limits)
    if limit_scale < 1.0:
        theta_dot = limit_scale * theta_dot
    position_limited = False
    if limit_horizon is not None:
        position_scale = position_limit_scale(
            theta, theta_dot, robot.lower_limits, robot.upper_limits, limit_horizon
        )
        if position_scale < 1.0:
            position_limited = True
            limit_scale *= position_scale
            theta_dot = position_scale * theta_dot
    return theta_dot, limit_scale, position_limited


def law_rates(
    robot: FreeFloatingModel,
    state: FreeFloatingState,
    omega_ref: np.ndarray,
    method: Method,
    gains: ControlGains,
    wrist_reference: np.ndarray | None,
    limit_horizon: float | None,
) -> LawRates:
    """theta_dot of eq. (4.5)/(4.15) (or 4.7-4.8) at ``state``, without the diagnostics record.

    Arguments as :func:`reactionless_camera_control`, already parsed: ``omega_ref`` (3,) and
    ``wrist_reference`` (3,) or None as float arrays, ``method`` a :class:`Method`.

    Where J-bar is well conditioned (DLS: sigma_min > epsilon, no damping; SC and pinv:
    sigma_min > _CLOSED_FORM_SIGMA) the law needs no SVD: J-bar^+ = J-bar^T S^-1 with
    S = J-bar J-bar^T (3 x 3), J-bar^SC = b sqrt(det S) J-bar^+ (4.13, mu_i = prod(sigma) /
    sigma_i), and P g = P_RNS g - J-bar^+ J-bar g, so with k = k_g (times det S for SC, 4.15)

        theta_dot = J-bar^T S^-1 (c omega_ref + k J-bar g) - k P_RNS g,  g = J_vw^T dp_w,

    c = 1 (dls, pinv) or b sqrt(det S) (sc): one 3 x 3 solve. Elsewhere the SVD of J-bar.
    """
    j_omega = state.camera.jacobian[3:]
    projector = state.reaction_null_space_projector
    restricted = j_omega @ projector
    gram = restricted @ restricted.T
    eigenvalues = symmetric_eigenvalues(gram).tolist()  # sigma_i^2 of J-bar, ascending
    sigma_min = math.sqrt(max(eigenvalues[0], 0.0))
    algorithmic = math.prod(eigenvalues)
    damping, sc_scale = 0.0, 1.0
    if method is Method.CONVENTIONAL:
        theta_dot, sigma_min = _conventional(robot, j_omega, omega_ref)
    else:
        wrist = wrist_reference is not None and gains.wrist_gain > 0.0
        regular = sigma_min > (gains.epsilon if method is Method.DLS else _CLOSED_FORM_SIGMA)
        if regular:
            scale = 1.0
            if method is Method.SC:
                sc_scale = gains.sc_gain * math.sqrt(algorithmic)
                scale = sc_scale
            rhs = scale * omega_ref
            if wrist:
                gain = gains.wrist_gain * (algorithmic if method is Method.SC else 1.0)
                gradient = state.wrist.jacobian[:3].T @ (wrist_offset(state) - wrist_reference)
                rhs = rhs + gain * (restricted @ gradient)
                theta_dot = restricted.T @ solve_small(gram, rhs) - gain * (projector @ gradient)
            else:
                theta_dot = restricted.T @ solve_small(gram, rhs)
        else:
            theta_dot, damping, sc_scale, sigma_min, algorithmic = _svd_law(
                state, restricted, omega_ref, method, gains, wrist_reference if wrist else None
            )
    theta_dot, limit_scale, position_limited = _limited(
        robot, state.theta, theta_dot, limit_horizon
    )
    return LawRates(
        theta_dot, sigma_min, algorithmic, damping, sc_scale, limit_scale, position_limited
    )


def _svd_law(state, restricted, omega_ref, method, gains, wrist_reference):
    """The law from the SVD of J-bar (inside the DLS region, near singular SC / pinv):
    (theta_dot (n,), lambda^2, SC scale, sigma_min, det(J-bar J-bar^T))."""
    svd = WideSvd(*svd_small(restricted))
    damping, sc_scale = 0.0, 1.0
    if method is Method.DLS:
        inverse = dls_from_svd(svd, gains.epsilon, gains.lambda2_max)
        matrix, damping = inverse.matrix, inverse.damping
    elif method is Method.SC:
        inverse = sc_from_svd(svd, gains.sc_gain)
        matrix, sc_scale = inverse.matrix, inverse.speed_scale
    else:
        matrix = pseudoinverse_from_svd(svd)
    determinant = float(np.prod(svd.sigma**2))
    theta_dot = matrix @ omega_ref
    if wrist_reference is not None:
        drift = wrist_offset(state) - wrist_reference
        # P = P_RNS (E - J-bar^+ J-bar) = P_RNS - V_r V_r^T: the right singular vectors of
        # J-bar with sigma > 0 already lie in range(P_RNS)
        kept = svd.vt[svd.sigma > _RANK_RCOND * max(svd.sigma[0], TINY)]
        gradient = state.wrist.jacobian[:3].T @ drift
        null_gradient = state.reaction_null_space_projector @ gradient - kept.T @ (kept @ gradient)
        term = -gains.wrist_gain * null_gradient
        if method is Method.SC:
            term *= determinant  # det(J-bar J-bar^T), eq. (4.15)
        theta_dot = theta_dot + term
    return theta_dot, damping, sc_scale, float(svd.sigma[-1]), determinant


def _conventional(robot: FreeFloatingModel, j_omega: np.ndarray, omega_ref: np.ndarray):
    """Eq. (4.7)-(4.8): wrist joints invert J_W_omega_e, positioning joints held."""
    if robot.subchains is None:
        raise ModelError("the conventional baseline needs positioning/wrist subchains")
    wrist = robot.subchains.wrist
    j_wrist = j_omega[:, wrist]
    svd = WideSvd(*svd_small(j_wrist))
    theta_dot = np.zeros(robot.n)
    theta_dot[wrist] = pseudoinverse_from_svd(svd) @ omega_ref
    return theta_dot, float(svd.sigma[-1])
