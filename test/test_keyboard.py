"""Key-hold state machine, key map and panel of the keyboard teleop (no DDS, no terminal)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rns_ros.control.controller import TwistFrame
from rns_ros.core.errors import ConfigError
from rns_ros.keyboard import (
    FORCE_KEY_HELP,
    FORCE_KEY_MAP,
    KEY_HELP,
    KEY_MAP,
    MIN_SPEED,
    Action,
    Binding,
    ControllerStatus,
    KeyboardTeleop,
    Mode,
    Speeds,
    TeleopCommand,
    limit_norm,
    render_panel,
    split_keys,
    status_line,
)

HOLD = 0.6  # [s]
ZEROS = 0.5  # [s]
SETTINGS = {
    "angular_speed": 0.1,
    "linear_speed": 0.05,
    "key_hold": HOLD,
    "zero_duration": ZEROS,
    "speed_step": 1.25,
    "max_angular_speed": 1.0,
    "max_linear_speed": 0.5,
}
ZERO3 = (0.0, 0.0, 0.0)


def teleop(**overrides) -> KeyboardTeleop:
    return KeyboardTeleop(**{**SETTINGS, **overrides})


def auto_repeat(keys: KeyboardTeleop, key: str, start: float, delay: float, stop: float) -> float:
    """A held key as a terminal sends it: press, first repeat after ``delay``, then 30 Hz up to
    ``stop`` [s]; returns the time of the newest repeat [s]."""
    keys.press(key, start)
    last = start
    t = start + delay
    while t <= stop:
        keys.press(key, t)
        last = t
        t += 1.0 / 30.0
    return last


@pytest.mark.parametrize(
    ("key", "angular", "linear"),
    [
        ("q", (0.1, 0, 0), ZERO3),
        ("e", (-0.1, 0, 0), ZERO3),
        ("w", (0, 0.1, 0), ZERO3),
        ("s", (0, -0.1, 0), ZERO3),
        ("a", (0, 0, 0.1), ZERO3),
        ("d", (0, 0, -0.1), ZERO3),
        ("i", ZERO3, (0.05, 0, 0)),
        ("k", ZERO3, (-0.05, 0, 0)),
        ("j", ZERO3, (0, 0.05, 0)),
        ("l", ZERO3, (0, -0.05, 0)),
        ("u", ZERO3, (0, 0, 0.05)),
        ("o", ZERO3, (0, 0, -0.05)),
    ],
)
def test_each_motion_key_drives_one_axis_with_its_sign(key, angular, linear):
    keys = teleop()
    event = keys.press(key, 0.0)
    assert event.binding.action is Action.MOVE
    assert event.urgent  # a start is published at once
    assert keys.command(0.1) == TeleopCommand(angular, linear, TwistFrame.CAMERA)


def test_auto_repeat_gaps_shorter_than_key_hold_keep_the_command():
    keys = teleop()
    # initial auto-repeat delay 0.55 s < key_hold: never a zero while the key is down
    auto_repeat(keys, "a", 0.0, delay=0.55, stop=2.0)
    for k in range(200):
        t = k * 0.01
        assert keys.tick(t).angular == (0.0, 0.0, 0.1), t


def test_a_gap_longer_than_key_hold_releases_to_zero():
    keys = teleop()
    last = auto_repeat(keys, "w", 0.0, delay=0.5, stop=1.0)
    assert keys.tick(last + HOLD - 0.01).angular == (0.0, 0.1, 0.0)
    assert keys.tick(last + HOLD + 0.01).is_zero
    assert keys.held_axes(last + HOLD + 0.01) == {}


def test_initial_delay_longer_than_key_hold_stutters():
    """Why key_hold must exceed the terminal's auto-repeat delay."""
    keys = teleop()
    keys.press("q", 0.0)
    assert keys.command(HOLD + 0.05).is_zero
    keys.press("q", HOLD + 0.1)  # the late first repeat starts it again
    assert not keys.command(HOLD + 0.1).is_zero


