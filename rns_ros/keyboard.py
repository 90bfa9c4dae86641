"""Keyboard teleoperation logic of ``rns_teleop_keyboard``: key map, key-hold state machine, panel.

Pure Python (never rclpy): the node in :mod:`rns_ros.nodes.teleop_keyboard` feeds key strings and
monotonic times in and publishes what comes out.

Keys (the first key of each pair is the positive direction):

    q / e   roll  +/-   angular x        i / k   linear x +/-
    w / s   pitch +/-   angular y        j / l   linear y +/-
    a / d   yaw   +/-   angular z        u / o   linear z +/-
    + / -   all speeds x speed_step / ÷ speed_step ('=' and '_' also work), bounded
    f       cycle the command frame camera -> world -> base (and stop)
    m       force mode on / off (and stop), see below
    space   stop now: zero command, held keys forgotten
    Q, Ctrl-C, Ctrl-D, Ctrl-\\   quit (a zero twist is sent first)

Force mode (Part II, docs/part2_ros.md; key ``m``) drives an end effector held on a surface by
a motion/force controller: the motion keys command the EE LINEAR velocity along the EE x / y axes
at the linear speed (w/s or i/k: x +/-, a/d or j/l: y +/-; q/e, u/o and f do nothing: the EE z
axis is the pushing direction and the controller holds the orientation) and the twist is sent in
the EE frame; + / - push harder / softer: the force setpoint f changes by ``force_step`` within
[0, ``max_force``] [N] and is sent (along EE z) at the rate for as long as force mode is on.
Toggling the mode stops the motion like the stop key (zeros in the frame of the mode being
left); leaving force mode keeps the force setpoint where it is (the controller holds the last
one it received; press - down to 0 N first to release the push).

The linear keys exist for completeness: a reactionless camera-pointing controller reports any
linear command as not achievable.

Terminals send no key-release events, only the characters of a press and then auto-repeats
(first repeat after ~250-660 ms, then ~25-30 Hz). So a key counts as *held* from its press until
``key_hold`` seconds pass without another repeat of it; ``key_hold`` must exceed the initial
auto-repeat delay or the command would drop to zero between the press and the first repeat. A
terminal repeats only the newest key, so holding two keys at once drives one axis, not two.

Keys of two or three axes pressed within ``key_hold`` combine. The speeds bound the whole vector:
a combination longer than ``max_angular_speed`` (``max_linear_speed``) is scaled down uniformly
(:func:`limit_norm`, direction kept), so two keys at full speed send |omega| = max_angular_speed,
not sqrt(2) times it (which a controller with the same limit would refuse).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import NamedTuple

import numpy as np

from rns_ros.control.controller import TwistFrame
from rns_ros.core.errors import ConfigError

#: Order of :attr:`KeyboardTeleop.frame` cycling with the frame key.
FRAME_CYCLE = (TwistFrame.CAMERA, TwistFrame.WORLD, TwistFrame.BASE)
#: Lowest speed the slow-down key reaches, in [rad/s] for angular and [m/s] for linear speed.
MIN_SPEED = 1e-3
#: A controller status older than this is shown as stale [s].
STATUS_STALE_AFTER = 1.0

_AXIS_NAMES = ("roll", "pitch", "yaw", "x", "y", "z")


class Action(StrEnum):
    """What a key does."""

    MOVE = "move"
    STOP = "stop"
    FASTER = "faster"
    SLOWER = "slower"
    FRAME = "frame"
    QUIT = "quit"
    FORCE_MODE = "force mode"
    HARDER = "push harder"
    SOFTER = "push softer"


@dataclass(frozen=True)
class Binding:
    """One key's meaning: ``axis`` 0-2 angular x/y/z, 3-5 linear x/y/z; ``sign`` +1 or -1."""

    action: Action
    axis: int = -1
    sign: int = 0

    @property
    def label(self) -> str:
        if self.action is Action.MOVE:
            return f"{_AXIS_NAMES[self.axis]} {'+' if self.sign > 0 else '-'}"
        return self.action.value


