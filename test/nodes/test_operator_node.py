"""rns_operator plays a scenario file as TwistStamped commands (and, for a Part II
``kind: motion_force`` file, WrenchStamped force setpoints) over DDS."""

from __future__ import annotations

import re

import numpy as np
import pytest
import rclpy
import yaml
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from rns_ros.control.contact_scenarios import load_motion_force_scenario, operator_sample
from rns_ros.control.scenario import load_scenario
from rns_ros.core import ConfigError
from rns_ros.harness import ProcessStack
from rns_ros.nodes.operator import FINAL_ZEROS, OperatorNode, node_names
from rns_ros.nodes.sim_clock import stamp_from_seconds

SCENARIO = {
    "initial_joint_positions_deg": [0, 10, 0, 20, 0, 30, 0],
    "frame": "camera",
    "axis": [0, 1, 0],
    "angle_deg": 30.0,
    "duration": 1.0,
    "time_scaling": "piecewise",
    "segments": [[0.4, 0.5], [0.2, 0.0], [0.4, 0.5]],
}


def test_operator_publishes_the_profile_then_zeros(ros, tmp_path):
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(SCENARIO))
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode,
        {"scenario": str(path), "rate": 100.0, "start_delay": 0.0, "zero_duration": 0.3},
    )
    assert ros.spin_until(lambda: operator.finished, timeout=10.0)
    # then silence: the tick that finished published nothing and no tick after it does; the
    # last twists may still be on their way then, but they are stamped before now
    finished = operator.get_clock().now().nanoseconds
    ros.spin_for(0.2)  # twenty periods at 100 Hz
    assert {m.header.frame_id for m in twists.messages} == {"camera"}
    rates = twists.array(lambda m: [m.twist.angular.x, m.twist.angular.y, m.twist.angular.z])
    ns = np.array([m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in twists.messages])
    assert ns.max() < finished
    # each twist is the profile at its stamp, however late a busy machine made the ticks
    # (times in integer ns from the profile's start, as the node takes them)
    t = _profile_times(twists, operator)
    assert t[0] >= 0.0
    expected = [operator.scenario.angular_velocity(k) for k in t]
    np.testing.assert_allclose(rates, expected, rtol=0.0, atol=1e-12)
    assert np.all(rates[:, [0, 2]] == 0.0)
    # piecewise: 0.5 * 30 deg in 0.4 s, a pause, then the rest
    assert rates[:, 1].max() == pytest.approx(np.deg2rad(15.0) / 0.4, rel=1e-9)
    # the whole profile, then zeros for zero_duration at most
    after = t > SCENARIO["duration"]
    assert after.any()
    assert np.all(rates[after] == 0.0)
    assert t[-1] <= SCENARIO["duration"] + 0.3


def _play_on_clock(
    ros, operator, twists, period: float, ticks: int, finish: bool = True
) -> list[float]:
    """Publish /clock from 10 s on every ``period`` [s] (at most ``ticks`` instants) until the
    operator finished (``finish``: it must); returns, for each instant that brought a twist, how
    far the newest twist's stamp is ahead of it [s]."""
    clock = ros.probe().create_publisher(Clock, "/clock", 10)
    ros.spin_until(lambda: operator.count_publishers("/clock") > 0, timeout=5.0)
    ahead = []
    for k in range(ticks):
        t = 10.0 + period * k
        count = len(twists)
        clock.publish(Clock(clock=stamp_from_seconds(t)))
        if ros.spin_until(lambda count=count: len(twists) > count, timeout=2.0):
            ahead.append(twists.stamps()[-1] - t)
        if operator.finished:
            break
    assert operator.finished or not finish
    return ahead


