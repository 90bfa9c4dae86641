"""The SpaceMouse device layer of ``rns_teleop_spacemouse``: a small protocol the node reads, and
its implementation on pyspacemouse (raw HID through hidapi: no 3Dconnexion driver, no spacenavd).

pyspacemouse is imported only when a device is opened, so the node module (and its tests, with a
scripted device) import without it. Every way opening can fail is a :class:`DeviceError` whose
one-line message says how to fix it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Protocol

from rns_ros.control.spacemouse import SpaceMouseReading
from rns_ros.core.errors import RnsError

#: udev rule that lets the logged-in user read 3Dconnexion devices (vendor ids 256f and, for the
#: older ones, Logitech's 046d) through hidraw.
UDEV_RULE = 'KERNEL=="hidraw*", ATTRS{idVendor}=="256f|046d", MODE="0666"'
#: The fix of a missing device or permission, one line.
UDEV_FIX = (
    f"plug it in; if it is plugged in, allow hidraw access: echo '{UDEV_RULE}' | sudo tee "
    "/etc/udev/rules.d/99-spacemouse.rules && sudo udevadm control --reload && "
    "sudo udevadm trigger, then replug it"
)
#: Reports read per tick at most: the device queues one report per axis group and button change,
#: and reading fewer than arrive would let the queue (and the latency) grow.
MAX_REPORTS_PER_READ = 64


class DeviceError(RnsError):
    """The SpaceMouse cannot be opened or read (the message says how to fix it)."""


class SpaceMouseDevice(Protocol):
    """What the node needs of a device."""

    def read(self) -> SpaceMouseReading:
        """The newest state (every report queued since the last call consumed).

        Raises:
            DeviceError: the device is gone.
        """
        ...

    def close(self) -> None: ...


class PySpaceMouseDevice:
    """A SpaceMouse opened with pyspacemouse (ROS axis convention: x forward, y left, z up).

    Args:
        path: hidraw path (``/dev/hidraw3``), or "" for the first supported device found.
        clock: monotonic time [s] of the reports.

    Raises:
        DeviceError: pyspacemouse or hidapi missing, no device, no permission.
    """

    def __init__(self, path: str = "", clock: Callable[[], float] = time.monotonic) -> None:
        try:
            import pyspacemouse
        except ImportError as exc:
            raise DeviceError(
                f"pyspacemouse does not import ({exc}): pip install -r requirements.txt"
            ) from None
        self._clock = clock
        convention = pyspacemouse.AxisConvention.ROS
        try:
            if path:
                self._device = pyspacemouse.open_by_path(path, axis_convention=convention)
            else:
                self._device = pyspacemouse.open(axis_convention=convention)
        except (RuntimeError, ValueError, FileNotFoundError, OSError) as exc:
            raise DeviceError(open_failure_text(str(exc), path)) from None
        self._reported = -float("inf")
        self._last_t = None

    def read(self) -> SpaceMouseReading:
        try:
            state = None
            for _ in range(MAX_REPORTS_PER_READ):
                state = self._device.read()
                if state.t == self._last_t:
                    break  # the queue is empty
                self._last_t = state.t
                self._reported = self._clock()
        except Exception as exc:  # easyhid's HIDException derives from Exception only
            raise DeviceError(f"SpaceMouse read failed: {exc}") from None
        return SpaceMouseReading(
            (state.x, state.y, state.z),
            (state.roll, state.pitch, state.yaw),
            tuple(bool(b) for b in state.buttons),
            self._reported,
        )

    def close(self) -> None:
        self._device.close()


def open_failure_text(reason: str, path: str = "") -> str:
    """The one-line message of a device that did not open, with its fix, from pyspacemouse's
    ``reason``."""
    if "HID API" in reason:
        return (
            "the hidapi library is missing (pyspacemouse reads the device through it): "
            "sudo apt-get install libhidapi-hidraw0"
        )
    if "Failed to open" in reason or "ermission" in reason:
        return f"SpaceMouse found but not readable ({reason}): {UDEV_FIX}"
    found = f"no SpaceMouse at {path}" if path else "no SpaceMouse found"
    return f"{found} ({reason}): {UDEV_FIX}"
