"""Named joint commands: reordering and every rejection names the problem."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rns_ros.core import InputError
from rns_ros.core.commands import (
    MAX_LISTED,
    MAX_REPORTED_SETS,
    ExtraJointsReport,
    listed,
    match_joint_state,
    match_named_command,
    partial_joint_goal,
)
from rns_ros.core.validation import apart

JOINTS = ("a", "b", "c")
LIMITS = np.array([1.0, 1.0, 2.0])


def test_reorders_into_model_order():
    command = match_named_command(
        ["c", "a", "b"], JOINTS, positions=[3.0, 1.0, 2.0], velocities=[0.3, 0.1, 0.2]
    )
    assert command.positions.tolist() == [1.0, 2.0, 3.0]
    assert command.velocities.tolist() == [0.1, 0.2, 0.3]
    assert command.accelerations is None


@pytest.mark.parametrize(
    ("names", "kwargs", "message"),
    [
        (
            ["a", "b", "x"],
            {"velocities": [0, 0, 0]},
            r"unknown joints \['x'\].*missing joints \['c'\]",
        ),
        (["a", "b"], {"velocities": [0, 0]}, r"missing joints \['c'\]"),
        (["a", "a", "b"], {"velocities": [0, 0, 0]}, r"duplicated joints \['a'\]"),
        (["a"] * 15000, {"velocities": [0] * 15000}, r"names 15000 joints; the model has 3"),
        (["a", "b", "c"], {"velocities": [0, 0]}, "velocities has 2 values for 3 joints"),
        (["a", "b", "c"], {"positions": [0, np.nan, 0]}, "positions must be finite"),
        (["a", "b", "c"], {"velocities": [0, np.inf, 0]}, "velocities must be finite"),
        (["a", "b", "c"], {}, "neither positions nor velocities"),
        (["a", "b", "c"], {"velocities": [0, 1.5, 0]}, "1.5 rad/s on b exceeds its limit 1"),
    ],
)
def test_rejections_name_the_problem(names, kwargs, message):
    with pytest.raises(InputError, match=message):
        match_named_command(names, JOINTS, velocity_limits=LIMITS, **kwargs)


def test_speed_at_the_limit_is_accepted():
    command = match_named_command(
        ["a", "b", "c"], JOINTS, velocities=[1.0, -1.005, 2.0], velocity_limits=LIMITS
    )
    assert command.velocities[1] == -1.005


GOAL_MODEL = ["a", "b", "c"]
GOAL_LIMITS = (np.full(3, -1.0), np.full(3, 1.0))


def test_a_partial_goal_keeps_the_unnamed_joints_where_they_are():
    goal = partial_joint_goal(
        ["c", "a"], [0.5, -0.25], GOAL_MODEL, np.array([0.1, 0.2, 0.3]), *GOAL_LIMITS
    )
    np.testing.assert_array_equal(goal, [-0.25, 0.2, 0.5])


@pytest.mark.parametrize(
    ("names", "positions", "message"),
    [
        ([], [], "goal names no joint"),
        (["a"] * 15000, [0.0] * 15000, "names 15000 joints; the model has 3"),
        (["a", "a"], [0.0, 0.1], r"duplicated joints \['a'\]"),
        (["a", "x"], [0.0, 0.1], r"unknown joints \['x'\]"),
        (["a"], [float("nan")], "goal position of a must be finite"),
        (["b"], [2.0], r"goal b = 2 rad is outside its limits \[-1, 1\] rad"),
    ],
)
def test_a_bad_partial_goal_is_rejected_with_its_reason(names, positions, message):
    """A goal with more names than the model has joints is rejected before any per-name check
    (a 15000-name goal must not cost seconds)."""
    with pytest.raises(InputError, match=message):
        partial_joint_goal(names, positions, GOAL_MODEL, np.zeros(3), *GOAL_LIMITS)


def test_long_name_lists_are_cut_in_messages():
    assert listed(["a", "b"]) == "['a', 'b']"
    assert listed([str(k) for k in range(25)]).endswith("'9'] and 15 more")


def test_absent_bounds_accept_any_finite_command():
    """+-inf limits (a continuous joint, or no velocity limit in the URDF) never reject."""
    from rns_ros.core.commands import check_reference_positions, check_velocity_limits

    limits = np.array([np.inf, 1.0, np.inf])
    check_velocity_limits(np.array([1e6, 1.0, -1e6]), limits, JOINTS)
    with pytest.raises(InputError, match=r"1\.5 rad/s on b exceeds its limit 1"):
        check_velocity_limits(np.array([1e6, 1.5, 0.0]), limits, JOINTS)
    lower, upper = np.array([-np.inf, -1.0, -np.inf]), np.array([np.inf, 1.0, np.inf])
    current = np.array([100.0, 0.0, -100.0])
    check_reference_positions(np.array([100.1, 0.1, -100.1]), current, lower, upper, 0.2, JOINTS)
    with pytest.raises(InputError, match=r"position 1.5 rad on b is outside its limits \[-1, 1\]"):
        check_reference_positions(np.array([100.1, 1.5, -100.1]), current, lower, upper, 1, JOINTS)
    goal = partial_joint_goal(["c"], [-1e3], GOAL_MODEL, current, lower, upper)
    assert goal.tolist() == [100.0, 0.0, -1e3]


ARM = tuple(f"joint_{i}" for i in range(1, 8))
FINGERS = ("finger_joint_1", "finger_joint_2")


def test_a_joint_state_with_extra_joints_is_used_by_name():
    """joint_state_broadcaster of an arm with a gripper: the fingers beside the arm's joints,
    in its own order; the extras are returned (their values are not checked: a finger without
    a velocity interface reports NaN)."""
    names = ["finger_joint_1", "c", "a", "finger_joint_2", "b"]
    state, extras = match_joint_state(
        names,
        JOINTS,
        positions=[0.04, 3.0, 1.0, 0.04, 2.0],
        velocities=[np.nan, 0.3, 0.1, np.nan, 0.2],
    )
    assert state.positions.tolist() == [1.0, 2.0, 3.0]
    assert state.velocities.tolist() == [0.1, 0.2, 0.3]
    assert state.accelerations is None
    assert extras == FINGERS
    state, extras = match_joint_state(["b", "c", "a"], JOINTS, positions=[2.0, 3.0, 1.0])
    assert state.positions.tolist() == [1.0, 2.0, 3.0]
    assert state.velocities is None
    assert extras == ()


@pytest.mark.parametrize(
    ("names", "kwargs", "message"),
    [
        (["a", "b", "x"], {"positions": [0, 0, 0]}, r"missing joints \['c'\]"),
        (["a", "a", "b", "c"], {"positions": [0] * 4}, r"duplicated joints \['a'\]"),
        (["a", "b", "c", "x"], {"positions": [0, 0, 0]}, "positions has 3 values for 4 joints"),
        (["a", "b", "c", "x"], {"velocities": [0] * 5}, "velocities has 5 values for 4 joints"),
        (["x", "a", "b", "c"], {"positions": [0, 0, np.nan, 0]}, "positions must be finite"),
        (["a", "b", "c", "x"], {"velocities": [0, np.inf, 0, 0]}, "velocities must be finite"),
        (["a", "b", "c", "x"], {}, "neither positions nor velocities"),
    ],
)
def test_a_bad_joint_state_is_rejected_with_its_reason(names, kwargs, message):
    with pytest.raises(InputError, match=message):
        match_joint_state(names, JOINTS, **kwargs)


@given(
    st.permutations(ARM + FINGERS + ("gripper_base",)),
    st.lists(st.floats(-3.0, 3.0), min_size=10, max_size=10),
)
def test_any_order_with_extras_gives_the_model_order(names, values):
    """A random permutation of the arm's joints and extra ones: each model joint gets its own
    value, the extras come back in message order."""
    value = dict(zip(names, values, strict=True))
    state, extras = match_joint_state(names, ARM, positions=values, velocities=[-v for v in values])
    assert state.positions.tolist() == [value[joint] for joint in ARM]
    assert state.velocities.tolist() == [-value[joint] for joint in ARM]
    assert extras == tuple(name for name in names if name not in ARM)


def test_extra_joints_are_reported_once_per_distinct_set():
    report = ExtraJointsReport()
    assert report.note(()) is None
    line = "joint_states: ignoring joints not in the model: finger_joint_1, finger_joint_2"
    assert report.note(FINGERS) == line
    assert report.note(FINGERS) is None
    assert report.note(FINGERS[:1], "/arm/joint_states") == (
        "/arm/joint_states: ignoring joints not in the model: finger_joint_1"
    )
    many = tuple(f"x{k}" for k in range(MAX_LISTED + 5))
    assert report.note(many).endswith(f"x{MAX_LISTED - 1} and 5 more")
    for k in range(MAX_REPORTED_SETS):
        report.note((f"y{k}",))
    assert report.note(("z",)) is None  # at most MAX_REPORTED_SETS sets


def test_a_command_bounded_to_the_edge_of_max_reference_error_is_accepted():
    """A sender that clips its command to max_reference_error from the angle it measured lands
    on the edge; the plant, whose angle has rounded the other way, takes it; a millirad past
    the edge is refused, naming the allowed range."""
    from rns_ros.core.commands import REFERENCE_SLACK, check_reference_positions

    lower, upper = np.full(3, -3.0), np.full(3, 3.0)
    current = np.array([0.9441, -2.835, 0.0])
    edge = current + np.array([0.25, 0.25, 0.0]) + 0.5 * REFERENCE_SLACK
    check_reference_positions(edge, current, lower, upper, 0.25, JOINTS)
    with pytest.raises(InputError, match=r"on a is 0.251 rad from its current angle 0.9441 rad"):
        check_reference_positions(
            edge + np.array([1e-3, 0.0, 0.0]), current, lower, upper, 0.25, JOINTS
        )


def test_a_position_just_past_a_limit_never_reads_as_the_limit():
    from rns_ros.core.commands import check_reference_positions

    lower, upper = np.full(2, -2.23), np.full(2, 2.23)
    positions = np.array([0.0, 2.23 + 4e-7])
    with pytest.raises(InputError) as caught:
        check_reference_positions(positions, positions, lower, upper, 0.25, ("a", "b"))
    assert "position 2.2300004 rad on b is outside its limits [-2.23, 2.23] rad" in str(
        caught.value
    )


@pytest.mark.parametrize(
    ("values", "texts"),
    [
        ((2.899, -2.9, 2.9), ["2.899", "-2.9", "2.9"]),
        ((1.0, 1.0), ["1", "1"]),
        ((3.0000000000000004, 3.0), ["3.0000000000000004", "3"]),
        ((0.123456789, 0.12345679), ["0.123456789", "0.12345679"]),
    ],
)
def test_apart_prints_distinct_values_distinctly_and_equal_ones_alike(values, texts):
    assert apart(*values) == texts