def test_zeros_follow_a_release_for_zero_duration_then_silence():
    keys = teleop()
    assert keys.tick(0.0) is None  # idle: nothing to publish
    keys.press("d", 0.0)
    assert not keys.tick(0.05).is_zero
    release = HOLD + 0.05
    ticks = {t: keys.tick(release + t) for t in (0.0, 0.2, ZEROS)}
    assert all(command is not None and command.is_zero for command in ticks.values())
    assert keys.sending
    assert keys.tick(release + ZEROS + 0.05) is None
    assert not keys.sending


def test_stop_key_zeroes_at_once_and_forgets_held_keys():
    keys = teleop()
    auto_repeat(keys, "q", 0.0, delay=0.3, stop=0.5)
    event = keys.press(" ", 0.51)
    assert event.binding.action is Action.STOP
    assert event.urgent
    assert keys.command(0.51).is_zero
    assert keys.tick(0.51).is_zero  # published now, not after key_hold
    assert keys.tick(0.51 + ZEROS + 0.01) is None


def test_stop_when_idle_still_sends_zeros():
    keys = teleop()
    assert keys.press(" ", 0.0).urgent
    assert keys.tick(0.0).is_zero


def test_newest_direction_of_an_axis_wins():
    keys = teleop()
    keys.press("q", 0.0)
    event = keys.press("e", 0.1)
    assert event.urgent
    assert keys.command(0.2).angular == (-0.1, 0.0, 0.0)


def test_two_axes_pressed_within_key_hold_combine():
    keys = teleop()
    keys.press("q", 0.0)
    keys.press("a", 0.1)
    assert keys.command(0.2).angular == (0.1, 0.0, 0.1)
    assert keys.command(HOLD + 0.05).angular == (0.0, 0.0, 0.1)  # q no longer repeats


def test_combined_keys_at_full_speed_stay_within_the_maximum_as_a_vector():
    """Two axes at 1 rad/s each used to give |omega| = 1.41 rad/s, which a controller with
    max_angular_speed 1 rad/s rejects; now the pair is scaled to 1 rad/s along the diagonal."""
    keys = teleop(angular_speed=1.0, linear_speed=0.5)
    keys.press("q", 0.0)
    keys.press("a", 0.1)
    keys.press("i", 0.15)
    keys.press("u", 0.2)
    command = keys.command(0.3)
    assert np.linalg.norm(command.angular) <= 1.0  # max_angular_speed, exactly as checked
    assert np.linalg.norm(command.angular) == pytest.approx(1.0)
    assert command.angular == pytest.approx((math.sqrt(0.5), 0.0, math.sqrt(0.5)))
    assert np.linalg.norm(command.linear) <= 0.5  # max_linear_speed
    assert command.linear == pytest.approx((0.5 * math.sqrt(0.5), 0.0, 0.5 * math.sqrt(0.5)))
    keys.press("w", 0.25)  # all three angular axes
    assert keys.tick(0.3).angular == pytest.approx((1 / math.sqrt(3),) * 3)


def test_combined_keys_below_the_maximum_are_not_scaled():
    keys = teleop(angular_speed=0.5)
    keys.press("q", 0.0)
    keys.press("s", 0.1)
    assert keys.command(0.2).angular == (0.5, -0.5, 0.0)  # |omega| 0.71 < 1


@given(
    # speeds, not denormals: a squared 1e-200 underflows in numpy's norm
    st.lists(st.floats(-1e3, 1e3).filter(lambda x: x == 0.0 or abs(x) > 1e-100), max_size=6),
    st.one_of(st.just(0.0), st.floats(1e-6, 100.0)),
)
def test_limit_norm_keeps_the_direction_and_never_exceeds_the_limit(vector, limit):
    result = np.array(limit_norm(vector, limit))
    norm = math.hypot(*vector)
    if norm <= limit:
        assert np.array_equal(result, vector)
    else:
        assert np.linalg.norm(result) <= limit
        assert math.hypot(*result) <= limit
        assert math.hypot(*result) == pytest.approx(limit, rel=1e-12)
        if limit > 0.0:
            assert result == pytest.approx(np.asarray(vector) * limit / norm, rel=1e-12)


@pytest.mark.parametrize("limit", [-1.0, math.nan, math.inf])
def test_limit_norm_rejects_a_bad_limit(limit):
    with pytest.raises(ConfigError, match="speed limit"):
        limit_norm((1.0, 0.0, 0.0), limit)


