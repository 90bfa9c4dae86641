"""The /tf link tree: composing the parent-to-child transforms from the base reaches every link
at the pose Pinocchio's forward kinematics gives it, for the default arm and three public-style
arms (held fingers, continuous joints, a replaced `world` root; `<ros2_control>`, `<gazebo>` and
`<transmission>` elements, whose `<joint>` entries are not kinematic)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from rns_ros.core import load_model
from rns_ros.core.link_tree import edge_transforms, link_edges
from rns_ros.resources import default_model_config

ARMS = Path(__file__).parents[1] / "data" / "arms"
MODELS = [default_model_config(), *sorted(ARMS.glob("*/model.yaml"))]


@pytest.mark.parametrize("path", MODELS, ids=lambda p: Path(p).parent.name)
def test_the_tree_reaches_every_link_where_forward_kinematics_puts_it(path):
    robot = load_model(path)
    rng = np.random.default_rng(5)
    theta = rng.uniform(-1.0, 1.0, robot.n)
    quaternion = rng.normal(size=4)
    q = robot.configuration(theta, rng.normal(size=3), quaternion)
    edges = link_edges(robot)
    rows = edge_transforms(robot, edges, q)
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    base = robot.model.getFrameId(robot.base_link)
    placed = {robot.base_link: data.oMf[base]}
    pending = list(zip(edges, rows, strict=True))
    while pending:  # compose parent to child down the tree, in any order the edges come
        rest = []
        for edge, row in pending:
            if edge.parent in placed:
                placed[edge.child] = placed[edge.parent] * pin.XYZQUATToSE3(row)
            else:
                rest.append((edge, row))
        assert len(rest) < len(pending), f"edges not connected to the base: {rest}"
        pending = rest
    bodies = {f.name for f in robot.model.frames if f.type == pin.FrameType.BODY}
    assert set(placed) == bodies
    for name, pose in placed.items():
        expected = data.oMf[robot.model.getFrameId(name, pin.FrameType.BODY)]
        np.testing.assert_allclose(pose.homogeneous, expected.homogeneous, atol=1e-12)


@pytest.mark.parametrize("path", MODELS, ids=lambda p: Path(p).parent.name)
def test_static_edges_do_not_move_and_moving_ones_follow_their_joint(path):
    robot = load_model(path)
    edges = link_edges(robot)
    rng = np.random.default_rng(9)
    one = edge_transforms(robot, edges, robot.configuration(rng.uniform(-1, 1, robot.n)))
    two = edge_transforms(robot, edges, robot.configuration(rng.uniform(-1, 1, robot.n)))
    static = np.array([edge.static for edge in edges])
    np.testing.assert_allclose(one[static], two[static], atol=1e-14)
    assert not np.allclose(one[~static], two[~static])
    assert sum(not edge.static for edge in edges) == robot.n  # one moving edge per joint
