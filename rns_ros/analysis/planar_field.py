"""Chapter 3: the reactionless vector field of the planar two-DoF free-floating arm (Fig. 3.1).

:class:`PlanarArm` holds M~_m and M~_ωm of thesis Fig. 3.1 / §3.2.1 in closed form (angles as in
choice A-1.1); the field is θ̇ = b n(θ), n the co-factor vector of M~_ωm (eq. 3.5), and its fixed
points are found exactly. Formulas and derivation: docs/chapter3.md, "The planar field in closed
form". Numpy/scipy only.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy import optimize

from rns_ros.core.errors import ConfigError

#: Relative size of det(Df) (against ‖Df‖²) below which a fixed point counts as degenerate [-].
DEGENERATE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class PlanarArm:
    """Parameters of the Fig. 3.1 model (defaults: thesis §3.2.1 and Fig. 3.1 caption).

    Attributes:
        attach_distance: r of eq. (3.6), base CoM to joint 1 [m]; the bifurcation parameter.
        attach_angle: ψ of eq. (3.6), direction of the attachment point in the base frame [rad].
        base_mass: m_b [kg].
        base_inertia: I_b about the plane normal [kg m²].
        link_lengths: (l_1, l_2) [m].
        link_masses: (m_1, m_2) [kg].
        link_inertias: (I_1, I_2) about each link's CoM [kg m²] (8.33 in §3.2.1; 8.3 in §5.2).
        com_distances: (l_c1, l_c2), joint i to the CoM of link i [m] (l_i/2: uniform rods).
    """

    attach_distance: float = 0.0
    attach_angle: float = 0.0
    base_mass: float = 1000.0
    base_inertia: float = 667.0
    link_lengths: tuple[float, float] = (1.0, 1.0)
    link_masses: tuple[float, float] = (100.0, 100.0)
    link_inertias: tuple[float, float] = (8.33, 8.33)
    com_distances: tuple[float, float] = (0.5, 0.5)

    def __post_init__(self):
        r = self.attach_distance
        if not (math.isfinite(r) and r >= 0.0):
            raise ConfigError(f"attach_distance must be finite and >= 0 m, got {r!r}")
        if not math.isfinite(self.attach_angle):
            raise ConfigError(f"attach_angle must be finite, got {self.attach_angle!r}")
        positives = {
            "base_mass": (self.base_mass,),
            "base_inertia": (self.base_inertia,),
            "link_lengths": self.link_lengths,
            "link_masses": self.link_masses,
            "link_inertias": self.link_inertias,
        }
        for name, values in positives.items():
            if len(values) not in (1, 2) or not all(math.isfinite(v) and v > 0 for v in values):
                raise ConfigError(f"{name} must be positive and finite, got {values!r}")
        if len(self.com_distances) != 2 or not all(
            math.isfinite(c) and c >= 0 for c in self.com_distances
        ):
            raise ConfigError(f"com_distances must be >= 0, got {self.com_distances!r}")

    def at(self, attach_distance: float) -> PlanarArm:
        """The same arm attached at another r [m]."""
        return replace(self, attach_distance=float(attach_distance))

    # --- constants of the closed form -------------------------------------------------------
    @property
    def total_mass(self) -> float:
        """m_C = m_b + m_1 + m_2 [kg]."""
        return self.base_mass + sum(self.link_masses)

    @property
    def base_mass_fraction(self) -> float:
        """k = m_b / m_C [-]: how much of the attachment offset survives the CoM shift."""
        return self.base_mass / self.total_mass

    @property
    def first_moments(self) -> tuple[float, float]:
        """(P, Q) = (m_1 l_c1 + m_2 l_1, m_2 l_c2) [kg m]: mass moments of the links about joint
        1 along link 1 and about joint 2 along link 2."""
        (l1, _), (m1, m2), (c1, c2) = self.link_lengths, self.link_masses, self.com_distances
        return m1 * c1 + m2 * l1, m2 * c2

    @property
    def inertia_constants(self) -> tuple[float, float, float]:
        """(α_1, α_2, β) [kg m²] with M~_m11 = α_1 + 2β cos θ2, M~_m12 = α_2 + β cos θ2,
        M~_m22 = α_2 (module docstring)."""
        (l1, _), (m1, m2), (i1, i2), (c1, c2) = (
            self.link_lengths,
            self.link_masses,
            self.link_inertias,
            self.com_distances,
        )
        P, Q = self.first_moments
        m_c = self.total_mass
        alpha_1 = i1 + i2 + m1 * c1**2 + m2 * (l1**2 + c2**2) - (P**2 + Q**2) / m_c
        alpha_2 = i2 + m2 * c2**2 - Q**2 / m_c
        beta = Q * (l1 - P / m_c)
        return alpha_1, alpha_2, beta

    # --- eq. (3.2) quantities, vectorized over theta of shape (..., 2) ----------------------
    def _angles(self, theta):
        theta = np.asarray(theta, dtype=float)
        if theta.shape[-1:] != (2,):
            raise ConfigError(f"theta must have shape (..., 2), got {theta.shape}")
        phi = theta[..., 0] - self.attach_angle
        return phi, theta[..., 1]

    def manipulator_inertia(self, theta) -> np.ndarray:
        """M~_m = M_m − M_vm^T M_v^{-1} M_vm (thesis_rest §0), shape (..., 2, 2) [kg m²].

        Depends on θ2 only (and not on r)."""
        _, s = self._angles(theta)
        alpha_1, alpha_2, beta = self.inertia_constants
        a1 = alpha_1 + 2.0 * beta * np.cos(s)
        a2 = alpha_2 + beta * np.cos(s)
        return np.stack([np.stack([a1, a2], -1), np.stack([a2, np.full_like(a1, alpha_2)], -1)], -2)

    def coupling_inertia(self, theta) -> np.ndarray:
        """M~_ωm of eq. (3.2), the z row of the coupling inertia, shape (..., 2) [kg m²].

        Args:
            theta: joint angles (θ1, θ2) [rad], shape (..., 2).
        """
        phi, s = self._angles(theta)
        alpha_1, alpha_2, beta = self.inertia_constants
        P, Q = self.first_moments
        kr = self.base_mass_fraction * self.attach_distance
        outer = kr * Q * np.cos(phi + s)
        m1 = alpha_1 + 2.0 * beta * np.cos(s) + kr * P * np.cos(phi) + outer
        m2 = alpha_2 + beta * np.cos(s) + outer
        return np.stack([m1, m2], -1)

    def coupling_inertia_jacobian(self, theta) -> np.ndarray:
        """∂M~_ωm/∂θ, shape (..., 2, 2) [kg m²/rad]; row j is the gradient of M~_j."""
        phi, s = self._angles(theta)
        _, _, beta = self.inertia_constants
        P, Q = self.first_moments
        kr = self.base_mass_fraction * self.attach_distance
        outer = -kr * Q * np.sin(phi + s)
        row_1 = np.stack([-kr * P * np.sin(phi) + outer, -2.0 * beta * np.sin(s) + outer], -1)
        row_2 = np.stack([outer, -beta * np.sin(s) + outer], -1)
        return np.stack([row_1, row_2], -2)

    def base_rotational_inertia(self, theta) -> np.ndarray:
        """M~_ω of eq. (3.2) (1×1 in the plane), shape (...) [kg m²]."""
        phi, s = self._angles(theta)
        alpha_1, _, beta = self.inertia_constants
        P, Q = self.first_moments
        k, r = self.base_mass_fraction, self.attach_distance
        return (
            self.base_inertia
            + alpha_1
            + 2.0 * beta * np.cos(s)
            + k * sum(self.link_masses) * r**2
            + 2.0 * k * r * (P * np.cos(phi) + Q * np.cos(phi + s))
        )

    def base_rate(self, theta, theta_dot) -> np.ndarray:
        """Base angular rate under zero momentum, ω_b = −M~_ωm θ̇ / M~_ω (eq. 3.2 with l_B = 0),
        shape (...) [rad/s]; ``theta_dot`` [rad/s] broadcasts against ``theta``, shape (..., 2)."""
        coupling = np.sum(self.coupling_inertia(theta) * np.asarray(theta_dot), -1)
        return -coupling / self.base_rotational_inertia(theta)

    def cofactor_field(self, theta) -> np.ndarray:
        """f(θ) = [−M~_2, M~_1], the un-normalized kernel vector of M~_ωm (co-factor method,
        eq. 3.5; A-1.3: its zeros are the fixed points), shape (..., 2) [kg m²]."""
        m = self.coupling_inertia(theta)
        return np.stack([-m[..., 1], m[..., 0]], -1)

    def reactionless_field(self, theta) -> np.ndarray:
        """n(θ) of eq. (3.5): f/|f|, unit vector spanning ker M~_ωm, shape (..., 2) [-].

        NaN at fixed points (M~_ωm = 0), where the normalized field is undefined (A-1.3)."""
        f = self.cofactor_field(theta)
        norm = np.linalg.norm(f, axis=-1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(norm > 0.0, f / norm, np.nan)

    def nullcline_functions(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """(M~_2, M~_1), shapes (...) [kg m²]: their zero sets are the joint-1 nullcline
        (θ̇1 = 0, red in Fig. 3.2) and the joint-2 nullcline (θ̇2 = 0, blue)."""
        m = self.coupling_inertia(theta)
        return m[..., 1], m[..., 0]

    def nullcline_theta1(self, joint: int, theta2) -> np.ndarray:
        """The joint-``joint`` nullcline as θ1 branches over θ2, shape (..., 2) [rad].

        Solves M~_2 = 0 (joint 1) or M~_1 = 0 (joint 2) for θ1 in closed form; NaN where the
        line θ2 = const does not meet the nullcline. Values are wrapped to [−π, π). At r = 0 the
        nullclines are lines θ2 = const, which this form cannot express (all NaN then).
        """
        s = np.asarray(theta2, dtype=float)
        alpha_1, alpha_2, beta = self.inertia_constants
        P, Q = self.first_moments
        kr = self.base_mass_fraction * self.attach_distance
        if joint == 1:  # kr Q cos(φ + s) = −(α_2 + β cos s)
            amplitude, shift, rest = kr * Q, s, alpha_2 + beta * np.cos(s)
        elif joint == 2:  # kr |P + Q e^{is}| cos(φ + δ) = −(α_1 + 2β cos s)
            amplitude = kr * np.hypot(P + Q * np.cos(s), Q * np.sin(s))
            shift = np.arctan2(Q * np.sin(s), P + Q * np.cos(s))
            rest = alpha_1 + 2.0 * beta * np.cos(s)
        else:
            raise ConfigError(f"joint must be 1 or 2, got {joint!r}")
        with np.errstate(invalid="ignore", divide="ignore"):
            angle = np.arccos(-rest / amplitude)  # NaN where |ratio| > 1
        branches = np.stack([angle, -angle], -1) - np.asarray(shift)[..., None] + self.attach_angle
        return wrap(branches)

    def manipulator_com_distance(self, theta) -> np.ndarray:
        """|c_m − c_b|, links-only CoM to base CoM (Fig. 3.3b, A-1.6), shape (...) [m]."""
        phi, s = self._angles(theta)
        P, Q = self.first_moments
        mu, r = sum(self.link_masses), self.attach_distance
        # in the frame of link 1: a = r e(−φ), first moment of the links about joint 1 = D
        x = r * np.cos(phi) + (P + Q * np.cos(s)) / mu
        y = -r * np.sin(phi) + Q * np.sin(s) / mu
        return np.hypot(x, y)

    def coupling_determinant(self, theta) -> np.ndarray:
        """det(M~_ωm M~_ωm^T) = |M~_ωm|² (Fig. 3.3a), shape (...) [kg² m⁴]."""
        return np.sum(self.coupling_inertia(theta) ** 2, -1)


def wrap(angle):
    """Angle(s) wrapped to [−π, π) [rad]."""
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi


def torus_grid(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An n×n grid over [−π, π]² (end points included, for plotting).

    Returns:
        (theta1 (n,), theta2 (n,), theta (n, n, 2)) [rad]; theta[i, j] = (theta1[j], theta2[i]),
        i.e. rows run along θ2 (image/contour layout: θ1 → x, θ2 → y, A-1.4).
    """
    axis = np.linspace(-np.pi, np.pi, int(n))
    t1, t2 = np.meshgrid(axis, axis, indexing="xy")
    return axis, axis, np.stack([t1, t2], -1)


