"""Chapter 3 (§3.2): the closed-form field of the planar two-DoF arm against Pinocchio and against
finite-difference momentum, the thesis_rest §1.2-§1.5 numbers, fixed points and r*."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import optimize

from rns_ros.analysis.planar_field import (
    PlanarArm,
    classify,
    com_distance_map,
    critical_distance,
    det_map,
    fixed_point_curve,
    fixed_points,
    integral_curve,
    torus_grid,
    torus_segments,
    wrap,
)
from rns_ros.core import ConfigError, FreeFloatingState
from rns_ros.core.planar import planar_2dof_model

ARM = PlanarArm()
angle = st.floats(-np.pi, np.pi, allow_nan=False)
thetas = st.tuples(angle, angle).map(np.array)
distances = st.sampled_from([0.0, 0.5, 0.945, 1.0, 1.5, 3.0])


@functools.cache
def _pinocchio(r: float, psi: float = 0.0):
    return planar_2dof_model(r, psi)


# --- (a) the closed form is the Pinocchio model ----------------------------------------------
@settings(max_examples=40, deadline=None)
@given(theta=thetas, r=distances, psi=st.sampled_from([0.0, np.pi / 3]))
def test_closed_form_equals_pinocchio(theta, r, psi):
    robot = _pinocchio(r, psi)
    state = FreeFloatingState.compute(robot, robot.configuration(theta))
    arm = PlanarArm(attach_distance=r, attach_angle=psi)
    # the z row is the planar one; the x/y rows vanish for a planar arm
    np.testing.assert_allclose(
        state.coupling_angular_momentum_matrix[2], arm.coupling_inertia(theta), atol=1e-9
    )
    np.testing.assert_allclose(state.coupling_angular_momentum_matrix[:2], 0.0, atol=1e-9)
    assert state.base_rotational_inertia[2, 2] == pytest.approx(
        arm.base_rotational_inertia(theta), abs=1e-9
    )
    # M~_m = M_m − M_vm^T M_v^{-1} M_vm from the CRBA blocks of eq. (2.7)
    M_v, M_vm = state.inertia_base[:3, :3], state.coupling_inertia[:3]
    tilde_m = state.manipulator_inertia - M_vm.T @ np.linalg.solve(M_v, M_vm)
    np.testing.assert_allclose(tilde_m, arm.manipulator_inertia(theta), atol=1e-9)


# --- (b) physics: momentum of the moving bodies, by finite differences -----------------------
def _bodies(arm: PlanarArm, q):
    """CoM positions (3, 2) [m] and angles (3,) [rad] of base, link 1, link 2 for
    q = (x_b, y_b, φ_b, θ1, θ2): plain forward kinematics, independent of the closed form."""
    x, y, phi, t1, t2 = q

    def e(a):
        return np.array([np.cos(a), np.sin(a)])

    (l1, _), (c1, c2) = arm.link_lengths, arm.com_distances
    base = np.array([x, y])
    joint_1 = base + arm.attach_distance * e(phi + arm.attach_angle)
    joint_2 = joint_1 + l1 * e(phi + t1)
    positions = np.array([base, joint_1 + c1 * e(phi + t1), joint_2 + c2 * e(phi + t1 + t2)])
    return positions, np.array([phi, phi + t1, phi + t1 + t2])


def _momentum(arm: PlanarArm, q, q_dot, h=1e-5):
    """(p (2,) [kg m/s], l (about the world origin) [kg m²/s]) for velocity q_dot."""
    masses = np.array([arm.base_mass, *arm.link_masses])
    inertias = np.array([arm.base_inertia, *arm.link_inertias])
    (pos_p, ang_p), (pos_m, ang_m) = _bodies(arm, q + h * q_dot), _bodies(arm, q - h * q_dot)
    positions, _ = _bodies(arm, q)
    velocity, rate = (pos_p - pos_m) / (2 * h), (ang_p - ang_m) / (2 * h)
    p = masses @ velocity
    cross = positions[:, 0] * velocity[:, 1] - positions[:, 1] * velocity[:, 0]
    return p, float(masses @ cross + inertias @ rate)


def _zero_momentum_base_rate(arm: PlanarArm, q, theta_dot):
    """Base rate ω_b that keeps p = 0 and l = 0 for the joint rates, from _momentum only."""
    columns = []
    for base_part in (np.eye(3)[0], np.eye(3)[1], np.eye(3)[2], np.zeros(3)):
        q_dot = np.concatenate([base_part, theta_dot if not base_part.any() else np.zeros(2)])
        p, lz = _momentum(arm, q, q_dot)
        columns.append(np.array([*p, lz]))
    # [p; l] = A [v_x, v_y, ω_b] + b = 0
    A, b = np.column_stack(columns[:3]), columns[3]
    return np.linalg.solve(A, -b)[2], A, b


@settings(max_examples=30, deadline=None)
@given(
    theta=thetas,
    r=distances,
    base=st.tuples(st.floats(-2, 2), st.floats(-2, 2), angle).map(np.array),
)
def test_field_keeps_the_base_still_and_matches_finite_difference_momentum(theta, r, base):
    arm = ARM.at(r)
    q = np.concatenate([base, theta])
    n = arm.reactionless_field(theta)
    # along n(θ) (eq. 3.5) the base does not turn: ω_b = 0 under zero momentum
    omega_b, A, _ = _zero_momentum_base_rate(arm, q, n)
    assert abs(omega_b) < 1e-7
    # along a generic direction it does, exactly as ω_b = −M~_ωm θ̇ / M~_ω predicts
    for direction in (np.array([1.0, 0.0]), np.array([0.0, 1.0]), np.array([0.6, -0.8])):
        omega_b, _, _ = _zero_momentum_base_rate(arm, q, direction)
        assert omega_b == pytest.approx(arm.base_rate(theta, direction), rel=1e-6, abs=1e-9)
    # with the base translation solved for p = 0 (eq. 3.2), l = M~_ω ω_b + M~_ωm θ̇
    for j in range(2):
        p_arm, _ = _momentum(arm, q, np.concatenate([np.zeros(3), np.eye(2)[j]]))
        v = -p_arm / arm.total_mass
        _, lz = _momentum(arm, q, np.concatenate([v, [0.0], np.eye(2)[j]]))
        assert lz == pytest.approx(arm.coupling_inertia(theta)[j], rel=1e-7, abs=1e-7)
    assert A[2, 2] - A[2, :2] @ A[:2, 2] / arm.total_mass == pytest.approx(
        arm.base_rotational_inertia(theta), rel=1e-7
    )


# --- (c) thesis_rest §1.2 reference values ---------------------------------------------------
REFERENCE = [  # r [m], θ [rad], M~_ωm [kg m²], M~_ω [kg m²]
    (0.0, (0.0, 0.0), (233.3267, 74.9967), 900.3267),
    (0.0, (0.0, np.pi / 2), (145.8267, 31.2467), 812.8267),
    (0.945, (0.0, 0.0), (390.8267, 114.3717), 1364.1642),
    (0.945, (1.0, -2.0), (194.5114, 34.3146), 1095.4465),
    (1.5, (0.0, 0.0), (483.3267, 137.4967), 1775.3267),
    (1.5, (np.pi / 2, np.pi / 2), (83.3267, -31.2533), 1062.8267),
]


@pytest.mark.parametrize(("r", "theta", "coupling", "base"), REFERENCE)
def test_reference_values(r, theta, coupling, base):
    arm = ARM.at(r)
    np.testing.assert_allclose(arm.coupling_inertia(theta), coupling, atol=1e-4)
    assert arm.base_rotational_inertia(theta) == pytest.approx(base, abs=1e-4)


def test_manipulator_inertia_depends_on_theta2_only():
    expected = [[233.3267, 74.9967], [74.9967, 31.2467]]
    for r in (0.0, 1.5):
        for theta_1 in (-2.0, 0.0, 1.0):
            np.testing.assert_allclose(
                ARM.at(r).manipulator_inertia((theta_1, 0.0)), expected, atol=1e-4
            )


# --- (d) r = 0: rotational symmetry and joint-2 dominance (§3.2.1) ---------------------------
def test_field_at_r0_is_independent_of_theta1_and_mostly_joint_2():
    _, _, theta = torus_grid(121)
    n = ARM.reactionless_field(theta)
    np.testing.assert_allclose(n, np.broadcast_to(n[:, :1], n.shape), atol=1e-12)
    assert np.abs(n[..., 1]).min() >= 0.95
    assert np.abs(n[..., 0]).max() <= 0.31
    assert np.linalg.norm(ARM.coupling_inertia(theta), axis=-1).min() == pytest.approx(
        59.65, abs=0.01
    )
    # the joint-1 nullclines at r = 0 are the lines θ2 = ±2.3663 rad (thesis_rest §1.3)
    m2 = ARM.coupling_inertia([[0.0, 2.3663], [0.0, -2.3663]])[:, 1]
    np.testing.assert_allclose(m2, 0.0, atol=2e-3)


@settings(max_examples=30, deadline=None)
@given(theta=thetas, shift=angle)
def test_field_at_r0_is_symmetric_in_theta1(theta, shift):
    moved = theta + np.array([shift, 0.0])
    np.testing.assert_allclose(
        ARM.reactionless_field(moved), ARM.reactionless_field(theta), atol=1e-12
    )


@settings(max_examples=30, deadline=None)
@given(theta=thetas, r=distances)
def test_field_is_a_unit_kernel_vector_with_the_a12_sign(theta, r):
    arm = ARM.at(r)
    n, m = arm.reactionless_field(theta), arm.coupling_inertia(theta)
    assert np.linalg.norm(n) == pytest.approx(1.0)
    assert abs(m @ n) < 1e-9 * np.linalg.norm(m)
    assert np.sign(n[1]) == np.sign(m[0]) or abs(m[0]) < 1e-12  # θ̇2 > 0 where M~_1 > 0


@settings(max_examples=30, deadline=None)
@given(theta=thetas, r=distances, psi=angle)
def test_psi_only_shifts_theta1(theta, r, psi):
    """§3.2.2: ψ 'does not influence the topological structure'; here it is a θ1 shift."""
    turned = PlanarArm(attach_distance=r, attach_angle=psi)
    np.testing.assert_allclose(
        turned.coupling_inertia(theta + np.array([psi, 0.0])),
        ARM.at(r).coupling_inertia(theta),
        atol=1e-9,
    )


@settings(max_examples=30, deadline=None)
@given(theta=thetas, r=distances)
def test_jacobian_matches_finite_differences(theta, r):
    arm, h = ARM.at(r), 1e-6
    numeric = np.column_stack(
        [
            (arm.coupling_inertia(theta + h * e) - arm.coupling_inertia(theta - h * e)) / (2 * h)
            for e in np.eye(2)
        ]
    )
    np.testing.assert_allclose(arm.coupling_inertia_jacobian(theta), numeric, atol=1e-5)


@pytest.mark.parametrize(("r", "joint"), [(0.5, 1), (1.5, 1), (1.5, 2), (0.945, 2)])
def test_nullcline_branches_are_zeros(r, joint):
    arm = ARM.at(r)
    theta2 = np.linspace(-np.pi, np.pi, 301)
    branches = arm.nullcline_theta1(joint, theta2)
    found = np.isfinite(branches)
    assert found.any()
    theta = np.stack([branches, np.broadcast_to(theta2[:, None], branches.shape)], -1)[found]
    joint_1_function, joint_2_function = arm.nullcline_functions(theta)
    values = joint_1_function if joint == 1 else joint_2_function
    np.testing.assert_allclose(values, 0.0, atol=1e-9)


def test_nullclines_at_r05_red_only():
    """§3.2.2 (r = 0.5): M~_1 > 0 everywhere (no blue nullcline); M~_2 changes sign."""
    _, _, theta = torus_grid(181)
    joint_1_function, joint_2_function = ARM.at(0.5).nullcline_functions(theta)
    assert joint_2_function.min() == pytest.approx(16.7, abs=0.05)
    assert joint_2_function.max() == pytest.approx(316.7, abs=0.05)
    assert joint_1_function.min() < 0.0 < joint_1_function.max()


# --- (e) fixed points ------------------------------------------------------------------------
FIXED_POINT_TABLE = {  # thesis_rest §1.4 [V]: one of each mirror pair, (θ1, θ2) [rad]
    0.946: [(2.3044, 2.5135), (2.3286, 2.4360)],
    0.95: [(2.2894, 2.5537), (2.3412, 2.3872)],
    1.0: [(2.2154, 2.6958), (2.3877, 2.1366)],
    1.5: [(1.9635, 2.9351), (2.4591, 0.7859)],
    3.0: [(1.7613, 3.0498), (2.0041, 0.2014)],
    10.0: [(1.6275, 3.1149), (1.6978, 0.0539)],
    100.0: [(1.5765, 3.1389), (1.5835, 0.0053)],
}


@pytest.mark.parametrize("r", [0.0, 0.5, 0.9])
def test_no_fixed_point_below_r_star(r):
    assert fixed_points(ARM.at(r)) == []


@pytest.mark.parametrize("r", sorted(FIXED_POINT_TABLE))
def test_four_fixed_points_above_r_star_as_in_the_table(r):
    points = fixed_points(ARM.at(r))
    assert len(points) == 4
    expected = [np.array(t) for t in FIXED_POINT_TABLE[r]]
    expected += [-t for t in expected]
    ours = np.array([p.theta for p in points])
    for theta in expected:
        assert np.min(np.max(np.abs(wrap(ours - theta)), axis=1)) < 1e-3
    for point in points:
        assert point.residual < 1e-10
        assert np.linalg.norm(ARM.at(r).coupling_inertia(point.theta)) < 1e-10
    # Poincaré-Hopf on the torus: the indices of f add up to χ = 0; one saddle and one
    # index +1 point in each mirror half
    assert sum(p.index for p in points) == 0
    assert sorted(p.kind for p in points).count("saddle") == 2


def _independent_fixed_points(arm: PlanarArm, n: int = 36) -> np.ndarray:
    """Zeros of M~_ωm by brute force: grid seeds + scipy.optimize.root, deduplicated mod 2π."""
    axis = np.linspace(-np.pi, np.pi, n, endpoint=False)
    found = []
    for a in axis:
        for b in axis:
            solution = optimize.root(
                arm.coupling_inertia, [a, b], jac=arm.coupling_inertia_jacobian, tol=1e-14
            )
            if solution.success and np.linalg.norm(arm.coupling_inertia(solution.x)) < 1e-9:
                theta = wrap(solution.x)
                if not any(np.max(np.abs(wrap(theta - f))) < 1e-6 for f in found):
                    found.append(theta)
    return np.array(found).reshape(-1, 2)


@pytest.mark.parametrize("r", [0.5, 1.0, 1.5])
def test_fixed_points_agree_with_a_brute_force_search(r):
    arm = ARM.at(r)
    ours = np.array([p.theta for p in fixed_points(arm)]).reshape(-1, 2)
    brute = _independent_fixed_points(arm)
    assert len(ours) == len(brute)
    for theta in brute:
        assert np.min(np.max(np.abs(wrap(ours - theta)), axis=1)) < 1e-8


def test_fixed_point_classes():
    """Each mirror half holds a saddle and an index +1 point (node near r*, focus at r = 1.5);
    the mirror map reverses f's time, so a stable point mirrors into an unstable one."""
    near = {(p.kind, p.stability) for p in fixed_points(ARM.at(0.95))}
    assert near == {("saddle", ""), ("node", "stable"), ("node", "unstable")}
    far = {(p.kind, p.stability) for p in fixed_points(ARM.at(1.5))}
    assert far == {("saddle", ""), ("focus", "stable"), ("focus", "unstable")}
    critical = critical_distance()
    degenerate = classify(ARM.at(critical.r_star), critical.theta[0], tolerance=1e-6)
    assert degenerate.kind == "degenerate"
    assert degenerate.index == 0


