"""rns_teleop_keyboard: drive the camera's angular velocity from a terminal, one key per axis.

Keys, key-hold semantics and the panel are in :mod:`rns_ros.keyboard` (pure logic); this module
owns the terminal and the ROS side.

Publishes:
    cmd_twist   geometry_msgs/TwistStamped, best effort depth 1 (as rns_operator): while a key is
                held, the command at ``rate`` (``header.frame_id``: ``world_frame``, ``base_frame``
                or ``camera_frame``; the latter two, left empty, the base link and camera frame
                of ``model_config``'s model); after release or the stop key, zeros at ``rate``
                for ``zero_duration``; then nothing until the next key (the controller idles on
                its own timeout). A few zeros are also sent on quit, Ctrl-C, SIGTERM and when the
                terminal goes away (SIGHUP, end of file or EIO on stdin). In force mode (key m)
                the twist is the EE linear velocity along EE x / y at ``linear_speed``,
                ``frame_id`` = ``ee_frame``; toggling the mode stops like the stop key (zeros in
                the frame of the mode left: leaving force mode sends EE-frame zeros).
    force_setpoint  geometry_msgs/WrenchStamped, best effort depth 1, force mode only: at
                ``rate`` (and at once on a push key), ``frame_id`` = ``ee_frame``, force =
                (0, 0, f) [N], f the setpoint in [0, ``max_force``] changed by ``force_step``
                per +/- key (docs/part2_ros.md: the force the EE exerts on the environment).
                Not sent outside force mode: the controller holds the last one (leaving force
                mode, or quitting, keeps the push; press - down to 0 N first to release it).
Subscribes:
    <controller_status_topic>  diagnostic_msgs/DiagnosticArray of rns_controller; the entry with
                a ``state`` value is shown in the panel.
    <force_status_topic>  diagnostic_msgs/DiagnosticArray of rns_force_controller; the entry with
                a ``state`` value (and its ``force_error_N`` [N], when given) is shown in the panel
                while in force mode or once one arrived.

Why ``key_hold`` (0.7 s) may exceed the controller's ``command_timeout`` (0.5 s): the timeout is
judged on the age of the newest message, and this node republishes the held command every
1/``rate`` s, so the controller never sees a command older than one period while a key is held.
``key_hold`` only has to bridge the terminal's auto-repeat delay.

The terminal runs in cbreak mode without signal characters (Ctrl-C arrives as a key and quits
cleanly; Ctrl-Z does nothing, since a stopped teleop would leave the terminal in cbreak mode) and
is restored on every way out.
"""

from __future__ import annotations

import codecs
import contextlib
import errno
import os
import select
import shutil
import signal
import sys
import termios
import threading
import time
import tty
from collections.abc import Callable, Sequence

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistStamped, WrenchStamped
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from rns_ros.cli import one_line, startup_interrupted
from rns_ros.core.errors import RnsError
from rns_ros.keyboard import (
    ControllerStatus,
    KeyboardTeleop,
    KeyEvent,
    TeleopCommand,
    render_panel,
    split_keys,
    status_line,
)
from rns_ros.nodes import teleop_keyboard_parameters
from rns_ros.nodes.parameters import declare_parameters, from_parameters, twist_frame_names
from rns_ros.nodes.runner import answer_help, publish_copies, start_node
from rns_ros.nodes.teleop_keyboard_parameters import NODE_NAME

#: Exit code when the terminal went away (a zero twist was still sent).
EXIT_TERMINAL_LOST = 1
#: Zero twists sent on the way out, this far apart [s]: best effort may drop one.
EXIT_ZEROS = 3
EXIT_ZERO_GAP = 0.02
#: Longest wait for a key before the loop looks at the clock again [s].
POLL = 0.05


class TerminalLost(Exception):  # noqa: N818 - an event, not a programming error
    """The controlling terminal hung up or stdin ended."""


class TerminalError(RnsError):
    """stdin cannot take the panel: not a terminal, or this process is not in its foreground."""


_RUN_IN_FOREGROUND = "run it in the foreground of an interactive terminal"


def check_terminal(fd: int) -> None:
    """Raise :class:`TerminalError` unless ``fd`` (stdin; -1: none) is a terminal this process
    may put into key mode: a terminal, and, when it is this process's controlling terminal, one
    whose foreground process group is this process's (in the background, changing its mode
    would stop the process with SIGTTOU, or fail with EIO once the shell is gone)."""
    if fd < 0 or not os.isatty(fd):
        raise TerminalError(
            "stdin is not a terminal; run it in an interactive terminal (not with a pipe, a "
            "file or a launch file without a console)"
        )
    try:
        foreground = os.tcgetpgrp(fd)
    except OSError:  # not the controlling terminal: no job control to respect
        return
    if foreground != os.getpgrp():
        raise TerminalError(
            "this process is in the background of its terminal (started with &, or moved "
            f"there with bg); {_RUN_IN_FOREGROUND}"
        )


