"""The state topics of rns_simulator's free-floating modes: joint_states, base_odom, momentum,
energy, wheel_states and /clock (layouts: :mod:`rns_ros.nodes.simulator`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from rns_ros.core import FreeFloatingModel, FreeFloatingState
from rns_ros.core.conventions import base_twist_to_world
from rns_ros.core.energy import EnergyCost, energy_metric, kinetic_energy
from rns_ros.nodes.cdr import (
    SerializedTemplate,
    TemplateError,
    clock_template,
    joint_state_template,
    odometry_template,
    wrench_template,
)
from rns_ros.nodes.sim_clock import stamp_from_seconds
from rns_ros.nodes.tf_publishing import TfPublisher
from rns_ros.sim.free_floating import SimulationState
from rns_ros.sim.reaction_wheels import WHEEL_NAMES

#: Layout of the ``energy`` topic (Float64MultiArray; also the label of its one dimension):
#: eq. (5.1) terms of the true state [J], the arm's motion costed with Lambda_m and Lambda_r of
#: eq. (5.3) [J], the running C_max [J] and C_sum [J s] of eqs. (5.12)-(5.13) since the start or
#: the last ~/reset, and the simulated time of the sample [s].
ENERGY_LABELS = (
    "base",
    "arm",
    "coupling",
    "wheels",
    "total",
    "lambda_arm",
    "lambda_wheels",
    "c_max",
    "c_sum",
    "time",
)


class WheelSnapshot(NamedTuple):
    """Wheel state to publish: angles [rad], speeds relative to the base [rad/s] and applied
    torques [N m], each (3,) in base x, y, z order."""

    angles: np.ndarray
    speeds: np.ndarray
    torques: np.ndarray


class _StateTemplates(NamedTuple):
    """Pre-serialized state messages (see :meth:`StatePublisher._state_templates`)."""

    joints: SerializedTemplate
    odom: SerializedTemplate
    momentum: SerializedTemplate
    clock: SerializedTemplate


class StatePublisher:
    """Publishes simulator states on ``node``'s topics.

    Args:
        node: the node the publishers belong to.
        robot: the simulated model.
        world_frame: frame id of base_odom and momentum.
        dynamic: joint_states carry efforts (dynamic mode).
        wheels: reaction wheels: wheel_states is published.
        publish_clock: /clock is published.
        energy_every: the energy topic with every k-th state; 0: none.
        wheel_inertia: I_r [kg m^2] of the energy metric.
        stamp: the header stamp of a state.
        publish_tf: /tf and /tf_static (:class:`rns_ros.nodes.tf_publishing.TfPublisher`).
    """

    def __init__(
        self,
        node: Node,
        robot: FreeFloatingModel,
        *,
        world_frame: str,
        dynamic: bool,
        wheels: bool,
        publish_clock: bool,
        energy_every: int,
        wheel_inertia: float,
        stamp: Callable[[SimulationState], TimeMsg],
        publish_tf: bool = True,
    ) -> None:
        self.robot = robot
        self._logger = node.get_logger()
        self._world_frame = world_frame
        self._dynamic = dynamic
        self._stamp = stamp
        self._energy_every = energy_every
        self._wheel_inertia = wheel_inertia
        self.energy_cost = EnergyCost()
        self._state_publications = 0
        # State streams: reliable, shallow; consumers want the latest state.
        state_qos = QoSProfile(depth=10)
        self.joint_pub = node.create_publisher(JointState, "joint_states", state_qos)
        self.odom_pub = node.create_publisher(Odometry, "base_odom", state_qos)
        self.momentum_pub = node.create_publisher(WrenchStamped, "momentum", state_qos)
        self.energy_pub = node.create_publisher(Float64MultiArray, "energy", state_qos)
        self.wheel_pub = (
            node.create_publisher(JointState, "wheel_states", state_qos) if wheels else None
        )
        self.clock_pub = (
            node.create_publisher(Clock, "/clock", QoSProfile(depth=1)) if publish_clock else None
        )
        # reused messages: only the stamp and the values change from one state to the next
        self._joints_msg = JointState(name=list(robot.joint_names))
        self._odom_msg = Odometry(child_frame_id=robot.base_link)
        self._odom_msg.header.frame_id = world_frame
        self._momentum_msg = WrenchStamped()
        self._momentum_msg.header.frame_id = world_frame
        self._clock_msg = Clock()
        self.templates = self._state_templates()
        self.tf = TfPublisher.create(node, robot, world_frame) if publish_tf else None

    def reset_energy(self) -> None:
        """C_max and C_sum count from now (a ~/reset)."""
        self.energy_cost = EnergyCost()

    def _state_templates(self) -> _StateTemplates | None:
        """The state messages pre-serialized (:mod:`rns_ros.nodes.cdr`: the conversion of four
        messages was about a third of a lockstep period's CPU here), or None to publish
        messages when a layout cannot be captured."""
        try:
            return _StateTemplates(
                joints=joint_state_template(self.robot.joint_names, effort=self._dynamic),
                odom=odometry_template(self._world_frame, self.robot.base_link),
                momentum=wrench_template(self._world_frame),
                clock=clock_template(),
            )
        except TemplateError as exc:
            self._logger.warn(f"{exc}: publishing state messages unserialized")
            return None

    def send_clock(self, sim_time: float) -> None:
        stamp = stamp_from_seconds(sim_time)
        if self.templates is not None:
            self.clock_pub.publish(self.templates.clock.serialize({}, (stamp.sec, stamp.nanosec)))
            return
        self._clock_msg.clock = stamp
        self.clock_pub.publish(self._clock_msg)

    def publish(
        self,
        state: SimulationState,
        momentum: np.ndarray,
        wheels: WheelSnapshot | None = None,
        clock: bool = False,
    ) -> None:
        """The state topics of ``state``, in the order consumers need them: what controllers
        read (joint_states, base_odom, wheel_states), then /clock at its time (with ``clock``:
        a sim-time timer woken by it finds the state there), then the monitoring topics
        (momentum, energy), which no control loop waits for. They go out as pre-serialized bytes
        (:meth:`_state_templates`), else as reused messages."""
        values = (state.q, state.v, state.effort, momentum)
        if wheels is not None:
            values += tuple(wheels)
        if not all(np.isfinite(value).all() for value in values):
            # the core never keeps a non-finite state; this guards the topics regardless
            self._logger.error(
                f"non-finite state at t = {state.time:.6g} s not published",
                throttle_duration_sec=1.0,
            )
            return
        stamp = self._stamp(state)
        if self.templates is not None:
            self._publish_serialized(state, (stamp.sec, stamp.nanosec))
        else:
            self._publish_messages(state, stamp)
        if wheels is not None:
            self._publish_wheels(wheels, stamp)
        if self.tf is not None:
            self.tf.publish(state.q, stamp)
        if clock:
            self.send_clock(state.time)

        self._publish_momentum(momentum, stamp)
        self._state_publications += 1
        if self._energy_every and (self._state_publications - 1) % self._energy_every == 0:
            self._publish_energy(state, wheels)

    def _publish_wheels(self, wheels: WheelSnapshot, stamp: TimeMsg) -> None:
        wheel_states = JointState()
        wheel_states.header.stamp = stamp
        wheel_states.header.frame_id = self.robot.base_link
        wheel_states.name = list(WHEEL_NAMES)
        wheel_states.position = wheels.angles.tolist()
        wheel_states.velocity = wheels.speeds.tolist()
        wheel_states.effort = wheels.torques.tolist()
        self.wheel_pub.publish(wheel_states)

    def _publish_serialized(self, state: SimulationState, stamp: tuple[int, int]) -> None:
        """joint_states and base_odom of ``state`` through the templates (stamp: sec, nanosec)."""
        values = {"position": state.q[7:], "velocity": state.v[6:]}
        if self._dynamic:
            values["effort"] = state.effort
        self.joint_pub.publish(self.templates.joints.serialize(values, stamp))
        self.odom_pub.publish(
            self.templates.odom.serialize({"pose": state.q[:7], "twist": state.v[:6]}, stamp)
        )

    def _publish_momentum(self, momentum: np.ndarray, stamp: TimeMsg) -> None:
        if self.templates is not None:
            values = {"wrench": momentum}
            self.momentum_pub.publish(
                self.templates.momentum.serialize(values, (stamp.sec, stamp.nanosec))
            )
            return
        wrench = self._momentum_msg
        wrench.header.stamp = stamp
        force, torque = wrench.wrench.force, wrench.wrench.torque
        force.x, force.y, force.z = momentum[:3].tolist()
        torque.x, torque.y, torque.z = momentum[3:].tolist()
        self.momentum_pub.publish(wrench)

    def _publish_messages(self, state: SimulationState, stamp: TimeMsg) -> None:
        """joint_states and base_odom of ``state`` as messages (no templates)."""
        joints = self._joints_msg
        joints.header.stamp = stamp
        joints.position = state.q[7:].tolist()
        joints.velocity = state.v[6:].tolist()
        if self._dynamic:
            joints.effort = state.effort.tolist()
        self.joint_pub.publish(joints)

        odom = self._odom_msg
        odom.header.stamp = stamp
        position, orientation = odom.pose.pose.position, odom.pose.pose.orientation
        position.x, position.y, position.z = state.q[:3].tolist()
        orientation.x, orientation.y, orientation.z, orientation.w = state.q[3:7].tolist()
        linear, angular = odom.twist.twist.linear, odom.twist.twist.angular
        linear.x, linear.y, linear.z = state.v[:3].tolist()
        angular.x, angular.y, angular.z = state.v[3:6].tolist()
        self.odom_pub.publish(odom)

    def _publish_energy(self, state: SimulationState, wheels: WheelSnapshot | None) -> None:
        """The ``energy`` topic (layout: :data:`ENERGY_LABELS`), from the true state."""
        physical = FreeFloatingState.compute(self.robot, state.q)
        twist = base_twist_to_world(physical.base_rotation, state.v[:6])
        theta_dot = state.v[6:]
        terms = kinetic_energy(
            physical,
            twist,
            theta_dot,
            None if wheels is None else wheels.speeds,
            self._wheel_inertia,
        )
        arm, wheel = energy_metric(physical, self._wheel_inertia).energy(theta_dot)
        self.energy_cost.add(state.time, arm + wheel)
        values = [
            *terms,
            arm,
            wheel,
            self.energy_cost.c_max,
            self.energy_cost.c_sum,
            state.time,
        ]
        if not np.isfinite(values).all():
            return
        msg = Float64MultiArray(data=[float(x) for x in values])
        msg.layout.dim = [
            MultiArrayDimension(label=" ".join(ENERGY_LABELS), size=len(values), stride=len(values))
        ]
        self.energy_pub.publish(msg)
