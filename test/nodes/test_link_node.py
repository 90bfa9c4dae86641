"""rns_link over real DDS, on a simulated clock the test advances: each message arrives its
delay later (simulated seconds), in order and byte for byte; outages lose what is sent in them;
oversized messages and bad parameters are refused with their reason."""

from __future__ import annotations

import os

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rns_testing import SimClock
from sensor_msgs.msg import JointState

from rns_ros.core.errors import ConfigError
from rns_ros.harness import Harness
from rns_ros.nodes.link import LinkNode
from rns_ros.nodes.sim_clock import stamp_from_seconds

STEP = 0.01  # [s] of simulated time per clock message
START = 100.0  # [s] the clock's first reading


def _link(ros, **overrides):
    parameters = [Parameter("use_sim_time", value=True)]
    parameters += [Parameter(name, value=value) for name, value in overrides.items()]
    return ros.add(LinkNode(context=ros.context, parameter_overrides=parameters))


class _Arrivals:
    """Messages of a topic with the simulated time they arrived at (the clock stands still
    between steps, so the reading at receipt is the arrival's)."""

    def __init__(self, node, msg_type, topic: str, clock: SimClock) -> None:
        self.items: list[tuple[float, object]] = []
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        node.create_subscription(
            msg_type, topic, lambda msg: self.items.append((clock.seconds, msg)), qos
        )


def _twist(t: float, k: int) -> TwistStamped:
    msg = TwistStamped()
    msg.header.stamp = stamp_from_seconds(t)
    msg.header.frame_id = "world"
    msg.twist.angular.z = 0.001 * k
    return msg


class _Stepper:
    """Advances the test's /clock in STEP steps and waits, each step, until the link node's
    clock has taken the new reading (its timers then run on it)."""

    def __init__(self, ros, link: LinkNode, clock: SimClock) -> None:
        self._ros, self._clock, self._seen = ros, clock, [0.0]
        link.create_timer(1e-3, lambda: self._seen.__setitem__(0, link.now_s()))
        clock.advance(0.0)
        ros.spin_until(lambda: self._seen[0] >= START - 1e-9, 20.0)

    def run(self, publish, until: float) -> None:
        """Call ``publish(t, k)`` at each step's reading t until ``until`` [s]."""
        k = 0
        while self._clock.seconds < until - 1e-9:
            publish(self._clock.seconds, k)
            reading = self._clock.advance(STEP)
            seconds = reading.sec + 1e-9 * reading.nanosec
            self._ros.spin_until(lambda t=seconds: self._seen[0] >= t - 1e-9, 10.0)
            k += 1


@pytest.fixture
def stack(ros):
    probe = ros.probe()
    return ros, probe, SimClock(probe, START)


def test_uplink_messages_arrive_their_delay_later_in_order_and_unchanged(stack):
    ros, probe, clock = stack
    link = _link(ros, uplink_delay=2.0, release_period=0.005)
    publisher = probe.create_publisher(TwistStamped, "/ground/cmd_twist", 1000)
    arrivals = _Arrivals(probe, TwistStamped, "/cmd_twist", clock)
    steps = _Stepper(ros, link, clock)
    ros.spin_until(lambda: publisher.get_subscription_count() > 0, 20.0)
    sent = []

    def publish(t, k):
        if t < START + 1.0 - 1e-9:
            msg = _twist(t, k)
            sent.append(msg)
            publisher.publish(msg)

    steps.run(publish, START + 3.5)
    ros.spin_until(lambda: len(arrivals.items) >= len(sent), 20.0)
    assert [msg for _, msg in arrivals.items] == sent  # all, in order, field for field
    for arrived, msg in arrivals.items:
        stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        # due at stamp + 2 s; handed on at the next release tick, seen at the next clock step
        assert 2.0 - 1e-6 <= arrived - stamp <= 2.0 + 0.005 + 2 * STEP + 1e-6


def test_a_point_to_point_goal_goes_up_and_its_status_comes_down_by_default(stack):
    """rns_ptp behind the link with the default topics: a ptp_goal sent on the ground reaches
    the spacecraft, rns_ptp's status reaches the ground, each one delay later."""
    ros, probe, clock = stack
    link = _link(ros, uplink_delay=1.0, downlink_delay=1.0, release_period=0.005)
    goals = probe.create_publisher(JointState, "/ground/ptp_goal", 10)
    statuses = probe.create_publisher(DiagnosticArray, "/rns_ptp/status", 10)
    up = _Arrivals(probe, JointState, "/ptp_goal", clock)
    down = _Arrivals(probe, DiagnosticArray, "/ground/rns_ptp/status", clock)
    steps = _Stepper(ros, link, clock)
    ros.spin_until(
        lambda: goals.get_subscription_count() > 0 and statuses.get_subscription_count() > 0,
        20.0,
    )
    goal = JointState(name=["joint_2"], position=[0.3])
    goal.header.stamp = stamp_from_seconds(clock.seconds)

    def publish(t, k):
        if k == 0:
            goals.publish(goal)
            statuses.publish(DiagnosticArray(header=goal.header))

    steps.run(publish, START + 1.5)
    ros.spin_until(lambda: up.items and down.items, 20.0)
    assert [msg for _, msg in up.items] == [goal]
    for arrivals in (up, down):
        (arrived, msg), *_ = arrivals.items
        stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        assert 1.0 - 1e-6 <= arrived - stamp <= 1.0 + 0.005 + 2 * STEP + 1e-6