def det_map(arm: PlanarArm, n: int = 201):
    """Fig. 3.3(a): (theta1 (n,), theta2 (n,), |M~_ωm|² (n, n) [kg² m⁴]) on :func:`torus_grid`."""
    t1, t2, theta = torus_grid(n)
    return t1, t2, arm.coupling_determinant(theta)


def com_distance_map(arm: PlanarArm, n: int = 201):
    """Fig. 3.3(b): (theta1 (n,), theta2 (n,), links-only CoM distance (n, n) [m])."""
    t1, t2, theta = torus_grid(n)
    return t1, t2, arm.manipulator_com_distance(theta)


# --- fixed points -----------------------------------------------------------------------------
@dataclass(frozen=True)
class FixedPoint:
    """A zero of M~_ωm (a fixed point of the co-factor field f = [−M~_2, M~_1]).

    Attributes:
        theta: (θ1, θ2) [rad], wrapped to [−π, π), shape (2,).
        kind: "saddle", "node", "focus", "center" or "degenerate" (linearization of f).
        stability: "stable", "unstable" or "" for f as signed (A-1.2; b < 0 swaps them).
        index: Poincaré index of f at the point, sign det(Df) = sign det(∂M~_ωm/∂θ), 0 if
            degenerate.
        eigenvalues: of Df, shape (2,) complex [kg m²/rad].
        residual: |M~_ωm(theta)| [kg m²].
    """

    theta: np.ndarray
    kind: str
    stability: str
    index: int
    eigenvalues: np.ndarray
    residual: float