def _moves(pairs: str) -> dict[str, Binding]:
    """'qewsad...' -> bindings: consecutive pairs are (+, -) of axes 0, 1, 2, ..."""
    keys = {}
    for axis in range(len(pairs) // 2):
        keys[pairs[2 * axis]] = Binding(Action.MOVE, axis, +1)
        keys[pairs[2 * axis + 1]] = Binding(Action.MOVE, axis, -1)
    return keys


#: Key string -> binding. Keys not in here are ignored.
KEY_MAP: dict[str, Binding] = {
    **_moves("qewsadikjluo"),
    **dict.fromkeys("+=", Binding(Action.FASTER)),
    **dict.fromkeys("-_", Binding(Action.SLOWER)),
    "f": Binding(Action.FRAME),
    "m": Binding(Action.FORCE_MODE),
    " ": Binding(Action.STOP),
    **dict.fromkeys(("Q", "\x03", "\x04", "\x1c"), Binding(Action.QUIT)),
}

#: Key string -> binding in force mode: EE x / y linear keys, push harder / softer; the keys of
#: the other axes and the frame key are not bound (ignored).
FORCE_KEY_MAP: dict[str, Binding] = {
    **{
        key: binding
        for key, binding in KEY_MAP.items()
        if binding.action not in (Action.MOVE, Action.FRAME)
    },
    **{key: Binding(Action.MOVE, 3, +1) for key in "wi"},
    **{key: Binding(Action.MOVE, 3, -1) for key in "sk"},
    **{key: Binding(Action.MOVE, 4, +1) for key in "aj"},
    **{key: Binding(Action.MOVE, 4, -1) for key in "dl"},
    **dict.fromkeys("+=", Binding(Action.HARDER)),
    **dict.fromkeys("-_", Binding(Action.SOFTER)),
}

#: Key help shown at the bottom of the panel.
KEY_HELP = (
    "q/e roll +/-     w/s pitch +/-    a/d yaw +/-     (angular x/y/z)",
    "i/k x +/-        j/l y +/-        u/o z +/-       (linear: not reactionless)",
    "+/- speed        f frame          space stop      Q or Ctrl-C quit",
    "m force mode (EE x/y motion, push along EE z)",
)
#: Key help in force mode.
FORCE_KEY_HELP = (
    "w/s or i/k EE x +/-      a/d or j/l EE y +/-      (linear, EE frame)",
    "+/- push harder/softer   space stop               Q or Ctrl-C quit",
    "m leave force mode (stops; the force setpoint stays what it is)",
)


class Mode(StrEnum):
    """What the keys drive."""

    CAMERA = "camera"  # the camera's (or EE's) twist in the command frame (Part I)
    FORCE = "force"  # EE x / y linear velocity in the EE frame + a force setpoint (Part II)


class Speeds(NamedTuple):
    """Magnitudes a held key commands: angular [rad/s], linear [m/s]."""

    angular: float
    linear: float


@dataclass(frozen=True)
class TeleopCommand:
    """One twist command.

    Attributes:
        angular: angular velocity (x, y, z) in ``frame`` axes [rad/s].
        linear: linear velocity (x, y, z) in ``frame`` axes [m/s].
        frame: axes of both vectors (camera mode).
        force_mode: True: both vectors are in the EE frame's axes (force mode), ``frame`` is
            not used.
    """

    angular: tuple[float, float, float]
    linear: tuple[float, float, float]
    frame: TwistFrame
    force_mode: bool = False

    @property
    def is_zero(self) -> bool:
        return not any(self.angular) and not any(self.linear)


class KeyEvent(NamedTuple):
    """Outcome of one key: its binding (None: ignored) and whether the command changed in a
    way that should be published at once rather than at the next rate tick."""

    key: str
    binding: Binding | None
    urgent: bool


class ControllerStatus(NamedTuple):
    """The controller's newest status entry: ``level`` is DiagnosticStatus.level (0 OK, 1 WARN,
    2 ERROR, 3 STALE); ``received`` is its receipt time on the monotonic clock [s]."""

    state: str
    level: int
    message: str
    received: float


class KeyboardTeleop:
    """Key presses in, twist commands out (see the module docstring for the key semantics).

    Args:
        angular_speed: initial angular speed of a held key [rad/s].
        linear_speed: initial linear speed of a held key [m/s].
        key_hold: a key stays held this long after its newest press or repeat [s].
        zero_duration: after motion ends (release, stop, frame change), :meth:`tick` returns zero
            commands this long, then None (nothing to publish) [s].
        speed_step: factor of one speed-up / slow-down key (> 1) [-].
        max_angular_speed: bound of the angular speed [rad/s].
        max_linear_speed: bound of the linear speed [m/s].
        frame: initial command frame.
        force_step: change of the force setpoint per push key in force mode [N] (> 0).
        max_force: upper bound of the force setpoint [N] (> 0); the lower bound is 0.

    Raises:
        ConfigError: a non-positive duration, speed, force step or maximum force,
            ``speed_step <= 1``, or an initial speed outside [MIN_SPEED, its maximum].
    """

    def __init__(
        self,
        *,
        angular_speed: float,
        linear_speed: float,
        key_hold: float,
        zero_duration: float,
        speed_step: float,
        max_angular_speed: float,
        max_linear_speed: float,
        frame: TwistFrame | str = TwistFrame.CAMERA,
        force_step: float = 1.0,
        max_force: float = 20.0,
    ) -> None:
        if not key_hold > 0.0:
            raise ConfigError(f"key_hold must be > 0 [s], got {key_hold!r}")
        if not zero_duration >= 0.0:
            raise ConfigError(f"zero_duration must be >= 0 [s], got {zero_duration!r}")
        if not speed_step > 1.0:
            raise ConfigError(f"speed_step must be > 1, got {speed_step!r}")
        for name, value in (("force_step", force_step), ("max_force", max_force)):
            if not (math.isfinite(value) and value > 0.0):
                raise ConfigError(f"{name} must be a finite number > 0 [N], got {value!r}")
        for name, speed, high, unit in (
            ("angular_speed", angular_speed, max_angular_speed, "[rad/s]"),
            ("linear_speed", linear_speed, max_linear_speed, "[m/s]"),
        ):
            if not MIN_SPEED <= speed <= high:
                raise ConfigError(
                    f"{name} must be in [{MIN_SPEED}, max_{name} = {high}] {unit}, got {speed!r}"
                )
        self.key_hold = float(key_hold)
        self.zero_duration = float(zero_duration)
        self.speed_step = float(speed_step)
        self.max_speeds = Speeds(float(max_angular_speed), float(max_linear_speed))
        self.speeds = Speeds(float(angular_speed), float(linear_speed))
        self.frame = TwistFrame.parse(frame)
        self.force_step, self.max_force = float(force_step), float(max_force)
        self.mode = Mode.CAMERA
        #: Force setpoint [N] in [0, max_force]; kept when force mode is left.
        self.force = 0.0
        self.quit_requested = False
        # Mode of the zeros owed (the mode the motion they stop was commanded in).
        self._zeros_mode = Mode.CAMERA
        # axis -> (sign, time of the newest press or repeat [s]); one entry per axis, so the
        # newest direction wins when both keys of a pair were pressed within key_hold.
        self._held: dict[int, tuple[int, float]] = {}
        # Zero commands still owed after motion: None = idle, else when the zeros started
        # (-inf: not started yet; the next tick starts them).
        self._zeros_since: float | None = None

    # --- input ----------------------------------------------------------------------------------
    @property
    def force_mode(self) -> bool:
        return self.mode is Mode.FORCE

    def press(self, key: str, now: float) -> KeyEvent:
        """Apply one key (a press or an auto-repeat) at monotonic time ``now`` [s]; the key's
        meaning depends on the mode (:data:`KEY_MAP`, :data:`FORCE_KEY_MAP`)."""
        binding = (FORCE_KEY_MAP if self.force_mode else KEY_MAP).get(key)
        if binding is None:
            return KeyEvent(key, None, False)
        before = (self.command(now), self.force)
        action = binding.action
        if action is Action.MOVE:
            self._held[binding.axis] = (binding.sign, now)
        elif action is Action.STOP:
            self._release_all()
        elif action is Action.FRAME:
            # New axes under a held key would swing the camera elsewhere mid-motion: stop first.
            self._release_all()
            self.frame = FRAME_CYCLE[(FRAME_CYCLE.index(self.frame) + 1) % len(FRAME_CYCLE)]
        elif action is Action.FASTER:
            self.speeds = self._scaled(self.speed_step)
        elif action is Action.SLOWER:
            self.speeds = self._scaled(1.0 / self.speed_step)
        elif action is Action.FORCE_MODE:
            # the motion stops (zeros in the frame of the mode left); the force stays
            self._release_all()
            self.mode = Mode.CAMERA if self.force_mode else Mode.FORCE
        elif action is Action.HARDER:
            self.force = min(self.force + self.force_step, self.max_force)
        elif action is Action.SOFTER:
            self.force = max(self.force - self.force_step, 0.0)
        else:
            self.quit_requested = True
            self._release_all()
        after = (self.command(now), self.force)
        urgent = after != before or action is Action.STOP
        return KeyEvent(key, binding, urgent)

    def _release_all(self) -> None:
        self._held.clear()
        self._zeros_mode = self.mode  # the zeros stop what was commanded in this mode
        # Always owe zeros after a stop, even when idle: the operator asked for a stop.
        self._zeros_since = float("-inf")

    def _scaled(self, factor: float) -> Speeds:
        return Speeds(
            min(max(self.speeds.angular * factor, MIN_SPEED), self.max_speeds.angular),
            min(max(self.speeds.linear * factor, MIN_SPEED), self.max_speeds.linear),
        )

    # --- output ---------------------------------------------------------------------------------
    def held_axes(self, now: float) -> dict[int, int]:
        """axis -> sign of every key still held at ``now`` [s]."""
        return {
            axis: sign for axis, (sign, last) in self._held.items() if now - last <= self.key_hold
        }

    def command(self, now: float) -> TeleopCommand:
        """The command at monotonic time ``now`` [s]: held axes at the current speeds, each
        vector scaled down to its maximum speed when combined keys would exceed it."""
        values = [0.0] * 6
        for axis, sign in self.held_axes(now).items():
            speed = self.speeds.angular if axis < 3 else self.speeds.linear
            values[axis] = sign * speed
        return TeleopCommand(
            limit_norm(values[:3], self.max_speeds.angular),
            limit_norm(values[3:], self.max_speeds.linear),
            self.frame,
            self.force_mode,
        )

    def tick(self, now: float) -> TeleopCommand | None:
        """What to publish at a rate tick at ``now`` [s]: the command while a key is held, then
        zeros for ``zero_duration``, then None (nothing) until the next key. The zeros are in
        the frame of the mode the stopped motion was commanded in (leaving force mode: the EE
        frame)."""
        self._held = {
            axis: entry
            for axis, entry in self._held.items()
            if now - entry[1] <= self.key_hold  # forget released keys
        }
        command = self.command(now)
        if not command.is_zero:
            self._zeros_since = float("-inf")
            self._zeros_mode = self.mode
            return command
        if self._zeros_since is None:
            return None
        command = dataclasses.replace(command, force_mode=self._zeros_mode is Mode.FORCE)
        if self._zeros_since == float("-inf"):
            self._zeros_since = now
        if now - self._zeros_since <= self.zero_duration:
            return command
        self._zeros_since = None
        return None

    @property
    def sending(self) -> bool:
        """True while :meth:`tick` returns commands (motion or trailing zeros)."""
        return self._zeros_since is not None

    def force_setpoint(self) -> float | None:
        """The force setpoint to publish at a tick [N]: :attr:`force` in force mode, else None
        (nothing: the controller holds the last one)."""
        return self.force if self.force_mode else None


def limit_norm(vector: Sequence[float], limit: float) -> tuple[float, ...]:
    """``vector`` scaled uniformly so that its Euclidean norm is at most ``limit``.

    Args:
        vector: components, any length (a twist's angular [rad/s] or linear [m/s] part).
        limit: largest allowed norm, same unit, >= 0.

    Returns:
        ``vector`` unchanged when its norm is within ``limit``, else ``vector * limit / norm``
        (same direction), rounded down if needed so that the norm never exceeds ``limit`` by
        an ulp (a controller with the same limit compares norms).

    Raises:
        ConfigError: ``limit`` negative or not finite.
    """
    if not (math.isfinite(limit) and limit >= 0.0):
        raise ConfigError(f"speed limit must be a finite number >= 0, got {limit!r}")
    values = tuple(float(v) for v in vector)
    norm = math.hypot(*values)
    if norm <= limit:
        return values
    scale = limit / norm
    scaled = tuple(v * scale for v in values)
    # as a receiver may compute the norm: hypot, or numpy's (rns_controller's check)
    while math.hypot(*scaled) > limit or float(np.linalg.norm(scaled)) > limit:
        scale = math.nextafter(scale, 0.0)
        scaled = tuple(v * scale for v in values)
    return scaled


def key_event_tap_angle(
    speed: float,
    command_timeout: float,
    stop_deceleration: float,
    start_acceleration: float = math.inf,
) -> float:
    """Angle one isolated command turns the camera under rns_controller's command gate [rad].

    A key-event teleop (upstream ``teleop_twist_keyboard``) publishes one twist per key press
    or auto-repeat and nothing in between; the controller applies the newest command until it
    is ``command_timeout`` (T) old, then ramps it to zero at ``stop_deceleration`` (a_stop).
    A controller that also ramps up from rest at ``start_acceleration`` (a_start) reaches
    v_peak = min(v, a_start T) by then. One tap at |omega| = v (``speed``) thus turns

        v_peak T - v_peak^2 / (2 a_start) + v_peak^2 / (2 a_stop)

    which is v T + v^2 / (2 a_stop) without a start ramp (a_start = inf, the default).
    rns_teleop_keyboard republishes at its rate and ends with zeros: this does not apply to it.

    Args:
        speed: |omega| of the command [rad/s], >= 0.
        command_timeout: the controller's ``command_timeout`` [s], > 0.
        stop_deceleration: the controller's ``stop_deceleration`` [rad/s^2], > 0.
        start_acceleration: its ramp-up from rest [rad/s^2], > 0; inf: none.

    Raises:
        ConfigError: a negative speed or a non-positive timeout, deceleration or acceleration.
    """
    if not (math.isfinite(speed) and speed >= 0.0):
        raise ConfigError(f"speed must be a finite number >= 0 [rad/s], got {speed!r}")
    for name, value, unit in (
        ("command_timeout", command_timeout, "[s]"),
        ("stop_deceleration", stop_deceleration, "[rad/s^2]"),
    ):
        if not (math.isfinite(value) and value > 0.0):
            raise ConfigError(f"{name} must be a finite number > 0 {unit}, got {value!r}")
    if not start_acceleration > 0.0:  # inf allowed: no ramp; NaN fails here too
        raise ConfigError(
            f"start_acceleration must be > 0 [rad/s^2] (inf: none), got {start_acceleration!r}"
        )
    peak = min(speed, start_acceleration * command_timeout)
    ramp_up = peak**2 / (2.0 * start_acceleration)  # 0 for inf
    return peak * command_timeout - ramp_up + peak**2 / (2.0 * stop_deceleration)


# --- terminal input -------------------------------------------------------------------------------
def split_keys(text: str) -> list[str]:
    """Split terminal input into keys: one character each, except escape sequences (arrow and
    function keys, Alt+key), which stay whole so that none of their characters acts as a key."""
    keys = []
    i = 0
    while i < len(text):
        if text[i] != "\x1b" or i + 1 >= len(text):
            keys.append(text[i])
            i += 1
            continue
        end = i + 2
        if text[i + 1] == "[":  # CSI: parameters, then one final byte in @..~
            while end < len(text) and not "@" <= text[end] <= "~":
                end += 1
            end += 1
        elif text[i + 1] == "O":  # SS3: one more character
            end += 1
        keys.append(text[i : min(end, len(text))])
        i = min(end, len(text))
    return keys


# --- panel ----------------------------------------------------------------------------------------
_LEVELS = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}


