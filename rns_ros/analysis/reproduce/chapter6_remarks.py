"""Chapter 6 remarks the thesis states without a figure, on the planar arc of §6.2.1.

* ``sec6.2.1``: "we assume zero gravity because gravity compensation induces a cyclic joint
  motion with a large velocity under the OS formulation based control". Labelled run: gravity
  9.81 m/s^2 along -y (the plane's vertical), every controller compensating it with its own
  model (OS-C: G_e of (6.11), tau_a = 0; RNS-C and OS-C-kinematic: the full g_l).
* ``sec6.1.2``: "we have to compensate the exact non-linear force term C_hat_A instead of ... its
  approximation C_hat_A ~ M_hat_A_dot V_A + M_hat_Al_dot theta_dot ...; otherwise, the task-space
  behavior cannot be guaranteed anymore". Labelled runs: the literal RNS-C loop (6.22) + (6.17) +
  (6.18) with the exact C_hat_A and with its momentum approximation.
"""

from __future__ import annotations

import functools

import numpy as np

from rns_ros.analysis.motion_force_runs import (
    CONTROL_PERIOD,
    CONTROLLERS,
    QUICK_PERIOD,
    VIRTUAL_MASS,
    ClosedLoopRun,
    Controller,
    run_closed_loop,
)
from rns_ros.analysis.motion_force_variants import PLANAR_UP, planar_gravity
from rns_ros.analysis.reproduce import chapter6_causes as causes
from rns_ros.analysis.reproduce import plotting as plot
from rns_ros.analysis.reproduce.registry import (
    Comparison,
    Outcome,
    Reproduction,
    register_all,
    resolution_choice,
)
from rns_ros.control.motion_force.osc import operational_space
from rns_ros.control.motion_force.task_space import PLANAR_ROWS, TaskSpace
from rns_ros.core.fixed_base import FixedBaseState

#: "large velocity": OS-C's peak joint speed with gravity over its peak without, above this [-].
GRAVITY_PEAK_FACTOR = 2.0
#: "cyclic": the OS-C self-motion velocity k(q).theta_dot reverses at least this often with gravity.
MIN_REVERSALS = 2
#: A reversal counts when a velocity crosses from beyond +band to beyond -band (or
#: back), band = this fraction of its largest magnitude in the run [-].
REVERSAL_BAND = 0.1
#: "cannot be guaranteed": the momentum-approximated run's max position error over the exact
#: run's above this [-].
C_A_ERROR_FACTOR = 2.0
_LITERAL = (Controller.RNS_C_LITERAL, Controller.RNS_C_MOMENTUM)
_COLORS = {
    Controller.RNS_C: "tab:red",
    Controller.OSC: "tab:green",
    Controller.OSC_KINEMATIC: "C0",
    Controller.RNS_C_LITERAL: "tab:purple",
    Controller.RNS_C_MOMENTUM: "tab:orange",
}

_CHOICES = (
    "Planar arc of fig6.3/fig6.4 (A-4.4, A-4.6-A-4.8): T_half = 1.6 s, two half cycles, the "
    "thesis gains k_p = 100, k_d = 10, k_f = 5, m_hat = 1e5 kg, same-instant force loop, RK4 "
    "with the control period as step.",
)


def _choices(quick: bool, *extra: str) -> tuple[str, ...]:
    return (
        *_CHOICES,
        *extra,
        resolution_choice(
            quick,
            f"one half cycle, {QUICK_PERIOD * 1e3:g} ms control period and RK4 step.",
            f"{CONTROL_PERIOD * 1e3:g} ms control period and RK4 step.",
        ),
    )


# --------------------------------------------------------------------------- §6.2.1 gravity


