"""rns_teleop_keyboard driven as a person would: the real executable in a tmux pane, keys typed
with ``tmux send-keys`` (repeated sends stand in for auto-repeat), the panel read back with
``tmux capture-pane``, and cmd_twist (and, in force mode, force_setpoint) recorded over DDS
(loopback only) by the harness probe."""

from __future__ import annotations

import itertools
import os
import pty
import shlex
import shutil
import subprocess
import sys
import termios
import time
import tty
import uuid
from collections.abc import Callable
from pathlib import Path

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.qos import QoSProfile

from rns_ros.harness import ros_environment
from rns_ros.nodes.teleop_keyboard import RawTerminal, TerminalError, check_terminal
from rns_ros.nodes.teleop_keyboard_parameters import PARAMETERS

REPO = Path(__file__).resolve().parents[2]
TMUX = shutil.which("tmux")
needs_tmux = pytest.mark.skipif(
    TMUX is None, reason="tmux is not installed: the terminal tests type into a tmux pane"
)
COMMAND = [sys.executable, "-m", "rns_ros.nodes.teleop_keyboard", "--ros-args"]
STATUS_TOPIC = "rns_controller/status"  # the node's default
STATUS_DETAIL = "sigma_min 0.04 near a singularity"
START_TIMEOUT = 20.0  # [s] for the process to start and see the fake controller


def _vector(v) -> tuple[float, float, float]:
    return (v.x, v.y, v.z)


def _is_zero(msg: TwistStamped) -> bool:
    return not any(_vector(msg.twist.angular)) and not any(_vector(msg.twist.linear))


class Pane:
    """One tmux pane on a private server (its own socket), 100 x 40."""

    def __init__(self, env: dict[str, str], command: list[str]) -> None:
        self.socket = f"rns-teleop-test-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        # The server, and so the pane, inherits this environment.
        self.tmux(
            "new-session", "-d", "-s", "teleop", "-x", "100", "-y", "40", "-c", str(REPO),
            *command, env=env,
        )  # fmt: skip
        try:
            self.socket_path = Path(self.show("#{socket_path}"))
        except BaseException:
            self.kill_server()
            raise

    def tmux(self, *args: str, env: dict[str, str] | None = None) -> str:
        result = subprocess.run(
            [TMUX, "-L", self.socket, "-f", "/dev/null", *args],
            capture_output=True,
            text=True,
            timeout=10,
            env=env,
            check=True,
        )
        return result.stdout

    def keys(self, *keys: str) -> float:
        """Type tmux key names (``q``, ``Space``, ``C-c``, ``Enter``); returns the monotonic
        time [s] just before they were sent: nothing the keys cause can happen earlier."""
        sent = time.monotonic()
        self.tmux("send-keys", "-t", "teleop", *keys)
        return sent

    def text(self) -> str:
        return self.tmux("capture-pane", "-p", "-t", "teleop")

    def show(self, fmt: str) -> str:
        return self.tmux("display-message", "-p", "-t", "teleop", fmt).strip()

    def kill_server(self) -> float:
        subprocess.run(
            [TMUX, "-L", self.socket, "kill-server"], capture_output=True, timeout=10, check=False
        )
        return time.monotonic()

    def remove_socket(self) -> None:
        """kill-server leaves the socket file behind."""
        self.socket_path.unlink(missing_ok=True)


@pytest.fixture
def terminal_env(ros) -> dict[str, str]:
    env = ros_environment(ros.domain_id)  # the test's domain, loopback discovery, Fast DDS
    env.update(PS1="$ ", HISTFILE="/dev/null", PYTHONUNBUFFERED="1")
    return env


@pytest.fixture
def fake_controller(ros):
    """Publishes a controller status (WARN, SINGULAR_REGION) at 10 Hz on the default topic."""
    probe = ros.probe()
    publisher = probe.create_publisher(DiagnosticArray, STATUS_TOPIC, QoSProfile(depth=10))

    def publish() -> None:
        status = DiagnosticStatus(
            level=DiagnosticStatus.WARN,
            name="rns_controller: reactionless control",
            message=f"SINGULAR_REGION: {STATUS_DETAIL}",
            values=[KeyValue(key="state", value="SINGULAR_REGION")],
        )
        publisher.publish(DiagnosticArray(status=[status]))

    probe.create_timer(0.1, publish)