@pytest.mark.parametrize(("start_delay", "profile_start"), [(0.0, 10.04), (0.1, 10.1)])
def test_with_lead_each_sample_goes_out_ahead_stamped_with_its_instant(
    ros, tmp_path, start_delay, profile_start
):
    """Under use_sim_time with ``lead`` (lockstep with an awaiting controller): at each /clock
    instant c the operator publishes the sample of c + lead, stamped c + lead. The stream
    starts at the start condition (/clock 10.0 here), with zeros until the profile starts
    max(start_delay, lead) later, then the profile at each stamp, which integrates to the
    scenario's angle."""
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(SCENARIO))
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode,
        {
            "scenario": str(path),
            "start_delay": start_delay,
            "zero_duration": 0.2,
            "lead": 0.04,
            "use_sim_time": True,
        },
    )
    ahead = _play_on_clock(ros, operator, twists, period=0.02, ticks=100)  # 2 s at 50 Hz
    assert ahead == pytest.approx([0.04] * len(ahead), abs=1e-9)  # each sample a lead early
    rates = twists.array(_angular)
    stamps = twists.stamps()
    assert stamps[0] == pytest.approx(10.04, abs=1e-9)  # from the start condition on
    first = int(np.argmax(np.abs(stamps - profile_start) < 1e-9))
    assert stamps[first] == pytest.approx(profile_start, abs=1e-9)
    assert np.all(rates[:first] == 0.0)  # zeros before the profile
    # then the profile from its start (piecewise: the first segment's rate), each sample the
    # profile at its stamp; the profile on the clock's grid integrates to the scenario's angle
    # (a sample lost in delivery leaves a gap in what arrived, not in what was sent)
    assert rates[first, 1] == pytest.approx(np.deg2rad(15.0) / 0.4, rel=1e-9)
    scenario = load_scenario(path)
    start_ns = round(profile_start * 1e9)
    for msg, rate in zip(twists.messages[first:], rates[first:], strict=True):
        t = (msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec - start_ns) * 1e-9
        np.testing.assert_allclose(rate, scenario.angular_velocity(t), atol=1e-12)
    grid = np.arange(round(scenario.duration / 0.02)) * 20_000_000 * 1e-9  # as the node: ns
    angle = np.sum([scenario.angular_velocity(t)[1] for t in grid]) * 0.02
    assert angle == pytest.approx(np.deg2rad(30.0), rel=1e-9)


def test_with_lead_zeros_go_out_before_the_start_condition_and_no_profile(ros, tmp_path):
    """lead: before its subscribers are there (min_subscribers), the operator already streams
    zeros ahead of the clock: an awaiting controller then holds every tick from its first
    sample on, so a profile that starts later can never find ticks served without it."""
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(SCENARIO))
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode,
        {"scenario": str(path), "lead": 0.04, "use_sim_time": True, "min_subscribers": 5},
    )
    ahead = _play_on_clock(ros, operator, twists, period=0.02, ticks=50, finish=False)
    assert len(ahead) >= 45  # a sample at (nearly) every instant
    assert ahead == pytest.approx([0.04] * len(ahead), abs=1e-9)
    assert np.all(twists.array(_angular) == 0.0)
    assert not operator.started


@pytest.mark.parametrize("lead", [0.04, 0.0])
def test_a_stall_before_the_first_motion_shifts_the_profile(ros, tmp_path, lead):
    """The operator's process waited for a core after its first sample (a rest) while time ran
    on (/clock 10.0 -> 11.0 here; the wall clock as the nodes start, no controller awaiting
    it): the profile goes on from its next sample, later, instead of from where the clock got
    to (a profile entered mid-way would cut its start off while the robot stood still). Once
    it moved, a jump is not shifted (an awaiting controller would have held the clock; on the
    wall clock the controller holds the newest rate). With ``lead`` each sample is stamped
    that much ahead."""
    path = tmp_path / "rest.yaml"
    path.write_text(yaml.safe_dump({**SCENARIO_FROM_REST}))
    scenario = load_scenario(path)
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode,
        {"scenario": str(path), "start_delay": 0.0, "lead": lead, "use_sim_time": True},
    )
    clock = ros.probe().create_publisher(Clock, "/clock", 10)
    ros.spin_until(lambda: operator.count_publishers("/clock") > 0, timeout=5.0)
    samples = {}
    for t in (10.0, 11.0, 11.02, 12.0):
        count = len(twists)
        clock.publish(Clock(clock=stamp_from_seconds(t)))
        assert ros.spin_until(lambda count=count: len(twists) > count, timeout=2.0), t
        msg = twists.messages[-1]
        samples[round(twists.stamps()[-1], 6)] = msg.twist.angular.y
    # stamp: profile time
    expected = {
        round(c + lead, 6): t for c, t in ((10.0, 0.0), (11.0, 0.02), (11.02, 0.04), (12.0, 1.02))
    }
    assert list(samples) == list(expected)
    for stamp, t in expected.items():
        assert samples[stamp] == pytest.approx(scenario.angular_velocity(t)[1], abs=1e-12)
    assert samples[round(11.0 + lead, 6)] > 0.0