def self_motion_velocity(run: ClosedLoopRun, robot) -> np.ndarray:
    """Signed self-motion velocity k(q) . theta_dot [rad/s] (k,) of a planar run: k = the unit
    kernel vector of the 2x3 position Jacobian (cross product of its rows, a continuous sign)."""
    out = np.zeros(run.t.shape)
    for i, (q, v) in enumerate(zip(run.q, run.v, strict=True)):
        jac = FixedBaseState.compute(robot, q, v).jacobian[list(PLANAR_ROWS)]
        kernel = np.cross(jac[0], jac[1])
        out[i] = kernel @ v / np.linalg.norm(kernel)
    return out


def reversals(signal: np.ndarray, band: float = REVERSAL_BAND) -> int:
    """How often ``signal`` crosses from above +band max|signal| to below -band max|signal| or
    back (a hysteresis zero-crossing count)."""
    level = band * float(np.abs(signal).max(initial=0.0))
    count, side = 0, 0
    for x in signal:
        now = 1 if x > level else -1 if x < -level else 0
        if now and side and now != side:
            count += 1
        side = now or side
    return count


def null_space_gravity(robot, q) -> np.ndarray:
    """(E - J^T J^{M+T}) g_l [N m] (3,) at q: the share of gravity that OS-C with tau_a = 0
    leaves uncompensated ((6.13), G_e = J^{M+T} g_l of (6.8))."""
    state = FixedBaseState.compute(robot, q, np.zeros(robot.n))
    task = TaskSpace.free(PLANAR_ROWS)
    os_ = operational_space(state, task)
    jac = task.jacobian(state)
    return state.gravity - jac.T @ os_.gravity


def _gravity_outcome(quick: bool) -> Outcome:
    nominal = {c: causes.planar_run(causes.BASELINE, c, quick) for c in CONTROLLERS}
    gravity = {c: causes.planar_run(causes.GRAVITY_FACTOR, c, quick) for c in CONTROLLERS}
    setup = causes.scenario(causes.BASELINE, quick).setup()
    robot = setup.robot
    motion = {
        "gravity": self_motion_velocity(gravity[Controller.OSC], robot),
        "nominal": self_motion_velocity(nominal[Controller.OSC], robot),
    }
    peak = {c.value: gravity[c].peak_joint_speed for c in CONTROLLERS}
    peak_off = {c.value: nominal[c].peak_joint_speed for c in CONTROLLERS}
    factor = peak["OS-C"] / peak_off["OS-C"]
    turns = {key: reversals(signal) for key, signal in motion.items()}
    swing = {
        "gravity": np.degrees(np.ptp(gravity[Controller.OSC].q, axis=0)).tolist(),
        "nominal": np.degrees(np.ptp(nominal[Controller.OSC].q, axis=0)).tolist(),
    }
    leftover = null_space_gravity(planar_gravity(robot, causes.GRAVITY), setup.initial_q)
    values = {
        "peak_joint_speed_gravity_rad_s": peak,
        "peak_joint_speed_no_gravity_rad_s": peak_off,
        "osc_peak_gravity_over_no_gravity": factor,
        "osc_joint_range_deg": swing,
        "osc_self_motion_reversals": turns,
        "osc_peak_self_motion_velocity_rad_s": {
            k: float(np.abs(v).max()) for k, v in motion.items()
        },
        "osc_uncompensated_gravity_at_start_Nm": leftover.tolist(),
        "max_position_error_gravity_m": {
            c.value: gravity[c].max_position_error for c in CONTROLLERS
        },
    }
    rows = [
        Comparison.input(
            "gravity_m_s2",
            None,
            causes.GRAVITY,
            "m/s^2",
            f"our choice (the thesis gives no value): along -{list(PLANAR_UP)} (-y), the plane's "
            "vertical (thesis x-z plane, z up -> our x-y, y up).",
        ),
        Comparison.trend(
            "osc_gravity_peak_factor",
            "'gravity compensation induces a cyclic joint motion with a large velocity under the "
            "OS formulation based control' (§6.2.1): the large velocity",
            factor,
            "",
            holds=factor > GRAVITY_PEAK_FACTOR,
            note=f"OS-C (literal, tau_a = 0) peak joint speed with gravity over without "
            f"({peak['OS-C']:.3g} vs {peak_off['OS-C']:.3g} rad/s; criterion > "
            f"{GRAVITY_PEAK_FACTOR:g}). Cause: G_e = J^{{M+T}} g_l compensates only the task "
            "share; (E - J^T J^{M+T}) g_l is left, "
            f"{np.linalg.norm(leftover):.3g} N m at the start, and drives the self-motion. "
            f"RNS-C and OS-C-kinematic compensate all of g_l: peaks {peak['RNS-C']:.3g} and "
            f"{peak['OS-C-kinematic']:.3g} rad/s with gravity, {peak_off['RNS-C']:.3g} and "
            f"{peak_off['OS-C-kinematic']:.3g} without.",
        ),
        _cyclic_row(turns, swing),
    ]
    settings = {"gravity_m_s2": causes.GRAVITY, "gravity_direction": [-x for x in PLANAR_UP]}
    choices = _choices(
        quick,
        "Gravity (labelled run): 9.81 m/s^2 along -y, in the controllers' model and the "
        "simulator alike; each controller compensates it as its law says (OS-C: G_e of (6.11) "
        "with tau_a = 0; RNS-C and OS-C-kinematic: the full g_l in the computed torque).",
    )
    figure = {"gravity": gravity, "motion": motion, "t": gravity[Controller.OSC].t}
    return Outcome(tuple(rows), values, settings, choices, figure)