def test_fixed_point_curve_passes_through_the_fixed_points():
    s = np.linspace(0.05, np.pi - 0.05, 50)
    rho, theta1 = fixed_point_curve(ARM, s)
    for r, t1, t2 in zip(rho, theta1, s, strict=True):
        assert np.linalg.norm(ARM.at(r).coupling_inertia((t1, t2))) < 1e-9


# --- (f) the bifurcation value r* ------------------------------------------------------------
def _smallest_coupling(arm: PlanarArm) -> float:
    """min_θ |M~_ωm| by least squares from the best grid seeds (independent of ρ)."""
    _, _, theta = torus_grid(49)
    seeds = theta.reshape(-1, 2)
    order = np.argsort(np.linalg.norm(arm.coupling_inertia(seeds), axis=-1))[:8]
    best = np.inf
    for seed in seeds[order]:
        solution = optimize.least_squares(
            arm.coupling_inertia,
            seed,
            jac=arm.coupling_inertia_jacobian,
            xtol=1e-15,
            ftol=1e-15,
            gtol=1e-15,
        )
        best = min(best, float(np.linalg.norm(solution.fun)))
    return best


def test_critical_distance():
    critical = critical_distance()
    assert 0.9448 <= critical.r_star <= 0.9450
    assert critical.r_star == pytest.approx(0.944885, abs=5e-7)
    assert round(critical.r_star, 3) == 0.945  # the thesis' "r ≈ 0.945 m"
    np.testing.assert_allclose(critical.theta[0], [2.3169, 2.4759], atol=1e-4)
    np.testing.assert_allclose(critical.theta[1], [-2.3169, -2.4759], atol=1e-4)
    assert len(critical.extrema) == 1  # one birth, no later annihilation
    below, above = ARM.at(critical.r_star - 1e-4), ARM.at(critical.r_star + 1e-4)
    assert fixed_points(below) == []
    assert len(fixed_points(above)) == 4
    assert _smallest_coupling(below) > 1e-3
    assert _smallest_coupling(above) < 1e-10
    # the tolerance in θ2 does not move r* beyond rounding
    assert critical_distance(tol=1e-8).r_star == pytest.approx(critical.r_star, abs=1e-12)