#: The roll of SCENARIO with a quintic profile: it starts (and ends) at rest.
SCENARIO_FROM_REST = {
    key: value for key, value in SCENARIO.items() if key not in ("time_scaling", "segments")
}

#: A slow roll that is still playing when the tests below stop the operator.
LONG_SCENARIO = {**SCENARIO, "time_scaling": "constant", "duration": 30.0, "segments": None}


def _long_scenario(tmp_path):
    path = tmp_path / "long.yaml"
    path.write_text(yaml.safe_dump({k: v for k, v in LONG_SCENARIO.items() if v is not None}))
    return path


def _angular(msg: TwistStamped) -> tuple[float, float, float]:
    return (msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z)


def test_operator_destroyed_mid_scenario_sends_zero_twists(ros, tmp_path):
    """Without them the controller would hold the last rate for its command_timeout, then ramp."""
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode, {"scenario": str(_long_scenario(tmp_path)), "start_delay": 0.0}
    )
    assert ros.spin_until(lambda: len(twists) >= 5, timeout=10.0)
    assert any(_angular(twists.latest()))  # moving: 1 deg/s about camera y
    ros.detach(operator)
    count = len(twists)
    operator.destroy_node()
    ros.spin_for(0.3)
    after = twists.messages[count:]
    zeros = [m for m in after if not any(_angular(m))]
    assert after, "nothing after destroy_node"
    assert not any(_angular(after[-1])), [_angular(m) for m in after]
    assert 1 <= len(zeros) <= FINAL_ZEROS
    assert {m.header.frame_id for m in zeros} == {"camera"}


def test_operator_destroyed_before_its_profile_sends_nothing(ros, tmp_path):
    twists = ros.record(TwistStamped, "cmd_twist")
    operator = ros.add(
        OperatorNode, {"scenario": str(_long_scenario(tmp_path)), "start_delay": 60.0}
    )
    assert ros.spin_until(lambda: operator.started, timeout=10.0)
    ros.detach(operator)
    operator.destroy_node()
    ros.spin_for(0.3)
    assert len(twists) == 0


def test_ctrl_c_on_the_installed_operator_sends_a_zero_twist(ros, tmp_path):
    """.venv/bin/rns_operator (run_node: SIGINT only sets a flag, destroy_node runs while the
    Context is alive), interrupted mid-scenario like a terminal user would."""
    twists = ros.record(TwistStamped, "cmd_twist")
    with ProcessStack(ros.domain_id) as stack:
        process = stack.start(
            "rns_operator", {"scenario": str(_long_scenario(tmp_path)), "start_delay": 0.0}
        )
        assert ros.spin_until(lambda: len(twists) >= 5, timeout=30.0), stack.output(process)
        assert any(_angular(twists.latest()))
        count = len(twists)
        codes = stack.stop()  # SIGINT
        ros.spin_for(0.3)
        output = stack.output(process)
    assert codes == [0], output
    after = twists.messages[count:]
    assert after, f"nothing after Ctrl-C; output:\n{output}"
    assert not any(_angular(after[-1])), output


def test_operator_waits_for_a_subscriber(ros):
    operator = ros.add(OperatorNode, {"start_delay": 0.0})
    ros.spin_for(0.3)
    assert not operator.started
    ros.record(TwistStamped, "cmd_twist")
    assert ros.spin_until(lambda: operator.started, timeout=5.0)


def test_a_strangers_subscriber_does_not_start_the_profile_for_a_named_one(ros):
    """subscriber_nodes: a plot or an echo on cmd_twist (here the probe node) is counted by
    min_subscribers but is not the recorder the run waits for; the profile starts once the
    named node subscribes (rns_demo names its controller, logger and recorder)."""
    operator = ros.add(OperatorNode, {"start_delay": 0.0, "subscriber_nodes": "the_recorder"})
    ros.record(TwistStamped, "cmd_twist")  # the stranger: rns_harness_probe
    ros.spin_for(0.3)
    assert not operator.started
    assert operator.missing_subscriber_nodes() == ["the_recorder"]
    ros.add(rclpy.create_node("the_recorder", context=ros.context)).create_subscription(
        TwistStamped, "cmd_twist", lambda _msg: None, 1
    )
    assert ros.spin_until(lambda: operator.started, timeout=5.0)
    assert operator.missing_subscriber_nodes() == []


