r"""C_ratio maps of a spatial k-joint subchain (Fig. 5.3, eqs. 5.8-5.9), chunked over processes.

:class:`SerialChain` is the subchain read out of a Pinocchio model, the held joints folded into
rigid bodies, in the frame of the first moving joint; a chunk (one theta_2 value) computes the arm
terms once and then every theta_1 with one matrix product (:func:`_chain_terms`). Chunks run in
local processes or, with a scheduler address, on a dask.distributed cluster. docs/chapter5.md,
"How the maps are computed".
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from rns_ros.analysis.energy_maps import WHEEL_MASS, c_ratio_batch, periodic_grid
from rns_ros.core.energy import WHEEL_INERTIA
from rns_ros.core.errors import ConfigError
from rns_ros.core.model import FreeFloatingModel


def wheeled_model(
    robot: FreeFloatingModel, wheel_mass: float = 3 * WHEEL_MASS
) -> FreeFloatingModel:
    """``robot`` with ``wheel_mass`` [kg] added at the base CoM (A-3.1: three 10 kg wheels).

    The base's rotational inertia about its CoM is left as it is (it does not enter Lambda).
    """
    model = pin.Model(robot.model)
    base = model.inertias[1]
    model.inertias[1] = pin.Inertia(base.mass + wheel_mass, base.lever.copy(), base.inertia.copy())
    return FreeFloatingModel(model, robot.spec, name=f"{robot.name}+{wheel_mass:g}kg wheels")


def _rotations(axis: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Rodrigues: rotations by ``angles`` [rad] (N,) about the unit ``axis`` (3,), (N, 3, 3)."""
    skew = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    s, c = np.sin(angles)[:, None, None], np.cos(angles)[:, None, None]
    return np.eye(3) + s * skew + (1.0 - c) * (skew @ skew)


@dataclass(frozen=True)
class SerialChain:
    """A serial subchain of k moving joints on a free-floating base, read out of Pinocchio.

    Frame i is the frame of moving joint i at theta_i = 0 relative to frame i-1 (frame 0 is the
    base); the rotation of joint i is applied after its placement. Body i is everything rigidly
    attached to joint i's child: its link plus the links of held joints up to the next moving
    joint.

    Attributes (all in the joint's own frame):
        axes: joint axes, (k, 3) [-].
        rotations: placement rotations, (k, 3, 3); translations: (k, 3) [m].
        masses: (k,) [kg]; levers: body CoMs, (k, 3) [m]; inertias: about the CoM, (k, 3, 3)
            [kg m^2].
        base_mass: base incl. anything added at it (the wheels) [kg];
        base_com: base CoM in the base frame, (3,) [m].
    """

    axes: np.ndarray
    rotations: np.ndarray
    translations: np.ndarray
    masses: np.ndarray
    levers: np.ndarray
    inertias: np.ndarray
    base_mass: float
    base_com: np.ndarray

    @property
    def k(self) -> int:
        return len(self.masses)

    @property
    def total_mass(self) -> float:
        """m_C [kg]."""
        return self.base_mass + float(self.masses.sum())

    @classmethod
    def from_model(cls, robot: FreeFloatingModel, joints: Sequence[int], held=None) -> SerialChain:
        """The subchain of ``robot`` moving ``joints`` (theta indices), others held at ``held``.

        Args:
            robot: a model whose arm is one serial chain (Pinocchio joint j's parent is j - 1).
            joints: increasing theta indices; the first arm joint must be among them.
            held: theta [rad] (n,) giving the angles of the held joints; None: zeros.

        Raises:
            ConfigError: the arm branches, or joint 0 is held.
        """
        model = robot.model
        joints = [int(j) for j in joints]
        held = np.zeros(robot.n) if held is None else np.asarray(held, dtype=float)
        if any(model.parents[j] != j - 1 for j in range(2, model.njoints)):
            raise ConfigError(f"{robot.name}: the arm is not one serial chain")
        if not joints or joints[0] != 0 or sorted(set(joints)) != joints:
            raise ConfigError(f"moving joints must be increasing and start at 0, got {joints}")
        data = model.createData()
        pin.computeJointJacobians(model, data, pin.neutral(model))
        local_axes = [
            pin.getJointJacobian(model, data, j, pin.LOCAL)[3:, 6 + j - 2]
            for j in range(2, model.njoints)
        ]
        axes, rotations, translations, bodies = [], [], [], []
        pending = pin.SE3.Identity()  # transform from the last moving joint's frame so far
        for index in range(robot.n):
            placement = pending * model.jointPlacements[index + 2]
            if index in joints:
                axes.append(local_axes[index])
                rotations.append(placement.rotation.copy())
                translations.append(placement.translation.copy())
                bodies.append(model.inertias[index + 2])
                pending = pin.SE3.Identity()
            else:
                rotation = pin.exp3(local_axes[index] * held[index])
                pending = placement * pin.SE3(rotation, np.zeros(3))
                bodies[-1] = bodies[-1] + pending.act(model.inertias[index + 2])
        base = model.inertias[1]
        return cls(
            axes=np.array(axes),
            rotations=np.array(rotations),
            translations=np.array(translations),
            masses=np.array([b.mass for b in bodies]),
            levers=np.array([b.lever for b in bodies]),
            inertias=np.array([b.inertia for b in bodies]),
            base_mass=float(base.mass),
            base_com=np.array(base.lever),
        )


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.cross(a, b, axis=-1)


