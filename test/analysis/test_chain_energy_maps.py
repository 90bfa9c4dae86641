"""C_ratio maps of the spatial subchain (Fig. 5.3) against the Pinocchio reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rns_ros.analysis import chain_energy_maps as cem
from rns_ros.analysis import energy_maps as em

EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def heavy(robot):
    return cem.wheeled_model(robot)


@pytest.fixture(scope="module")
def chain(robot):
    return cem.positioning_chain(robot)


def test_wheeled_model_adds_30_kg_at_the_base_com_only(robot, heavy):
    assert heavy.total_mass == pytest.approx(robot.total_mass + 30.0)
    base, heavier = robot.model.inertias[1], heavy.model.inertias[1]
    assert np.allclose(heavier.lever, base.lever)
    assert np.allclose(heavier.inertia, base.inertia)
    assert robot.total_mass == 2760.0  # the original model is untouched


def test_4dof_kernel_matches_pinocchio_at_1000_random_configurations(
    heavy, chain, reference_c_ratio
):
    """Against core.energy.c_ratio on the Pinocchio state of the 30-kg-heavier model.

    c_ratio takes sigma_min from LAPACK on the assembled Lambda, accurate to ~eps cond(Lambda)
    (cond up to ~2e7 here, i.e. ~1e-9); our value is compared to it within 1e-9 or that bound,
    and to an independent accurate evaluation of the same Pinocchio matrices within 1e-9."""
    rng = np.random.default_rng(20261201)
    joints = heavy.subchains.positioning
    worst_reference, worst_accurate = 0.0, 0.0
    for _ in range(1000):
        theta = np.zeros(7)
        theta[:4] = rng.uniform(-math.pi, math.pi, 4)
        theta[1] *= 0.5  # the map's theta_2 range
        reference, condition, accurate = reference_c_ratio(heavy, theta, joints)
        ours = cem.chain_c_ratio_chunk(chain, [theta[0]], theta[1], [[theta[2]], [theta[3]]])
        ours = float(ours.item())
        error = abs(ours / reference - 1.0)
        assert error <= max(1e-9, 4.0 * EPS * condition), (theta, ours, reference, condition)
        worst_reference = max(worst_reference, error)
        worst_accurate = max(worst_accurate, abs(ours / accurate - 1.0))
        assert ours >= 1.0 - 1e-9
    assert worst_accurate < 1e-9
    assert worst_reference < 1e-8


def test_wrist_held_at_other_angles_is_a_different_rigid_payload(robot, reference_c_ratio):
    """The held joints are folded in at their given angles (checked at theta_5..7 != 0)."""
    model = cem.wheeled_model(robot)
    held = np.array([0.0, 0.0, 0.0, 0.0, 0.7, -1.1, 0.4])
    chain = cem.SerialChain.from_model(model, robot.subchains.positioning, held)
    rng = np.random.default_rng(3)
    for _ in range(20):
        theta = held.copy()
        theta[:4] = rng.uniform(-math.pi, math.pi, 4)
        _, _, accurate = reference_c_ratio(model, theta, robot.subchains.positioning)
        ours = cem.chain_c_ratio_chunk(chain, [theta[0]], theta[1], [[theta[2]], [theta[3]]])
        assert ours.item() == pytest.approx(accurate, rel=1e-9)


def test_grid_map_equals_pointwise_chunks_and_is_at_least_one(chain):
    grids = cem.positioning_grids(6)
    grid_map = cem.chain_c_ratio_map(chain, grids, workers=1)
    assert grid_map.shape == (6, 6, 6, 6)
    assert np.all(np.isfinite(grid_map))
    assert grid_map.min() >= 1.0 - 1e-9
    i, j, k, m = 1, 4, 2, 5
    point = cem.chain_c_ratio_chunk(
        chain, [grids[0][i]], grids[1][j], [[grids[2][k]], [grids[3][m]]]
    )
    assert grid_map[i, j, k, m] == pytest.approx(point.item(), rel=1e-12)


def test_local_processes_give_the_same_numbers(chain):
    grids = [em.periodic_grid(4), em.periodic_grid(3, -0.5 * math.pi, math.pi)] + [
        em.periodic_grid(5)
    ] * 2
    inline = cem.chain_c_ratio_map(chain, grids, workers=1)
    pooled = cem.chain_c_ratio_map(chain, grids, workers=2)
    assert np.array_equal(inline, pooled)


def test_dask_local_cluster_gives_the_same_numbers(chain):
    distributed = pytest.importorskip("distributed")
    grids = [em.periodic_grid(3), em.periodic_grid(2, -0.5 * math.pi, math.pi)] + [
        em.periodic_grid(4)
    ] * 2
    local = cem.chain_c_ratio_map(chain, grids, workers=1)
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        remote = cem.chain_c_ratio_map(chain, grids, dask_scheduler=cluster.scheduler_address)
    assert np.array_equal(local, remote)


def test_unreachable_dask_scheduler_is_a_config_error(chain):
    pytest.importorskip("distributed")
    from rns_ros.core.errors import ConfigError

    with pytest.raises(ConfigError, match="dask scheduler"):
        cem._dask_client("tcp://127.0.0.1:1", timeout=1.0)