def test_repeats_are_not_urgent():
    keys = teleop()
    assert keys.press("w", 0.0).urgent
    assert not keys.press("w", 0.5).urgent


def test_speed_keys_scale_both_speeds_within_bounds():
    keys = teleop()
    keys.press("+", 0.0)
    assert keys.speeds == pytest.approx(Speeds(0.125, 0.0625))
    keys.press("-", 0.0)
    assert keys.speeds == pytest.approx(Speeds(0.1, 0.05))
    for _ in range(100):
        keys.press("=", 0.0)
    assert keys.speeds == Speeds(1.0, 0.5)  # max_angular_speed, max_linear_speed
    for _ in range(100):
        keys.press("_", 0.0)
    assert keys.speeds == Speeds(MIN_SPEED, MIN_SPEED)


def test_speed_change_applies_to_a_held_key_at_once():
    keys = teleop()
    keys.press("a", 0.0)
    event = keys.press("+", 0.1)
    assert event.urgent
    assert keys.command(0.1).angular == pytest.approx((0.0, 0.0, 0.125))


def test_frame_key_cycles_camera_world_base_and_stops():
    keys = teleop()
    keys.press("w", 0.0)
    frames = []
    for _ in range(3):
        event = keys.press("f", 0.1)
        frames.append(keys.frame)
    assert frames == [TwistFrame.WORLD, TwistFrame.BASE, TwistFrame.CAMERA]
    assert event.binding.action is Action.FRAME
    assert keys.command(0.1).is_zero  # motion does not carry over to new axes
    assert teleop(frame="base").command(0.0).frame is TwistFrame.BASE


@pytest.mark.parametrize("key", ["x", "W", "1", "\r", "\x1b", "\x1b[A", "\x1bq", "\x1a", "ä"])
def test_unknown_keys_are_ignored(key):
    keys = teleop()
    keys.press("q", 0.0)
    before = (keys.command(0.1), keys.speeds, keys.frame)
    event = keys.press(key, 0.1)
    assert event.binding is None
    assert not event.urgent
    assert (keys.command(0.1), keys.speeds, keys.frame) == before
    assert not keys.quit_requested


@pytest.mark.parametrize("key", ["Q", "\x03", "\x04", "\x1c"])
def test_quit_keys_request_quit_and_stop(key):
    keys = teleop()
    keys.press("a", 0.0)
    event = keys.press(key, 0.1)
    assert event.binding.action is Action.QUIT
    assert keys.quit_requested
    assert keys.command(0.1).is_zero


def test_commands_are_immutable():
    command = teleop().command(0.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        command.frame = TwistFrame.WORLD


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"key_hold": 0.0}, "key_hold"),
        ({"speed_step": 1.0}, "speed_step"),
        ({"zero_duration": -1.0}, "zero_duration"),
        ({"angular_speed": 2.0}, "angular_speed"),
        ({"linear_speed": 0.0}, "linear_speed"),
        ({"frame": "tool"}, "twist frame"),
        ({"force_step": 0.0}, r"force_step must be a finite number > 0 \[N\], got 0.0"),
        ({"max_force": math.nan}, "max_force must be a finite number > 0"),
    ],
)
def test_bad_settings_are_config_errors(overrides, message):
    with pytest.raises(ConfigError, match=message):
        teleop(**overrides)


def test_key_map_has_no_letter_for_two_actions_and_help_names_every_motion_key():
    help_text = " ".join(KEY_HELP)
    for key, binding in KEY_MAP.items():
        if binding.action is Action.MOVE:
            assert f"{key}/" in help_text or f"/{key}" in help_text, key


def test_split_keys_keeps_escape_sequences_whole():
    text = "q\x1b[Aw\x1b[1;5D\x1bOPa\x1bq\x1b"
    assert split_keys(text) == ["q", "\x1b[A", "w", "\x1b[1;5D", "\x1bOP", "a", "\x1bq", "\x1b"]
    # none of an arrow key's characters acts as a key ('[' and 'A' alone are unbound anyway)
    keys = teleop()
    for key in split_keys("\x1b[D\x1b[C"):
        assert keys.press(key, 0.0).binding is None


