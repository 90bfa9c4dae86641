"""Command-line pieces shared by the executables: ROS-argument checks, one-line errors, start-up.

Start-up contract of every console script (docs/ros2_integration.md, "Start-up errors"): a bad
argument, parameter, params file or configuration is one line ``<executable>: <problem>`` on
stderr and exit code 2; Ctrl-C at any time during start-up is exit code 0 without a traceback.

This module is imported by ``rns_ros/__init__.py`` before anything heavy (numpy, Pinocchio,
rclpy: about 0.4 s of imports), so it imports nothing beyond the standard library at module level.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

#: Largest domain ID Fast DDS can map to UDP ports (7400 + 250 d + offsets <= 65535); above it,
#: creating a node ends the process with exit code 1 and an RTPS error, from C++.
DDS_MAX_DOMAIN_ID = 232
#: ROS 2 domain IDs accepted here: what rcl accepts with Fast DDS.
DOMAIN_ID_RANGE = (0, DDS_MAX_DOMAIN_ID)
#: Largest domain ID whose UDP ports lie below every platform's ephemeral ports (Linux hands
#: out 32768 and up to outgoing connections, which may then hold a port a participant needs).
PORTABLE_MAX_DOMAIN_ID = 101
#: Environment variable naming the process (pid) whose end stops a node started by it as Ctrl-C
#: does (rns_ros.harness.ProcessStack sets it; rns_ros.nodes.runner reads it).
STOP_WITH_PARENT = "RNS_STOP_WITH_PARENT"


#: The console scripts of setup.py (test/test_startup.py keeps the two in sync).
EXECUTABLES = frozenset(
    {
        "rns_demo",
        "rns_simulator",
        "rns_controller",
        "rns_force_controller",
        "rns_ptp",
        "rns_attitude_control",
        "rns_link",
        "rns_predictor",
        "rns_rerun_logger",
        "rns_operator",
        "rns_teleop_keyboard",
        "rns_teleop_spacemouse",
        "rns_observer",
        "rns_param",
        "rns_topic",
        "rns_service",
        "rns_reproduce",
        "rns_model",
        "rns_bag",
    }
)

# Signals that arrived before an executable's main() took over (see install_startup_handler).
_startup_signals: list[int] = []


def _record_startup_signal(signum: int, _frame) -> None:
    # Raised where Python's own handler would raise KeyboardInterrupt (between bytecodes of the
    # imports), so it unwinds the same way, but ends the console script quietly with code 0. The
    # record serves a main() that runs anyway (the exit swallowed by an "ignored" callback).
    _startup_signals.append(signum)
    raise SystemExit(0)


def install_startup_handler() -> None:
    """In an rns_ros executable, make Ctrl-C during the imports exit code 0, not a traceback.

    Called when the ``rns_ros`` package is imported, i.e. before numpy, Pinocchio and rclpy load.
    A no-op unless the process is one of :data:`EXECUTABLES` (so importing rns_ros as a library
    changes no signal handling) and runs in the main thread with Python's default SIGINT handler
    or the package's (``rns_ros/__init__`` takes Ctrl-C over for any ``rns_*`` program first and
    gives it back here to one that is not ours).
    Each main() takes the signal over first thing (:func:`run_main`, ``run_node``); one that does
    not still ends quietly with code 0 on Ctrl-C (SystemExit instead of KeyboardInterrupt).
    """
    program = os.path.basename(sys.argv[0]) if getattr(sys, "argv", None) else ""
    if threading.current_thread() is not threading.main_thread():
        return
    handler = signal.getsignal(signal.SIGINT)
    # rns_ros/__init__ took Ctrl-C over for any rns_* program before this module loaded
    early = getattr(sys.modules.get("rns_ros"), "_quiet_interrupt", None)
    taken_early = early is not None and handler is early
    if program.removesuffix(".exe") not in EXECUTABLES:
        if taken_early:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        return
    if taken_early or handler is signal.default_int_handler:
        signal.signal(signal.SIGINT, _record_startup_signal)
        sys.excepthook = _quiet_after_startup_signal(sys.excepthook)


def _quiet_after_startup_signal(previous):
    """An excepthook that ends the process quietly with code 0 when Ctrl-C came during the
    imports: the SystemExit raised in a C extension's initialization (rclpy's) reaches the top
    as an ImportError with a traceback, not as SystemExit. Anything else goes to ``previous``."""

    def hook(kind, value, traceback) -> None:
        if _startup_signals:
            sys.stderr.flush()
            os._exit(0)
        previous(kind, value, traceback)

    return hook


def startup_interrupted() -> bool:
    """True when Ctrl-C arrived during the imports (the executable should exit 0 at once)."""
    return bool(_startup_signals)


def restore_default_interrupt() -> None:
    """Give Ctrl-C back to Python (KeyboardInterrupt) once main() is ready to catch it."""
    if signal.getsignal(signal.SIGINT) is _record_startup_signal:
        signal.signal(signal.SIGINT, signal.default_int_handler)


class Interrupted(KeyboardInterrupt):
    """A stop asked for by a signal (SIGTERM; Ctrl-C raises KeyboardInterrupt itself), as an
    exception that unwinds like Ctrl-C: ``signum``, and the shell's exit code 128 + signum."""

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def interrupt_exit_code(error: KeyboardInterrupt) -> int:
    """128 + the signal number: 130 for Ctrl-C, 143 for SIGTERM."""
    return 128 + getattr(error, "signum", signal.SIGINT)


