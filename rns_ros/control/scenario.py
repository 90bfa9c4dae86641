"""Inspection scenarios (``config/scenarios/*.yaml``): a camera rotation commanded over time.

A scenario is the thesis' test case of section 4.2.2 / 4.3: initial joint angles, then the camera
angular velocity omega(t) = angle * s_dot(t) * axis about a fixed axis expressed in ``frame``
axes. Keys (all validated; unknown keys are rejected by name):

    name: text                          (default: file stem)
    description: text
    initial_joint_positions_deg: [n numbers]   [deg]
    frame: world | base | camera        (default world)
    axis: [x, y, z]                     (normalised; must be non-zero)
    angle_deg: total rotation           [deg], may be negative
    duration: command duration          [s], > 0
    time_scaling: quintic | constant | piecewise   (default quintic; constant: angle / duration)
    segments: [[duration_s, fraction], ...]   piecewise only: constant rate in each segment,
                                        durations summing to ``duration``, fractions of the
                                        angle summing to 1 (a fraction may be 0: a pause)
    controller: {method, wrist_gain, epsilon, lambda2_max, sc_gain, max_angular_speed,
                 tracking_gain}         (controller overrides, optional; rns_demo in
                                        lockstep runs the thesis' law, tracking_gain 0,
                                        on the wall clock the node's default, unless set)

The peak commanded speed is known before anything runs (:meth:`Scenario.peak_angular_speed`):
|angle| * max s_dot, i.e. 15/8 |angle| / duration for quintic, |angle| / duration for constant,
max |fraction| * |angle| / segment duration for piecewise. :func:`check_speed_limit` compares it
with the controller's ``max_angular_speed``: a controller rejects (or clips) faster commands, so
such a scenario would not play as written.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from rns_ros.control.camera_law import ControlGains, Method
from rns_ros.control.controller import TwistFrame
from rns_ros.core.config import check_keys, read_yaml_mapping
from rns_ros.core.errors import ConfigError, InputError
from rns_ros.core.timing import QUINTIC_PEAK_RATE, quintic
from rns_ros.core.validation import Choice, as_vector, positive, short_repr

_KEYS = {
    "name",
    "description",
    "initial_joint_positions_deg",
    "frame",
    "axis",
    "angle_deg",
    "duration",
    "time_scaling",
    "segments",
    "controller",
}
_REQUIRED = ("initial_joint_positions_deg", "axis", "angle_deg", "duration")
#: Controller settings a scenario may override, with their types.
CONTROLLER_OVERRIDES = {
    "method": str,
    "wrist_gain": float,
    "epsilon": float,
    "lambda2_max": float,
    "sc_gain": float,
    "max_angular_speed": float,
    "tracking_gain": float,
}
#: Overrides that are controller-node settings rather than :class:`ControlGains` fields.
_NOT_GAINS = {"method", "max_angular_speed", "tracking_gain"}


class TimeScaling(Choice):
    """Shape of the rotation angle over time."""

    __label__ = "time_scaling"

    QUINTIC = "quintic"
    CONSTANT = "constant"
    PIECEWISE = "piecewise"


@dataclass(frozen=True)
class Scenario:
    """One inspection scenario.

    Attributes:
        name: identifier.
        initial_theta: initial joint angles [rad], shape (n,).
        frame: axes of ``axis``.
        axis: unit rotation axis, shape (3,).
        angle: total rotation [rad].
        duration: command duration [s].
        time_scaling: :class:`TimeScaling`.
        controller: overrides of controller settings (keys of CONTROLLER_OVERRIDES).
        description: free text.
        segments: piecewise scaling only: (duration [s], fraction [-]) pairs.
    """

    name: str
    initial_theta: np.ndarray
    frame: TwistFrame
    axis: np.ndarray
    angle: float
    duration: float
    time_scaling: TimeScaling = TimeScaling.QUINTIC
    controller: dict = field(default_factory=dict)
    description: str = ""
    segments: tuple[tuple[float, float], ...] = ()

    def progress(self, t: float) -> tuple[float, float]:
        """(s [-], s_dot [1/s]) of the time scaling at time t [s]; s = 1 after the end."""
        if self.time_scaling is TimeScaling.QUINTIC:
            return quintic(t, self.duration)
        if self.time_scaling is TimeScaling.PIECEWISE:
            return _piecewise(self.segments, t)
        inside = 0.0 <= t < self.duration
        return min(max(t / self.duration, 0.0), 1.0), (1.0 / self.duration if inside else 0.0)

    def peak_angular_speed(self) -> float:
        """Largest commanded |omega(t)| over the profile [rad/s], from the time scaling
        analytically: quintic 15/8 * |angle| / duration (at t = duration / 2), constant
        |angle| / duration, piecewise max over segments of |fraction| * |angle| / segment
        duration."""
        if self.time_scaling is TimeScaling.QUINTIC:
            peak_rate = QUINTIC_PEAK_RATE / self.duration
        elif self.time_scaling is TimeScaling.PIECEWISE:
            peak_rate = max(abs(fraction) / duration for duration, fraction in self.segments)
        else:
            peak_rate = 1.0 / self.duration
        return abs(self.angle) * peak_rate

    def angular_velocity(self, t: float) -> np.ndarray:
        """Commanded camera angular velocity at t, ``frame`` axes [rad/s], shape (3,)."""
        return self.angle * self.progress(t)[1] * self.axis

    def target_rotation(self, camera_0: np.ndarray, base_0: np.ndarray, t: float) -> np.ndarray:
        """Camera orientation the command asks for at t, given the initial camera and base
        rotations (world <- frame, (3, 3)); the base is assumed not to turn."""
        turn = pin.exp3(self.angle * self.progress(t)[0] * self.axis)
        if self.frame is TwistFrame.WORLD:
            return turn @ camera_0
        if self.frame is TwistFrame.CAMERA:
            return camera_0 @ turn
        return base_0 @ turn @ base_0.T @ camera_0

    def gains(self, base: ControlGains | None = None) -> ControlGains:
        """``base`` gains (thesis values by default) with this scenario's overrides applied."""
        base = base or ControlGains()
        values = {key: value for key, value in self.controller.items() if key not in _NOT_GAINS}
        return ControlGains(**{**base.__dict__, **values})

    def method(self, default: Method | str = Method.DLS) -> Method:
        """The scenario's method override, else ``default``."""
        return Method.parse(str(self.controller.get("method", default)))