def _cyclic_row(turns: dict[str, int], swing: dict[str, list[float]]) -> Comparison:
    """The 'cyclic' part of the §6.2.1 remark: reversals of OS-C's self-motion velocity."""
    holds = turns["gravity"] >= MIN_REVERSALS
    note = (
        f"reversals of OS-C's self-motion velocity k(q).theta_dot with gravity (criterion >= "
        f"{MIN_REVERSALS}, band {REVERSAL_BAND:g} of its peak): {turns['gravity']}, without "
        f"gravity {turns['nominal']}; joint ranges with gravity "
        f"{[round(x) for x in swing['gravity']]} deg, without "
        f"{[round(x) for x in swing['nominal']]} deg."
    )
    if not holds:
        note += (
            " The run shows a long travel along the self-motion (its set at a point is a closed "
            "loop for the 3R arm), the joints swinging over the ranges above, rather than a "
            "repeated oscillation; whether the thesis' 'cyclic' means that travel is open (it "
            "shows no figure of it)."
        )
    return Comparison.trend(
        "osc_gravity_self_motion_reversals",
        "'gravity compensation induces a cyclic joint motion ...' (§6.2.1): the cycles",
        turns["gravity"],
        "",
        holds=holds,
        note=note,
    )


def _plot_gravity(outcome: Outcome, figure) -> None:
    runs, motion, t = (outcome.figure_data[k] for k in ("gravity", "motion", "t"))
    axes = figure.subplots(3, 1, sharex=True)
    for ax, controller in zip(axes, (Controller.OSC, Controller.RNS_C), strict=False):
        run = runs[controller]
        plot.joint_lines(ax, run.t, run.v, plot.THETA_DOT_LABEL, lw=0.9)
        title = f"{controller.value}, gravity on: joint velocities, peak {run.peak_joint_speed:.3g}"
        plot.label_axes(ax, None, "[rad/s]", title + " rad/s")
        plot.legend_grid(ax, ncol=3, loc="upper right")
    for key, color in (("gravity", "tab:green"), ("nominal", "0.5")):
        axes[2].plot(t[: motion[key].size], motion[key], color=color, label=f"OS-C, {key}")
    plot.time_axes(axes[2], "[rad/s]", "OS-C self-motion velocity k(q).theta_dot")
    plot.legend_grid(axes[2])


# --------------------------------------------------------------------------- §6.1.2 exact C_A


