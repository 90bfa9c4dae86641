r"""Thesis chapter 6 closed loops: one controller on one motion/force task, torque level.

Every control period (= the simulator step ``dt``, 1 ms by default) :func:`run_closed_loop`
computes the :class:`FixedBaseState`, the task references, the motion loop (6.33), the force loop
(6.34) with the contact force measured at that instant and the controller torque (RNS-C closed
form, OS-C literal or OS-C kinematic; labelled variants: the literal RNS-C loop with the exact or
the momentum-approximated C_hat_A), and holds that torque over the next
:class:`~rns_ros.sim.contact.ContactSimulator` RK4 step (zero-order hold). The tasks:
:mod:`rns_ros.control.contact_tasks`; errors, signs and the contact frame {E}: docs/part2.md.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from rns_ros.analysis.arrays import read_only
from rns_ros.control.contact_tasks import ArcScenario, Reference, Setup, WallScenario
from rns_ros.control.motion_force.null_space import damper_term, velocity_level_term
from rns_ros.control.motion_force.osc import OscVariant, os_control
from rns_ros.control.motion_force.outer_loops import (
    ForceGains,
    MotionGains,
    force_loop,
    motion_loop,
)
from rns_ros.control.motion_force.projectors import kernel_projector
from rns_ros.control.motion_force.reversed_model import ReversedModel
from rns_ros.control.motion_force.rnsc import rns_control, rns_literal_step
from rns_ros.control.motion_force.task_space import TaskSpace
from rns_ros.core.contact_geometry import PlaneConstraint
from rns_ros.core.errors import ConfigError
from rns_ros.core.fixed_base import FixedBaseModel, FixedBaseState
from rns_ros.core.validation import Choice, positive
from rns_ros.sim.contact import ContactSimulator

#: Control model's virtual-link mass m_hat [kg] (thesis section 6.2.1; I_hat = m_hat / 12).
VIRTUAL_MASS = 1.0e5
#: Default control period = simulator step [s] (thesis_rest 4.7: RK4 at 1 ms).
CONTROL_PERIOD = 1e-3
#: Thesis gains (section 6.2.1): k_p = 100 1/s^2, k_d = 10 1/s (6.33); k_f = 5 (6.34). Frozen.
THESIS_MOTION_GAINS, THESIS_FORCE_GAINS = MotionGains(k_p=100.0, k_d=10.0), ForceGains(k_f=5.0)


class Controller(Choice):
    """The controllers compared in chapter 6 (labels as in the JSON of ``fig6.*``)."""

    __label__ = "controller"
    RNS_C = "RNS-C"
    OSC = "OS-C"
    OSC_KINEMATIC = "OS-C-kinematic"
    # labelled variants (section 6.1.2): (6.22) + (6.17) + (6.18) with the previous period's
    # motion torque, exact C_hat_A or its momentum approximation
    RNS_C_LITERAL = "RNS-C-literal"
    RNS_C_MOMENTUM = "RNS-C-literal-momentum"


class ForceMeasurement(Choice):
    """The contact force f in the force loop (6.34) f_ref = f_des + k_f (f_des - f).

    * ``same-instant`` (default): f is the force at the same instant. Against a rigid surface the
      contact force answers the torque at once: every controller's torque is tau_0 + J^T n f_ref
      and gives f = lambda_0 + f_ref, lambda_0 being the force of tau_0 alone (read from the
      simulator at the current state). (6.34) is solved with it:
      f_ref = (f_des + k_f (f_des - lambda_0)) / (1 + k_f), i.e. f - f_des = lambda_0 / (1 + k_f).
    * ``previous-step``: f is the force at the current state under the torque held over the
      previous period (a sampled sensor, one period late). With a rigid contact the error then
      obeys e_{k+1} = -k_f e_k: unstable for k_f > 1 (the thesis' k_f = 5 diverges).
    """

    __label__ = "force measurement"
    SAME_INSTANT = "same-instant"
    PREVIOUS_STEP = "previous-step"


#: Report order.
CONTROLLERS = (Controller.RNS_C, Controller.OSC, Controller.OSC_KINEMATIC)


class NullSpaceTerm(Choice):
    """The chapter-7 null-space acceleration theta_ddot_a added to RNS-C (7.3) (OS-C: unused).

    * ``none``: theta_ddot_a = 0 (chapter 6 as printed).
    * ``velocity-level``: (7.13) in the velocity form +P_hat_RNS Wdot^T W^{+T} theta_dot.
    * ``damper``: theta_ddot_a = -k_d theta_dot (section 7.2.2), held over the period like the
      torque: the sampled loop is stable for k_d dt < 2 (deadbeat at k_d dt = 1).
    """

    __label__ = "null-space term"
    NONE = "none"
    VELOCITY_LEVEL = "velocity-level"
    DAMPER = "damper"


@dataclass(frozen=True)
class ClosedLoopRun:
    """One controller on one scenario: k = N + 1 samples at t_k = k dt (k = 0..N), arrays
    read-only. Sample k holds the state at t_k, the torque computed there (held over
    [t_k, t_k + dt]) and the contact force the controller measured at t_k (the state reached,
    under the torque held over the previous period; 0 at t = 0).

    Attributes:
        scenario: "planar_arc" or "lwr_wall"; controller: :class:`Controller` value.
        dt: control period = simulator step [s].
        t: (k,) [s]. q [rad], v [rad/s], tau [N m]: (k, n).
        position_error: p_des - p in {E} axes [m], (k, 3): x_E along the motion, y_E the second
            in-plane direction, z_E the normal (the surface holds it; for the arc it is the
            chord between the desired and actual points).
        orientation_error: log(R_des R^T) in world axes [rad], (k, r); r = 3 when the
            orientation is a task (wall), 0 when it is free (planar).
        force_desired: f_des (k,) [N]; force_reference: f_ref of (6.34) (k,) [N].
        contact_force: lambda over [t_k, t_k + dt) at t_k, under the torque of sample k (k,) [N];
        force_error: force_desired - contact_force (k,) [N].
        joint_speed: max_i |v_i| (k,) [rad/s] ([A-4.5]).
        null_space_velocity: ||P_hat_RNS v|| (k,) [rad/s] (7.14, m_hat of the run);
        null_space_velocity_jacobian: ||P_J v|| (k,) [rad/s].
        phi: constraint error (k,) [m] (> 0: penetration).
        pulling_steps: simulator steps that ended with the bilateral contact pulling.
        wall_time: seconds the run took.
        description: the resolved scenario (:attr:`Setup.description`).
    """

    scenario: str
    controller: str
    dt: float
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    force_desired: np.ndarray
    force_reference: np.ndarray
    contact_force: np.ndarray
    force_error: np.ndarray
    joint_speed: np.ndarray
    null_space_velocity: np.ndarray
    null_space_velocity_jacobian: np.ndarray
    phi: np.ndarray
    pulling_steps: int
    wall_time: float
    description: dict = field(default_factory=dict, compare=False)

    @property
    def tangential_error(self) -> np.ndarray:
        """In-plane position error ||(e_x, e_y)|| in {E} [m], (k,)."""
        return np.hypot(self.position_error[:, 0], self.position_error[:, 1])

    @property
    def peak_joint_speed(self) -> float:
        """max over joints and time of |theta_dot_i| [rad/s] ([A-4.5])."""
        return float(self.joint_speed.max())

    @property
    def max_position_error(self) -> float:
        """max over time of the in-plane position error [m]."""
        return float(self.tangential_error.max())

    @property
    def max_orientation_error(self) -> float:
        """max over time of ||orientation error|| [rad] (0 when the orientation is free)."""
        if self.orientation_error.shape[1] == 0:
            return 0.0
        return float(np.linalg.norm(self.orientation_error, axis=1).max())

    @property
    def max_force_error(self) -> float:
        """max over time of |f_des - f| [N]."""
        return float(np.abs(self.force_error).max())

    @property
    def max_constraint_error(self) -> float:
        """max |phi| [m]."""
        return float(np.abs(self.phi).max())

    def summary(self) -> dict:
        """The scalar results, JSON-able."""
        return {
            "peak_joint_speed_rad_s": self.peak_joint_speed,
            "max_position_error_m": self.max_position_error,
            "max_orientation_error_rad": self.max_orientation_error,
            "max_force_error_N": self.max_force_error,
            "final_force_error_N": float(self.force_error[-1]),
            "final_position_error_m": float(self.tangential_error[-1]),
            "max_null_space_velocity_rad_s": float(self.null_space_velocity.max()),
            "max_constraint_error_m": self.max_constraint_error,
            "pulling_steps": self.pulling_steps,
            "wall_time_s": self.wall_time,
        }


class _Log:
    """The per-sample arrays of a run being recorded (k samples, n joints, r orientation rows)."""

    def __init__(self, k: int, n: int, r: int) -> None:
        self.q, self.v, self.tau = np.zeros((k, n)), np.zeros((k, n)), np.zeros((k, n))
        self.position_error, self.orientation_error = np.zeros((k, 3)), np.zeros((k, r))
        self.force_desired, self.force_reference = np.zeros(k), np.zeros(k)
        self.contact_force, self.rns, self.jacobian, self.phi = (np.zeros(k) for _ in range(4))

    def run(self, setup: Setup, controller: Controller, dt: float, sim, wall: float):
        """The :class:`ClosedLoopRun` of the recorded samples."""
        return ClosedLoopRun(
            scenario=setup.name,
            controller=controller.value,
            dt=dt,
            t=read_only(np.arange(self.q.shape[0]) * dt),
            q=read_only(self.q),
            v=read_only(self.v),
            tau=read_only(self.tau),
            position_error=read_only(self.position_error),
            orientation_error=read_only(self.orientation_error),
            force_desired=read_only(self.force_desired),
            force_reference=read_only(self.force_reference),
            contact_force=read_only(self.contact_force),
            force_error=read_only(self.force_desired - self.contact_force),
            joint_speed=read_only(np.abs(self.v).max(axis=1)),
            null_space_velocity=read_only(self.rns),
            null_space_velocity_jacobian=read_only(self.jacobian),
            phi=read_only(self.phi),
            pulling_steps=sim.pulling_steps,
            wall_time=wall,
            description=dict(setup.description),
        )


class _MotionForceLoop:
    """One controller closing the motion (6.33) and force (6.34) loops on a simulated task."""

    def __init__(
        self,
        setup: Setup,
        controller: Controller,
        measurement: ForceMeasurement,
        motion_gains: MotionGains,
        force_gains: ForceGains,
        virtual_mass: float,
        dt: float,
        plant: FixedBaseModel,
        null_space: tuple[NullSpaceTerm, float],
    ) -> None:
        self.setup, self.measurement = setup, measurement
        self.null_space, self.damper_gain = null_space
        self.motion_gains, self.force_gains = motion_gains, force_gains
        robot, constraint, rows = setup.robot, setup.constraint, setup.rows
        self.reversed_model = ReversedModel(robot, rows, virtual_mass=virtual_mass)
        self.sim = ContactSimulator(plant, constraint, initial_q=setup.initial_q, dt=dt)
        self.orientation_rows = [i for i, r in enumerate(rows) if r >= 3]
        self.fixed_task = None
        if isinstance(constraint, PlaneConstraint):
            self.fixed_task = TaskSpace.from_contact(rows, constraint.normal, setup.tangent(None))
        self.variant = {
            Controller.OSC: OscVariant.LITERAL,
            Controller.OSC_KINEMATIC: OscVariant.KINEMATIC,
        }.get(controller)
        self.momentum_approximation = {
            Controller.RNS_C_LITERAL: False,
            Controller.RNS_C_MOMENTUM: True,
        }.get(controller)
        self.previous_motion_torque: np.ndarray | None = None

    def period(self, t: float, log: _Log, i: int) -> None:
        """Compute and hold the torque of time ``t`` [s]; record sample ``i``."""
        setup, constraint, sim = self.setup, self.setup.constraint, self.sim
        state = FixedBaseState.compute(setup.robot, sim.q, sim.v)
        p = state.ee_position
        p_dot = state.jacobian[:3] @ state.v
        normal = constraint.gradient(p)
        task = self.fixed_task or TaskSpace.from_contact(setup.rows, normal, setup.tangent(p))
        ref = setup.reference(t)
        error = task.pose_error(state, ref.position, ref.rotation)
        a_ref = self._acceleration_reference(task, state, ref, error)
        f_des = setup.force(t)
        a_n = None
        if setup.normal_feedforward:
            a_n = [-constraint.curvature(p, p_dot)]  # n . p_ddot keeping phi_ddot = 0
        w = self.reversed_model.w(state.q)
        if self.variant is not None:
            command = os_control(state, task, a_ref, variant=self.variant, normal_acceleration=a_n)
        elif self.momentum_approximation is not None:
            previous = self.previous_motion_torque
            if previous is None:  # before the first period: the torque holding the arm at rest
                previous = state.coriolis + state.gravity
            command = rns_literal_step(
                state,
                task,
                self.reversed_model,
                a_ref,
                previous_torque=previous,
                normal_acceleration=a_n,
                momentum_approximation=self.momentum_approximation,
            ).command
            self.previous_motion_torque = command.torque
        else:
            extra = self._null_space_acceleration(state, task)
            command = rns_control(
                state,
                task,
                self.reversed_model,
                a_ref,
                normal_acceleration=a_n,
                null_space_acceleration=extra,
                w=w,
            )
        # the force term of every controller is J^T N f_ref, added to the motion torque tau_0
        push = task.jacobian(state).T @ task.force_wrench([1.0])
        f_ref = self._force_reference(command.torque, f_des)
        torque = command.torque + push * f_ref
        sim.set_torque(torque)
        log.q[i], log.v[i], log.tau[i] = state.q, state.v, torque
        log.position_error[i] = task.contact_rotation.T @ (ref.position - p)
        log.orientation_error[i] = error[self.orientation_rows]
        log.force_desired[i], log.contact_force[i] = f_des, sim.contact_force
        log.force_reference[i] = f_ref
        log.rns[i] = np.linalg.norm(kernel_projector(w) @ state.v)
        log.jacobian[i] = np.linalg.norm(kernel_projector(task.jacobian(state)) @ state.v)
        log.phi[i] = constraint.phi(p)

    def _null_space_acceleration(self, state: FixedBaseState, task: TaskSpace):
        """theta_ddot_a of RNS-C [rad/s^2] (n,), or None (:class:`NullSpaceTerm`)."""
        if self.null_space is NullSpaceTerm.VELOCITY_LEVEL:
            return velocity_level_term(state, task, self.reversed_model)
        if self.null_space is NullSpaceTerm.DAMPER:
            return damper_term(state.v, self.damper_gain)
        return None

    def _acceleration_reference(
        self, task: TaskSpace, state: FixedBaseState, ref: Reference, error: np.ndarray
    ) -> np.ndarray:
        """nu_dot_ref of the motion loop (6.33) on the task rows."""
        rows = list(self.setup.rows)
        full_accel = np.concatenate([ref.acceleration, np.zeros(3)])
        full_vel = np.concatenate([ref.velocity, np.zeros(3)])
        return motion_loop(
            self.motion_gains, full_accel[rows], full_vel[rows], task.velocity(state), error
        )

    def _force_reference(self, motion_torque: np.ndarray, f_des: float) -> float:
        """f_ref of the force loop (6.34) with the contact force of :class:`ForceMeasurement`."""
        sim, k_f = self.sim, self.force_gains.k_f
        if self.measurement is ForceMeasurement.SAME_INSTANT:
            sim.set_torque(motion_torque)
            motion_force = sim.contact_force  # lambda_0: the force tau_0 alone produces now
            # (6.34) with f = lambda_0 + f_ref (rigid contact: f answers the torque at once)
            return (f_des + k_f * (f_des - motion_force)) / (1.0 + k_f)
        return force_loop(self.force_gains, [f_des], [sim.contact_force])[0]


def run_closed_loop(
    scenario: ArcScenario | WallScenario | Setup,
    controller: Controller | str,
    *,
    dt: float = CONTROL_PERIOD,
    duration: float | None = None,
    motion_gains: MotionGains = THESIS_MOTION_GAINS,
    force_gains: ForceGains = THESIS_FORCE_GAINS,
    virtual_mass: float = VIRTUAL_MASS,
    force_measurement: ForceMeasurement | str = ForceMeasurement.SAME_INSTANT,
    plant: FixedBaseModel | None = None,
    null_space: NullSpaceTerm | str = NullSpaceTerm.NONE,
    damper_gain: float | None = None,
) -> ClosedLoopRun:
    """Run ``controller`` on ``scenario`` (see the module docstring for one period).

    Args:
        scenario: :class:`ArcScenario`, :class:`WallScenario` or a resolved :class:`Setup`.
        controller: :class:`Controller` or its label ("RNS-C", "OS-C", "OS-C-kinematic").
        dt: control period = RK4 step [s] (> 0, <= 0.1).
        duration: simulated time [s]; default the scenario's; rounded to whole periods.
        motion_gains, force_gains: (6.33)-(6.34), thesis k_p = 100, k_d = 10, k_f = 5.
        virtual_mass: m_hat [kg] of the RNS-C control model (and of P_hat_RNS in the log).
        force_measurement: which contact force f the force loop (6.34) sees
            (:class:`ForceMeasurement`).
        plant: the arm the simulator moves; default the scenario's, which the controllers
            use as their model. Another model (same joints and EE frame, e.g. with a payload)
            is a model error the controllers do not know.
        null_space: RNS-C's chapter-7 null-space term (:class:`NullSpaceTerm`).
        damper_gain: k_d of the ``damper`` term [1/s] (> 0); None -> 1 / dt (deadbeat).

    Raises:
        ConfigError: bad controller, dt, duration, scenario or plant (another joint count).
            SimulationDivergedError: the
            closed loop blew up (the message names the step). InputError: a task singularity
            (OS-C: J M^-1 J^T singular).
    """
    controller = Controller.parse(controller)
    measurement = ForceMeasurement.parse(force_measurement)
    setup = scenario if isinstance(scenario, Setup) else scenario.setup()
    dt = positive(dt, "dt", "[s]")
    duration = setup.duration if duration is None else positive(duration, "duration", "[s]")
    steps = max(1, round(duration / dt))
    plant = setup.robot if plant is None else plant
    if plant.n != setup.robot.n:
        raise ConfigError(f"plant has {plant.n} joints, the controllers' model {setup.robot.n}")
    term = NullSpaceTerm.parse(null_space)
    gain = 1.0 / dt if damper_gain is None else positive(damper_gain, "damper_gain", "[1/s]")
    loop = _MotionForceLoop(
        setup,
        controller,
        measurement,
        motion_gains,
        force_gains,
        virtual_mass,
        dt,
        plant,
        (term, gain),
    )
    log = _Log(steps + 1, setup.robot.n, len(loop.orientation_rows))
    started = time.perf_counter()
    for i in range(steps + 1):
        loop.period(i * dt, log, i)
        if i < steps:
            loop.sim.step()
    return log.run(setup, controller, dt, loop.sim, time.perf_counter() - started)


#: Control period of the quick runs [s] (the simulator's Baumgarte rate allows it).
QUICK_PERIOD = 2e-3


__all__ = [
    "CONTROLLERS",
    "CONTROL_PERIOD",
    "QUICK_PERIOD",
    "THESIS_FORCE_GAINS",
    "THESIS_MOTION_GAINS",
    "VIRTUAL_MASS",
    "ClosedLoopRun",
    "Controller",
    "ForceMeasurement",
    "NullSpaceTerm",
    "run_closed_loop",
]
