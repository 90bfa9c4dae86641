"""Parameter files for the standard key-event teleop (upstream teleop_twist_keyboard): within
rns_controller's parameter ranges, upstream parameter names only, headroom below the controller's
limit, and the documented one-tap arithmetic checked against the controller's command gate."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from rns_ros.control.controller import TwistFrame
from rns_ros.control.teleop import CommandGate, TwistCommand
from rns_ros.core.errors import ConfigError
from rns_ros.keyboard import key_event_tap_angle
from rns_ros.nodes.controller_parameters import SPECS

REPO = Path(__file__).resolve().parents[1]
DOC = (REPO / "docs" / "teleop.md").read_text()
#: X11's default auto-repeat delay [s] (`xset q`: "auto repeat delay: 660").
X11_REPEAT_DELAY = 0.66
#: X11's default auto-repeat rate [Hz].
X11_REPEAT_RATE = 25.0
#: ros2/teleop_twist_keyboard 2.4.1 declares exactly these (stamped, frame_id since 2.4.0;
#: speed, turn since 2.4.1); it ignores any other name without a word.
UPSTREAM_PARAMETERS = {"stamped": bool, "frame_id": str, "speed": float, "turn": float}
#: Upstream speed keys: 'e' / 'q' multiply the turn rate by this.
UPSTREAM_SPEED_UP = 1.1
#: The upstream turn rate before 2.4.1 (hard-coded) [rad/s].
UPSTREAM_DEFAULT_TURN = 1.0
PERIOD = 0.01  # controller period [s]


def _parameters(name: str) -> dict:
    return yaml.safe_load((REPO / "config" / name).read_text())["/**"]["ros__parameters"]


KEY_TELEOP = _parameters("controller_key_teleop.yaml")
KEYBOARD = _parameters("teleop_twist_keyboard.yaml")
DEFAULTS = {name: SPECS[name].default for name in ("command_timeout", "stop_deceleration")}
#: The controller's ramp-up from rest [rad/s^2].
START_ACCELERATION = SPECS["start_acceleration"].default


def _gate(settings: dict) -> CommandGate:
    """The gate as rns_controller builds it from these settings."""
    return CommandGate(
        settings["command_timeout"],
        settings["stop_deceleration"],
        acceleration=settings.get("start_acceleration", START_ACCELERATION),
    )


def test_key_teleop_controller_file_overrides_only_timeout_and_stop_within_range():
    assert set(KEY_TELEOP) == {"command_timeout", "stop_deceleration"}
    for name, value in KEY_TELEOP.items():
        spec = SPECS[name]
        assert type(value) is type(spec.default), name  # a params file must match the type
        assert spec.low <= value <= spec.high, name
    assert KEY_TELEOP["command_timeout"] > X11_REPEAT_DELAY
    assert DEFAULTS["command_timeout"] < X11_REPEAT_DELAY  # why the file exists
    assert KEY_TELEOP["stop_deceleration"] > DEFAULTS["stop_deceleration"]


def test_teleop_twist_keyboard_file_uses_upstream_names_and_leaves_headroom():
    assert set(KEYBOARD) <= set(UPSTREAM_PARAMETERS), "upstream would ignore the others"
    for name, value in KEYBOARD.items():
        assert type(value) is UPSTREAM_PARAMETERS[name], name
    assert KEYBOARD["stamped"] is True
    assert KEYBOARD["frame_id"] in {"world", "base_link", "camera"}
    limit = SPECS["max_angular_speed"].default
    assert 0.0 < KEYBOARD["turn"] <= limit / 4
    # speed-up presses before a command exceeds the limit (the old start needed none)
    presses = math.floor(math.log(limit / KEYBOARD["turn"]) / math.log(UPSTREAM_SPEED_UP)) + 1
    assert presses >= 10
    assert limit < UPSTREAM_DEFAULT_TURN * UPSTREAM_SPEED_UP  # before 2.4.1: one press over
    assert KEYBOARD["speed"] > 0.0


def _gate_run(speed: float, settings: dict, key_times, end: float) -> np.ndarray:
    """|omega| [rad/s] the controller's gate outputs every PERIOD from 0 to ``end`` [s] for
    one yaw message of |omega| = ``speed`` per key event at ``key_times`` [s]."""
    gate = _gate(settings)
    pending = sorted(key_times)
    speeds = []
    for t in np.arange(0.0, end, PERIOD):
        while pending and pending[0] <= t + 1e-12:
            received = pending.pop(0)
            gate.accept(
                TwistCommand(np.array([0, 0, speed]), np.zeros(3), TwistFrame.CAMERA, received)
            )
        speeds.append(np.linalg.norm(gate.update(t, PERIOD).angular))
    return np.array(speeds)


@pytest.mark.parametrize(
    ("speed", "settings", "start_acceleration", "documented_deg"),
    [
        # before the controller's start ramp: the issue (defaults, turn after two 'c' presses)
        (0.81, DEFAULTS, math.inf, 42.0),
        (UPSTREAM_DEFAULT_TURN, DEFAULTS, math.inf, 57.3),  # the upstream start before 2.4.1
        (0.81, DEFAULTS, START_ACCELERATION, 14.3),
        (KEYBOARD["turn"], KEY_TELEOP, START_ACCELERATION, 7.7),  # the shipped files
        (KEYBOARD["turn"], KEY_TELEOP, math.inf, 8.9),
        (0.1, KEY_TELEOP, START_ACCELERATION, 4.1),  # "for finer steps"
    ],
)
def test_documented_tap_angles(speed, settings, start_acceleration, documented_deg):
    timeout, deceleration = settings["command_timeout"], settings["stop_deceleration"]
    angle = key_event_tap_angle(speed, timeout, deceleration, start_acceleration)
    if start_acceleration == math.inf:
        assert angle == pytest.approx(speed * timeout + speed**2 / (2 * deceleration))
    text = f"{math.degrees(angle):.1f} deg"
    assert text == f"{documented_deg:.1f} deg"
    assert text in DOC


def test_the_shipped_tap_angle_is_quoted_consistently():
    angle = key_event_tap_angle(
        KEYBOARD["turn"],
        KEY_TELEOP["command_timeout"],
        KEY_TELEOP["stop_deceleration"],
        START_ACCELERATION,
    )
    text = f"{math.degrees(angle):.1f} deg"
    for path in (
        "docs/ros2_integration.md",
        "config/teleop_twist_keyboard.yaml",
        "config/controller_key_teleop.yaml",
    ):
        assert text in (REPO / path).read_text(), path


@pytest.mark.parametrize(
    ("speed", "settings"),
    [(KEYBOARD["turn"], KEY_TELEOP), (0.81, DEFAULTS), (UPSTREAM_DEFAULT_TURN, DEFAULTS)],
)
def test_tap_angle_is_what_the_controller_gate_turns(speed, settings):
    """One message at t = 0 through rns_controller's own gate, integrated per period."""
    timeout, deceleration = settings["command_timeout"], settings["stop_deceleration"]
    angle = key_event_tap_angle(speed, timeout, deceleration, START_ACCELERATION)
    gated = _gate_run(speed, settings, [0.0], end=timeout + speed / deceleration + 0.5)
    assert gated.sum() * PERIOD == pytest.approx(angle, abs=2 * speed * PERIOD)
    assert gated[-1] == 0.0