@functools.cache
def _literal_run(controller: Controller, quick: bool) -> ClosedLoopRun:
    scenario = causes.scenario(causes.BASELINE, quick)
    return run_closed_loop(scenario, controller, dt=causes.period(quick))


def _c_a_outcome(quick: bool) -> Outcome:
    runs = {c: _literal_run(c, quick) for c in _LITERAL}
    closed = causes.planar_run(causes.BASELINE, Controller.RNS_C, quick)
    position = {
        c.value: r.max_position_error for c, r in {**runs, Controller.RNS_C: closed}.items()
    }
    force = {c.value: r.max_force_error for c, r in {**runs, Controller.RNS_C: closed}.items()}
    exact, approx = (position[c.value] for c in _LITERAL)
    ratio = approx / exact
    values = {
        "max_position_error_m": position,
        "max_force_error_N": force,
        "peak_joint_speed_rad_s": {c.value: r.peak_joint_speed for c, r in runs.items()},
        "runs": {c.value: r.summary() for c, r in runs.items()},
    }
    row = Comparison.trend(
        "momentum_c_a_position_error_ratio",
        "'we have to compensate the exact non-linear force term C_A instead of compensating its "
        "approximation ... otherwise, the task-space behavior cannot be guaranteed anymore' "
        "(§6.1.2)",
        ratio,
        "",
        holds=ratio > C_A_ERROR_FACTOR,
        note="literal RNS-C loop, max in-plane EE position error with the momentum approximation "
        f"over with the exact C_hat_A (criterion > {C_A_ERROR_FACTOR:g}): "
        + ", ".join(f"{k} {position[k] * 1e3:.3g} mm / {force[k]:.3g} N" for k in position)
        + " (position / force error; RNS-C = the closed form). The approximation equals the "
        "exact term in the linear rows and misses v_A x p in the angular row about the moving A; "
        "the constraint force F_B of (6.22) absorbs it into a wrong torque.",
    )
    choices = _choices(
        quick,
        "Literal RNS-C (A-4.3): (6.22) + (6.17) + (6.18) with the previous period's motion "
        "torque in Q_hat (the bias torque c_l + g_l at t = 0); the force term J^T n f_ref added "
        "as for every controller. Exact C_hat_A: Featherstone bias of the control model; "
        "momentum approximation: (M_hat_dot q_hat_dot)[:6], M_hat_dot by a central difference "
        "(h = 1e-6 s) along the real motion.",
    )
    settings = {"virtual_mass_kg": VIRTUAL_MASS, "controllers": [c.value for c in _LITERAL]}
    figure = {"runs": {**runs, Controller.RNS_C: closed}}
    return Outcome((row,), values, settings, choices, figure)


def _plot_c_a(outcome: Outcome, figure) -> None:
    axes = figure.subplots(2, 1, sharex=True)
    for controller, run in outcome.figure_data["runs"].items():
        style = {"color": _COLORS[controller], "lw": 1.0, "label": controller.value}
        axes[0].plot(run.t, run.position_error[:, 0] * 1e3, **style)
        axes[1].plot(run.t, run.force_error, **style)
    plot.label_axes(axes[0], None, "x_E error [mm]", "EE position error (tangential x_E)")
    plot.time_axes(axes[1], "f_des - f [N]", "force error along the normal z_E")
    for ax in axes:
        plot.legend_grid(ax)


REPRODUCTIONS = register_all(
    Reproduction(
        "sec6.1.2",
        "§6.1.2",
        "literal RNS-C with the exact C_A vs its momentum approximation: task-space errors",
        _c_a_outcome,
        _plot_c_a,
        (8.0, 6.0),
    ),
    Reproduction(
        "sec6.2.1",
        "§6.2.1",
        "planar arc with gravity on and compensated: OS-C's cyclic joint motion",
        _gravity_outcome,
        _plot_gravity,
        (9.0, 9.0),
    ),
)
