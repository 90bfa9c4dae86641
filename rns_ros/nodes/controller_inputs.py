"""rns_controller's measured state intake: the newest joint_states sample and base pose, when each
arrived, and what the state watchdogs judge from them.

The node parses the messages (joint_states matched by joint name, base_odom's pose) and hands
the values over; :class:`MeasuredState` keeps them with their receipt times on the input clock
(:class:`rns_ros.nodes.input_clock.InputClock`: simulated time under use_sim_time, else
monotonic wall time) and on the monotonic wall clock, notes a discontinuity in joint_states (a
reset, a re-homed robot, a second source), and says at a tick whether the state is fresh enough
to run the law on (STATE_GAP past ``state_hold_age``) or cannot be trusted at all (STALE_STATE
past ``state_timeout``, CONFLICTING_STATE for two sources), and where the joints will be when
the tick's output acts (:func:`rns_ros.control.prediction.predict_joint_angles`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rns_ros.control.prediction import OutputTiming, PublishedOutput, predict_joint_angles
from rns_ros.control.teleop import ControllerState
from rns_ros.nodes.input_clock import InputClock
from rns_ros.nodes.robot_io import measured_state_problem

#: joint_states older than this [s] are used as they are, not extrapolated.
MAX_PREDICTION_AGE = 0.1


@dataclass(frozen=True)
class JointSample:
    """One joint_states sample in the model's joint order."""

    #: joint angles theta [rad] (n,)
    theta: np.ndarray
    #: joint rates theta_dot [rad/s] (n,); None when the message carries none
    theta_rate: np.ndarray | None
    #: header stamp [ns] (the node clock's type)
    stamp: int


def discontinuity(
    previous: JointSample,
    theta: np.ndarray,
    stamp: int,
    reference: np.ndarray | None,
    tolerance: float,
    joint_names: Sequence[str],
) -> str | None:
    """Why ``theta`` [rad] (n,) stamped ``stamp`` [ns] cannot follow from the ``previous``
    sample, or None.

    Between two samples each joint moved from the previous angle toward where its previous
    rate takes it over the stamp difference (clipped to [0, MAX_PREDICTION_AGE]) or toward
    the ``reference`` [rad] (n,) the controller commanded meanwhile (through a gap in the stream
    it drives the arm on, then holds it), or stayed: a sample within ``tolerance`` [rad]
    (``state_jump_tolerance``) of the range those span follows; a reset, a re-homed robot or a
    second source does not.
    """
    dt = (stamp - previous.stamp) * 1e-9
    low = high = previous.theta
    if previous.theta_rate is not None:
        moved = previous.theta + min(max(dt, 0.0), MAX_PREDICTION_AGE) * previous.theta_rate
        low, high = np.minimum(low, moved), np.maximum(high, moved)
    if reference is not None:
        low, high = np.minimum(low, reference), np.maximum(high, reference)
    error = np.maximum(low - theta, theta - high)
    joint = int(np.argmax(error))
    if error[joint] <= tolerance:
        return None
    return (
        f"joint_states jumped: {joint_names[joint]} {theta[joint]:.4g} rad where "
        f"[{low[joint]:.4g}, {high[joint]:.4g}] rad was reachable from the previous sample "
        "and the reference "
        f"(state_jump_tolerance {tolerance} rad)"
    )