class TeleopKeyboardNode(Node):
    """Publishes the :class:`~rns_ros.keyboard.KeyboardTeleop` commands (module docstring).

    Raises:
        ConfigError: a parameter is out of range, or an initial speed exceeds its maximum.
    """

    def __init__(self, **node_kwargs) -> None:
        super().__init__(NODE_NAME, **node_kwargs)
        params = declare_parameters(self, teleop_keyboard_parameters.PARAMETERS)
        self.teleop = from_parameters(KeyboardTeleop, params, frame=params["initial_frame"])
        self.ee_frame = params["ee_frame"]
        self.period = 1.0 / params["rate"]
        self.frame_ids = twist_frame_names(params)
        # Commands: best effort, depth 1 - a late twist is worth nothing (as rns_operator).
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self._publisher = self.create_publisher(TwistStamped, "cmd_twist", qos)
        self._force_publisher = self.create_publisher(WrenchStamped, "force_setpoint", qos)
        # Best effort also matches the controller's reliable status publisher; only the newest
        # entry is shown.
        self.status_topic = self.resolve_topic_name(params["controller_status_topic"])
        self.create_subscription(DiagnosticArray, self.status_topic, self._on_status, qos)
        self.status: ControllerStatus | None = None
        self.force_status_topic = self.resolve_topic_name(params["force_status_topic"])
        self.create_subscription(
            DiagnosticArray, self.force_status_topic, self._on_force_status, qos
        )
        self.force_status: ControllerStatus | None = None

    def _on_status(self, msg: DiagnosticArray) -> None:
        status = _controller_status(msg)
        if status is not None:
            self.status = status  # one assignment: the panel thread reads it without a lock

    def _on_force_status(self, msg: DiagnosticArray) -> None:
        status = _controller_status(msg, FORCE_ERROR_KEYS)
        if status is not None:
            self.force_status = status

    def frame_id(self, command: TeleopCommand) -> str:
        """header.frame_id of ``command``: the EE frame in force mode."""
        return self.ee_frame if command.force_mode else self.frame_ids[command.frame]

    def publish(self, command: TeleopCommand) -> None:
        """Publish one command as TwistStamped stamped with the node clock."""
        msg = TwistStamped()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.header.frame_id = self.frame_id(command)
        msg.twist.angular.x, msg.twist.angular.y, msg.twist.angular.z = command.angular
        msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z = command.linear
        self._publisher.publish(msg)

    def publish_force(self, force: float) -> None:
        """One force setpoint: WrenchStamped, EE frame, force (0, 0, ``force``) [N], torque 0."""
        msg = WrenchStamped()
        msg.header.stamp = self.get_clock().now().to_msg()
        msg.header.frame_id = self.ee_frame
        msg.wrench.force.z = float(force)
        self._force_publisher.publish(msg)

    def publish_tick(self, now: float) -> None:
        """What :class:`KeyboardTeleop` has to send at monotonic ``now`` [s]: the twist (or
        nothing) and, in force mode, the force setpoint."""
        command = self.teleop.tick(now)
        if command is not None:
            self.publish(command)
        force = self.teleop.force_setpoint()
        if force is not None:
            self.publish_force(force)

    def publish_exit_zeros(self) -> None:
        """A few zero twists, :data:`EXIT_ZERO_GAP` apart, before the node goes away (in the EE
        frame in force mode; the force setpoint is left as it is)."""
        zero = TeleopCommand(
            (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), self.teleop.frame, self.teleop.force_mode
        )
        publish_copies(lambda: self.publish(zero), EXIT_ZEROS, EXIT_ZERO_GAP)


#: Status keys holding the force error [N] (rns_force_controller's first), shown in the panel.
FORCE_ERROR_KEYS = ("force_error_N", "force_error")