def _chain_terms(chain: SerialChain, angles: np.ndarray):
    """The theta_1-free terms of one chunk, in frame 1 (joint 1 at theta_1 = 0 + its rotation).

    Args:
        angles: theta_2..theta_k [rad], shape (P, k - 1).

    Returns:
        (tilde_m (P, k, k), h_cm (P, 3, k), basis (3, P, 3, k)) such that for a base CoM at q (3,)
        [m] in frame 1, M~_omega_m = h_cm - (m_b / m_C) [q^x] L = h_cm - (m_b / m_C) sum_c q_c
        basis[c] in frame 1 (its rotation to world axes changes neither the kernel nor
        M~_omega_m^T M~_omega_m). h_cm is the arm's angular momentum matrix about the arm's
        share of the system CoM, L the arm's linear momentum matrix (3, k) [kg m].
    """
    k, count = chain.k, angles.shape[0]
    orientation = np.broadcast_to(np.eye(3), (count, 3, 3))
    origin = np.zeros((count, 3))
    axes, origins, coms, inertias = [], [], [], []
    for i in range(k):
        if i > 0:
            origin = origin + orientation @ chain.translations[i]
            orientation = (
                orientation @ chain.rotations[i] @ _rotations(chain.axes[i], angles[:, i - 1])
            )
        axes.append(orientation @ chain.axes[i])
        origins.append(origin)
        coms.append(origin + orientation @ chain.levers[i])
        inertias.append(orientation @ chain.inertias[i] @ np.swapaxes(orientation, -1, -2))
    eye = np.eye(3)

    def spread(d):  # [d^x]^T [d^x] = |d|^2 E - d d^T
        return np.einsum("pi,pi->p", d, d)[:, None, None] * eye - d[:, :, None] * d[:, None, :]

    mass = 0.0
    moment = np.zeros((count, 3))
    inertia_origin = np.zeros((count, 3, 3))  # subtree inertia about the frame-1 origin
    linear = np.empty((count, 3, k))
    angular = np.empty((count, 3, k))
    for j in range(k - 1, -1, -1):
        m_j = chain.masses[j]
        mass += m_j
        moment = moment + m_j * coms[j]
        inertia_origin = inertia_origin + inertias[j] + m_j * spread(coms[j])
        centre = moment / mass
        about_joint = inertia_origin - mass * spread(centre) + mass * spread(centre - origins[j])
        linear[:, :, j] = _cross(axes[j], moment - mass * origins[j])
        angular[:, :, j] = np.einsum("pab,pb->pa", about_joint, axes[j]) + _cross(
            origins[j], linear[:, :, j]
        )
    # fixed-base joint-space inertia (CRBA): M[i, j] = a_i . (H_j - o_i x L_j), i <= j
    arm = np.empty((count, k, k))
    for i in range(k):
        for j in range(i, k):
            torque = angular[:, :, j] - _cross(origins[i], linear[:, :, j])
            arm[:, i, j] = arm[:, j, i] = np.einsum("pa,pa->p", axes[i], torque)
    total = chain.total_mass
    tilde_m = arm - np.einsum("pai,paj->pij", linear, linear) / total
    arm_centre = moment / total  # the arm's part of the system CoM, sum m_i c_i / m_C
    h_cm = angular - _cross(arm_centre[:, None, :], np.swapaxes(linear, 1, 2)).swapaxes(1, 2)
    basis = np.stack(
        [_cross(e[None, None, :], np.swapaxes(linear, 1, 2)).swapaxes(1, 2) for e in eye]
    )
    return tilde_m, h_cm, basis