@pytest.fixture
def panes():
    """Every pane made through it; their tmux servers are killed at teardown, whatever happens."""
    made: list[Pane] = []

    def make(env: dict[str, str], command: list[str]) -> Pane:
        made.append(Pane(env, command))
        return made[-1]

    yield make
    for pane in made:
        pane.kill_server()
        pane.remove_socket()


def wait(ros, condition: Callable[[], bool], timeout: float, what: str, pane=None) -> None:
    """Spin the harness until ``condition()``; fail naming ``what`` (and showing the pane)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            screen = f"\n--- pane ---\n{pane.text()}" if pane is not None else ""
            pytest.fail(f"timed out after {timeout} s waiting for {what}{screen}")
        ros.spin_for(0.05)


def hold(ros, pane: Pane, key: str, duration: float, first_gap: float) -> tuple[float, float]:
    """A held key as a terminal sends it: press, a first repeat after ``first_gap``, then repeats
    every 0.1 s for ``duration`` [s]. Returns the times of the press and of the last repeat."""
    start = last = pane.keys(key)
    ros.spin_for(first_gap)
    while last - start < duration:
        last = pane.keys(key)
        ros.spin_for(0.1)
    return start, last


def matched(ros, topic: str) -> Callable[[], bool]:
    """Whether the probe's subscription to ``topic`` is matched with a publisher (data can flow;
    discovery of a fresh process can take seconds on a loaded machine)."""
    subscription = next(s for s in ros.probe().subscriptions if s.topic_name == f"/{topic}")
    return lambda: subscription.get_publisher_count() > 0


def received_after(twists, t: float) -> list[tuple[float, TwistStamped]]:
    return [(r, m) for r, m in zip(twists.received, twists.messages, strict=True) if r > t]


def _stamp(msg) -> float:
    """header.stamp [s]: the node's system clock when it published (as time.time())."""
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec


#: How long the node may take to read a key and publish what it causes before a test reads it as
#: "not at once" [s]: the alternatives the tests tell apart (a key-hold release) come >= 0.8 s
#: later, so only a stalled machine comes near it.
AT_ONCE = 0.7