def status_line(
    status: ControllerStatus | None, now: float, topic: str, label: str = "controller"
) -> str:
    """One line describing a controller's newest status at monotonic time ``now`` [s],
    starting with ``label`` (``"controller"``; the force controller's: ``"force ctrl"``)."""
    if status is None:
        return f"{label}  no status yet on {topic}"
    detail = status.message.removeprefix(f"{status.state}:").strip()
    text = f"{label}  {status.state} [{_LEVELS.get(status.level, status.level)}]"
    if detail and detail != status.state:
        text += f"  {detail}"
    age = now - status.received
    if age > STATUS_STALE_AFTER:
        text += f"  (no update for {age:.1f} s)"
    return text


def _vector(values: Sequence[float]) -> str:
    return "  ".join(f"{name} {value:+.3f}" for name, value in zip("xyz", values, strict=True))


def render_panel(
    command: TeleopCommand,
    speeds: Speeds,
    status: str,
    *,
    frame_id: str = "",
    sending: bool = False,
    last_key: KeyEvent | None = None,
    help_lines: Sequence[str] | None = None,
    force: float | None = None,
    force_step: float = 1.0,
    max_force: float = 20.0,
    force_status: str | None = None,
) -> list[str]:
    """Panel text, one string per line (no escape codes, at most 80 columns plus the status).

    Args:
        command: the command now (its frame, or force mode, is shown).
        speeds: current speeds.
        status: the controller line (:func:`status_line`).
        frame_id: header.frame_id sent for ``command`` (the EE frame in force mode).
        sending: whether twists are being published.
        last_key: the newest key, shown with what it did.
        help_lines: key help; default :data:`KEY_HELP`, :data:`FORCE_KEY_HELP` in force mode.
        force: the force setpoint [N] (None: no force line); sent while in force mode.
        force_step, max_force: the push key step and the upper bound [N], shown.
        force_status: the force controller line (:func:`status_line`), or None (not shown).
    """
    frames = " -> ".join(frame.value for frame in FRAME_CYCLE)
    if last_key is None:
        key_text = "-"
    else:
        label = last_key.binding.label if last_key.binding else "ignored"
        key_text = f"{last_key.key!r} {label}"
    if not sending:
        activity = "idle (nothing published)"
    elif command.is_zero:
        activity = "sending zero"
    else:
        activity = "sending"
    if command.force_mode:
        title = "rns_teleop_keyboard  FORCE MODE: EE motion + force setpoint"
        mode = "force (m: back to camera mode)"
        frame = f"EE (frame_id '{frame_id}')   keys move along EE x / y"
        help_lines = FORCE_KEY_HELP if help_lines is None else help_lines
    else:
        title = "rns_teleop_keyboard  reactionless camera teleop"
        mode = "camera (m: force mode)"
        frame = f"{command.frame.value} (frame_id '{frame_id}')   f cycles {frames}"
        help_lines = KEY_HELP if help_lines is None else help_lines
    lines = [
        title,
        "",
        f"mode      {mode}",
        f"frame     {frame}",
        f"speed     angular {speeds.angular:.3f} rad/s   linear {speeds.linear:.3f} m/s",
        f"angular   {_vector(command.angular)}  [rad/s]",
        f"linear    {_vector(command.linear)}  [m/s]",
        f"cmd_twist {activity}",
    ]
    if force is not None:
        limits = f"(+/- {force_step:g} N, 0..{max_force:g} N)"
        if command.force_mode:
            lines.append(f"force     setpoint {force:.3f} N along EE z {limits}, sending")
        else:
            lines.append(f"force     setpoint {force:.3f} N, not sent (held by the controller)")
    lines += [f"last key  {key_text}", status]
    if force_status is not None:
        lines.append(force_status)
    return [*lines, "", *help_lines]
