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

Each singularity treatment is one :class:`SingularityTreatment` object (DLS, SC, pseudoinverse,
conventional), selected from :class:`Method` by :func:`singularity_treatment`.

Joint speed and position limits scale the whole theta_dot uniformly
(:mod:`rns_ros.control.joint_limits`), which keeps it in the reaction null space.

This module is the continuous-time law; holding its output over a control period needs the
hold-interval correction of :mod:`rns_ros.control.controller`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import ClassVar, NamedTuple

import numpy as np

from rns_ros.control.joint_limits import scale_to_joint_limits
from rns_ros.control.law_matrices import (
    RestrictedJacobian,
    StackedJacobian,
    determinant_3x3,
    restricted_jacobian,
    stacked_jacobian,
)
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
from rns_ros.core.state import ArmKinematics, Determinants, FreeFloatingState
from rns_ros.core.validation import Choice, as_vector, positive

#: Singular values of J-bar below this fraction of sigma_max count as lost for P [-].
_RANK_RCOND = 1e-12
#: SC and pinv take the closed form of :class:`ReactionlessInverse` while sigma_min(J-bar)
#: exceeds this [-] (S = J-bar J-bar^T then has a condition number below ~1e7); closer, the SVD.
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


class UnscaledRates(NamedTuple):
    """theta_dot of one treatment before the speed and position-limit scaling.

    Attributes:
        joint_velocity: theta_dot_ref [rad/s], shape (n,).
        sigma_min: smallest singular value of J-bar (of J_W_omega_e for the baseline) [-].
        algorithmic: det(J-bar J-bar^T) [-].
        damping: DLS lambda^2 applied [-] (0 for other treatments).
        sc_scale: SC's b prod(sigma) [-] (1 for other treatments).
    """

    joint_velocity: np.ndarray
    sigma_min: float
    algorithmic: float
    damping: float
    sc_scale: float


class SingularityTreatment(ABC):
    """How omega_ref becomes theta_dot (section 4.3): one object per :class:`Method`, chosen by
    :func:`singularity_treatment`.

    Attributes:
        method: the :class:`Method` this object evaluates.
    """

    method: ClassVar[Method]

    @abstractmethod
    def state_rates(
        self, robot, state, jacobian, omega_ref, gains, wrist_reference
    ) -> UnscaledRates:
        """theta_dot at the full ``state`` (arguments as :func:`law_rates`; ``jacobian`` the
        :class:`RestrictedJacobian` of ``state``)."""

    @abstractmethod
    def arm_rates(
        self, robot, arm, omega_ref, gains, wrist_reference, limit_horizon, coupling_scale
    ) -> tuple[LawRates, ControlOutput] | None:
        """The law on :class:`ArmKinematics` (arguments as :func:`arm_law_rates`), or None
        where its closed form does not apply."""