@needs_tmux
def test_keys_drive_cmd_twist_and_ctrl_c_restores_the_terminal(
    ros, terminal_env, fake_controller, panes
):
    """The real process in a terminal: a held key streams its twist in the frame shown (no
    stutter through the auto-repeat delay) and is released to zeros key_hold after its last
    repeat, then zeros for zero_duration (on the node's stamps) and silence; the stop key and
    Ctrl-C zero at once (stamped well before key_hold would release the key); the terminal is
    restored. Instants on the node's own timing are run_panel's test on simulated time
    (test_the_panel_publishes_a_press_at_once_at_the_rate_and_releases_after_key_hold)."""
    key_hold, zero_duration = 1.0, 0.3  # [s]
    twists = ros.record(TwistStamped, "cmd_twist")
    pane = panes(terminal_env, ["bash", "--norc", "--noprofile"])
    command = [*COMMAND, "-p", f"key_hold:={key_hold}", "-p", f"zero_duration:={zero_duration}"]
    pane.keys("-l", shlex.join(command))
    pane.keys("Enter")
    wait(ros, lambda: STATUS_DETAIL in pane.text(), START_TIMEOUT, "the controller status", pane)
    wait(ros, matched(ros, "cmd_twist"), START_TIMEOUT, "cmd_twist to match", pane)
    screen = pane.text()
    assert "controller  SINGULAR_REGION [WARN]  " + STATUS_DETAIL in screen
    assert "frame     camera (frame_id 'camera')" in screen
    assert "cmd_twist idle (nothing published)" in screen
    assert not twists.messages  # nothing before a key

    # --- roll held through an auto-repeat delay shorter than key_hold: no stutter -------------
    _, last = hold(ros, pane, "q", duration=1.2, first_gap=0.5)
    assert "angular   x +0.100  y +0.000  z +0.000" in pane.text()
    wait(ros, lambda: any(_is_zero(m) for m in twists.messages), 10.0, "the release zero", pane)
    moving = [(r, m) for r, m in zip(twists.received, twists.messages, strict=True)]
    first_zero = next(i for i, (_, m) in enumerate(moving) if _is_zero(m))
    held, release = moving[:first_zero], moving[first_zero][0]
    assert held, "no twist while q was held"
    for _, msg in held:
        assert _vector(msg.twist.angular) == (0.1, 0.0, 0.0)
        assert _vector(msg.twist.linear) == (0.0, 0.0, 0.0)
        assert msg.header.frame_id == "camera"
    assert len(held) >= 5  # streamed while held, not sent once
    assert release - last > key_hold  # released key_hold after the last repeat, not before
    # then zeros for zero_duration (the node's stamps), then silence
    wait(ros, lambda: "cmd_twist idle" in pane.text(), 10.0, "cmd_twist idle", pane)
    ros.spin_for(0.3)
    after = received_after(twists, release - 1e-6)
    assert all(_is_zero(m) for _, m in after)  # no stutter: nothing moves after the release
    assert _stamp(after[-1][1]) - _stamp(after[0][1]) <= zero_duration + 0.05

    # --- frame toggle, then yaw in world axes; the stop key zeroes before key_hold ------------
    pane.keys("f")
    wait(ros, lambda: "frame     world (frame_id 'world')" in pane.text(), 10.0, "frame world")
    mark = time.monotonic()
    hold(ros, pane, "d", duration=0.2, first_gap=0.1)
    stop_wall = time.time()
    stop = pane.keys("Space")
    wait(ros, lambda: any(_is_zero(m) for _, m in received_after(twists, stop)), 10.0, "stop zero")
    during = received_after(twists, mark)
    yaw = [m for _, m in during if not _is_zero(m)]
    assert yaw
    assert all(_vector(m.twist.angular) == (0.0, 0.0, -0.1) for m in yaw)
    assert {m.header.frame_id for _, m in during} == {"world"}
    zero = next(m for _, m in received_after(twists, stop) if _is_zero(m))
    # stamped at once: key_hold (1.0 s) would have released the key >= 0.9 s after the stop
    assert _stamp(zero) - stop_wall < AT_ONCE
    assert "last key  ' ' stop" in pane.text()

    # --- faster, pitch held, Ctrl-C: the last word is zero, exit 0, terminal restored ---------
    pane.keys("+")
    wait(ros, lambda: "angular 0.125 rad/s" in pane.text(), 10.0, "the faster speed")
    hold(ros, pane, "w", duration=0.3, first_gap=0.1)
    assert "angular   x +0.000  y +0.125  z +0.000" in pane.text()
    interrupt_wall = time.time()
    interrupt = pane.keys("C-c")
    wait(ros, lambda: pane.show("#{pane_current_command}") == "bash", 10.0, "the exit", pane)
    before = [m for r, m in zip(twists.received, twists.messages, strict=True) if r <= interrupt]
    assert _vector(before[-1].twist.angular) == pytest.approx((0.0, 0.125, 0.0))
    ros.spin_for(0.3)
    # (receipt times are when the probe spun: a tick sent while send-keys ran may come later)
    after = received_after(twists, interrupt)
    first = next((i for i, (_, m) in enumerate(after) if _is_zero(m)), None)
    assert first is not None, "no zero twist after Ctrl-C"
    # the exit zero, not the key-hold release (>= 0.9 s after the interrupt)
    assert _stamp(after[first][1]) - interrupt_wall < AT_ONCE
    assert all(_is_zero(m) for _, m in after[first:])

    pane.keys("-l", "echo exit=$?")
    pane.keys("Enter")
    wait(ros, lambda: "exit=0" in pane.text(), 5.0, "the exit code", pane)
    assert "rns_teleop_keyboard: stopped, zero twist sent" in pane.text()
    pane.keys("-l", "stty -a")
    pane.keys("Enter")
    wait(ros, lambda: "icanon" in pane.text(), 5.0, "stty -a", pane)
    flags = set(pane.text().split())
    assert {"icanon", "echo", "isig", "ixon"} <= flags  # not -icanon, -echo, ...