def classify(arm: PlanarArm, theta, tolerance: float = DEGENERATE_TOLERANCE) -> FixedPoint:
    """Linearize f = [−M~_2, M~_1] at ``theta`` (shape (2,)) [rad] and classify it.

    Df = [[0, −1], [1, 0]] ∂M~_ωm/∂θ, so det Df = det ∂M~_ωm/∂θ (the index) and
    trace Df = ∂M~_1/∂θ2 − ∂M~_2/∂θ1 (≠ 0 in general: f is not Hamiltonian, the reactionless
    constraint is non-holonomic).
    """
    theta = np.asarray(theta, dtype=float)
    rotation = np.array([[0.0, -1.0], [1.0, 0.0]])
    df = rotation @ arm.coupling_inertia_jacobian(theta)
    det, trace = float(np.linalg.det(df)), float(np.trace(df))
    scale = float(np.sum(df**2))
    eigenvalues = np.linalg.eigvals(df).astype(complex)
    stability = ""
    if abs(det) <= tolerance * scale:
        kind, index = "degenerate", 0
    elif det < 0.0:
        kind, index = "saddle", -1
    else:
        index = 1
        discriminant = trace**2 - 4.0 * det
        if abs(trace) <= tolerance * math.sqrt(scale):
            kind = "center"
        else:
            kind = "node" if discriminant >= 0.0 else "focus"
            stability = "stable" if trace < 0.0 else "unstable"
    residual = float(np.linalg.norm(arm.coupling_inertia(theta)))
    return FixedPoint(wrap(theta), kind, stability, index, eigenvalues, residual)