class ReactionlessInverse(SingularityTreatment):
    """Eq. (4.5)/(4.15) with a generalized inverse of J-bar: closed form where J-bar is well
    conditioned, the SVD of J-bar elsewhere.

    Closed form (sigma_min > :meth:`closed_form_limit`): J-bar^+ = J-bar^T S^-1 with
    S = J-bar J-bar^T (3 x 3) and P g = P_RNS g - J-bar^+ J-bar g, so with k = k_g w

        theta_dot = J-bar^T S^-1 (c omega_ref + k J-bar g) - k P_RNS g,  g = J_vw^T dp_w,

    one 3 x 3 solve; c is :meth:`command_scale`, w is :meth:`wrist_weight`.
    SVD form: theta_dot = J-bar^inv omega_ref - k_g w P g with J-bar^inv from
    :meth:`svd_inverse` and P = P_RNS - V_r V_r^T (V_r the right singular vectors of J-bar with
    sigma > 0, which already lie in range(P_RNS)).
    """

    def closed_form_limit(self, gains: ControlGains) -> float:
        """sigma_min(J-bar) above which the closed form is used [-]."""
        return _CLOSED_FORM_SIGMA

    def command_scale(self, gains: ControlGains, determinant: float) -> float:
        """c of the closed form (1: J-bar^inv omega_ref = J-bar^+ omega_ref) [-]."""
        return 1.0

    def wrist_weight(self, determinant: float) -> float:
        """w multiplying k_g of the wrist term (1: eq. 4.5) [-]."""
        return 1.0

    @abstractmethod
    def svd_inverse(self, svd: WideSvd, gains: ControlGains) -> tuple[np.ndarray, float, float]:
        """(J-bar^inv (n, 3), lambda^2 [-], SC scale [-]) from the SVD of J-bar."""

    def state_rates(self, robot, state, jacobian, omega_ref, gains, wrist_reference):
        if wrist_reference is None or not gains.wrist_gain > 0.0:
            wrist_reference = None
        if jacobian.sigma_min > self.closed_form_limit(gains):
            return self.closed_form_rates(state, jacobian, omega_ref, gains, wrist_reference)
        return self.svd_rates(state, jacobian.matrix, omega_ref, gains, wrist_reference)

    def closed_form_rates(
        self,
        state: FreeFloatingState,
        jacobian: RestrictedJacobian,
        omega_ref: np.ndarray,
        gains: ControlGains,
        wrist_reference: np.ndarray | None,
    ) -> UnscaledRates:
        """The closed form (see the class); ``wrist_reference`` None: no wrist term."""
        restricted, gram = jacobian.matrix, jacobian.gram
        sc_scale = self.command_scale(gains, jacobian.determinant)
        rhs = sc_scale * omega_ref
        if wrist_reference is None:
            theta_dot = restricted.T @ solve_small(gram, rhs)
        else:
            gain = gains.wrist_gain * self.wrist_weight(jacobian.determinant)
            gradient = state.wrist.jacobian[:3].T @ (wrist_offset(state) - wrist_reference)
            rhs = rhs + gain * (restricted @ gradient)
            theta_dot = restricted.T @ solve_small(gram, rhs) - gain * (
                jacobian.projector @ gradient
            )
        return UnscaledRates(theta_dot, jacobian.sigma_min, jacobian.determinant, 0.0, sc_scale)

    def svd_rates(
        self,
        state: FreeFloatingState,
        restricted: np.ndarray,
        omega_ref: np.ndarray,
        gains: ControlGains,
        wrist_reference: np.ndarray | None,
    ) -> UnscaledRates:
        """The SVD form (see the class) for J-bar = ``restricted`` (3, n); ``wrist_reference``
        None: no wrist term."""
        svd = WideSvd(*svd_small(restricted))
        matrix, damping, sc_scale = self.svd_inverse(svd, gains)
        determinant = float(np.prod(svd.sigma**2))
        theta_dot = matrix @ omega_ref
        if wrist_reference is not None:
            drift = wrist_offset(state) - wrist_reference
            kept = svd.vt[svd.sigma > _RANK_RCOND * max(svd.sigma[0], TINY)]
            gradient = state.wrist.jacobian[:3].T @ drift
            projector = state.reaction_null_space_projector
            null_gradient = projector @ gradient - kept.T @ (kept @ gradient)
            term = -gains.wrist_gain * null_gradient
            term *= self.wrist_weight(determinant)
            theta_dot = theta_dot + term
        return UnscaledRates(theta_dot, float(svd.sigma[-1]), determinant, damping, sc_scale)

    def arm_rates(
        self, robot, arm, omega_ref, gains, wrist_reference, limit_horizon, coupling_scale
    ):
        system = stacked_jacobian(arm, coupling_scale)
        if system is None:
            return None
        inverse = inverse_small(system.gram)
        inverse_eigenvalues = symmetric_eigenvalues(inverse[:3, :3]).tolist()  # 1 / sigma_i^2
        sigma_min = 1.0 / math.sqrt(inverse_eigenvalues[-1])
        if sigma_min <= self.closed_form_limit(gains):
            return None
        algorithmic = 1.0 / math.prod(inverse_eigenvalues)
        sc_scale = self.command_scale(gains, algorithmic)
        command = sc_scale * omega_ref
        stacked, gram = system.matrix, system.gram
        if wrist_reference is not None and gains.wrist_gain > 0.0:
            gain = gains.wrist_gain * self.wrist_weight(algorithmic)
            gradient = arm.wrist_linear_jacobian.T @ (arm.wrist_offset - wrist_reference)
            gradient *= gain
            rhs = stacked @ gradient
            rhs[:3] += command
        else:
            gradient = None
            rhs = np.zeros(6)
            rhs[:3] = command
        # y = (A A^T)^-1 rhs with one step of iterative refinement: cond(A A^T) reaches 1e4-1e6
        # near the singular region, and M~ theta_dot = 0 rests on (A A^T) y = rhs (the residual
        # M~ theta_dot is 1e-11 kg m^2/s with the step, as P_RNS gives, 1e-9 without)
        multipliers = inverse @ rhs
        multipliers += inverse @ (rhs - gram @ multipliers)
        theta_dot = stacked.T @ multipliers
        if gradient is not None:
            theta_dot -= gradient
        theta_dot, limit_scale, position_limited = scale_to_joint_limits(
            robot, arm.theta, theta_dot, limit_horizon
        )
        rates = LawRates(
            theta_dot, sigma_min, algorithmic, 0.0, sc_scale, limit_scale, position_limited
        )
        return rates, _stacked_output(system, omega_ref, rates)