@pytest.mark.parametrize("bad", ["/ns/the_recorder", "2nd_recorder", "the recorder"])
def test_a_subscriber_node_no_node_can_be_named_is_refused_by_name(ros, bad):
    """subscriber_nodes takes node base names: one no node can have would wait forever."""
    with pytest.raises(ConfigError, match=f"subscriber_nodes: '{re.escape(bad)}' is no node name"):
        OperatorNode(
            context=ros.context,
            parameter_overrides=[Parameter("subscriber_nodes", value=f"rns_controller,{bad}")],
        )
    assert node_names(" rns_controller, ,the_recorder ") == {"rns_controller", "the_recorder"}


def test_unknown_scenario_is_a_clear_error(ros):
    with pytest.raises(ConfigError, match="neither a file nor one of"):
        OperatorNode(
            context=ros.context,
            parameter_overrides=[Parameter("scenario", value="nope")],
        )


# --- Part II: kind motion_force ----------------------------------------------------------------
#: Short custom Part II scenarios: one 1 s wall stroke, one 0.5 s arc half cycle.
SHORT_WALL = {"kind": "motion_force", "task": "wall", "stroke": 1.0, "strokes": 1,
              "force_ramp": 0.4}  # fmt: skip
SHORT_ARC = {"kind": "motion_force", "task": "arc", "half_cycle": 0.5, "half_cycles": 1,
             "force": 6.0, "force_ramp": 0.3}  # fmt: skip


def _linear(msg: TwistStamped) -> tuple[float, float, float]:
    return (msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z)


def _force(msg: WrenchStamped) -> tuple[float, float, float]:
    return (msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z)


def _torque(msg: WrenchStamped) -> tuple[float, float, float]:
    return (msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z)


def _profile_times(log, operator) -> np.ndarray:
    """Profile time t of each message's stamp [s], from integer nanoseconds (a float of the
    absolute stamp loses ~1e-7 s)."""
    start = operator._start.nanoseconds
    return np.array(
        [(m.header.stamp.sec * 10**9 + m.header.stamp.nanosec - start) * 1e-9 for m in log.messages]
    )


@pytest.mark.parametrize("content", [SHORT_WALL, SHORT_ARC], ids=["wall", "arc"])
def test_motion_force_profile_integrates_to_the_reference_and_pushes_f_des_n(
    ros, tmp_path, content
):
    """Each received twist and force setpoint is the profile at its stamp, and the profile,
    sampled at the operator's rate, integrates to the reference displacement. Best-effort
    samples lost and ticks made late by a busy machine leave gaps in what arrives: the
    integral is taken over the profile, not over the samples received."""
    path = tmp_path / "short_part2.yaml"
    path.write_text(yaml.safe_dump(content))
    scenario = load_motion_force_scenario(path)
    setup, duration, zero_duration, rate = scenario.setup, scenario.duration, 0.3, 250.0
    twists = ros.record(TwistStamped, "cmd_twist")
    wrenches = ros.record(WrenchStamped, "force_setpoint")
    operator = ros.add(
        OperatorNode,
        {"scenario": str(path), "rate": rate, "start_delay": 0.0, "zero_duration": zero_duration},
    )
    assert operator.motion_force
    assert ros.spin_until(lambda: operator.finished, timeout=20.0)
    # then silence: nothing stamped after the tick that finished (earlier ones may still arrive)
    finished = (operator.get_clock().now() - operator._start).nanoseconds * 1e-9
    ros.spin_for(0.2)
    frames = {m.header.frame_id for m in twists.messages + wrenches.messages}
    assert frames == {"world"}

    # cmd_twist: the reference velocity at its stamps, angular 0, zeros after the profile
    t = _profile_times(twists, operator)
    v = twists.array(_linear)
    assert np.all(np.diff(t) > 0.0)
    assert 0.0 <= t[0] < duration
    assert duration < t[-1] <= duration + zero_duration < finished
    assert np.all(twists.array(lambda m: [m.twist.angular.x, m.twist.angular.y,
                                          m.twist.angular.z]) == 0.0)  # fmt: skip
    expected = np.array([operator_sample(setup, min(ti, duration)).linear for ti in t])
    np.testing.assert_allclose(v[t <= duration], expected[t <= duration], atol=1e-12)
    assert np.all(v[t > duration] == 0.0)
    # the profile at the operator's rate: its trapezoid integral is the reference displacement
    grid = np.linspace(0.0, duration, round(rate * duration) + 1)
    profile = np.array([operator_sample(setup, ti).linear for ti in grid])
    displacement = np.trapezoid(profile, grid, axis=0)
    reference = setup.reference(duration).position - setup.reference(0.0).position
    length = np.linalg.norm(reference)
    assert length > 0.1  # [m]: a real stroke / chord
    assert np.linalg.norm(displacement - reference) < PROFILE_INTEGRAL_TOLERANCE * length

    # force_setpoint: f_des(t) n(t) at the stamps, n at the reference point, held after the end
    tf = _profile_times(wrenches, operator)
    forces = wrenches.array(_force)
    assert np.all(np.diff(tf) > 0.0)
    assert np.all(wrenches.array(_torque) == 0.0)
    for ti, force in zip(tf, forces, strict=True):
        tau = min(ti, duration)
        f_des = setup.force(tau)
        normal = setup.constraint.gradient(setup.reference(tau).position)
        assert abs(np.linalg.norm(force) - f_des) <= 1e-9
        np.testing.assert_allclose(force, f_des * normal, atol=1e-9)
    held = forces[tf > duration]
    assert len(held) > 0
    assert np.all(held == held[-1])  # held at its final value
    assert np.linalg.norm(held[-1]) == pytest.approx(setup.force(duration), abs=1e-9)
    assert duration < tf[-1] <= duration + zero_duration