def test_a_held_key_is_never_slowed_down_with_the_key_teleop_file():
    """X11: press, first repeat after 660 ms, then 25 Hz. With the default 0.5 s timeout the
    command ramps down from 0.5 s to 0.66 s (0.2 -> 0.04 rad/s); with 0.75 s it stays (after
    any ramp-up from rest, done by 0.3 s)."""
    speed = KEYBOARD["turn"]
    keys = [0.0, *np.arange(X11_REPEAT_DELAY, 2.0, 1.0 / X11_REPEAT_RATE)]
    held = slice(round(0.3 / PERIOD), round(2.0 / PERIOD))
    with_file = _gate_run(speed, KEY_TELEOP, keys, end=2.0)[held]
    assert with_file.min() == speed
    default = _gate_run(speed, DEFAULTS, keys, end=2.0)[held]
    assert default.min() == pytest.approx(
        speed - DEFAULTS["stop_deceleration"] * (X11_REPEAT_DELAY - 0.5), abs=0.011
    )


@pytest.mark.parametrize(
    ("arguments", "message"),
    [((-0.1, 0.5, 1.0), "speed"), ((0.1, 0.0, 1.0), "command_timeout"),
     ((0.1, 0.5, math.nan), "stop_deceleration")],
)  # fmt: skip
def test_tap_angle_rejects_bad_settings(arguments, message):
    with pytest.raises(ConfigError, match=message):
        key_event_tap_angle(*arguments)