@needs_tmux
def test_lost_terminal_publishes_zero_and_exits(ros, terminal_env, panes):
    """A terminal that goes away (tmux server killed) while a key is held: the node sends a zero
    twist and exits, before the key's release would have sent one."""
    key_hold = 3.0  # [s]: the zero must come from the hang-up, long before the key's release
    twists = ros.record(TwistStamped, "cmd_twist")
    pane = panes(terminal_env, [*COMMAND, "-p", f"key_hold:={key_hold}", "-p", "rate:=50.0"])
    pid = int(pane.show("#{pane_pid}"))
    wait(ros, lambda: "no status yet on /rns_controller/status" in pane.text(), START_TIMEOUT,
         "the panel", pane)  # fmt: skip
    wait(ros, matched(ros, "cmd_twist"), START_TIMEOUT, "cmd_twist to match", pane)
    pressed_wall = time.time()
    pane.keys("a")
    wait(ros, lambda: len(twists) >= 10, 10.0, "yaw twists", pane)  # matched and flowing
    assert all(_vector(m.twist.angular) == (0.0, 0.0, 0.1) for m in twists.messages)

    lost = pane.kill_server()
    wait(ros, lambda: _process_gone(pid), 10.0, "the process to exit")
    ros.spin_for(0.2)
    zeros = [(r, m) for r, m in received_after(twists, lost) if _is_zero(m)]
    assert zeros, "no zero twist after the terminal went away"
    # from the hang-up: stamped before key_hold after the only press would release the key
    assert _stamp(zeros[0][1]) < pressed_wall + key_hold
    assert _is_zero(twists.latest())


FORCE_STATUS_TOPIC = "/rns_force_controller/status"  # the node's default


@pytest.fixture
def fake_force_controller(ros):
    """Publishes a force controller status (OK, CONTACT, force_error_N) at 10 Hz, keys as
    rns_force_controller's."""
    probe = ros.probe()
    publisher = probe.create_publisher(DiagnosticArray, FORCE_STATUS_TOPIC, QoSProfile(depth=10))

    def publish() -> None:
        status = DiagnosticStatus(
            level=DiagnosticStatus.OK,
            name="rns_force_controller: motion/force control",
            message="CONTACT: pushing",
            values=[
                KeyValue(key="state", value="CONTACT"),
                KeyValue(key="force_error_N", value="0.0123"),
            ],
        )
        publisher.publish(DiagnosticArray(status=[status]))

    probe.create_timer(0.1, publish)


def _force(msg: WrenchStamped) -> tuple[float, float, float]:
    return _vector(msg.wrench.force)