def _controller_status(
    msg: DiagnosticArray, detail_keys: Sequence[str] = ()
) -> ControllerStatus | None:
    """The entry of ``msg`` with a ``state`` value (as rns_rerun_logger reads it), or None; the
    first of ``detail_keys`` present (a force error [N]) leads its message."""
    for entry in msg.status:
        values = {kv.key: kv.value for kv in entry.values}
        if "state" not in values:
            continue
        level = entry.level[0] if isinstance(entry.level, bytes) else int(entry.level)
        message = entry.message
        key = next((key for key in detail_keys if key in values), None)
        if key is not None:
            rest = message.removeprefix(f"{values['state']}:").strip()
            try:
                detail = f"force error {float(values[key]):+.3f} N"
            except ValueError:
                detail = f"force error {values[key]}"
            message = f"{values['state']}: {detail}" + (f"  {rest}" if rest else "")
        return ControllerStatus(values["state"], level, message, time.monotonic())
    return None


def _reason(error: termios.error) -> str:
    """``termios.error``'s text, e.g. ``Input/output error``."""
    return str(error.args[1]) if len(error.args) > 1 else str(error)


class RawTerminal:
    """stdin in cbreak mode without signal characters or flow control, the panel drawn on the
    alternate screen; :meth:`restore` (idempotent, also on a dead terminal) undoes both."""

    def __init__(self, fd_in: int, fd_out: int) -> None:
        self.fd_in, self.fd_out = fd_in, fd_out
        self._saved: list | None = None
        self._decoder = codecs.getincrementaldecoder("utf-8")(errors="replace")
        self._shown: list[str] = []

    def __enter__(self) -> RawTerminal:
        """Raises: TerminalError: the terminal refuses key mode (one line)."""
        try:
            self._saved = termios.tcgetattr(self.fd_in)
        except termios.error as exc:
            raise TerminalError(f"cannot read the terminal's mode: {_reason(exc)}") from None
        try:
            tty.setcbreak(self.fd_in, termios.TCSAFLUSH)  # drop keys typed before the panel
            mode = termios.tcgetattr(self.fd_in)
            mode[tty.LFLAG] &= ~termios.ISIG  # Ctrl-C, Ctrl-\, Ctrl-Z arrive as keys
            mode[tty.IFLAG] &= ~termios.IXON  # Ctrl-S must not freeze the panel
            termios.tcsetattr(self.fd_in, termios.TCSANOW, mode)
            self._write("\x1b[?1049h\x1b[?25l")  # alternate screen, hide cursor
        except termios.error as exc:
            self.restore()
            raise TerminalError(
                f"cannot put the terminal into key mode: {_reason(exc)}; {_RUN_IN_FOREGROUND}"
            ) from None
        except BaseException:
            self.restore()
            raise
        return self

    def __exit__(self, *_exc) -> None:
        self.restore()

    def restore(self) -> None:
        if self._saved is None:
            return
        saved, self._saved = self._saved, None
        with contextlib.suppress(TerminalLost):
            self._write("\x1b[?25h\x1b[?1049l")  # show cursor, main screen
        # a hung-up terminal refuses: then there is nothing left to restore
        with contextlib.suppress(termios.error, OSError):
            termios.tcsetattr(self.fd_in, termios.TCSANOW, saved)

    def read_keys(self, timeout: float) -> list[str]:
        """Keys typed within ``timeout`` [s] (possibly none).

        Raises:
            TerminalLost: end of file or EIO on stdin.
        """
        ready, _, _ = select.select([self.fd_in], [], [], max(timeout, 0.0))
        if not ready:
            return []
        try:
            data = os.read(self.fd_in, 1024)
        except OSError as exc:
            if exc.errno == errno.EIO:
                raise TerminalLost("stdin: input/output error") from None
            raise
        if not data:
            raise TerminalLost("stdin: end of file")
        return split_keys(self._decoder.decode(data))

    def draw(self, lines: Sequence[str]) -> None:
        """Show ``lines`` from the top left, cut to the terminal width; no-op when unchanged."""
        width = shutil.get_terminal_size((100, 40)).columns
        lines = [line[: max(width - 1, 1)] for line in lines]
        if lines == self._shown:
            return
        self._shown = lines
        self._write("\x1b[H" + "".join(f"{line}\x1b[K\r\n" for line in lines) + "\x1b[J")

    def _write(self, text: str) -> None:
        data = text.encode()
        try:
            while data:
                data = data[os.write(self.fd_out, data) :]
        except OSError as exc:
            # a hung-up terminal answers EIO; a closed pipe EPIPE
            raise TerminalLost(f"stdout: {exc.strerror}") from None