class DampedLeastSquares(ReactionlessInverse):
    """DLS inverse with numerical filtering, eq. (4.10)-(4.12).

    Closed form outside the singular region (sigma_min > epsilon): lambda^2 = 0 by (4.12), so
    J-bar^# = J-bar^+ = J-bar^T S^-1 (4.9-4.10). SVD form inside it: J-bar^# of (4.11)
    (:func:`~rns_ros.core.inverses.dls_from_svd`).
    """

    method = Method.DLS

    def closed_form_limit(self, gains: ControlGains) -> float:
        return gains.epsilon

    def svd_inverse(self, svd, gains):
        inverse = dls_from_svd(svd, gains.epsilon, gains.lambda2_max)
        return inverse.matrix, inverse.damping, 1.0


class SingularityConsistent(ReactionlessInverse):
    """Singularity-Consistent inverse, eq. (4.13)-(4.15).

    J-bar^SC = b sum_i mu_i v_i u_i^T with mu_i = prod(sigma) / sigma_i (4.13-4.14), so
    J-bar^SC = b sqrt(det S) J-bar^+: closed form with c = b sqrt(det S); SVD form
    :func:`~rns_ros.core.inverses.sc_from_svd`. The wrist term is weighted by det S (4.15).
    """

    method = Method.SC

    def command_scale(self, gains: ControlGains, determinant: float) -> float:
        return gains.sc_gain * math.sqrt(determinant)

    def wrist_weight(self, determinant: float) -> float:
        return determinant

    def svd_inverse(self, svd, gains):
        inverse = sc_from_svd(svd, gains.sc_gain)
        return inverse.matrix, 0.0, inverse.speed_scale


class Pseudoinverse(ReactionlessInverse):
    """Moore-Penrose pseudoinverse, eq. (4.9): closed form J-bar^T S^-1, SVD form
    :func:`~rns_ros.core.inverses.pseudoinverse_from_svd` (unbounded as sigma_min -> 0)."""

    method = Method.PINV

    def svd_inverse(self, svd, gains):
        return pseudoinverse_from_svd(svd), 0.0, 1.0