def test_status_line_shows_state_level_message_and_staleness():
    status = ControllerStatus("SINGULAR_REGION", 1, "SINGULAR_REGION: sigma_min 0.1", 10.0)
    line = status_line(status, 10.2, "/rns_controller/status")
    assert line == "controller  SINGULAR_REGION [WARN]  sigma_min 0.1"
    assert "no update for 3.0 s" in status_line(status, 13.0, "/x")
    assert status_line(ControllerStatus("OK", 0, "OK", 0.0), 0.0, "/x") == "controller  OK [OK]"
    assert "no status yet on /rns_controller/status" in status_line(
        None, 0.0, "/rns_controller/status"
    )


def test_panel_shows_command_frame_speeds_status_and_help():
    keys = teleop()
    keys.press("f", 0.0)
    event = keys.press("d", 0.0)
    lines = render_panel(
        keys.command(0.1),
        keys.speeds,
        "controller  OK [OK]",
        frame_id="world",
        sending=True,
        last_key=event,
    )
    text = "\n".join(lines)
    assert "frame     world (frame_id 'world')" in text
    assert "angular 0.100 rad/s   linear 0.050 m/s" in text
    assert "angular   x +0.000  y +0.000  z -0.100  [rad/s]" in text
    assert "linear    x +0.000  y +0.000  z +0.000  [m/s]" in text
    assert "cmd_twist sending" in text
    assert "last key  'd' yaw -" in text
    assert "controller  OK [OK]" in lines
    assert lines[-len(KEY_HELP) :] == list(KEY_HELP)
    assert max(len(line) for line in lines) <= 80
    idle = render_panel(keys.command(5.0), keys.speeds, "", sending=False)
    assert "cmd_twist idle (nothing published)" in idle


# --- force mode (Part II) -----------------------------------------------------------------------
def force_teleop(**overrides) -> KeyboardTeleop:
    keys = teleop(force_step=1.0, max_force=3.0, **overrides)
    event = keys.press("m", 0.0)
    assert event.binding.action is Action.FORCE_MODE
    assert keys.mode is Mode.FORCE
    keys.tick(0.0)
    return keys


@pytest.mark.parametrize(
    ("key", "linear"),
    [
        ("w", (0.05, 0, 0)),
        ("i", (0.05, 0, 0)),
        ("s", (-0.05, 0, 0)),
        ("k", (-0.05, 0, 0)),
        ("a", (0, 0.05, 0)),
        ("j", (0, 0.05, 0)),
        ("d", (0, -0.05, 0)),
        ("l", (0, -0.05, 0)),
    ],
)
def test_force_mode_motion_keys_drive_the_ee_x_y_linear_velocity(key, linear):
    keys = force_teleop()
    event = keys.press(key, 1.0)
    assert event.binding == Binding(
        Action.MOVE, 3 if linear[0] else 4, 1 if sum(linear) > 0 else -1
    )
    assert event.urgent
    command = keys.tick(1.0)
    assert command == TeleopCommand(ZERO3, linear, TwistFrame.CAMERA, force_mode=True)
    # key hold and the zeros after release are those of camera mode
    assert keys.tick(1.0 + HOLD + 0.01).is_zero
    assert keys.tick(1.0 + HOLD + 0.01).force_mode
    assert keys.tick(1.0 + HOLD + ZEROS + 0.05) is None


@pytest.mark.parametrize("key", ["q", "e", "u", "o", "f"])
def test_force_mode_ignores_the_other_axes_and_the_frame_key(key):
    keys = force_teleop()
    event = keys.press(key, 1.0)
    assert event.binding is None
    assert keys.command(1.0).is_zero
    assert keys.frame is TwistFrame.CAMERA