class MeasuredState:
    """The newest measured state of the arm and the base, and its receipt times (see the module
    docstring).

    Args:
        joint_names: the model's joints, in model order (a jump names its joint).
        input_clock: the clock the receipt times are noted on.
    """

    def __init__(self, joint_names: Sequence[str], input_clock: InputClock) -> None:
        self._joint_names = tuple(joint_names)
        self._input_clock = input_clock
        #: the newest joint_states sample; None until the first
        self.joints: JointSample | None = None
        #: the base pose in world: position [m] (3,), unit quaternion x y z w (4,); identity
        #: until base_odom
        self.base_position = np.zeros(3)
        self.base_orientation = np.array([0.0, 0.0, 0.0, 1.0])
        #: receipt times [s] on the input clock of the newest joint state (-inf before the
        #: first) and base_odom (None before the first: not watched until then)
        self.state_received = -np.inf
        self.odom_received: float | None = None
        #: monotonic receipt time [s] of the newest joint state (output_lead's catch-up, the
        #: /clock watch)
        self.state_received_wall = -np.inf
        self._jump: str | None = None  # a discontinuity not yet taken by a tick

    @property
    def theta(self) -> np.ndarray | None:
        """The newest joint angles [rad] (n,); None until a joint state has arrived."""
        return None if self.joints is None else self.joints.theta

    def take_joint_state(
        self,
        theta: np.ndarray,
        theta_rate: np.ndarray | None,
        stamp: int,
        reference: np.ndarray | None,
        jump_tolerance: float,
    ) -> None:
        """A joint state: angles ``theta`` [rad], rates ``theta_rate`` [rad/s] (n,) or None,
        stamped ``stamp`` [ns]; judged against the previous sample and the controller's
        ``reference`` [rad] (n,) within ``jump_tolerance`` [rad] (:func:`discontinuity`; the
        first jump is kept until a tick takes it)."""
        if self.joints is not None and self._jump is None:
            self._jump = discontinuity(
                self.joints, theta, stamp, reference, jump_tolerance, self._joint_names
            )
        self.joints = JointSample(theta, theta_rate, stamp)
        self.state_received = self._input_clock.receipt_time(stamp * 1e-9)
        self.state_received_wall = time.monotonic()

    def take_base_pose(self, position: np.ndarray, orientation: np.ndarray, stamp: float) -> None:
        """A base pose in world: ``position`` [m] (3,), unit quaternion x y z w (4,), stamped
        ``stamp`` [s]."""
        self.base_position, self.base_orientation = position, orientation
        self.odom_received = self._input_clock.receipt_time(stamp)

    def take_jump(self) -> str | None:
        """The discontinuity seen in joint_states since the last call (why), or None."""
        jump, self._jump = self._jump, None
        return jump

    def wall_quiet(self) -> float:
        """Monotonic wall time [s] since the newest joint state arrived (inf before the first)."""
        return time.monotonic() - self.state_received_wall

    def drop_future_receipts(self, now: float) -> None:
        """Receipt times later than ``now`` [s] (noted on a clock that then went back) become
        ``now``: the watchdogs age them from here instead of never."""
        self.state_received = min(self.state_received, now)
        if self.odom_received is not None:
            self.odom_received = min(self.odom_received, now)

    def gap(self, now: float, hold_age: float, timeout: float) -> str | None:
        """Why the arm is held at a tick ``now`` [s] (input clock): joint_states or base_odom
        older than ``hold_age`` [s] (``state_hold_age``), beyond what the prediction can bridge
        (a law evaluated on an old configuration turns the base); None when both are fresh. The
        text names ``timeout`` [s] (``state_timeout``), where the hold becomes STALE_STATE."""
        ages = {"joint_states": now - self.state_received}
        if self.odom_received is not None:
            ages["base_odom"] = now - self.odom_received
        topic, age = max(ages.items(), key=lambda item: item[1])
        if age <= hold_age:
            return None
        return (
            f"{topic} {age:.3f} s old (state_hold_age {hold_age} s): held until fresh "
            f"(STALE_STATE at state_timeout {timeout} s)"
        )

    def output_start(
        self,
        now: int,
        hold: float | None,
        lead: float,
        timing: OutputTiming,
        outputs: Sequence[PublishedOutput],
    ) -> tuple[np.ndarray, float | None]:
        """Where the joints are when an output planned at ``now`` [ns] acts, and how long it acts
        there: (joint angles [rad] (n,), ``hold`` [s] moved onto the plant's ``timing``, or
        None for the period T). The newest sample moved on by its rate and the recent
        ``outputs`` (:func:`predict_joint_angles`); taken as it is without rates, or when it is
        older than MAX_PREDICTION_AGE or more than ``lead`` [s] newer than ``now`` (a late tick
        in lockstep may find a state up to ``output_lead`` ahead)."""
        sample = self.joints
        if sample.theta_rate is None:
            return sample.theta, hold
        seconds, stamp = now * 1e-9, sample.stamp * 1e-9
        if not -lead <= seconds - stamp < MAX_PREDICTION_AGE:
            return sample.theta, hold  # clocks disagree or the state is stale: do not extrapolate
        start = predict_joint_angles(
            sample.theta, sample.theta_rate, stamp, seconds, outputs, timing
        )
        if hold is not None:
            ends = timing.acting_time(seconds + hold, stamp)
            hold = ends - start.acting_time if ends > start.acting_time else None
        return start.theta, hold

    def fault(
        self, now: float, state_publishers: Sequence[str], state_topic: str, timeout: float
    ) -> tuple[ControllerState, str] | None:
        """(state, detail) when the measured state cannot be trusted at ``now`` [s] (input
        clock): older than ``timeout`` [s] (``state_timeout``), or more than one of
        ``state_publishers`` on ``state_topic``; None when it can."""
        problem = measured_state_problem(
            now,
            state_publishers,
            state_topic,
            self.state_received,
            self.odom_received,
            timeout,
        )
        return None if problem is None else (ControllerState(problem[0]), problem[1])
