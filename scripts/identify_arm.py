#!/usr/bin/env python3
"""Search the 7-DoF geometry the thesis used: discrete axes x continuous lengths.

Discrete space (symmetry-reduced, see docs/arm_identification.md): the straight arm at theta = 0
points along u (+z, -x, +x, -y, +y of the base); joints 3, 5, 7 roll about +u (every thesis
configuration has theta_3, theta_5 in {0, 180} deg and theta_7 = 0 at the start, so their signs
only mirror the motion); joint 1 rolls about +-u or yaws about +-z; joints 2, 4, 6 pitch about
+-e1 or +-e2 (the two axes normal to u). Continuous: the seven link lengths (0.6-1.3 x the
uniform-prism length of Table 4.1) and lateral shoulder / elbow / wrist offsets (+-0.3 m).

Stages: (1) least squares on the EE position (numpy FK) for every discrete candidate, 3 seeded
starts; (2) cheap path scores (folds, deployment) for those within 0.15 m; (3) Nelder-Mead on the
sum of cheap shortfalls for the best ``--refine``; (4) closed-loop scores (coarse, then full) for
the best ``--finalists``. Two worker processes.

    .venv/bin/python scripts/identify_arm.py            # default search
    .venv/bin/python scripts/identify_arm.py --quick    # smoke test (~1 min)
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
import time
from multiprocessing import Pool
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares, minimize

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rns_ros.analysis import arm_geometry as ag
from rns_ros.analysis import arm_identification as ai
from rns_ros.core.errors import RnsError

SEED = 13
LOG_BOUNDS = (math.log(0.6), math.log(1.3))
OFFSET_BOUND = 0.3
ELBOW_MIN = 0.15  # [m] two link radii: the folded forearm lies beside the upper arm
CHEAP_STEP = 0.005  # [rad] arc step of the path scores during the search (finalists: 0.003)


def discrete_space(directions: list[str]) -> list[tuple[str, tuple[str, ...]]]:
    """(u, axes) candidates of the symmetry-reduced space."""
    out = []
    for u in directions:
        uv = ag.axis_vector(u)
        e1, e2 = ag.perpendicular_basis(u)
        pitches = [ag.axis_label(s * e) for e in (e1, e2) for s in (1, -1)]
        roll = ag.axis_label(uv)
        firsts = [roll, ag.axis_label(-uv)]
        if abs(uv[2]) < 0.5:
            firsts += ["+z", "-z"]
        for j1, j2, j4, j6 in itertools.product(firsts, pitches, pitches, pitches):
            out.append((u, (j1, j2, roll, j4, roll, j6, roll)))
    return out


def geometry_from(u: str, axes: tuple[str, ...], x: np.ndarray) -> ag.Geometry:
    """Continuous vector x (13,): log length scales (7), shoulder, elbow, wrist offsets (2 each)."""
    lengths = ag.uniform_lengths() * np.exp(x[:7])
    return ag.Geometry(
        direction=u,
        axes=axes,
        lengths=tuple(float(v) for v in lengths),
        shoulder=(float(x[7]), float(x[8])),
        elbow=(float(x[9]), float(x[10])),
        wrist=(float(x[11]), float(x[12])),
    )


def _bounds():
    lower = [LOG_BOUNDS[0]] * 7 + [-OFFSET_BOUND] * 6
    upper = [LOG_BOUNDS[1]] * 7 + [OFFSET_BOUND] * 6
    return np.array(lower), np.array(upper)


def _ee_residual(x, u, axes, final):
    geometry = geometry_from(u, axes, x)
    error = ag.camera_position(geometry, final) - ai.THESIS_EE_POSITION
    elbow = math.hypot(x[9], x[10])
    return np.concatenate((error, 0.05 * x[:7], 0.05 * x[7:], [max(0.0, ELBOW_MIN - elbow)]))


def fit_ee(u: str, axes: tuple[str, ...], starts: int, seed: int) -> tuple[np.ndarray, float]:
    """Stage 1: least squares on the EE error with a small pull to uniform lengths, no offsets
    beyond an elbow offset of >= 0.15 m. Returns (x, EE error [m])."""
    rng = np.random.default_rng(seed)
    lower, upper = _bounds()
    final = np.deg2rad(ai.THREE_PHASE_FINAL_DEG)
    best, best_error = None, math.inf
    for k in range(starts):
        x0 = np.zeros(13)
        x0[10] = ELBOW_MIN
        if k:
            x0 = np.clip(rng.uniform(lower, upper), lower, upper)
        fit = least_squares(_ee_residual, x0, bounds=(lower, upper), args=(u, axes, final))
        error = float(np.linalg.norm(fit.fun[:3]))
        if error < best_error - 1e-6:
            best, best_error = fit.x, error
    return best, best_error


def _cheap_total(x, u, axes, step):
    try:
        scores = ai.score_all(geometry_from(u, axes, x), closed_loop=False, step=step)
    except RnsError:
        return 1e3
    lower, upper = _bounds()
    outside = float(np.sum(np.maximum(0, lower - x) + np.maximum(0, x - upper)))
    elbow = max(0.0, ELBOW_MIN - math.hypot(x[9], x[10]))
    return ai.total_shortfall(scores) + 10.0 * (outside + elbow)


def stage_one_two(job):
    """Worker: fit the EE, then the cheap scores if the fit is within tolerance."""
    index, u, axes, starts = job
    x, error = fit_ee(u, axes, starts, SEED + index)
    total = _cheap_total(x, u, axes, CHEAP_STEP) if error <= ai.EE_TOLERANCE else math.inf
    return index, u, axes, x, error, total


def stage_three(job):
    """Worker: Nelder-Mead on the cheap shortfall sum from the stage-1 point."""
    index, u, axes, x, maxfev = job
    result = minimize(
        _cheap_total,
        x,
        args=(u, axes, CHEAP_STEP),
        method="Nelder-Mead",
        options={"maxfev": maxfev, "xatol": 1e-3, "fatol": 1e-4},
    )
    return index, u, axes, result.x, float(result.fun)


def stage_four(job):
    """Worker: every score, closed loop included (coarse or full)."""
    index, u, axes, x, full = job
    geometry = geometry_from(u, axes, x)
    scores = ai.score_all(geometry, coarse=not full, step=0.003 if full else CHEAP_STEP)
    return index, geometry, scores


def _row(rank, geometry, scores) -> str:
    cells = [f"{rank:>2}", f"{geometry.label():<28}", f"{ai.total_shortfall(scores):8.3f}"]
    for name in ai.PATH_CONSTRAINTS + ai.CLOSED_LOOP_CONSTRAINTS:
        if name in scores:
            score = scores[name]
            cells.append(f"{score.value:8.3f}{'*' if score.passed else ' '}")
    return " ".join(cells)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="smoke test: +z only, tiny budgets")
    parser.add_argument("--directions", default="+z,-x,+x,-y,+y")
    parser.add_argument("--starts", type=int, default=3, help="stage-1 starts per candidate")
    parser.add_argument("--refine", type=int, default=12, help="stage-3 candidates")
    parser.add_argument("--maxfev", type=int, default=120, help="stage-3 evaluations each")
    parser.add_argument("--finalists", type=int, default=6, help="stage-4 candidates")
    parser.add_argument("--full", type=int, default=3, help="finalists checked at full rate")
    parser.add_argument("--json", type=Path, help="write the finalists' scores here")
    parser.add_argument("--urdf", type=Path, help="write the best candidate's URDF here")
    args = parser.parse_args(argv)
    if args.quick:
        args.directions, args.starts, args.refine, args.maxfev = "+z", 1, 2, 10
        args.finalists, args.full = 2, 1
    t0 = time.time()
    space = discrete_space(args.directions.split(","))
    if args.quick:
        space = space[:16]
    print(f"{len(space)} discrete candidates", flush=True)
    with Pool(2) as pool:
        jobs = [(i, u, axes, args.starts) for i, (u, axes) in enumerate(space)]
        stage1 = sorted(pool.map(stage_one_two, jobs, chunksize=4), key=lambda r: r[5])
        fitted = sum(1 for r in stage1 if r[4] <= ai.EE_TOLERANCE)
        print(f"stage 1-2: {fitted} fit the EE within {ai.EE_TOLERANCE} m "
              f"({time.time() - t0:.0f} s)", flush=True)  # fmt: skip
        for r in stage1[:10]:
            print(f"   {r[1]} {' '.join(r[2])}  EE {r[4]:.3f} m  cheap shortfall {r[5]:.3f}")
        top = [r for r in stage1 if math.isfinite(r[5])][: args.refine]
        jobs = [(r[0], r[1], r[2], r[3], args.maxfev) for r in top]
        stage3 = sorted(pool.map(stage_three, jobs, chunksize=1), key=lambda r: r[4])
        print(f"stage 3: refined {len(stage3)} ({time.time() - t0:.0f} s)", flush=True)
        for r in stage3:
            print(f"   {r[1]} {' '.join(r[2])}  cheap shortfall {r[4]:.3f}")
        jobs = [(r[0], r[1], r[2], r[3], False) for r in stage3[: args.finalists]]
        stage4 = pool.map(stage_four, jobs, chunksize=1)
        stage4.sort(key=lambda r: ai.total_shortfall(r[2]))
        jobs = [(r[0], r[1].direction, r[1].axes, _x_of(r[1]), True) for r in stage4[: args.full]]
        full = pool.map(stage_four, jobs, chunksize=1)
    full.sort(key=lambda r: ai.total_shortfall(r[2]))
    current = ai.score_all(ag.INFERRED_GEOMETRY, coarse=False, step=0.003)
    header = " ".join(["rk", f"{'geometry':<28}", "  total "] + [f"{n[:9]:>9}" for n in
                      ai.PATH_CONSTRAINTS + ai.CLOSED_LOOP_CONSTRAINTS])  # fmt: skip
    print(f"\nranked finalists, full checks (* = passed) ({time.time() - t0:.0f} s)")
    print(header)
    print(_row(0, ag.INFERRED_GEOMETRY, current) + "   <- current default")
    for rank, (_, geometry, scores) in enumerate(full, 1):
        print(_row(rank, geometry, scores))
    print("\ncoarse closed-loop ranking")
    for rank, (_, geometry, scores) in enumerate(stage4, 1):
        print(_row(rank, geometry, scores))
    for rank, (_, geometry, scores) in enumerate(full[:3], 1):
        print(f"\n#{rank} {geometry!r}")
        for score in scores.values():
            verdict = "PASS" if score.passed else "fail"
            print(f"   {score.name:<22} {score.value:9.3f} {score.unit:<22} {verdict}  "
                  f"target {score.target}; {score.detail}")  # fmt: skip
    print("\ncurrent default:")
    for score in current.values():
        print(f"   {score.name:<22} {score.value:9.3f} {'PASS' if score.passed else 'fail'}; "
              f"{score.detail}")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(_dump(full + stage4), indent=1))
    if args.urdf and full:
        args.urdf.write_text(ag.geometry_urdf(full[0][1], name="rns_7dof_arm_identified"))
        print(f"wrote {args.urdf}")
    print(f"wall time {time.time() - t0:.0f} s")
    return 0


def _x_of(geometry: ag.Geometry) -> np.ndarray:
    scales = np.log(np.array(geometry.lengths) / ag.uniform_lengths())
    return np.concatenate((scales, geometry.shoulder, geometry.elbow, geometry.wrist))


def _dump(results):
    return [
        {
            "geometry": repr(geometry),
            "scores": {
                s.name: {"value": float(s.value), "passed": bool(s.passed), "detail": s.detail}
                for s in scores.values()
            },
        }
        for _, geometry, scores in results
    ]


if __name__ == "__main__":
    raise SystemExit(main())