def run_panel(
    node: TeleopKeyboardNode,
    terminal: RawTerminal,
    signals: Sequence[int] = (),
    clock: Callable[[], float] = time.monotonic,
) -> None:
    """Keys in, twists out, panel redrawn, until a quit key, a signal or a lost terminal.

    ``signals`` is read each loop: once it holds a signal number the panel ends (within
    ``POLL`` [s]); SIGHUP means the terminal is gone. ``clock``: monotonic time [s] of the key
    presses and the rate ticks (``terminal.read_keys`` waits on the same clock).
    """
    teleop = node.teleop
    next_tick = clock()
    last_key: KeyEvent | None = None
    while rclpy.ok(context=node.context) and not teleop.quit_requested:
        if signals:
            if signal.SIGHUP in signals:
                raise TerminalLost("terminal hung up (SIGHUP)")
            return
        # wake at the next tick, and at least every POLL so the status age stays fresh
        wait = min(next_tick - clock(), POLL)
        for key in terminal.read_keys(wait):
            now = clock()
            last_key = teleop.press(key, now)
            if teleop.quit_requested:
                break  # keys typed after a quit key must not move anything
            if last_key.urgent:
                # a start, change, stop or push goes out now, not up to one period later
                node.publish_tick(now)
                next_tick = now + node.period
        now = clock()
        if now >= next_tick:
            node.publish_tick(now)
            # late (a slow redraw): restart the grid instead of publishing a burst
            next_tick = max(next_tick + node.period, now)
        command = teleop.command(now)
        show_force = teleop.force_mode or teleop.force > 0.0
        terminal.draw(
            render_panel(
                command,
                teleop.speeds,
                status_line(node.status, now, node.status_topic),
                frame_id=node.frame_id(command),
                sending=teleop.sending,
                last_key=last_key,
                force=teleop.force if show_force else None,
                force_step=teleop.force_step,
                max_force=teleop.max_force,
                force_status=(
                    status_line(node.force_status, now, node.force_status_topic, "force ctrl")
                    if teleop.force_mode or node.force_status is not None
                    else None
                ),
            )
        )


# --- signals --------------------------------------------------------------------------------------
# Handlers only record the signal: an exception raised from a handler can land inside rclpy's C++
# argument conversion (a publish), which turns it into a RuntimeError. The panel loop reads it.
_signals: list[int] = []


def _on_signal(signum, _frame) -> None:
    _signals.append(signum)


def _spin(executor: SingleThreadedExecutor, stop: threading.Event) -> None:
    try:
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)
    except ExternalShutdownException:
        pass


def main(args: Sequence[str] | None = None) -> int:
    """Run the teleop in this terminal; exit code 0 (quit, Ctrl-C, SIGTERM), 1 (terminal lost)
    or 2 (bad parameters, stdin not a terminal or this process in its background)."""
    argv = list(sys.argv if args is None else args)
    code = answer_help(teleop_keyboard_parameters, argv)
    if code is not None:
        return code
    # Our own handlers (no rclpy one), before rclpy.init: the Context must outlive the final zero
    # twists, and Ctrl-C during start-up (imports included, see rns_ros.cli) is a clean exit 0.
    _signals.clear()
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, _on_signal)
    if startup_interrupted():
        return 0
    node = executor = spinner = None
    stop_spinning = threading.Event()
    code = 0
    panel_started = False
    try:
        node = start_node(NODE_NAME, TeleopKeyboardNode, argv)
        if node is None:
            return 2
        if _signals and signal.SIGHUP not in _signals:
            return 0  # Ctrl-C / SIGTERM while starting: nothing was sent yet
        stdin = sys.stdin.fileno() if sys.stdin is not None else -1
        check_terminal(stdin)
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        spinner = threading.Thread(
            target=_spin, args=(executor, stop_spinning), name="ros-spin", daemon=True
        )
        spinner.start()
        panel_started = True
        with RawTerminal(stdin, sys.stdout.fileno()) as terminal:
            run_panel(node, terminal, _signals)
    except RnsError as exc:
        print(f"{NODE_NAME}: {one_line(exc)}", file=sys.stderr)
        return 2
    except TerminalLost:
        code = EXIT_TERMINAL_LOST
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        try:
            # whatever ended the panel, the last word on cmd_twist is zero
            if panel_started and rclpy.ok():
                node.publish_exit_zeros()
        finally:
            stop_spinning.set()
            if spinner is not None:
                spinner.join(timeout=2.0)
            if node is not None:
                node.destroy_node()
            if executor is not None:
                executor.shutdown()
            rclpy.try_shutdown()
    if code == 0:
        with contextlib.suppress(OSError):  # the terminal may be gone (SIGTERM after hang-up)
            print(f"{NODE_NAME}: stopped, zero twist sent")
    return code


if __name__ == "__main__":
    raise SystemExit(main())