def _curve_terms(arm: PlanarArm, s):
    """u, w of the fixed-point curve and their s-derivatives (module docstring)."""
    s = np.asarray(s, dtype=float)
    alpha_1, alpha_2, beta = arm.inertia_constants
    P, Q = arm.first_moments
    k = arm.base_mass_fraction
    c, sn = np.cos(s), np.sin(s)
    u = -(alpha_1 - alpha_2 + beta * c) / (k * P)
    v = -(alpha_2 + beta * c) / (k * Q)
    du = beta * sn / (k * P)
    dv = beta * sn / (k * Q)
    numerator = u * c - v
    d_numerator = du * c - u * sn - dv
    with np.errstate(divide="ignore", invalid="ignore"):  # sin s = 0: ρ -> ∞ (generic case)
        w = numerator / sn
        dw = (d_numerator * sn - numerator * c) / sn**2
    return u, w, du, dw, numerator


def fixed_point_curve(arm: PlanarArm, theta2) -> tuple[np.ndarray, np.ndarray]:
    """The fixed-point set over (θ2, r): for each θ2 = s ∉ {0, π}, the only attachment distance
    ρ(s) [m] at which (θ1(s), s) is a fixed point, and that θ1 [rad]; shapes like ``theta2``.

    Derived from M~_1 − M~_2 = 0 and M~_2 = 0, which are linear in r (cos φ, sin φ)."""
    u, w, *_ = _curve_terms(arm, theta2)
    return np.hypot(u, w), wrap(arm.attach_angle + np.arctan2(w, u))


