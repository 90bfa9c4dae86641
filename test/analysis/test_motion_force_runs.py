"""Chapter 6 closed loops (rns_ros.analysis.motion_force_runs): physics of the quick runs (one
planar half cycle, one wall stroke, 2 ms period) and the run checks."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.analysis.motion_force_runs import (
    CONTROLLERS,
    QUICK_PERIOD,
    ClosedLoopRun,
    Controller,
    NullSpaceTerm,
    run_closed_loop,
)
from rns_ros.control.contact_tasks import (
    FORCE,
    ArcScenario,
    WallScenario,
    quick_scenarios,
)
from rns_ros.core.errors import ConfigError, RnsError, SimulationDivergedError

#: "Almost identical" task errors: max errors of OS-C within this factor of RNS-C's [-].
SAME_FACTOR = 2.0


@pytest.fixture(scope="module")
def runs() -> dict[tuple[str, Controller], ClosedLoopRun]:
    """{(scenario, controller): run} of the quick scenarios (about 5 s in all)."""
    out = {}
    for scenario in quick_scenarios():
        for controller in CONTROLLERS:
            run = run_closed_loop(scenario, controller, dt=QUICK_PERIOD)
            out[run.scenario, controller] = run
    return out


SCENARIOS = ("planar_arc", "lwr_wall")


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_shapes_are_documented_and_read_only(runs, scenario, controller):
    run = runs[scenario, controller]
    n, r = (3, 0) if scenario == "planar_arc" else (7, 3)
    k = run.t.shape[0]
    duration = 1.6 if scenario == "planar_arc" else 2.5
    assert k == round(duration / QUICK_PERIOD) + 1
    assert run.t[1] - run.t[0] == pytest.approx(QUICK_PERIOD)
    assert run.q.shape == run.v.shape == run.tau.shape == (k, n)
    assert run.position_error.shape == (k, 3)
    assert run.orientation_error.shape == (k, r)
    for name in ("force_desired", "force_reference", "contact_force", "force_error", "phi"):
        assert getattr(run, name).shape == (k,)
    assert run.joint_speed.shape == run.null_space_velocity.shape == (k,)
    assert run.controller == controller.value
    with pytest.raises(ValueError, match="read-only"):
        run.q[0, 0] = 1.0
    assert np.isfinite(run.tau).all()


@pytest.mark.parametrize("scenario", SCENARIOS)
@pytest.mark.parametrize("controller", CONTROLLERS)
def test_task_errors_stay_within_bounds_and_the_force_reaches_10_N(runs, scenario, controller):
    run = runs[scenario, controller]
    # tangential tracking: < 0.5 mm (measured 0.17-0.19 mm planar, 0.02 mm wall)
    assert run.max_position_error < 5e-4
    assert run.max_orientation_error < 2e-3  # measured 0.3-0.5 mrad (wall)
    # force: the ramp is tracked to 1e-3 N and the end force is 10 N
    assert run.max_force_error < 1e-3
    assert run.contact_force[-1] == pytest.approx(FORCE, abs=1e-3)
    assert run.force_desired[-1] == FORCE
    after_ramp = run.t >= 1.0
    assert np.abs(run.contact_force[after_ramp] - FORCE).max() < 1e-3
    # the rigid surface holds and the arm keeps pushing (one pulling step allowed at t = 0,
    # where the desired force is 0)
    assert run.max_constraint_error < 1e-8
    assert run.pulling_steps <= 1
    assert (run.contact_force[run.t >= 0.05] > 0.0).all()


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_rns_c_peak_joint_speed_is_below_os_c_literal(runs, scenario):
    """The thesis claim (Fig. 6.4: 0.73 vs 4.22 rad/s); both OS-C variants here."""
    rns = runs[scenario, Controller.RNS_C].peak_joint_speed
    assert rns < runs[scenario, Controller.OSC].peak_joint_speed
    assert rns < runs[scenario, Controller.OSC_KINEMATIC].peak_joint_speed
    if scenario == "planar_arc":  # quick: 0.71 vs 1.36 (literal) and 3.37 (kinematic) rad/s
        assert rns == pytest.approx(0.73, rel=0.1)
        assert runs[scenario, Controller.OSC].peak_joint_speed > 1.5 * rns


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_rns_c_and_os_c_give_almost_identical_task_errors(runs, scenario):
    rns = runs[scenario, Controller.RNS_C]
    for controller in (Controller.OSC, Controller.OSC_KINEMATIC):
        other = runs[scenario, controller]
        ratio = other.max_position_error / rns.max_position_error
        assert 1.0 / SAME_FACTOR <= ratio <= SAME_FACTOR
        # pointwise: the error curves differ by less than their own size
        difference = np.abs(other.tangential_error - rns.tangential_error).max()
        assert difference < rns.max_position_error


def test_planar_run_starts_at_the_arc_end_and_sweeps_the_quarter_circle(runs):
    run = runs["planar_arc", Controller.RNS_C]
    assert run.description["start_point_m"] == pytest.approx([1.203, 1.91])
    assert run.description["initial_joint_positions_deg"] == pytest.approx(
        [106.4324, -45.7055, -56.2218], abs=1e-3
    )
    assert run.position_error[0] == pytest.approx(np.zeros(3), abs=1e-12)
    # RNS-C keeps its acceleration in the row space of W: the null-space velocity stays small
    assert run.null_space_velocity.max() < 0.1  # measured 0.040 rad/s
    assert (
        run.null_space_velocity.max() < runs["planar_arc", Controller.OSC].null_space_velocity.max()
    )


def test_wall_geometry_is_the_documented_choice(runs):
    description = runs["lwr_wall", Controller.RNS_C].description
    assert description["start_point_m"] == pytest.approx([0.514814, 0.187377, 0.464199], abs=1e-6)
    assert description["wall_normal"] == pytest.approx([0.883022, 0.321394, -0.34202], abs=1e-6)
    assert description["stroke_direction"] == pytest.approx([-0.34202, 0.939693, 0.0], abs=1e-6)
    assert description["stroke_length_m"] == pytest.approx(0.514814 - 0.24, abs=1e-6)


def test_bad_run_parameters_raise_typed_errors():
    arc = ArcScenario(half_cycles=1)
    with pytest.raises(ConfigError, match="controller"):
        run_closed_loop(arc, "PD")
    with pytest.raises(ConfigError, match="dt"):
        run_closed_loop(arc, "RNS-C", dt=0.0)
    with pytest.raises(ConfigError, match="force measurement"):
        run_closed_loop(arc, "RNS-C", force_measurement="late")
    with pytest.raises(ConfigError, match="parallel"):
        WallScenario(normal=(1.0, 0.0, 0.0), direction=(-2.0, 0.0, 0.0)).setup()
    with pytest.raises(ConfigError, match="out of reach"):
        ArcScenario(center=(9.0, 9.0)).setup()


def test_a_force_sensor_one_period_late_diverges_with_the_thesis_gain():
    """Why the force loop is solved at the same instant: e_{k+1} = -k_f e_k, k_f = 5."""
    with pytest.raises(SimulationDivergedError) as caught:
        run_closed_loop(
            ArcScenario(half_cycles=1),
            "RNS-C",
            dt=QUICK_PERIOD,
            duration=0.2,
            force_measurement="previous-step",
        )
    assert isinstance(caught.value, RnsError)


@pytest.mark.parametrize("controller", ["RNS-C", "OS-C"])
def test_force_and_motion_are_decoupled_on_the_wall(controller):
    """A 10 N force step (0.02 s ramp) with the arm holding still does not move the end
    effector in the wall plane; a stroke with zero force keeps the contact force at zero."""
    from rns_ros.analysis.motion_force_runs import run_closed_loop
    from rns_ros.control.contact_tasks import WallScenario

    hold = WallScenario(stroke=1e6, strokes=1, force=10.0, force_ramp=0.02)
    run = run_closed_loop(hold, controller, dt=2e-3, duration=0.5)
    assert run.contact_force[-1] == pytest.approx(10.0, abs=1e-3)
    in_plane = np.abs(run.position_error[:, :2]).max()
    print(f"{controller}: in-plane error during the force step {in_plane:.2e} m")
    assert in_plane < 1e-6
    stroke = WallScenario(stroke=0.5, strokes=1, length=0.05, force=0.0)
    run = run_closed_loop(stroke, controller, dt=2e-3, duration=0.5)
    print(f"{controller}: contact force during the stroke {np.abs(run.contact_force).max():.2e} N")
    assert np.abs(run.contact_force).max() < 1e-3


@pytest.fixture(scope="module")
def null_space_runs() -> dict[tuple[str, float | None], ClosedLoopRun]:
    """RNS-C on 0.6 s of the quick wall stroke per chapter-7 null-space term (about 2 s)."""
    scenario = WallScenario(strokes=1)
    return {
        (term, gain): run_closed_loop(
            scenario,
            Controller.RNS_C,
            dt=QUICK_PERIOD,
            duration=0.6,
            null_space=term,
            damper_gain=gain,
        )
        for term, gain in (
            (NullSpaceTerm.NONE, None),
            (NullSpaceTerm.VELOCITY_LEVEL, None),
            (NullSpaceTerm.DAMPER, None),
            (NullSpaceTerm.DAMPER, 1.9 / QUICK_PERIOD),
        )
    }


def test_chapter7_null_space_terms_shrink_the_null_space_velocity_not_the_task(
    null_space_runs,
):
    """(7.3): theta_ddot_a enters through P_hat_RNS and the oblique projector, so the task
    motion is unchanged while ||P_hat_RNS theta_dot|| falls by an order (7.13, §7.2.2)."""
    plain = null_space_runs[NullSpaceTerm.NONE, None]
    for key, run in null_space_runs.items():
        assert run.max_position_error == pytest.approx(plain.max_position_error, rel=1e-4)
        assert run.max_force_error < 1e-6
        if key[0] is not NullSpaceTerm.NONE:
            assert run.null_space_velocity.max() < 0.1 * plain.null_space_velocity.max(), key


def test_a_held_damper_is_stable_below_two_over_the_period_and_diverges_above():
    """Held over the period, theta_ddot_a = -k_d theta_dot gives P theta_dot_(k+1) ~
    (1 - k_d dt) P theta_dot_k: |1 - 2.5| > 1 grows from round-off until the run stops."""
    with pytest.raises(SimulationDivergedError):
        run_closed_loop(
            WallScenario(strokes=1),
            Controller.RNS_C,
            dt=QUICK_PERIOD,
            duration=0.6,
            null_space=NullSpaceTerm.DAMPER,
            damper_gain=2.5 / QUICK_PERIOD,
        )


def test_a_bad_null_space_term_or_damper_gain_raises():
    with pytest.raises(ConfigError, match="null-space term"):
        run_closed_loop(WallScenario(strokes=1), Controller.RNS_C, null_space="bogus")
    with pytest.raises(ConfigError, match="damper_gain"):
        run_closed_loop(WallScenario(strokes=1), Controller.RNS_C, damper_gain=-1.0)