def raise_on_sigterm() -> None:
    """Let SIGTERM unwind the main thread as Ctrl-C does (:class:`Interrupted`), so ``finally``
    blocks close what is open (files, child processes) instead of the process just ending."""

    def interrupted(signum: int, _frame) -> None:
        raise Interrupted(signum)

    signal.signal(signal.SIGTERM, interrupted)


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM until the block ends (main thread only; elsewhere a no-op): a
    Ctrl-C raised in the middle of the block (a file record half written) arrives right after
    it instead."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def output_file_problem(path: Path) -> str | None:
    """Why a file cannot be written at ``path`` (new, or replacing one), or None: checked
    before a long run, so its result is not lost at the end."""
    try:
        return _file_problem(Path(path))
    except OSError as exc:  # a name too long, a loop of links
        return f"cannot be written: {exc.strerror or exc}"


def _file_problem(path: Path) -> str | None:
    if path.is_dir():
        return "is a folder, not a file"
    folder = path.parent
    if not folder.is_dir():
        return f"cannot be written: its folder {str(folder)!r} does not exist"
    if not os.access(folder, os.W_OK | os.X_OK) or (path.exists() and not os.access(path, os.W_OK)):
        return "cannot be written: permission denied"
    return None


def output_folder_problem(path: Path) -> str | None:
    """Why ``path`` cannot be an output folder (made with its parents when missing), or None."""
    try:
        return _folder_problem(Path(path))
    except OSError as exc:  # a name too long, a loop of links
        return f"cannot be made: {exc.strerror or exc}"


def _folder_problem(path: Path) -> str | None:
    existing = path
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return f"cannot be a folder: {str(existing)!r} is a file"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"cannot be written: {str(existing)!r} is not writable"
    return None


def make_output_folder(path: Path) -> str | None:
    """Make the output folder ``path`` with its parents now (before a long run, whose results
    it holds); why it cannot be made, or None."""
    if problem := output_folder_problem(path):
        return problem
    try:
        Path(path).mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # a file system that refuses it (/proc, a name too long, ...)
        return f"cannot be made: {exc.strerror or exc}"
    return None


class OneLineParser(argparse.ArgumentParser):
    """argparse that raises ConfigError (one line, exit 2 in :func:`run_main`) instead of
    printing its usage; the line points at the program's --help."""

    def error(self, message: str):
        from rns_ros.core.errors import ConfigError

        raise ConfigError(f"{message} (see {self.prog.split()[0]} --help)")


def one_line(error: BaseException | str) -> str:
    """The text of ``error`` on one line, without rcl's C source locations.

    rcl messages look like ``Couldn't parse params file ... at line 1, at /project/src/parse.c:841,
    at /project/src/rcl/arguments.c:415``: the locations help nobody who typed a bad argument.
    """
    text = re.sub(r",?\s*at /\S+\.(?:c|cc|cpp|h|hpp):\d+", "", str(error))
    return " ".join(text.split())