def test_push_keys_step_the_force_within_its_bounds_and_leave_the_speed():
    keys = teleop(force_step=1.5, max_force=4.0)
    assert keys.force_setpoint() is None  # camera mode: no force setpoint
    keys.press("m", 0.0)
    assert keys.force_setpoint() == 0.0
    event = keys.press("+", 0.1)
    assert event.binding.action is Action.HARDER
    assert event.urgent  # a push goes out at once
    assert keys.force_setpoint() == 1.5
    keys.press("=", 0.2)
    keys.press("+", 0.3)  # 4.5 > max_force
    assert keys.force_setpoint() == 4.0
    assert keys.speeds == Speeds(0.1, 0.05)  # +/- push in force mode, the speeds stay
    event = keys.press("-", 0.4)
    assert event.binding.action is Action.SOFTER
    assert keys.force_setpoint() == 2.5
    for _ in range(5):
        keys.press("_", 0.5)
    assert keys.force_setpoint() == 0.0
    assert not keys.press("-", 0.6).urgent  # nothing changed


def test_leaving_force_mode_stops_in_the_ee_frame_and_keeps_the_force():
    keys = force_teleop()
    keys.press("+", 0.1)
    keys.press("+", 0.2)
    keys.press("w", 0.3)
    assert keys.tick(0.35).linear == (0.05, 0.0, 0.0)
    event = keys.press("m", 0.4)
    assert event.urgent
    assert keys.mode is Mode.CAMERA
    zero = keys.tick(0.4)  # published at once: the final zero twist, in the EE frame
    assert zero.is_zero
    assert zero.force_mode
    assert keys.tick(0.4 + ZEROS).force_mode
    assert keys.tick(0.4 + ZEROS + 0.05) is None
    assert keys.force == 2.0  # kept; no longer sent
    assert keys.force_setpoint() is None
    assert keys.press("+", 1.0).binding.action is Action.FASTER  # camera mode keys again
    assert keys.force == 2.0
    keys.press("m", 2.0)
    assert keys.force_setpoint() == 2.0  # back in force mode: the same push


def test_entering_force_mode_stops_the_camera_in_its_frame():
    keys = teleop()
    keys.press("f", 0.0)  # world
    keys.press("a", 0.1)
    keys.press("m", 0.2)
    zero = keys.tick(0.2)
    assert zero.is_zero
    assert not zero.force_mode
    assert zero.frame is TwistFrame.WORLD
    assert keys.command(0.2).force_mode  # what the keys drive now


def test_force_key_help_names_every_force_mode_motion_key():
    help_text = " ".join(FORCE_KEY_HELP)
    for key, binding in FORCE_KEY_MAP.items():
        if binding.action is Action.MOVE:
            assert f"{key}/" in help_text or f"/{key}" in help_text, key
    assert "m force mode" in " ".join(KEY_HELP)


def test_panel_in_force_mode_shows_mode_frame_force_and_force_status():
    keys = force_teleop()
    keys.press("+", 0.1)
    keys.press("+", 0.1)
    event = keys.press("j", 0.2)
    force_status = status_line(
        ControllerStatus("CONTACT", 0, "CONTACT: force error +0.012 N", 0.2),
        0.3,
        "/rns_force_controller/status",
        "force ctrl",
    )
    lines = render_panel(
        keys.command(0.3),
        keys.speeds,
        "controller  no status yet on /rns_controller/status",
        frame_id="ee",
        sending=True,
        last_key=event,
        force=keys.force,
        force_step=keys.force_step,
        max_force=keys.max_force,
        force_status=force_status,
    )
    text = "\n".join(lines)
    assert "mode      force (m: back to camera mode)" in text
    assert "frame     EE (frame_id 'ee')" in text
    assert "linear    x +0.000  y +0.050  z +0.000  [m/s]" in text
    assert "force     setpoint 2.000 N along EE z (+/- 1 N, 0..3 N), sending" in text
    assert "force ctrl  CONTACT [OK]  force error +0.012 N" in lines
    assert "last key  'j' y +" in text
    assert lines[-len(FORCE_KEY_HELP) :] == list(FORCE_KEY_HELP)
    assert max(len(line) for line in lines) <= 80
    keys.press("m", 1.0)
    camera = render_panel(keys.command(1.0), keys.speeds, "", force=keys.force)
    assert "mode      camera (m: force mode)" in camera
    assert "force     setpoint 2.000 N, not sent (held by the controller)" in camera
    assert camera[-len(KEY_HELP) :] == list(KEY_HELP)