class ConventionalWrist(SingularityTreatment):
    """The conventional baseline, eq. (4.7)-(4.8): the wrist joints invert J_W_omega_e (through
    its SVD, eq. 4.9), the positioning joints are held. Not reactionless, so no closed form on
    :class:`ArmKinematics`."""

    method = Method.CONVENTIONAL

    def state_rates(self, robot, state, jacobian, omega_ref, gains, wrist_reference):
        if robot.subchains is None:
            raise ModelError("the conventional baseline needs positioning/wrist subchains")
        wrist = robot.subchains.wrist
        svd = WideSvd(*svd_small(jacobian.angular[:, wrist]))
        theta_dot = np.zeros(robot.n)
        theta_dot[wrist] = pseudoinverse_from_svd(svd) @ omega_ref
        return UnscaledRates(theta_dot, float(svd.sigma[-1]), jacobian.determinant, 0.0, 1.0)

    def arm_rates(
        self, robot, arm, omega_ref, gains, wrist_reference, limit_horizon, coupling_scale
    ):
        return None


_TREATMENTS: Mapping[Method, SingularityTreatment] = MappingProxyType(
    {
        treatment.method: treatment
        for treatment in (
            DampedLeastSquares(),
            SingularityConsistent(),
            Pseudoinverse(),
            ConventionalWrist(),
        )
    }
)


def singularity_treatment(method: Method | str) -> SingularityTreatment:
    """The :class:`SingularityTreatment` of ``method`` (a :class:`Method` or its value)."""
    return _TREATMENTS[Method.parse(method)]


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
    ``wrist_reference`` (3,) or None as float arrays, ``method`` a :class:`Method`. The
    treatment of ``method`` (:func:`singularity_treatment`) gives theta_dot; the speed and
    position limits then scale it uniformly.
    """
    rates = singularity_treatment(method).state_rates(
        robot, state, restricted_jacobian(state), omega_ref, gains, wrist_reference
    )
    theta_dot, limit_scale, position_limited = scale_to_joint_limits(
        robot, state.theta, rates.joint_velocity, limit_horizon
    )
    return LawRates(
        theta_dot,
        rates.sigma_min,
        rates.algorithmic,
        rates.damping,
        rates.sc_scale,
        limit_scale,
        position_limited,
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

    With A = [J_omega_e; M~_omega_m / s] (6, n) (:class:`StackedJacobian`, s =
    ``coupling_scale`` [kg m^2]) and Y = (A A^T)^-1 (6 x 6), as in the closed form of
    :class:`ReactionlessInverse`:

        theta_dot = A^T Y ([c omega_ref; 0] + k A g) - k g,  g = J_vw^T dp_w,

    one 6 x 6 inverse. Returns None where this form does not apply: sigma_min(J-bar) at or
    below the treatment's closed-form limit (DLS: epsilon; SC and pinv: _CLOSED_FORM_SIGMA),
    M~ closer to a coupling singularity than GRAM_CONDITION_LIMIT, the conventional baseline;
    the caller then evaluates :func:`law_rates` on the full state.
    """
    return singularity_treatment(method).arm_rates(
        robot, arm, omega_ref, gains, wrist_reference, limit_horizon, coupling_scale
    )


def _stacked_output(
    system: StackedJacobian, omega_ref: np.ndarray, rates: LawRates
) -> ControlOutput:
    """The :class:`ControlOutput` of ``rates`` from the stacked A: A A^T holds
    J_omega_e J_omega_e^T and M~ M~^T for the determinants, A theta_dot the achieved rate and
    the coupling momentum."""
    theta_dot = rates.joint_velocity
    achieved = system.matrix @ theta_dot  # [J_omega_e theta_dot; M~ theta_dot / s]
    return ControlOutput(
        joint_velocity=theta_dot,
        sigma_min=rates.sigma_min,
        determinants=Determinants(
            kinematic=determinant_3x3(system.gram[:3, :3].tolist()),
            coupling=system.coupling_determinant * system.coupling_scale**6,
            algorithmic=rates.algorithmic,
        ),
        damping=0.0,
        speed_scale=rates.sc_scale * rates.limit_scale,
        limit_scale=rates.limit_scale,
        position_limited=rates.position_limited,
        angular_residual=omega_ref - achieved[:3],
        coupling_momentum=system.coupling_scale * achieved[3:],
    )