#: Relative error of the trapezoid integral of a Part II velocity profile sampled at 250 Hz
#: (2.6e-10 for the short wall and arc).
PROFILE_INTEGRAL_TOLERANCE = 1e-6


def test_motion_force_with_lead_both_streams_go_out_ahead_the_setpoints_from_the_start(
    ros, tmp_path
):
    """Under use_sim_time with ``lead`` (lockstep with rns_force_controller's
    ``await_commands``): at each /clock instant c the operator publishes the sample of
    c + lead, force setpoint and twist both stamped c + lead. From the start condition until the
    profile starts only zero twists go out (a force setpoint would start the controller's force
    task): the first force setpoint is stamped at the profile's start, max(start_delay, lead)
    after the start condition, and from there every twist has its setpoint of the same stamp."""
    path = tmp_path / "short_wall.yaml"
    path.write_text(yaml.safe_dump({**SHORT_WALL, "stroke": 0.1, "force_ramp": 0.05}))
    scenario = load_motion_force_scenario(path)
    twists = ros.record(TwistStamped, "cmd_twist")
    wrenches = ros.record(WrenchStamped, "force_setpoint")
    operator = ros.add(
        OperatorNode,
        {
            "scenario": str(path),
            "rate": 500.0,
            "start_delay": 0.01,
            "zero_duration": 0.02,
            "lead": 0.004,
            "use_sim_time": True,
        },
    )
    ahead = _play_on_clock(ros, operator, twists, period=0.002, ticks=200)  # 0.4 s at 500 Hz
    ros.spin_for(0.1)
    assert ahead == pytest.approx([0.004] * len(ahead), abs=1e-9)  # each sample a lead early
    twist_times, force_times = _profile_times(twists, operator), _profile_times(wrenches, operator)
    assert twist_times[0] == pytest.approx(-0.006, abs=1e-9)  # from the start condition on
    assert np.all(twists.array(_linear)[twist_times < 0.0] == 0.0)  # zeros before the profile
    assert force_times[0] == pytest.approx(0.0, abs=1e-9)  # the setpoints from the profile on
    np.testing.assert_allclose(force_times, twist_times[twist_times >= -1e-9], atol=1e-9)
    duration = scenario.duration
    for tau, force in zip(force_times, wrenches.array(_force), strict=True):
        sample = operator_sample(scenario.setup, min(max(tau, 0.0), duration))
        np.testing.assert_allclose(force, sample.force_vector, atol=1e-12)
    moving = twist_times[np.any(twists.array(_linear) != 0.0, axis=1)]
    assert moving.size > 0
    assert moving[0] > 0.0
    assert moving[-1] < duration


