"""SpaceMouse teleoperation logic of ``rns_teleop_spacemouse``: dead zone, scaling, buttons,
watchdog.

Pure Python (never rclpy or a HID library): the node feeds device readings and monotonic times in
and publishes what comes out.

* Each axis a in [-1, 1] (the cap's deflection, the device's full scale 1) passes a dead zone d
  that keeps the output continuous: a' = sign(a) max(|a| - d, 0) / (1 - d). The rotation axes
  give omega = ``angular_scale`` a', the translation axes v = ``linear_scale`` a'; each vector is
  then bounded by its scale as a whole (direction kept), so a full twist about two axes at once
  commands |omega| = ``angular_scale``, not sqrt(2) times it.
* A press of the frame button cycles the command frame camera -> world -> base; a press of the
  pause button pauses (zero twist) or resumes. After either, and after the watchdog tripped, the
  output stays zero until the cap is back inside the dead zone: a deflection held through a
  change never starts a motion about another axis or after a pause.
* Watchdog: a device that deflects but sends no report for ``device_timeout`` (unplugged,
  stalled) counts as silent: zero twist, as a released cap.
* Publishing follows rns_teleop_keyboard: a moving command every tick, then zeros for
  ``zero_duration`` after it stops, then nothing (the controller idles on its own timeout).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from rns_ros.control.controller import TwistFrame
from rns_ros.core.errors import ConfigError

#: Order of the frame button's cycle (as rns_teleop_keyboard's f key).
FRAME_CYCLE = (TwistFrame.CAMERA, TwistFrame.WORLD, TwistFrame.BASE)


@dataclass(frozen=True)
class SpaceMouseReading:
    """The device's newest state.

    Attributes:
        translation: cap displacement x, y, z, full scale 1 [-], (3,).
        rotation: cap rotation about x, y, z (roll, pitch, yaw), full scale 1 [-], (3,).
        buttons: pressed state of each button.
        received: monotonic time of the newest report from the device [s]; -inf when none came.
    """

    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    buttons: tuple[bool, ...] = ()
    received: float = -np.inf


class Mode(StrEnum):
    """What the teleop sends."""

    MOVING = "MOVING"  # a twist from the cap
    CENTRED = "CENTRED"  # cap inside the dead zone: zero
    PAUSED = "PAUSED"  # pause button: zero until pressed again
    RECENTRE = "RECENTRE"  # after a frame change, a resume or a silent device: zero until centred
    DEVICE_SILENT = "DEVICE_SILENT"  # deflected but no report for device_timeout: zero


@dataclass(frozen=True)
class SpaceMouseCommand:
    """One tick's twist.

    Attributes:
        angular: [rad/s], (3,); linear: [m/s], (3,), both in ``frame`` axes.
        frame: the command frame.
        mode: why it is what it is.
    """

    angular: tuple[float, float, float]
    linear: tuple[float, float, float]
    frame: TwistFrame
    mode: Mode

    @property
    def moving(self) -> bool:
        return any(self.angular) or any(self.linear)


def dead_zone(value: float, width: float) -> float:
    """sign(a) max(|a| - d, 0) / (1 - d), a clipped to [-1, 1]: zero inside the dead zone,
    continuous at its edge, full scale at |a| = 1."""
    magnitude = min(abs(float(value)), 1.0) - width
    if magnitude <= 0.0:
        return 0.0
    return float(np.copysign(magnitude / (1.0 - width), value))


def _bounded(vector: list[float], scale: float) -> tuple[float, float, float]:
    """scale * vector, its norm bounded by scale (direction kept)."""
    out = np.asarray(vector, dtype=float) * scale
    norm = float(np.linalg.norm(out))
    if norm > scale:
        out *= scale / norm
    return tuple(float(x) for x in out)


@dataclass(frozen=True)
class SpaceMouseSettings:
    """Settings of :class:`SpaceMouseTeleop` (the node's parameters of the same names)."""

    angular_scale: float = 0.2
    linear_scale: float = 0.0
    dead_zone: float = 0.1
    device_timeout: float = 0.5
    zero_duration: float = 0.5
    frame_button: int = 0
    pause_button: int = 1

    def __post_init__(self) -> None:
        if not 0.0 <= self.dead_zone < 1.0:
            raise ConfigError(f"dead_zone must be in [0, 1), got {self.dead_zone!r}")
        if self.frame_button == self.pause_button and self.frame_button >= 0:
            raise ConfigError(f"frame_button and pause_button are both {self.frame_button}")


class SpaceMouseTeleop:
    """Readings in, twists out (module docstring).

    Args:
        settings: scales, dead zone, timing, buttons.
        frame: the command frame at start.
    """

    def __init__(
        self, settings: SpaceMouseSettings | None = None, frame: TwistFrame = TwistFrame.CAMERA
    ) -> None:
        self.settings = settings or SpaceMouseSettings()
        self.frame = TwistFrame.parse(frame)
        self.paused = False
        self._armed = True  # False: wait for the cap inside the dead zone
        self._buttons: tuple[bool, ...] = ()
        self._zeros_until: float | None = None  # zeros are sent until then [s]
        self.events: list[str] = []  # what changed at the last update, for the log

    def _pressed(self, buttons: tuple[bool, ...], index: int) -> bool:
        """Button ``index`` went down since the previous reading."""
        if not 0 <= index < len(buttons):
            return False
        before = self._buttons[index] if index < len(self._buttons) else False
        return bool(buttons[index]) and not before

    def update(self, reading: SpaceMouseReading, now: float) -> SpaceMouseCommand | None:
        """The command to publish at monotonic time ``now`` [s], or None (nothing to send)."""
        settings = self.settings
        self.events = []
        if self._pressed(reading.buttons, settings.frame_button):
            index = FRAME_CYCLE.index(self.frame) if self.frame in FRAME_CYCLE else -1
            self.frame = FRAME_CYCLE[(index + 1) % len(FRAME_CYCLE)]
            self._armed = False
            self.events.append(f"frame {self.frame.value}")
        if self._pressed(reading.buttons, settings.pause_button):
            self.paused = not self.paused
            self._armed = False
            self.events.append("paused" if self.paused else "resumed")
        self._buttons = tuple(bool(b) for b in reading.buttons)
        rotation = [dead_zone(a, settings.dead_zone) for a in reading.rotation]
        translation = [dead_zone(a, settings.dead_zone) for a in reading.translation]
        deflected = any(rotation) or any(translation)
        if not deflected:
            self._armed = True
        if self.paused:
            mode = Mode.PAUSED
        elif deflected and now - reading.received > settings.device_timeout:
            if self._armed:
                self.events.append("device silent while deflected: zero twist")
            self._armed = False
            mode = Mode.DEVICE_SILENT
        elif not deflected:
            mode = Mode.CENTRED
        elif not self._armed:
            mode = Mode.RECENTRE
        else:
            mode = Mode.MOVING
        if mode is Mode.MOVING:
            self._zeros_until = now + settings.zero_duration
            return SpaceMouseCommand(
                _bounded(rotation, settings.angular_scale),
                _bounded(translation, settings.linear_scale),
                self.frame,
                mode,
            )
        if self.events and self._zeros_until is None:
            self._zeros_until = now + settings.zero_duration  # a change: confirm it with zeros
        if self._zeros_until is None or now > self._zeros_until:
            self._zeros_until = None
            return None
        return SpaceMouseCommand((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), self.frame, mode)
