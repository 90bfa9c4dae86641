"""Free-floating simulator core: fixed-step RK4 of the satellite + arm, no external wrench.

Two modes (:class:`SimulationMode`):

* ``kinematic`` - the joints follow the commanded joint velocities exactly, up to their URDF
  position limits, where they stop as at a mechanical stop (a step never takes a joint past a
  limit; a rate away from it is followed); the base twist follows
  from momentum conservation. With the conserved centroidal momentum h_G (world axes, about the
  system CoM) and Pinocchio's centroidal momentum matrix A_G(q) = [A_b, A_m]:
  A_b v_b + A_m theta_dot = h_G, i.e. eq. (2.33) solved for the base twist, moved to the CoM.
* ``dynamic`` - full free-floating forward dynamics (Pinocchio ABA, zero gravity) driven by joint
  torques from a joint servo. The servo runs once per step (zero-order hold, like a digital servo
  at 1/dt) with computed-torque feedforward on the free-floating joint-space dynamics
  (eq. 2.18-2.19 with the base eliminated):

      tau = H* (theta_dd_ref + K_d (theta_dot_ref - theta_dot) + K_p (theta_ref - theta)) + c*,
      H* = M_m - M_bm^T M_b^-1 M_bm,   c* = c_m - M_bm^T M_b^-1 c_b.

  The servo respects the URDF joint limits the way a real drive does, without changing anything
  while they are not reached. Its acceleration is rewritten as a velocity loop,

      a = theta_dd_ref + K_d (theta_dot_d - theta_dot),
      theta_dot_d = theta_dot_ref + (K_p / K_d) (theta_ref - theta)    [rad/s], (n,),

  and the demanded velocity theta_dot_d is scaled *uniformly* (the whole vector, so its direction,
  e.g. a reactionless one, is kept; clipping joints one by one would turn the base) until no joint
  exceeds its velocity limit. With computed torque the joint rates then relax to theta_dot_d at
  rate K_d (a first-order lag, each step a convex combination while K_d dt <= 1), so they stay
  within the limits. Then the acceleration a is scaled uniformly (again keeping its direction) so
  that tau fits the URDF effort limits, and finally tau is clipped per joint (the actuator's hard
  limit, only active when the bias c* alone exceeds it). URDF limits that are zero, negative or
  infinite count as absent (unlimited).

  Optional viscous joint friction -D theta_dot acts in the plant (default D = 0, so momentum is
  exactly conserved).

A step that would leave a non-finite state (q, v or effort) keeps the previous state and raises
:class:`rns_ros.core.errors.SimulationDivergedError`.

Integration: classical RK4 in Runge-Kutta-Munthe-Kaas form on the configuration manifold. Stage
configurations are ``pin.integrate(q, Theta)``; each stage velocity is pulled back to the step's
tangent space with dexp^-1 = Jlog6(exp6(Theta)) on the SE(3) base block, so the scheme is fourth
order and the quaternion stays unit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.core.errors import ConfigError, InputError, SimulationDivergedError
from rns_ros.core.fastmath import solve_small
from rns_ros.core.model import FreeFloatingModel
from rns_ros.core.validation import Choice, as_vector, positive
from rns_ros.sim.reaction_wheels import (
    ReactionWheels,
    limit_wheel_torque,
    spin_reduced_model,
    wheel_speeds,
)

#: theta_dot = f(t [s], q (7 + n,)) [rad/s], shape (n,): a continuous-time joint-velocity law.
JointVelocityField = Callable[[float, np.ndarray], np.ndarray]

#: Default servo bandwidth: natural frequency [rad/s] and damping ratio [-] of the joint error
#: dynamics e_dd + K_d e_d + K_p e = 0 (K_p = omega_n^2, K_d = 2 zeta omega_n).
DEFAULT_SERVO_NATURAL_FREQUENCY = 50.0
DEFAULT_SERVO_DAMPING_RATIO = 1.0
#: Largest share [-] of an effort limit the velocity-product torques c* may take before the servo
#: slows the arm (the rest is kept to accelerate and brake); see ``_speed_cap``.
BIAS_SHARE = 0.5


class SimulationMode(Choice):
    """How joints move: follow velocity commands exactly, or through torques and dynamics."""

    __label__ = "mode"

    KINEMATIC = "kinematic"
    DYNAMIC = "dynamic"


@dataclass(frozen=True)
class ServoGains:
    """Joint servo gains (dynamic mode), each shape (n,).

    Attributes:
        stiffness: K_p [1/s^2] (acceleration per rad of error; computed-torque form), >= 0.
        damping: K_d [1/s], >= 0; > 0 wherever K_p > 0 (the velocity-limited servo needs
            theta_dot_d = theta_dot_ref + (K_p / K_d) e, see the module docstring).
        friction: viscous joint friction D [N m s/rad] acting in the plant, >= 0.
    """

    stiffness: np.ndarray
    damping: np.ndarray
    friction: np.ndarray

    @classmethod
    def critically_damped(
        cls,
        n: int,
        natural_frequency: float = DEFAULT_SERVO_NATURAL_FREQUENCY,
        damping_ratio: float = DEFAULT_SERVO_DAMPING_RATIO,
        friction: float = 0.0,
    ) -> ServoGains:
        """Same gains on every joint: K_p = omega_n^2, K_d = 2 zeta omega_n."""
        omega = positive(natural_frequency, "natural_frequency", "[rad/s]")
        zeta = positive(damping_ratio, "damping_ratio")
        if not (np.isfinite(friction) and friction >= 0.0):
            raise ConfigError(f"friction must be finite and >= 0 N m s/rad, got {friction!r}")
        return cls(
            stiffness=np.full(n, omega**2),
            damping=np.full(n, 2.0 * zeta * omega),
            friction=np.full(n, float(friction)),
        )


@dataclass(frozen=True)
class JointReference:
    """What the joints should do, shape (n,) each, in theta order.

    Attributes:
        positions: theta_ref [rad] (used by the dynamic-mode servo).
        velocities: theta_dot_ref [rad/s] (the kinematic mode follows these exactly).
        accelerations: theta_dd_ref [rad/s^2] feedforward (dynamic mode), usually zero.
    """

    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray


#: What a step changes (restored when it diverges). Each step assigns new arrays, never edits
#: them in place, so keeping references is enough.
_STEP_STATE = ("time", "q", "_v", "effort", "reference", "wheel_momentum", "wheel_angles")


@dataclass(frozen=True)
class SimulationState:
    """Snapshot after a step (copies; safe to keep).

    Attributes:
        time: simulated time [s].
        q: Pinocchio configuration (7 + n,): base position [m], quaternion xyzw, theta [rad].
        v: Pinocchio velocity (6 + n,): base twist in the *base* frame [m/s, rad/s], theta_dot.
        effort: joint torques applied during the last step [N m], shape (n,) (zero in kinematic).
    """

    time: float
    q: np.ndarray
    v: np.ndarray
    effort: np.ndarray


class FreeFloatingSimulator:
    """Fixed-step free-floating simulator (see the module docstring for the physics).

    Args:
        robot: the model (its ``pin.Data`` is used as scratch space).
        mode: :class:`SimulationMode` or its string value.
        dt: step [s], in (0, 0.1].
        initial_q: initial configuration (7 + n,); default the model's neutral configuration.
        initial_momentum: conserved centroidal momentum h_G = [p [kg m/s]; l_G [kg m^2/s]] about
            the system CoM, world axes, shape (6,); default zero.
        gains: servo gains for the dynamic mode; default critically damped at 50 rad/s.
        wheels: :class:`ReactionWheels` on the base (gyrostat model, see
            :mod:`rns_ros.sim.reaction_wheels`), driven by :meth:`set_wheel_torque`; None: none.
    """

    def __init__(
        self,
        robot: FreeFloatingModel,
        *,
        mode: SimulationMode | str = SimulationMode.KINEMATIC,
        dt: float = 1e-3,
        initial_q=None,
        initial_momentum=None,
        gains: ServoGains | None = None,
        wheels: ReactionWheels | None = None,
    ) -> None:
        self.robot = robot
        self.wheels = wheels
        self.mode = SimulationMode.parse(mode)
        self.dt = positive(dt, "dt", "[s]")
        if self.dt > 0.1:
            raise ConfigError(f"dt must be in (0, 0.1] s, got {dt!r}")
        n = robot.n
        q0 = robot.neutral() if initial_q is None else as_vector(initial_q, robot.model.nq, "q")
        self._initial_q = pin.normalize(robot.model, q0.copy())
        self._initial_momentum = (
            np.zeros(6) if initial_momentum is None else as_vector(initial_momentum, 6, "momentum")
        )
        self.gains = gains or ServoGains.critically_damped(n)
        for name in ("stiffness", "damping", "friction"):
            as_vector(getattr(self.gains, name), n, f"gains.{name}")
        self._check_servo_gains()
        stiffness, damping = self.gains.stiffness, self.gains.damping
        # K_p / K_d [1/s]; 0 where the joint has no servo at all (K_p = K_d = 0)
        self._position_rate = np.divide(stiffness, damping, out=np.zeros(n), where=damping > 0.0)
        self.velocity_limits = _limits(robot.velocity_limits)
        self.effort_limits = _limits(robot.model.effortLimit[6:])
        #: URDF position limits [rad] (n,); -inf / +inf for continuous joints
        self.lower_limits = np.asarray(robot.lower_limits, dtype=float)
        self.upper_limits = np.asarray(robot.upper_limits, dtype=float)
        if wheels is None:
            self._model, self._data = robot.model, robot.data
        else:
            self._model = spin_reduced_model(robot.model, wheels)
            self._data = self._model.createData()
            self._fext = pin.StdVec_Force()
            for _ in range(self._model.njoints):
                self._fext.append(pin.Force.Zero())
        self._tau_full = np.zeros(robot.model.nv)
        self._check_friction_stiffness()
        self.reset()

    def _check_servo_gains(self) -> None:
        """K_p, K_d >= 0, and K_d > 0 wherever K_p > 0 (an undamped servo has no velocity loop)."""
        for name in ("stiffness", "damping"):
            values = getattr(self.gains, name)
            if (values < 0.0).any():
                raise ConfigError(f"gains.{name} must be >= 0, got {values.tolist()}")
        undamped = np.flatnonzero((self.gains.stiffness > 0.0) & (self.gains.damping == 0.0))
        if undamped.size:
            joint = undamped[0]
            raise ConfigError(
                f"servo on {self.robot.joint_names[joint]} has stiffness "
                f"{self.gains.stiffness[joint]} 1/s^2 but damping 0; damping must be > 0 "
                "wherever stiffness > 0"
            )

    def _check_friction_stiffness(self) -> None:
        """Reject viscous friction so stiff that an explicit step cannot resolve it.

        A joint with effective inertia H*_ii and friction D_i decays at rate D_i / H*_ii; RK4
        resolves that only while D_i dt / H*_ii stays small (<= 0.5 here).
        """
        if not self.gains.friction.any():
            return
        inertia = pin.crba(self._model, self._data, self._initial_q)
        h_star, _ = base_eliminated_dynamics(inertia, np.zeros(self._model.nv))
        limits = 0.5 * np.diag(h_star) / self.dt
        too_stiff = np.flatnonzero(self.gains.friction > limits)
        if too_stiff.size:
            joint = too_stiff[0]
            raise ConfigError(
                f"friction {self.gains.friction[joint]} N m s/rad on "
                f"{self.robot.joint_names[joint]} is too stiff for dt = {self.dt} s; "
                f"use <= {limits[joint]:.3g} N m s/rad or a smaller dt"
            )

    # --- state ---------------------------------------------------------------------------------
    def reset(self) -> None:
        """Back to the initial configuration with the initial momentum and a still arm."""
        n = self.robot.n
        self.time = 0.0
        self.q = self._initial_q.copy()
        self.momentum = self._initial_momentum.copy()
        self.effort = np.zeros(n)
        self.reference = JointReference(
            positions=self.q[7:].copy(), velocities=np.zeros(n), accelerations=np.zeros(n)
        )
        #: absolute axial wheel momenta H [N m s] (3,), base axes; zero without wheels
        self.wheel_momentum = np.zeros(3)
        #: wheel spin angles relative to the base [rad] (3,)
        self.wheel_angles = np.zeros(3)
        #: commanded and applied (limited) wheel torques [N m] (3,), and the limited wheels
        self.wheel_command = np.zeros(3)
        self.wheel_torque = np.zeros(3)
        self.wheel_saturated = np.zeros(3, dtype=bool)
        self._v = self._kinematic_velocity(self.q, np.zeros(n))
        #: joint displacement [rad] (n,) still to make up in the next kinematic step
        self._catch_up = np.zeros(n)
        #: joints whose rate a position limit cut in the last kinematic step, (n,) bool
        self.at_stop = np.zeros(n, dtype=bool)

    @property
    def v(self) -> np.ndarray:
        """Pinocchio velocity (6 + n,): base twist in the base frame [m/s, rad/s], theta_dot."""
        if self._v is None:
            self._v = self._kinematic_velocity(self.q, self.stopped_rate(self.reference.velocities))
        return self._v

    def joint_stop(self) -> tuple[int, str, float]:
        """The first joint the last kinematic step held at a position limit (:attr:`at_stop`):
        (its index, ``"lower"`` or ``"upper"``, the limit [rad])."""
        joint = int(np.flatnonzero(self.at_stop)[0])
        theta = self.q[7 + joint]
        lower, upper = self.lower_limits[joint], self.upper_limits[joint]
        if abs(theta - upper) < abs(theta - lower):
            return joint, "upper", float(upper)
        return joint, "lower", float(lower)

    def stopped_rate(self, theta_dot: np.ndarray) -> np.ndarray:
        """The joint rate [rad/s] (n,) kinematic mode applies for ``theta_dot`` over the next
        step: cut per joint so that no joint passes its position limit within the step (a joint
        at a limit stands there, as at a mechanical stop; a joint outside its limits is not
        moved further out). Unlimited joints are untouched."""
        theta, dt = self.q[7:], self.dt
        low = np.minimum(0.0, (self.lower_limits - theta) / dt)
        high = np.maximum(0.0, (self.upper_limits - theta) / dt)
        return np.clip(theta_dot, low, high)

    def set_reference(
        self, positions=None, velocities=None, accelerations=None, *, since: float = 0.0
    ) -> None:
        """Set the joint reference held until the next call; omitted parts keep sensible values.

        Omitted positions follow the previous reference advanced by nothing (hold); omitted
        velocities/accelerations are zero. All arrays shape (n,), finite.

        ``since`` [s], >= 0 (kinematic mode): the reference was meant to act that long ago, as
        a trajectory stamped then that reached the plant late. The joints make up the motion
        they missed, since * (theta_dot_new - theta_dot_old), during the next step (its base
        reaction included), so they are back on the timed path after one step. A
        trajectory-following plant (ros2_control's joint trajectory controller samples a
        trajectory from its header stamp) does the same through its position loop.
        """
        n = self.robot.n
        previous = self.reference.velocities
        since = float(since)
        if not (math.isfinite(since) and since >= 0.0):
            raise InputError(f"since must be a finite time >= 0 s, got {since!r}")
        self.reference = JointReference(
            positions=self.reference.positions.copy()
            if positions is None
            else as_vector(positions, n, "reference positions"),
            velocities=np.zeros(n)
            if velocities is None
            else as_vector(velocities, n, "reference velocities"),
            accelerations=np.zeros(n)
            if accelerations is None
            else as_vector(accelerations, n, "reference accelerations"),
        )
        if self.mode is SimulationMode.KINEMATIC:
            self._v = None  # the joints take the new rates at once
            self._catch_up = self._catch_up + since * (self.reference.velocities - previous)

    def set_wheel_torque(self, torque) -> None:
        """Motor torques of the three wheels [N m] (3,), base x y z, held until the next call;
        the limits apply at every step (:func:`limit_wheel_torque`).

        Raises:
            ConfigError: the simulator has no wheels. InputError: not a finite 3-vector.
        """
        if self.wheels is None:
            raise ConfigError("this simulator has no reaction wheels")
        self.wheel_command = as_vector(torque, 3, "wheel torque")

    @property
    def wheel_speeds(self) -> np.ndarray:
        """Wheel spin rates relative to the base [rad/s] (3,); zero without wheels."""
        if self.wheels is None:
            return np.zeros(3)
        return wheel_speeds(self.wheel_momentum, self.v[3:6], self.wheels.inertia)

    def snapshot(self) -> SimulationState:
        """Copies of time, q, v and effort."""
        return SimulationState(self.time, self.q.copy(), self.v.copy(), self.effort.copy())

    def centroidal_momentum(self) -> np.ndarray:
        """h_G = A_G(q) v: [p; l_G] about the system CoM, world axes, shape (6,), measured now."""
        momentum = pin.computeCentroidalMomentum(self._model, self._data, self.q, self.v).vector
        return momentum + self._wheel_couple(self.q, self.wheel_momentum)

    def _wheel_couple(self, q: np.ndarray, wheel_momentum: np.ndarray) -> np.ndarray:
        """[0; R_b H] (6,): the wheels' spin momentum in world axes, a pure couple."""
        couple = np.zeros(6)
        if self.wheels is not None:
            rotation = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
            couple[3:] = rotation @ wheel_momentum
        return couple

    # --- stepping ------------------------------------------------------------------------------
    def step(self, joint_velocity: JointVelocityField | None = None) -> None:
        """Advance by dt; the state stays finite.

        Args:
            joint_velocity: kinematic mode only: a continuous-time law theta_dot = f(t, q)
                evaluated at every RK4 stage instead of the held reference velocity (for closed
                loops without sampling, e.g. the reactionless field P_RNS(q) theta_dot_a).
                None: the current reference is held over the step (zero-order hold).

        Raises:
            SimulationDivergedError: the step produced a non-finite q, v or effort; time, state and
                reference are left as they were before the step (the last finite state).
        """
        before = {name: getattr(self, name) for name in _STEP_STATE}
        with np.errstate(all="ignore"):  # overflow is reported below, as SimulationDivergedError
            if self.wheels is not None:
                speeds_before = self.wheel_speeds
                self.wheel_torque, self.wheel_saturated = limit_wheel_torque(
                    self.wheel_command, speeds_before, self.wheels
                )
            self._advance(joint_velocity)
            if self.wheels is not None:
                self.wheel_momentum = self.wheel_momentum + self.dt * self.wheel_torque
                self._v = None if self.mode is SimulationMode.KINEMATIC else self._v
                # trapezoidal angle: the angles are for display; the speeds are exact
                self.wheel_angles = self.wheel_angles + 0.5 * self.dt * (
                    speeds_before + self.wheel_speeds
                )
        values = (("q", self.q), ("v", self._v), ("effort", self.effort))
        if self.wheels is not None:
            values += (("wheel momentum", self.wheel_momentum),)
        bad = [name for name, value in values if value is not None and not np.isfinite(value).all()]
        if bad:
            for name, value in before.items():
                setattr(self, name, value)
            raise SimulationDivergedError(
                f"{self.mode} simulation diverged in the step from t = {self.time:.6g} s: "
                f"non-finite {' and '.join(bad)}; kept the last finite state"
            )

    def _advance(self, joint_velocity: JointVelocityField | None) -> None:
        if joint_velocity is not None:
            if self.mode is not SimulationMode.KINEMATIC:
                raise ConfigError("a joint-velocity law needs mode 'kinematic'")
            self._step_kinematic_field(joint_velocity)
        else:
            if self.mode is SimulationMode.KINEMATIC:
                self._step_kinematic()
            else:
                self._step_dynamic()
            # The reference position advances with its velocity, so a velocity-only command held
            # over many steps still gives the servo a consistent position target.
            ref = self.reference
            self.reference = JointReference(
                ref.positions + self.dt * ref.velocities, ref.velocities, ref.accelerations
            )
        self.time += self.dt

    def _base_velocity(
        self, q: np.ndarray, theta_dot: np.ndarray, wheel_momentum: np.ndarray | None = None
    ) -> np.ndarray:
        """Base twist (base frame) that keeps h_G: solve A_b v_b = h_G - A_m theta_dot, (6,)
        (minus the wheels' couple [0; R_b H], H default the current wheel momentum)."""
        centroidal_map = pin.computeCentroidalMap(self._model, self._data, q)
        rhs = self.momentum - centroidal_map[:, 6:] @ theta_dot
        if self.wheels is not None:
            momentum = self.wheel_momentum if wheel_momentum is None else wheel_momentum
            rhs = rhs - self._wheel_couple(q, momentum)
        return solve_small(centroidal_map[:, :6], rhs)

    def _stage_wheel_momentum(self, fraction: float) -> np.ndarray:
        """H at ``fraction`` of the step: the applied torque is held over it."""
        return self.wheel_momentum + fraction * self.dt * self.wheel_torque

    def _kinematic_velocity(self, q: np.ndarray, theta_dot: np.ndarray) -> np.ndarray:
        return np.concatenate((self._base_velocity(q, theta_dot), theta_dot))

    def _step_kinematic(self) -> None:
        # Joint rates are held over the step, so only the base block varies between stages.
        model, q, dt = self._model, self.q, self.dt
        theta_dot = self.reference.velocities
        if self._catch_up.any():  # a late reference: make up the missed motion (set_reference)
            theta_dot = theta_dot + self._catch_up / dt
            self._catch_up = np.zeros(self.robot.n)
        wanted, theta_dot = theta_dot, self.stopped_rate(theta_dot)
        self.at_stop = theta_dot != wanted
        increment = np.empty(model.nv)

        def stage(fraction: float, base_rate: np.ndarray) -> np.ndarray:
            increment[:6] = fraction * dt * base_rate
            increment[6:] = fraction * dt * theta_dot
            base = self._base_velocity(
                pin.integrate(model, q, increment), theta_dot, self._stage_wheel_momentum(fraction)
            )
            return pin.Jlog6(pin.exp6(increment[:6])) @ base  # dexp^-1 pull-back

        k1 = self._base_velocity(q, theta_dot)
        k2 = stage(0.5, k1)
        k3 = stage(0.5, k2)
        k4 = stage(1.0, k3)
        increment[:6] = dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        increment[6:] = dt * theta_dot
        self.q = pin.integrate(model, q, increment)
        self._v = None  # recomputed on demand (publishing is slower than stepping)
        self.effort = np.zeros(self.robot.n)

    def _step_kinematic_field(self, joint_velocity: JointVelocityField) -> None:
        model, q, dt, t = self._model, self.q, self.dt, self.time

        def stage(fraction: float, rate: np.ndarray) -> np.ndarray:
            increment = fraction * dt * rate
            q_stage = pin.integrate(model, q, increment)
            theta_dot = as_vector(
                joint_velocity(t + fraction * dt, q_stage), self.robot.n, "f(t, q)"
            )
            base = self._base_velocity(q_stage, theta_dot, self._stage_wheel_momentum(fraction))
            return np.concatenate((pin.Jlog6(pin.exp6(increment[:6])) @ base, theta_dot))

        k1 = stage(0.0, np.zeros(model.nv))
        k2 = stage(0.5, k1)
        k3 = stage(0.5, k2)
        k4 = stage(1.0, k3)
        self.q = pin.integrate(model, q, dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4))
        self.reference = JointReference(self.q[7:].copy(), k4[6:].copy(), np.zeros(self.robot.n))
        self._v = None
        self.effort = np.zeros(self.robot.n)

    def _servo_torque(self) -> np.ndarray:
        """Limited computed-torque servo on the base-eliminated dynamics (eq. 2.18-2.19), [N m],
        (n,): see the module docstring for the velocity and effort limits."""
        model, data, q, v = self._model, self._data, self.q, self.v
        ref = self.reference
        h_star, c_star = base_eliminated_dynamics(
            pin.crba(model, data, q), pin.nonLinearEffects(model, data, q, v)
        )
        theta, theta_dot = q[7:], v[6:]
        demand = ref.velocities + self._position_rate * (ref.positions - theta)  # [rad/s]
        demand *= _uniform_scale(demand, self._speed_cap(theta_dot, c_star))
        acceleration = ref.accelerations + self.gains.damping * (demand - theta_dot)
        effort = h_star @ acceleration
        effort *= _effort_scale(effort, c_star, self.effort_limits)
        return np.clip(effort + c_star, -self.effort_limits, self.effort_limits)

    def _speed_cap(self, theta_dot: np.ndarray, bias: np.ndarray) -> np.ndarray:
        """Velocity limits [rad/s] (n,) for the demand: the URDF limits, lowered uniformly while
        the velocity-product torques c* take more than BIAS_SHARE of an effort limit.

        c* is quadratic in the joint rates (zero gravity; exactly so at zero momentum), so
        running a factor k slower divides it by k^2: the cap keeps the rest of each actuator's
        effort free to accelerate and, above all, to brake.
        """
        load = np.max(np.abs(bias) / self.effort_limits)
        if load <= BIAS_SHARE:
            return self.velocity_limits
        limits = self.velocity_limits
        speed = np.max(np.abs(theta_dot) / limits)  # fraction of the limits
        cap = np.full_like(limits, np.inf)  # an unlimited joint stays unlimited (not inf * 0)
        bounded = np.isfinite(limits)
        cap[bounded] = limits[bounded] * (speed * np.sqrt(BIAS_SHARE / load))
        return cap

    def _acceleration(
        self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, fraction: float = 0.0
    ) -> np.ndarray:
        self._tau_full[6:] = tau - self.gains.friction * v[6:]
        if self.wheels is None:
            return pin.aba(self._model, self._data, q, v, self._tau_full)
        # the wheels push back on the base: -(tau_w + omega^B x H), a couple in base axes
        momentum = self._stage_wheel_momentum(fraction)
        couple = -(self.wheel_torque + np.cross(v[3:6], momentum))
        self._fext[1] = pin.Force(np.zeros(3), couple)
        return pin.aba(self._model, self._data, q, v, self._tau_full, self._fext)

    def _step_dynamic(self) -> None:
        model, q, v, dt = self._model, self.q, self.v, self.dt
        tau = self._servo_torque()
        accel = self._acceleration
        k1q, k1v = v, accel(q, v, tau)
        v2 = v + 0.5 * dt * k1v
        q2 = 0.5 * dt * k1q
        k2q, k2v = _pull_back(q2, v2), accel(pin.integrate(model, q, q2), v2, tau, 0.5)
        v3 = v + 0.5 * dt * k2v
        q3 = 0.5 * dt * k2q
        k3q, k3v = _pull_back(q3, v3), accel(pin.integrate(model, q, q3), v3, tau, 0.5)
        v4 = v + dt * k3v
        q4 = dt * k3q
        k4q, k4v = _pull_back(q4, v4), accel(pin.integrate(model, q, q4), v4, tau, 1.0)
        self.q = pin.integrate(model, q, dt / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q))
        self._v = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        self.effort = tau