def _rho_squared_slope(arm: PlanarArm, s) -> np.ndarray:
    """d(ρ²)/ds [m²/rad]."""
    u, w, du, dw, _ = _curve_terms(arm, s)
    return 2.0 * (u * du + w * dw)


def _critical_theta2(arm: PlanarArm, samples: int, xtol: float) -> np.ndarray:
    """All s ∈ (0, π) with dρ²/ds = 0 (the extrema of ρ), by sign changes on a grid + brentq."""
    edge = 1e-9
    grid = np.linspace(edge, np.pi - edge, samples)
    slope = _rho_squared_slope(arm, grid)
    roots = []
    for i in np.flatnonzero(np.sign(slope[:-1]) * np.sign(slope[1:]) < 0):
        roots.append(
            optimize.brentq(
                lambda x: float(_rho_squared_slope(arm, x)), grid[i], grid[i + 1], xtol=xtol
            )
        )
    roots += [float(x) for x in grid[slope == 0.0]]
    return np.array(sorted(roots))


@dataclass(frozen=True)
class CriticalDistance:
    """Where fixed points are born (the bifurcation of §3.2.2).

    Attributes:
        r_star: smallest r with a fixed point [m].
        theta: the degenerate fixed points at r*, a mirror pair, shape (2, 2) [rad].
        theta2_tolerance: brentq tolerance on θ2 of the minimizer [rad]; r* is a minimum of a
            smooth ρ, so its own error is O(tolerance²) plus rounding (~1e-15 m).
        extrema: all (θ2 [rad], r [m]) where ρ has an extremum on (0, π): pairs of fixed points
            are born (minima) or annihilate (maxima) there.
    """

    r_star: float
    theta: np.ndarray
    theta2_tolerance: float
    extrema: tuple[tuple[float, float], ...]


def critical_distance(
    arm: PlanarArm | None = None, tol: float = 1e-13, samples: int = 4001
) -> CriticalDistance:
    """r* = min_θ2 ρ(θ2), the attachment distance at which fixed points appear (§3.2.2).

    Found by a root finder: brentq on dρ²/dθ2 = 0 between sign changes on a ``samples`` grid
    over (0, π) (ρ → ∞ at θ2 → 0, π for generic parameters, so the global minimum is one of
    these roots). ``arm.attach_distance`` is ignored.

    Args:
        tol: xtol of brentq on θ2 [rad].
        samples: grid size used only to bracket the roots.
    """
    arm = arm or PlanarArm()
    s_critical = _critical_theta2(arm, samples, tol)
    if s_critical.size == 0:
        raise ConfigError("ρ(θ2) has no interior extremum: no fixed point ever appears")
    rho, theta1 = fixed_point_curve(arm, s_critical)
    best = int(np.argmin(rho))
    point = np.array([theta1[best], s_critical[best]])
    mirror = wrap(np.array([2.0 * arm.attach_angle - point[0], -point[1]]))  # (φ, s) -> (−φ, −s)
    return CriticalDistance(
        r_star=float(rho[best]),
        theta=np.stack([point, mirror]),
        theta2_tolerance=tol,
        extrema=tuple((float(s), float(r)) for s, r in zip(s_critical, rho, strict=True)),
    )


