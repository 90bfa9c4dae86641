"""rns_ros.analysis.recorded_run: the singular-region figures of a recorded run. sigma_min of
J-bar is taken by SVD here and compared with the eigenvalues of J-bar J-bar^T
(rns_ros.control.law_matrices, another route to the same number); the time in the singular
region counts each sample until the next."""

from __future__ import annotations

import numpy as np
import pytest

from rns_ros.analysis.closed_loop import run_scenario
from rns_ros.analysis.recorded_run import run_figures
from rns_ros.control.law_matrices import restricted_jacobian
from rns_ros.control.scenario import load_scenario
from rns_ros.core import FreeFloatingState
from rns_ros.resources import scenario_path


def _record(robot, thetas, dt=0.1):
    k = len(thetas)
    return {
        "times": np.arange(k) * dt,
        "joint_positions": np.asarray(thetas),
        "joint_velocities": np.zeros((k, robot.n)),
        "base_positions": np.zeros((k, 3)),
        "base_orientations": np.tile([0.0, 0.0, 0.0, 1.0], (k, 1)),
        "base_angular_velocities": np.zeros((k, 3)),
        "angular_momentum": np.zeros((k, 3)),
        "command_times": np.zeros(0),
        "commands": np.zeros((0, 3)),
    }


def test_sigma_min_and_the_time_below_the_threshold(robot):
    """Fig. 4.6's run passes the algorithmic singularity: along its joint path sigma_min dips
    far below the DLS epsilon 0.2 and rises again."""
    scenario = load_scenario(scenario_path("algorithmic_singularity"))
    samples = []
    run_scenario(robot, scenario, method="dls", rate=20.0, on_period=samples.append)
    path = [sample.state.theta for sample in samples[::5]]
    sigmas = []
    for theta in path:
        state = FreeFloatingState.compute(robot, robot.configuration(theta))
        sigmas.append(restricted_jacobian(state).sigma_min)
    sigmas = np.array(sigmas)
    threshold = 0.2
    assert sigmas.min() < 0.1 < threshold < sigmas.max()  # the path goes through it
    figures = run_figures(robot, scenario, **_record(robot, path), singular_threshold=threshold)
    assert figures.min_sigma == pytest.approx(sigmas.min(), rel=1e-6, abs=1e-9)
    below = np.flatnonzero(sigmas < threshold)
    expected = 0.1 * np.sum(below < len(path) - 1)  # the last sample is held for no time
    assert figures.singular_time_s == pytest.approx(expected, abs=1e-9)


def test_the_singular_value_products_are_determinant_roots(robot):
    """prod(sigma_i) of J-bar is sqrt(det(J-bar J-bar^T)): SC's speed scale over b (eq. 4.13)."""
    scenario = load_scenario(scenario_path("algorithmic_singularity"))
    samples = []
    run_scenario(robot, scenario, method="dls", rate=20.0, on_period=samples.append)
    path = [sample.state.theta for sample in samples[::10]]
    roots = []
    for theta in path:
        state = FreeFloatingState.compute(robot, robot.configuration(theta))
        matrix = restricted_jacobian(state).matrix
        roots.append(np.sqrt(np.linalg.det(matrix @ matrix.T)))
    figures = run_figures(robot, scenario, **_record(robot, path))
    assert figures.min_singular_product == pytest.approx(min(roots), rel=1e-6, abs=1e-12)
    assert figures.max_singular_product == pytest.approx(max(roots), rel=1e-6)


@pytest.mark.parametrize("frame", ["world", "camera", "base"])
def test_the_commanded_attitude_is_the_integral_of_the_held_rates(frame):
    """A rate held over stamps 0 .. T turns the camera by exp(omega T) in its frame's axes
    (world: on the left; camera: on the right; base: conjugated by the base rotation); the
    last sample counts for nothing (the stream's end)."""
    from types import SimpleNamespace

    import pinocchio as pin

    from rns_ros.analysis.recorded_run import commanded_rotation
    from rns_ros.control.controller import TwistFrame

    scenario = SimpleNamespace(frame=TwistFrame(frame))
    camera_0 = pin.exp3(np.array([0.3, -0.2, 0.5]))
    base_0 = pin.exp3(np.array([-0.1, 0.4, 0.2]))
    omega = np.array([0.2, -0.1, 0.05])
    times = np.linspace(0.0, 2.0, 41)
    commands = np.tile(omega, (41, 1))
    commands[-1] = [50.0, 0.0, 0.0]  # held for nothing
    turn = pin.exp3(2.0 * omega)
    expected = {
        "world": turn @ camera_0,
        "camera": camera_0 @ turn,
        "base": base_0 @ turn @ base_0.T @ camera_0,
    }[frame]
    got = commanded_rotation(scenario, camera_0, base_0, times, commands)
    np.testing.assert_allclose(got, expected, atol=1e-12)


def test_the_sampled_profile_adds_up_to_the_scenarios_target():
    """The scenario's rates sampled every 1 ms and held add up to its target attitude
    (Scenario.target_rotation, from the closed-form progress), to the hold's O(dt) error."""
    from rns_ros.analysis.recorded_run import commanded_rotation
    from rns_ros.core.integration import attitude_deviation

    scenario = load_scenario(scenario_path("satellite_observation"))
    times = np.arange(0.0, scenario.duration + 0.0015, 0.001)
    commands = np.array([scenario.angular_velocity(t) for t in times])
    camera_0, base_0 = np.eye(3), np.eye(3)
    target = scenario.target_rotation(camera_0, base_0, scenario.duration)
    got = commanded_rotation(scenario, camera_0, base_0, times, commands)
    assert attitude_deviation(target, got) < 1e-3
    assert attitude_deviation(target, camera_0) > 0.1  # it turned
