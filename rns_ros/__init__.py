"""rns_ros: reactionless (Reaction Null-Space) teleoperation of free-floating space manipulators.

The math lives in :mod:`rns_ros.core` (numpy + Pinocchio, no ROS imports); ROS 2 nodes wrap it.
"""

# the interpreter has these loaded at start-up (``signal`` itself would be read from disk,
# a window in which Ctrl-C still meets Python's default handler)
import _signal
import os as _os
import sys as _sys

__version__ = "0.1.0"


def _quiet_interrupt(_signum: int, _frame) -> None:
    raise SystemExit(0)  # Ctrl-C before rns_ros.cli took over: end quietly, code 0


# Ctrl-C while a console script (each is named rns_*) is still importing (numpy, Pinocchio,
# rclpy: ~0.4 s) must end it with exit code 0, not a traceback. Taken over first thing, with
# modules the interpreter has loaded already, before even rns_ros.cli's standard-library imports;
# rns_ros.cli.install_startup_handler then keeps it for our executables only (a no-op when
# imported as a library).
if (
    _os.path.basename(_sys.argv[0] if getattr(_sys, "argv", None) else "").startswith("rns_")
    and _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler
):
    try:  # noqa: SIM105 - contextlib is not loaded yet
        _signal.signal(_signal.SIGINT, _quiet_interrupt)
    except ValueError:
        pass  # not the main thread: a library import

from rns_ros.cli import install_startup_handler as _install_startup_handler  # noqa: E402

_install_startup_handler()