def _limits(values) -> np.ndarray:
    """URDF limits (n,) with absent ones (<= 0, non-finite) as +inf."""
    limits = np.array(values, dtype=float)
    limits[~(np.isfinite(limits) & (limits > 0.0))] = np.inf
    return limits


def _uniform_scale(vector: np.ndarray, limits: np.ndarray) -> float:
    """Largest s in [0, 1] with |s vector_i| <= limits_i for every i."""
    magnitude = np.abs(vector)
    over = magnitude > limits
    return float((limits[over] / magnitude[over]).min()) if over.any() else 1.0


def _effort_scale(varying: np.ndarray, bias: np.ndarray, limits: np.ndarray) -> float:
    """Largest s in [0, 1] with |s varying_i + bias_i| <= limits_i for every i (0 if even the
    bias alone exceeds a limit)."""
    scale = 1.0
    for b, c, limit in zip(varying, bias, limits, strict=True):
        if abs(c) >= limit:
            return 0.0
        if b > 0.0:
            scale = min(scale, (limit - c) / b)
        elif b < 0.0:
            scale = min(scale, (-limit - c) / b)
    return scale


def base_eliminated_dynamics(
    inertia: np.ndarray, bias: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Joint-space dynamics with the unactuated base eliminated (eq. 2.18-2.19).

    Args:
        inertia: M (6 + n, 6 + n); bias: nonlinear effects (6 + n,) (any base-twist convention:
            the result does not depend on it).

    Returns:
        (H* = M_m - M_bm^T M_b^-1 M_bm (n, n), c* = c_m - M_bm^T M_b^-1 c_b (n,)).
    """
    m_b, m_bm = inertia[:6, :6], inertia[:6, 6:]
    eliminate = np.linalg.solve(m_b, np.column_stack((m_bm, bias[:6])))
    return inertia[6:, 6:] - m_bm.T @ eliminate[:, :-1], bias[6:] - m_bm.T @ eliminate[:, -1]


def _pull_back(increment: np.ndarray, velocity: np.ndarray) -> np.ndarray:
    """dexp^-1: the tangent-space rate at q of the curve q (+) Theta whose body velocity is v.

    Only the free-flyer block is curved: Theta_dot_b = Jlog6(exp6(Theta_b)) v_b; joints are flat.
    """
    pulled = velocity.copy()
    pulled[:6] = pin.Jlog6(pin.exp6(increment[:6])) @ velocity[:6]
    return pulled