@needs_tmux
def test_force_mode_drives_the_ee_and_steps_the_force_setpoint(
    ros, terminal_env, fake_force_controller, panes
):
    """Force mode in the real process: the force setpoint (EE frame) streams and steps by
    force_step per push; a held key drives the EE linearly and is released key_hold after its
    last repeat, zeros then last zero_duration while the setpoint keeps streaming; leaving force
    mode zeroes at once in the EE frame and stops the setpoint (none stamped after that zero),
    the last setpoint kept."""
    key_hold, zero_duration, force_step, pushes = 1.0, 0.3, 2.5, 3
    twists = ros.record(TwistStamped, "cmd_twist")
    setpoints = ros.record(WrenchStamped, "force_setpoint")
    command = [*COMMAND, "-p", f"key_hold:={key_hold}", "-p", f"zero_duration:={zero_duration}",
               "-p", f"force_step:={force_step}"]  # fmt: skip
    pane = panes(terminal_env, command)
    wait(ros, lambda: "mode      camera (m: force mode)" in pane.text(), START_TIMEOUT,
         "the panel", pane)  # fmt: skip
    wait(ros, matched(ros, "cmd_twist"), START_TIMEOUT, "cmd_twist to match", pane)
    wait(ros, matched(ros, "force_setpoint"), START_TIMEOUT, "force_setpoint to match", pane)
    ros.spin_for(0.3)
    assert not setpoints.messages  # camera mode: no force setpoint

    # --- into force mode: the setpoint (0 N) flows at rate in the EE frame ---------------------
    entered = pane.keys("m")
    wait(ros, lambda: len(setpoints) >= 5, 10.0, "force setpoints", pane)
    screen = pane.text()
    assert "mode      force (m: back to camera mode)" in screen
    assert "frame     EE (frame_id 'ee')" in screen
    assert "force ctrl  CONTACT [OK]  force error +0.012 N  pushing" in screen
    assert {m.header.frame_id for m in setpoints.messages} == {"ee"}
    assert all(_force(m) == (0.0, 0.0, 0.0) for m in setpoints.messages)
    assert all(_vector(m.wrench.torque) == (0.0, 0.0, 0.0) for m in setpoints.messages)
    # entering stops the camera: zeros in the camera frame (what was being commanded)
    assert all(_is_zero(m) for _, m in received_after(twists, entered))
    assert {m.header.frame_id for _, m in received_after(twists, entered)} <= {"camera"}

    # --- N pushes raise the published setpoint by N * force_step -------------------------------
    before = setpoints.latest().wrench.force.z
    for _ in range(pushes):
        pane.keys("+")
        ros.spin_for(0.1)
    target = before + pushes * force_step
    wait(ros, lambda: setpoints.latest().wrench.force.z == target, 10.0, "the pushed setpoint",
         pane)  # fmt: skip
    assert f"force     setpoint {target:.3f} N along EE z" in pane.text()
    values = {m.wrench.force.z for m in setpoints.messages}
    assert values <= {before + k * force_step for k in range(pushes + 1)}

    # --- EE x held: linear x at linear_speed in the EE frame; released after key_hold ---------
    mark = time.monotonic()
    _, last = hold(ros, pane, "i", duration=0.4, first_gap=0.2)
    assert "linear    x +0.050  y +0.000  z +0.000" in pane.text()
    wait(ros, lambda: any(_is_zero(m) for _, m in received_after(twists, mark)), 10.0,
         "the release zero", pane)  # fmt: skip
    during = received_after(twists, mark)
    first_zero = next(i for i, (_, m) in enumerate(during) if _is_zero(m))
    moving, release = during[:first_zero], during[first_zero][0]
    assert moving, "no twist while i was held"
    for _, msg in moving:
        assert _vector(msg.twist.linear) == (0.05, 0.0, 0.0)
        assert _vector(msg.twist.angular) == (0.0, 0.0, 0.0)
    assert release - last > key_hold  # released key_hold after the last repeat, not before
    wait(ros, lambda: "cmd_twist idle" in pane.text(), 10.0, "cmd_twist idle", pane)
    ros.spin_for(0.3)
    assert {m.header.frame_id for _, m in received_after(twists, mark)} == {"ee"}
    after = received_after(twists, release - 1e-6)
    assert all(_is_zero(m) for _, m in after)
    # zeros for zero_duration, then silence on cmd_twist, while the setpoint keeps flowing
    assert _stamp(after[-1][1]) - _stamp(after[0][1]) <= zero_duration + 0.05
    silent_from = _stamp(after[-1][1])
    wait(ros, lambda: _stamp(setpoints.latest()) > silent_from + 0.2, 10.0, "more setpoints")

    # --- softer once, then leave force mode: an EE-frame zero, the setpoint stays as it is ----
    pane.keys("-")
    wait(ros, lambda: setpoints.latest().wrench.force.z == target - force_step, 10.0, "softer")
    hold(ros, pane, "j", duration=0.2, first_gap=0.1)
    left_wall = time.time()
    left = pane.keys("m")
    wait(ros, lambda: "mode      camera (m: force mode)" in pane.text(), 10.0, "camera mode", pane)
    wait(ros, lambda: any(_is_zero(m) for _, m in received_after(twists, left)), 10.0, "exit zero")
    zero = next(m for _, m in received_after(twists, left) if _is_zero(m))
    assert _stamp(zero) - left_wall < AT_ONCE  # at once, not after key_hold
    assert zero.header.frame_id == "ee"
    ros.spin_for(0.7)
    # no longer sent: none stamped after the zero of leaving (published on the same tick) ...
    assert max(_stamp(m) for m in setpoints.messages) <= _stamp(zero)
    assert setpoints.latest().wrench.force.z == target - force_step  # ... the last one stays
    screen = pane.text()
    assert f"force     setpoint {target - force_step:.3f} N, not sent" in screen