def _base_com_in_frame_1(chain: SerialChain, theta1: np.ndarray) -> np.ndarray:
    """Base CoM seen from joint 1's frame at each theta_1 [m], shape (T, 3)."""
    at_zero = chain.rotations[0].T @ (chain.base_com - chain.translations[0])
    return np.einsum("tab,b->ta", np.swapaxes(_rotations(chain.axes[0], theta1), 1, 2), at_zero)


def chain_c_ratio_chunk(
    chain: SerialChain,
    theta1: np.ndarray,
    theta2: float,
    rest: Sequence[np.ndarray],
    wheel_inertia: float = WHEEL_INERTIA,
) -> np.ndarray:
    """C_ratio (5.5) of the subchain on the grid theta1 x {theta2} x rest[0] x rest[1] x ...

    One chunk of :func:`chain_c_ratio_map` (a plain function of arrays: it pickles for local
    processes and dask workers).

    Returns:
        shape (len(theta1), len(rest[0]), ...) [-].
    """
    theta1 = np.atleast_1d(np.asarray(theta1, dtype=float))
    mesh = np.meshgrid(*[np.asarray(r, dtype=float) for r in rest], indexing="ij")
    shape = mesh[0].shape if mesh else ()
    angles = np.stack(
        [np.full(mesh[0].size if mesh else 1, float(theta2))] + [m.ravel() for m in mesh], -1
    )
    tilde_m, h_cm, basis = _chain_terms(chain, angles)
    q = _base_com_in_frame_1(chain, theta1)
    factor = chain.base_mass / chain.total_mass
    count, k = tilde_m.shape[0], chain.k
    shift = (q @ basis.reshape(3, -1)).reshape(len(theta1), count, 3, k)
    coupling = h_cm[None] - factor * shift
    ratio = c_ratio_batch(
        np.broadcast_to(tilde_m, (*coupling.shape[:2], k, k)), coupling, wheel_inertia
    )
    return ratio.reshape((len(theta1), *shape))


def _progress_line(done: int, total: int, start: float, width: int = 30) -> None:
    filled = round(width * done / total)
    line = f"C_ratio map [{'#' * filled}{'.' * (width - filled)}] {done}/{total} chunks "
    line += f"({time.perf_counter() - start:.1f} s)"
    end = "\n" if done == total or not sys.stderr.isatty() else ""
    print(("\r" if sys.stderr.isatty() else "") + line, end=end, file=sys.stderr, flush=True)


def _run_chunks(
    chunk: Callable,
    arguments: list[tuple],
    workers: int | None,
    dask_scheduler: str | None,
    progress: bool,
) -> list[np.ndarray]:
    """``chunk(*a)`` for every a of ``arguments``, in order, with a progress line on stderr."""
    start, total = time.perf_counter(), len(arguments)
    results: list = [None] * total
    done = 0

    def finished(index, value):
        nonlocal done
        results[index] = value
        done += 1
        if progress:
            _progress_line(done, total, start)

    if dask_scheduler is not None:
        client = _dask_client(dask_scheduler)
        try:
            futures = [client.submit(chunk, *a, pure=False) for a in arguments]
            for i, future in enumerate(futures):  # in order: the bar lags a little at worst
                finished(i, future.result())
        finally:
            client.close()
        return results
    workers = (os.cpu_count() or 1) if workers is None else int(workers)
    if workers <= 1 or total <= 1:
        for i, a in enumerate(arguments):
            finished(i, chunk(*a))
        return results
    with ProcessPoolExecutor(max_workers=min(workers, total)) as pool:
        futures = {pool.submit(chunk, *a): i for i, a in enumerate(arguments)}
        from concurrent.futures import as_completed

        for future in as_completed(futures):
            finished(futures[future], future.result())
    return results