def check_speed_limit(scenario: Scenario, max_angular_speed: float) -> float:
    """Check that ``scenario`` never commands more than the controller's limit.

    Args:
        scenario: the scenario; its own ``controller.max_angular_speed`` override, when given,
            replaces ``max_angular_speed`` (the scenario's controller runs with it).
        max_angular_speed: the controller's ``max_angular_speed`` otherwise [rad/s], > 0.

    Returns:
        The limit that applies [rad/s].

    Raises:
        ConfigError: the peak speed (:meth:`Scenario.peak_angular_speed`) exceeds the limit;
            the message names the scenario, its peak, the limit and the shortest duration that
            would fit.
    """
    limit = positive(
        scenario.controller.get("max_angular_speed", max_angular_speed),
        "max_angular_speed",
        "[rad/s]",
    )
    peak = scenario.peak_angular_speed()
    if peak > limit:
        shortest = scenario.duration * peak / limit
        raise ConfigError(
            f"scenario {scenario.name!r}: peak angular speed {peak:.4g} rad/s "
            f"({scenario.time_scaling.value}, {np.rad2deg(scenario.angle):.4g} deg in "
            f"{scenario.duration:.4g} s) exceeds the controller's max_angular_speed "
            f"{limit:.4g} rad/s; make 'duration' at least {shortest:.4g} s or override "
            "controller.max_angular_speed"
        )
    return limit


def _piecewise(segments, t: float) -> tuple[float, float]:
    done = 0.0
    for duration, fraction in segments:
        if t < duration:
            rate = fraction / duration
            return done + rate * max(t, 0.0), (rate if t >= 0.0 else 0.0)
        t -= duration
        done += fraction
    return 1.0, 0.0