# --- (g) Fig. 3.3 ----------------------------------------------------------------------------
def test_det_map_peaks_at_the_extended_arm():
    arm = ARM.at(1.5)
    t1, t2, values = det_map(arm, 201)
    i, j = np.unravel_index(np.argmax(values), values.shape)
    assert abs(t1[j]) < 1e-12
    assert abs(t2[i]) < 1e-12
    assert values[i, j] == pytest.approx(2.5251e5, rel=1e-3)
    # and a local search from the best off-grid neighbours returns to θ = 0
    best = optimize.minimize(lambda x: -arm.coupling_determinant(x), [0.1, -0.1])
    np.testing.assert_allclose(best.x, 0.0, atol=1e-4)
    _, _, distance = com_distance_map(arm, 201)
    assert distance.max() == pytest.approx(2.5)
    assert np.unravel_index(np.argmax(distance), distance.shape) == (i, j)
    assert np.corrcoef(values.ravel(), distance.ravel())[0, 1] == pytest.approx(0.80, abs=0.02)
    # "no fixed point within the area where the distance is large": all lie below the median
    for point in fixed_points(arm):
        assert arm.manipulator_com_distance(point.theta) < np.median(distance)


# --- integral curves and input checks --------------------------------------------------------
def test_integral_curve_is_reactionless_and_wraps_on_the_torus():
    arm = ARM.at(0.0)
    curve = integral_curve(arm, (0.0, 0.0), length=8.0, step=0.02)
    assert np.all(np.abs(arm.base_rate(curve, arm.reactionless_field(curve))) < 1e-12)
    steps = np.linalg.norm(np.diff(curve, axis=0), axis=1)
    np.testing.assert_allclose(steps, 0.02, rtol=1e-3)  # unit speed (chord ≈ arc)
    segments = torus_segments(curve)
    assert len(segments) >= 2  # θ2 runs around the torus (joint 2 never stops at r = 0)
    for segment in segments:
        assert np.all(np.abs(segment) <= np.pi)
    # r = 0 symmetry: a seed moved along θ1 gives the same curve moved along θ1
    moved = integral_curve(arm, (1.0, 0.0), length=8.0, step=0.02)
    np.testing.assert_allclose(moved - [1.0, 0.0], curve, atol=1e-9)


def test_integral_curve_is_an_rk4_solution():
    """Halving the step changes the end point by ~1/16 of the error (4th order)."""
    arm = ARM.at(1.0)
    ends = [integral_curve(arm, (0.3, -0.5), length=2.0, step=h)[-1] for h in (0.1, 0.05, 0.025)]
    ratio = np.linalg.norm(ends[0] - ends[1]) / np.linalg.norm(ends[1] - ends[2])
    assert 10.0 < ratio < 24.0


def test_bad_parameters_are_rejected():
    with pytest.raises(ConfigError, match="attach_distance"):
        PlanarArm(attach_distance=-1.0)
    with pytest.raises(ConfigError, match="link_masses"):
        PlanarArm(link_masses=(100.0, 0.0))
    with pytest.raises(ConfigError, match="shape"):
        ARM.coupling_inertia(np.zeros(3))