def _dask_client(address: str, timeout: float = 10.0):
    """A distributed.Client connected to ``address`` within ``timeout`` [s]; ConfigError (one
    line) if it cannot."""
    try:
        from distributed import Client
        from distributed.comm import resolve_address
    except ImportError:  # pragma: no cover - pinned in requirements.txt
        raise ConfigError(
            "--dask-scheduler needs the 'distributed' package (requirements.txt)"
        ) from None
    try:
        # a malformed address is caught here: a Client failing in __init__ on one prints a
        # traceback from its finalizer at exit
        address = resolve_address(address)
        return Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"cannot connect to the dask scheduler {address!r}: {reason}") from None


def check_dask_scheduler(address: str, timeout: float = 10.0) -> None:
    """Connect to the dask.distributed scheduler at ``address`` once and disconnect.

    Raises:
        ConfigError: one line, when it cannot be reached within ``timeout`` [s] or the address is
            malformed.
    """
    _dask_client(address, timeout).close()


def chain_c_ratio_map(
    chain: SerialChain,
    grids: Sequence[np.ndarray],
    *,
    wheel_inertia: float = WHEEL_INERTIA,
    workers: int | None = None,
    dask_scheduler: str | None = None,
    progress: bool = False,
) -> np.ndarray:
    """C_ratio (5.5) of the subchain on the tensor grid ``grids[0] x grids[1] x ...`` (Fig. 5.3).

    Args:
        chain: the subchain (k joints), e.g. ``SerialChain.from_model(wheeled_model(robot),
            robot.subchains.positioning)``.
        grids: k 1-D arrays of joint angles [rad].
        wheel_inertia: I_r [kg m^2].
        workers: local processes (None: one per core; 1: in this process). Ignored with dask.
        dask_scheduler: address of a running dask.distributed scheduler ("tcp://host:8786"), or
            None for the local cores.
        progress: a progress-bar line on stderr, one update per chunk (one theta_2 value).

    Returns:
        shape (len(grids[0]), ..., len(grids[k-1])) [-].

    Raises:
        ConfigError: wrong number of grids, or the scheduler cannot be reached.
    """
    if len(grids) != chain.k:
        raise ConfigError(f"need {chain.k} grids (one per moving joint), got {len(grids)}")
    grids = [np.atleast_1d(np.asarray(g, dtype=float)) for g in grids]
    if chain.k == 1:
        raise ConfigError("a one-joint subchain has no 1-D reactionless kernel here")
    arguments = [(chain, grids[0], float(t2), grids[2:], wheel_inertia) for t2 in grids[1]]
    chunks = _run_chunks(chain_c_ratio_chunk, arguments, workers, dask_scheduler, progress)
    return np.stack(chunks, axis=1)


def positioning_chain(robot: FreeFloatingModel | None = None) -> SerialChain:
    """Joints 1-4 of the 7-DoF default arm with 30 kg of wheels at the base CoM and the wrist
    (joints 5-7) held at 0 as a rigid payload (choice A-3.4)."""
    if robot is None:
        from rns_ros.core import load_model
        from rns_ros.resources import default_model_config

        robot = load_model(default_model_config())
    return SerialChain.from_model(wheeled_model(robot), robot.subchains.positioning)


def positioning_grids(count: int = 50) -> list[np.ndarray]:
    """The Fig. 5.3 grid: theta_1, theta_3, theta_4 = -pi + 2 pi k / count, theta_2 = -pi/2 +
    pi k / count, k = 0..count-1 [rad] (count = 50: 6.25e6 points)."""
    full = periodic_grid(count)
    return [full, periodic_grid(count, -0.5 * math.pi, math.pi), full, full]