def _segments(value, duration: float, where: str) -> tuple[tuple[float, float], ...]:
    try:
        segments = tuple((float(d), float(f)) for d, f in value)
    except (TypeError, ValueError, OverflowError):
        raise ConfigError(
            f"{where}: 'segments' must be a list of [duration_s, fraction] pairs, got "
            f"{short_repr(value)}"
        ) from None
    if not segments or any(not (d > 0.0 and np.isfinite(d)) for d, _ in segments):
        raise ConfigError(f"{where}: 'segments' durations must be > 0 s, got {short_repr(value)}")
    if any(not np.isfinite(f) for _, f in segments):
        raise ConfigError(f"{where}: 'segments' fractions must be finite, got {short_repr(value)}")
    total_time = sum(d for d, _ in segments)
    total_fraction = sum(f for _, f in segments)
    if abs(total_time - duration) > 1e-9 * max(duration, 1.0):
        raise ConfigError(
            f"{where}: 'segments' durations sum to {total_time} s, 'duration' is {duration} s"
        )
    if abs(total_fraction - 1.0) > 1e-9:
        raise ConfigError(f"{where}: 'segments' fractions sum to {total_fraction}, must be 1")
    return segments


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario YAML file (see the module docstring for keys)."""
    path, content = read_yaml_mapping(path, _KEYS, "scenario file")
    where = str(path)
    missing = [key for key in _REQUIRED if key not in content]
    if missing:
        raise ConfigError(f"{where}: missing key(s) {missing}")
    try:
        theta = np.deg2rad(
            as_vector(
                content["initial_joint_positions_deg"],
                len(content["initial_joint_positions_deg"]),
                "initial_joint_positions_deg",
            )
        )
        axis = as_vector(content["axis"], 3, "axis")
        angle = np.deg2rad(float(content["angle_deg"]))
        duration = float(content["duration"])
    except (InputError, TypeError, ValueError, OverflowError) as exc:
        raise ConfigError(f"{where}: {exc}") from exc
    if np.linalg.norm(axis) < 1e-9:
        raise ConfigError(f"{where}: 'axis' must be non-zero, got {axis.tolist()}")
    if not (np.isfinite(angle) and np.isfinite(duration) and duration > 0.0):
        raise ConfigError(
            f"{where}: 'duration' must be > 0 s and 'angle_deg' finite, got "
            f"{short_repr(content['duration'])}, {short_repr(content['angle_deg'])}"
        )
    scaling = TimeScaling.parse(content.get("time_scaling", "quintic"))
    if (scaling is TimeScaling.PIECEWISE) != ("segments" in content):
        raise ConfigError(f"{where}: 'segments' is required with, and only with, piecewise scaling")
    segments = (
        _segments(content["segments"], duration, where) if scaling is TimeScaling.PIECEWISE else ()
    )
    controller = content.get("controller") or {}
    if not isinstance(controller, dict):
        raise ConfigError(f"{where}: 'controller' must be a mapping, got {short_repr(controller)}")
    check_keys(controller, set(CONTROLLER_OVERRIDES), f"{where}: controller")
    try:
        controller = {key: CONTROLLER_OVERRIDES[key](value) for key, value in controller.items()}
        if "max_angular_speed" in controller:
            positive(controller["max_angular_speed"], "controller.max_angular_speed", "[rad/s]")
        scenario = Scenario(
            name=str(content.get("name", path.stem)),
            initial_theta=theta,
            frame=TwistFrame.parse(content.get("frame", "world")),
            axis=axis / np.linalg.norm(axis),
            angle=float(angle),
            duration=duration,
            time_scaling=scaling,
            controller=controller,
            description=str(content.get("description", "")),
            segments=segments,
        )
        scenario.gains()
        scenario.method()
    except (ConfigError, TypeError, ValueError) as exc:
        raise ConfigError(f"{where}: {exc}") from exc
    return scenario