def _process_gone(pid: int) -> bool:
    """True once ``pid`` has exited (reaped, or a zombie of a parent that does not reap)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return True
    return stat.rsplit(")", 1)[1].split()[0] in {"Z", "X"}


def _run(args: list[str], ros, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [*COMMAND[:3], *args],
        env=ros_environment(ros.domain_id),
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
        **kwargs,
    )


def test_without_a_terminal_it_exits_2_with_a_clear_message(ros):
    result = _run([], ros, stdin=subprocess.DEVNULL)
    assert result.returncode == 2
    assert "stdin is not a terminal" in result.stderr
    assert "Traceback" not in result.stderr + result.stdout


#: Runs argv[1:] in a background process group of a fresh session whose controlling terminal is
#: stdin (a pty): as `rns_teleop_keyboard &` from an interactive shell. Exits with the child's
#: code, or 99 if the child was stopped (SIGTTOU: the terminal's mode changed from the background).
_IN_THE_BACKGROUND = """
import fcntl, os, subprocess, sys, termios, time
fcntl.ioctl(0, termios.TIOCSCTTY, 0)
child = subprocess.Popen(sys.argv[1:], process_group=0)
deadline = time.monotonic() + 50.0
while time.monotonic() < deadline:
    pid, status = os.waitpid(child.pid, os.WUNTRACED | os.WNOHANG)
    if pid and os.WIFSTOPPED(status):
        child.kill()
        sys.exit(99)
    if pid:
        sys.exit(os.waitstatus_to_exitcode(status))
    time.sleep(0.05)