def fixed_points(arm: PlanarArm, samples: int = 4001, xtol: float = 1e-14) -> list[FixedPoint]:
    """Every zero of M~_ωm on the torus at ``arm.attach_distance``, classified, sorted by θ.

    ρ(θ2) − r has exactly one root on each monotone piece of ρ over (0, π) that straddles r;
    each is found by brentq (on sin²θ2 (ρ² − r²), which stays finite at the ends), θ1 follows in
    closed form, then one Newton step on M~_ωm = 0 polishes the pair. The mirror images
    (θ1, θ2) -> (2ψ − θ1, −θ2) are the fixed points with θ2 ∈ (−π, 0). Generic parameters are
    assumed: no fixed point with θ2 ∈ {0, π} (true for the Fig. 3.1 model).
    """
    r = arm.attach_distance

    def g(s):
        u, _, _, _, numerator = _curve_terms(arm, s)
        return float(u**2 * np.sin(s) ** 2 + numerator**2 - r**2 * np.sin(s) ** 2)

    breaks = np.concatenate([[0.0], _critical_theta2(arm, samples, 1e-15), [np.pi]])
    roots = []
    for lo, hi in itertools.pairwise(breaks):
        g_lo, g_hi = g(lo), g(hi)
        if g_lo == 0.0 and lo > 0.0:
            roots.append(lo)
        elif g_lo * g_hi < 0.0:
            roots.append(optimize.brentq(g, lo, hi, xtol=xtol))
    points = []
    for s in sorted(set(roots)):
        _, theta1 = fixed_point_curve(arm, s)
        theta = _newton_polish(arm, np.array([float(theta1), s]))
        mirror = np.array([2.0 * arm.attach_angle - theta[0], -theta[1]])
        points += [classify(arm, theta), classify(arm, wrap(mirror))]
    return sorted(points, key=lambda p: tuple(p.theta))


def _newton_polish(arm: PlanarArm, theta: np.ndarray, steps: int = 2) -> np.ndarray:
    """A couple of Newton steps on M~_ωm(θ) = 0 (skipped where the Jacobian is singular)."""
    for _ in range(steps):
        jacobian = arm.coupling_inertia_jacobian(theta)
        if abs(np.linalg.det(jacobian)) < 1e-12 * np.sum(jacobian**2):
            break
        step = np.linalg.solve(jacobian, -arm.coupling_inertia(theta))
        candidate = theta + step
        if np.linalg.norm(arm.coupling_inertia(candidate)) > np.linalg.norm(
            arm.coupling_inertia(theta)
        ):
            break
        theta = candidate
    return theta


# --- integral curves --------------------------------------------------------------------------
def integral_curve(
    arm: PlanarArm, seed, length: float, step: float = 0.02, backward: bool = False
) -> np.ndarray:
    """Integrate dθ/ds = n(θ) (eq. 3.5 with b = ±1 rad per unit arc length) by RK4.

    Args:
        seed: start (θ1, θ2) [rad], shape (2,).
        length: arc length to integrate [rad]; stops early at a fixed point (n undefined).
        step: RK4 step in arc length [rad].
        backward: integrate dθ/ds = −n(θ).

    Returns:
        points (N, 2) [rad], unwrapped (continuous); wrap with :func:`wrap` to draw on the torus.
    """
    sign = -1.0 if backward else 1.0
    field = lambda x: sign * arm.reactionless_field(x)  # noqa: E731
    theta = np.asarray(seed, dtype=float).copy()
    points = [theta.copy()]
    for _ in range(math.ceil(length / step)):
        k1 = field(theta)
        k2 = field(theta + 0.5 * step * k1)
        k3 = field(theta + 0.5 * step * k2)
        k4 = field(theta + step * k3)
        update = theta + step / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        if not np.all(np.isfinite(update)):
            break
        theta = update
        points.append(theta.copy())
    return np.array(points)


def torus_segments(points: np.ndarray) -> list[np.ndarray]:
    """Split an unwrapped curve (N, 2) [rad] into pieces that stay inside [−π, π)² once
    wrapped (cut where a coordinate crosses ±π), for plotting on the torus."""
    wrapped = wrap(points)
    jumps = np.flatnonzero(np.any(np.abs(np.diff(wrapped, axis=0)) > np.pi, axis=1))
    return [piece for piece in np.split(wrapped, jumps + 1) if len(piece) > 1]