def test_an_outage_loses_what_is_sent_in_it_and_the_status_says_so(stack):
    ros, probe, clock = stack
    link = _link(
        ros,
        uplink_delay=0.5,
        outages=f"{START + 0.5}:{START + 1.0}",
        status_period=0.1,
    )
    publisher = probe.create_publisher(TwistStamped, "/ground/cmd_twist", 1000)
    arrivals = _Arrivals(probe, TwistStamped, "/cmd_twist", clock)
    statuses = []
    probe.create_subscription(DiagnosticArray, "/rns_link/status", statuses.append, 100)
    steps = _Stepper(ros, link, clock)
    ros.spin_until(lambda: publisher.get_subscription_count() > 0, 20.0)
    sent = []

    def publish(t, k):
        if t < START + 1.5 - 1e-9:
            sent.append(t)
            publisher.publish(_twist(t, k))

    steps.run(publish, START + 2.5)
    # the link times a message by its own clock when it takes it: one published just before a
    # step may be taken just after it, so the samples next to the outage's ends may go either way
    inside = [t for t in sent if START + 0.5 <= t < START + 1.0 - STEP - 1e-9]
    outside = [t for t in sent if t < START + 0.5 - STEP - 1e-9 or t >= START + 1.0 - 1e-9]
    ros.spin_until(lambda: len(arrivals.items) >= len(outside), 20.0)
    steps.run(lambda t, k: None, START + 3.0)
    received = [m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for _, m in arrivals.items]
    assert received == sorted(received)
    assert all(min(abs(t - r) for r in received) < 1e-6 for t in outside)
    assert all(min(abs(t - r) for r in received) > 1e-6 for t in inside)
    ros.spin_until(lambda: statuses, 20.0)
    values = {kv.key: kv.value for kv in statuses[-1].status[0].values}
    assert int(values["uplink lost in outage"]) == len(sent) - len(received) >= len(inside) > 0
    assert any(s.status[0].message == "OUTAGE" for s in statuses)


def test_an_oversized_message_is_refused_and_counted(stack):
    ros, probe, clock = stack
    link = _link(ros, max_message_size=200, status_period=0.05)
    publisher = probe.create_publisher(JointState, "/joint_states", 10)
    arrivals = _Arrivals(probe, JointState, "/ground/joint_states", clock)
    statuses = []
    probe.create_subscription(DiagnosticArray, "/rns_link/status", statuses.append, 100)
    steps = _Stepper(ros, link, clock)
    ros.spin_until(lambda: publisher.get_subscription_count() > 0, 20.0)
    big = JointState(name=[f"joint_{i}" for i in range(100)], position=[0.0] * 100)
    small = JointState(name=["joint_1"], position=[0.5])
    publisher.publish(big)
    publisher.publish(small)
    steps.run(lambda t, k: None, START + 0.2)
    ros.spin_until(lambda: arrivals.items, 20.0)
    assert [msg for _, msg in arrivals.items] == [small]
    ros.spin_until(lambda: statuses and statuses[-1].status[0].values, 20.0)
    values = {kv.key: kv.value for kv in statuses[-1].status[0].values}
    assert values["downlink refused"] == "1"


def test_the_ground_side_on_its_own_domain(ros):
    """ground_domain_id: the ground's topics are another ROS domain's (a ground station's
    network): a twist published there reaches the spacecraft's domain, a joint state goes back,
    and the ground topic on the spacecraft's own domain is not carried."""
    domain = int(os.environ["ROS_DOMAIN_ID"])
    ground_domain = domain ^ 1  # the neighbour in this test's block of domains
    link = ros.add(
        LinkNode(
            context=ros.context,
            parameter_overrides=[Parameter("ground_domain_id", value=ground_domain)],
        )
    )
    probe = ros.probe()
    onboard_twists = ros.record(TwistStamped, "/cmd_twist")
    joints = probe.create_publisher(JointState, "/joint_states", 10)
    stray = probe.create_publisher(TwistStamped, "/ground/cmd_twist", 10)
    with Harness(ground_domain) as ground:
        twists = ground.probe().create_publisher(TwistStamped, "/ground/cmd_twist", 10)
        ground_joints = ground.record(JointState, "/ground/joint_states")
        ground_probe = ground.probe("ground_probe")
        assert ground.spin_until(
            lambda: (
                twists.get_subscription_count() > 0
                and ground_probe.count_publishers("/ground/joint_states") > 0
            ),
            20.0,
        )
        assert ros.spin_until(
            lambda: joints.get_subscription_count() > 0 and probe.count_publishers("/cmd_twist"),
            20.0,
        )
        assert stray.get_subscription_count() == 0  # nothing takes it on this domain
        sent, state = _twist(1.0, 7), JointState(name=["joint_1"], position=[0.25])
        for _ in range(200):  # best effort both ways: until each got through once
            twists.publish(sent)
            stray.publish(_twist(2.0, 9))
            joints.publish(state)
            ground.spin_until(lambda: len(ground_joints.messages) > 0, 0.05)
            if ros.spin_until(lambda: len(onboard_twists.messages) > 0, 0.05) and len(
                ground_joints.messages
            ):
                break
        assert onboard_twists.messages[0] == sent
        assert all(msg == sent for msg in onboard_twists.messages)  # never the stray one
        assert ground_joints.messages[0] == state
    assert any("(domain" in route for d in link._directions for route in d.routes)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"ground_namespace": "/"}, "ground_namespace must not be empty"),
        ({"uplink_topics": ["cmd_twist"]}, "must be 'topic:package/msg/Type'"),
        ({"downlink_topics": ["x:nosuch_msgs/msg/X"]}, "nosuch_msgs/msg/X is not installed"),
        ({"outages": "5:1"}, r"link outage must be \(start, end\)"),
    ],
)
def test_bad_parameters_are_one_line_errors(ros, overrides, message):
    with pytest.raises(ConfigError, match=message):
        _link(ros, **overrides)