child.kill()
sys.exit(98)
"""


def test_in_the_background_of_its_terminal_it_exits_2_in_one_line(ros):
    master, slave = pty.openpty()
    try:
        result = subprocess.run(
            [sys.executable, "-c", _IN_THE_BACKGROUND, *COMMAND[:3]],
            stdin=slave,
            stdout=slave,
            stderr=subprocess.PIPE,
            env=ros_environment(ros.domain_id),
            cwd=REPO,
            text=True,
            timeout=60,
            start_new_session=True,
        )
    finally:
        os.close(slave)
        os.close(master)
    assert result.returncode == 2, result.stderr[-3000:]
    assert "Traceback" not in result.stderr
    assert result.stderr.splitlines() == [
        "rns_teleop_keyboard: this process is in the background of its terminal (started with "
        "&, or moved there with bg); run it in the foreground of an interactive terminal"
    ]


def test_check_terminal_refuses_a_pipe_and_takes_a_terminal_it_does_not_control():
    read_end, write_end = os.pipe()
    master, slave = pty.openpty()
    try:
        with pytest.raises(TerminalError, match=r"^stdin is not a terminal; "):
            check_terminal(read_end)
        with pytest.raises(TerminalError, match=r"^stdin is not a terminal; "):
            check_terminal(-1)
        check_terminal(slave)  # not this process's controlling terminal: no job control
    finally:
        for fd in (read_end, write_end, master, slave):
            os.close(fd)


def test_a_terminal_refusing_key_mode_is_one_line_and_left_as_it_was(monkeypatch):
    """tcsetattr fails with EIO in an orphaned background process group."""

    def refuse(*_args):
        raise termios.error(5, "Input/output error")

    master, slave = pty.openpty()
    try:
        before = termios.tcgetattr(slave)
        monkeypatch.setattr(tty, "setcbreak", refuse)
        with pytest.raises(TerminalError) as caught, RawTerminal(slave, master):
            pass
        assert str(caught.value) == (
            "cannot put the terminal into key mode: Input/output error; run it in the "
            "foreground of an interactive terminal"
        )
        assert termios.tcgetattr(slave) == before
    finally:
        os.close(slave)
        os.close(master)


def test_bad_parameter_is_one_line_and_exit_2(ros):
    result = _run(["--ros-args", "-p", "key_hold:=0.0"], ros, stdin=subprocess.DEVNULL)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1
    assert "key_hold" in lines[0]
    assert "Traceback" not in result.stderr


def test_help_lists_every_parameter(ros):
    result = _run(["--help"], ros, stdin=subprocess.DEVNULL)
    assert result.returncode == 0
    assert result.stdout.startswith("usage: rns_teleop_keyboard")
    for spec in PARAMETERS:
        assert f"  {spec.name} = " in result.stdout


class ScriptedTerminal:
    """Keys typed at given instants of a simulated monotonic clock [s]: :meth:`read_keys` waits
    on that clock (it jumps to the next key or to the end of the wait), so the panel loop runs
    the same on any machine."""

    def __init__(self, keys: list[tuple[float, str]]) -> None:
        self.now = 0.0
        self.keys = sorted(keys)

    def clock(self) -> float:
        return self.now

    def read_keys(self, timeout: float) -> list[str]:
        until = self.now + max(timeout, 0.0)
        if self.keys and self.keys[0][0] <= until:
            at, key = self.keys.pop(0)
            self.now = max(self.now, at)
            return [key]
        self.now = until
        return []

    def draw(self, _lines) -> None:
        pass


def _panel_run(ros, keys: list[tuple[float, str]], **parameters):
    """run_panel of a real node on simulated time, typing ``keys``; returns [(instant [s],
    (angular, linear)), ...] of every twist published and the simulated time it returned at."""
    from rclpy.parameter import Parameter

    from rns_ros.nodes.teleop_keyboard import TeleopKeyboardNode, run_panel

    overrides = [Parameter(name, value=value) for name, value in parameters.items()]
    node = TeleopKeyboardNode(context=ros.context, parameter_overrides=overrides)
    terminal = ScriptedTerminal(keys)
    sent = []
    node.publish = lambda command: sent.append((terminal.now, (command.angular, command.linear)))
    try:
        run_panel(node, terminal, clock=terminal.clock)
    finally:
        node.destroy_node()
    return sent, terminal.now


def test_the_panel_publishes_a_press_at_once_at_the_rate_and_releases_after_key_hold(ros):
    """run_panel on simulated time (20 Hz, key_hold 1 s, zero_duration 0.3 s): a press is
    published at its instant, then every period while held through a 0.5 s auto-repeat delay
    and 0.1 s repeats; the first zero comes within a period after key_hold past the last repeat,
    the zeros last zero_duration, then nothing; the stop key zeroes at its instant; the quit
    key ends the loop at its instant (main() then sends the exit zeros)."""
    roll = [(1.0, "q"), *[(1.5 + 0.1 * k, "q") for k in range(8)]]  # last repeat at 2.2
    yaw = [(5.0, "d"), (5.1, "d"), (5.2, " ")]  # a stop 0.1 s after the last repeat
    sent, ended = _panel_run(
        ros, [*roll, *yaw, (7.0, "w"), (7.3, "Q")], key_hold=1.0, zero_duration=0.3, rate=20.0
    )
    period = 1.0 / 20.0

    def moving(axis: int, sign: float, start: float, end: float) -> list[float]:
        return [t for t, (angular, _) in sent if start <= t < end and angular[axis] * sign > 0.0]

    def zeros(start: float, end: float) -> list[float]:
        return [t for t, (a, v) in sent if start <= t < end and not any(a) and not any(v)]

    held = moving(0, 1.0, 0.0, 4.0)
    assert held[0] == 1.0  # the press, at once
    assert max(b - a for a, b in itertools.pairwise(held)) <= period + 1e-9  # at rate
    release = zeros(0.0, 4.0)
    assert held[-1] <= 2.2 + 1.0 < release[0] <= 2.2 + 1.0 + period + 1e-9
    assert release[-1] - release[0] <= 0.3 + 1e-9  # zeros for zero_duration ...
    assert len(release) >= 0.3 / period
    assert not [t for t, _ in sent if release[-1] < t < 5.0]  # ... then silence
    assert moving(2, -1.0, 4.0, 6.0)[0] == 5.0
    assert zeros(4.0, 6.0)[0] == 5.2  # the stop, at once
    assert not moving(2, -1.0, 5.2, 7.0)
    assert moving(1, 1.0, 7.0, 8.0)[0] == 7.0
    assert ended == 7.3
    assert max(t for t, _ in sent) < 7.3  # the quit key publishes nothing itself