def test_motion_force_destroyed_mid_profile_sends_zero_twists_and_keeps_the_force(ros, tmp_path):
    path = tmp_path / "long_wall.yaml"
    path.write_text(yaml.safe_dump({**SHORT_WALL, "stroke": 30.0, "force_ramp": 0.2}))
    twists = ros.record(TwistStamped, "cmd_twist")
    wrenches = ros.record(WrenchStamped, "force_setpoint")
    operator = ros.add(OperatorNode, {"scenario": str(path), "start_delay": 0.0, "rate": 100.0})
    assert ros.spin_until(lambda: operator.elapsed() > 0.4 and len(twists) >= 5, timeout=20.0)
    assert any(_linear(twists.latest()))  # moving along the wall
    ros.detach(operator)
    counts = (len(twists), len(wrenches))
    current = np.array(_force(wrenches.latest()))
    assert np.linalg.norm(current) == pytest.approx(10.0, abs=1e-9)  # ramp done: 10 N
    operator.destroy_node()
    ros.spin_for(0.3)
    after_twists, after_wrenches = twists.messages[counts[0] :], wrenches.messages[counts[1] :]
    assert after_twists, "no twist after destroy_node"
    assert after_wrenches, "no force setpoint after destroy_node"
    zeros = [m for m in after_twists if not any(_linear(m))]  # (a tick may still be in flight)
    assert 1 <= len(zeros) <= FINAL_ZEROS
    assert not any(_linear(after_twists[-1]))
    assert {m.header.frame_id for m in zeros} == {"world"}
    # the final force setpoints are the current one (the arm stops on the wall, pushing on):
    # 10 N along the constant wall normal, nothing jumps
    final = np.array([_force(m) for m in after_wrenches])
    # + 1: a tick's setpoint goes out just before its twist, on another topic, so it may arrive
    # after the counts were taken while its twist arrived before
    assert len(final) <= FINAL_ZEROS + len(after_twists) - len(zeros) + 1
    assert np.all(final == current)


def test_motion_force_waits_for_both_subscribers(ros, tmp_path):
    path = tmp_path / "wall.yaml"
    path.write_text(yaml.safe_dump(SHORT_WALL))
    operator = ros.add(OperatorNode, {"scenario": str(path), "start_delay": 0.0})
    ros.record(TwistStamped, "cmd_twist")
    ros.spin_for(0.3)
    assert not operator.started  # no force_setpoint subscriber yet
    ros.record(WrenchStamped, "force_setpoint")
    assert ros.spin_until(lambda: operator.started, timeout=5.0)


def test_motion_force_waits_for_min_subscribers_on_both_topics(ros, tmp_path):
    """min_subscribers counts on force_setpoint too: a recorder of the task's first setpoint
    matched late would miss it (best effort)."""
    path = tmp_path / "wall.yaml"
    path.write_text(yaml.safe_dump(SHORT_WALL))
    operator = ros.add(
        OperatorNode, {"scenario": str(path), "start_delay": 0.0, "min_subscribers": 2}
    )
    ros.record(TwistStamped, "cmd_twist")
    ros.record(TwistStamped, "cmd_twist")
    ros.record(WrenchStamped, "force_setpoint")
    ros.spin_for(0.3)
    assert not operator.started  # one force_setpoint subscriber of two
    ros.record(WrenchStamped, "force_setpoint")
    assert ros.spin_until(lambda: operator.started, timeout=5.0)


def test_shipped_contact_scenarios_are_motion_force(ros):
    operator = ros.add(OperatorNode, {"scenario": "wall_contact", "wait_for_subscriber": False,
                                      "start_delay": 60.0})  # fmt: skip
    assert operator.motion_force
    assert operator.scenario.duration == 10.0


def test_bad_motion_force_scenario_is_a_config_error_naming_the_value(ros, tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump({**SHORT_WALL, "stroke": -1.0}))
    with pytest.raises(ConfigError, match=r"stroke must be a finite number > 0 \[s\], got -1.0"):
        OperatorNode(
            context=ros.context, parameter_overrides=[Parameter("scenario", value=str(path))]
        )