def describe_ros_error(error: BaseException) -> str:
    """One line for what rcl / rclpy raise on bad ROS arguments, params files or environment."""
    if type(error).__name__ == "UnknownROSArgsError":  # its text is only the list of arguments
        return (
            f"unknown ROS arguments {error}; after --ros-args use -p NAME:=VALUE, "
            "--params-file FILE, -r FROM:=TO, --log-level LEVEL, -e ENCLAVE"
        )
    text = one_line(error)
    # rcl's own prefix; "invalid ROS arguments" is what the harness and the observer say too
    return re.sub(r"^Failed to parse ROS arguments: ", "invalid ROS arguments: ", text)


def check_ros_args(ros_args: list[str]) -> None:
    """Parse ``--ros-args ...`` the way rcl will, without initialising anything.

    Raises:
        ConfigError: a trailing ``-p``, an unreadable ``--params-file``, an unknown flag, ...
            (one line, from rcl's own message).
    """
    if not ros_args:
        return
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    from rclpy.utilities import remove_ros_args

    from rns_ros.core.errors import ConfigError

    try:
        remove_ros_args(["rns_ros", *ros_args])
    except (_rclpy.RCLError, _rclpy.UnknownROSArgsError) as exc:
        raise ConfigError(describe_ros_error(exc)) from None


def split_ros_args(argv: list[str]) -> tuple[list[str], list[str]]:
    """(own arguments, ROS arguments): ``--ros-args ... [--]`` is cut out, as rcl reads it.

    Raises:
        ConfigError: the ROS arguments are not what rcl accepts (:func:`check_ros_args`).
    """
    if "--ros-args" not in argv:
        return list(argv), []
    start = argv.index("--ros-args")
    end = argv.index("--", start) if "--" in argv[start:] else len(argv)
    check_ros_args(argv[start:end])
    return argv[:start] + argv[end + 1 :], argv[start:end]


def run_main(program: str, body: Callable[[], int]) -> int:
    """Run an argparse executable's ``body`` under the start-up contract; return its exit code.

    Ctrl-C during the imports or at any time later: exit code 0, no traceback. An
    :class:`~rns_ros.core.errors.RnsError` that ``body`` lets through (bad option, scenario,
    model, ROS arguments): one line ``<program>: <problem>`` on stderr, exit code 2.
    """
    if startup_interrupted():
        return 0
    restore_default_interrupt()
    from rns_ros.core.errors import RnsError

    try:
        return body()
    except RnsError as exc:
        print(f"{program}: {one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 0


def check_domain_id_environment(env: dict[str, str] | None = None) -> None:
    """Raise ConfigError for an integer ``ROS_DOMAIN_ID`` above :data:`DDS_MAX_DOMAIN_ID`.

    A non-integer one is left to rcl (its own one-line error at ``rclpy.init``).
    """
    text = (os.environ if env is None else env).get("ROS_DOMAIN_ID", "").strip()
    try:
        value = int(text)
    except ValueError:
        return
    if not 0 <= value <= DDS_MAX_DOMAIN_ID:
        from rns_ros.core.errors import ConfigError

        raise ConfigError(
            f"ROS_DOMAIN_ID={text} is out of range: DDS takes [0, {DDS_MAX_DOMAIN_ID}] "
            f"([0, {PORTABLE_MAX_DOMAIN_ID}] on every platform)"
        )


def add_domain_id_argument(parser: argparse.ArgumentParser, fallback: int, what: str) -> None:
    """``--domain-id``: default ``ROS_DOMAIN_ID`` of the environment, else ``fallback``.

    The environment value is checked by the same rule as the option (an integer in
    :data:`DOMAIN_ID_RANGE`), so a bad ``ROS_DOMAIN_ID`` is a usage error naming it.
    """
    low, high = DOMAIN_ID_RANGE

    def domain_id(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"must be an integer in [{low}, {high}] (option or ROS_DOMAIN_ID), got {text!r}"
            )
        return value

    parser.add_argument(
        "--domain-id",
        type=domain_id,
        default=os.environ.get("ROS_DOMAIN_ID", str(fallback)),  # argparse converts it
        help=f"ROS domain {what} [{low}, {high}] as rcl takes it (up to "
        f"{PORTABLE_MAX_DOMAIN_ID} its UDP ports stay clear of the ephemeral ports; "
        f"default: ROS_DOMAIN_ID, else {fallback})",
    )
