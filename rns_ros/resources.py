"""Where the package's data files (URDFs, YAML, the DDS profile) are: installed share folder or
source checkout; and the environment that applies the loopback-only DDS profile."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import MutableMapping
from pathlib import Path

PACKAGE = "rns_ros"


def share_folders(package: str) -> list[Path]:
    """Where ``share/<package>`` may be, in the order looked in: the ament index's (a Jazzy
    install, or a colcon workspace sourced: needs ``AMENT_PREFIX_PATH``), then the running
    Python environment's prefix (the PyPI wheels and ``pip install`` put the interface packages'
    ``.msg`` files and this package's data there). Folders that do not exist are left out; a
    console script run from the venv's ``bin/`` with nothing else set finds the second."""
    found = []
    try:
        from ament_index_python.packages import PackageNotFoundError, get_package_share_directory
    except ImportError:  # plain Python install without the ament index
        pass
    else:
        # not in the index, or no AMENT_PREFIX_PATH (OSError): the prefix's folder below
        with contextlib.suppress(PackageNotFoundError, OSError, ValueError):
            found.append(Path(get_package_share_directory(package)))
    found.append(Path(sys.prefix) / "share" / package)
    unique = []
    for folder in found:
        if folder.is_dir() and folder not in unique:
            unique.append(folder)
    return unique


def config_dir() -> Path:
    """The ``config`` folder: ``share/rns_ros/config`` of an install, else the source tree's."""
    candidates = [folder / "config" for folder in share_folders(PACKAGE)]
    candidates.append(Path(__file__).resolve().parent.parent / "config")
    for candidate in candidates:
        if (candidate / "model.yaml").is_file():
            return candidate
    raise FileNotFoundError(f"no {PACKAGE} config folder among {[str(c) for c in candidates]}")


def default_model_config() -> Path:
    """Path of the default model file ``config/model.yaml`` (7-DoF arm, ETS-VII-class base)."""
    return config_dir() / "model.yaml"


def scenario_path(name_or_path: str | Path) -> Path:
    """A scenario file: an existing path as given, else ``config/scenarios/<name>.yaml``.

    Raises:
        ConfigError: neither exists; the message lists the shipped scenarios.
    """
    from rns_ros.core.errors import ConfigError

    path = Path(name_or_path)
    if path.is_file():
        return path
    shipped = config_dir() / "scenarios"
    candidate = shipped / f"{name_or_path}.yaml"
    if candidate.is_file():
        return candidate
    names = sorted(p.stem for p in shipped.glob("*.yaml"))
    raise ConfigError(f"scenario {str(name_or_path)!r} is neither a file nor one of {names}")


#: Fast DDS profile (``config/dds``) that keeps a process's DDS sockets on 127.0.0.1
LOOPBACK_PROFILE = Path("dds") / "loopback_only.xml"
#: environment variables through which a user names a Fast DDS profile of their own
PROFILE_VARIABLES = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")
#: the Fast DDS profile file a process reads from its working folder when no variable names one
DEFAULT_PROFILE_FILE = "DEFAULT_FASTRTPS_PROFILES.xml"
FAST_DDS_RMWS = ("", "rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp")


def loopback_profile() -> Path | None:
    """The shipped loopback-only Fast DDS profile, or None where the config folder lacks it."""
    try:
        path = config_dir() / LOOPBACK_PROFILE
    except FileNotFoundError:
        return None
    return path if path.is_file() else None


def apply_loopback_profile(env: MutableMapping[str, str] | None = None) -> Path | None:
    """Where localhost discovery is asked for, put the DDS sockets on the loopback interface too.

    Applies when ``ROS_AUTOMATIC_DISCOVERY_RANGE`` is ``LOCALHOST``, the RMW is Fast DDS (unset
    or ``rmw_fastrtps_cpp``/``_dynamic_cpp``), ``ROS_STATIC_PEERS`` is empty (peers reach other
    machines on purpose) and the user names no profile of their own (:data:`PROFILE_VARIABLES`,
    or ``DEFAULT_FASTRTPS_PROFILES.xml`` in the working folder). Then it sets
    ``FASTRTPS_DEFAULT_PROFILES_FILE`` to :func:`loopback_profile`: a UDP transport on 127.0.0.1
    only, discovery by unicast to 127.0.0.1, shared memory for data.

    It also sets the discovery range to ``SYSTEM_DEFAULT`` where the profile is sure to be in
    force: in ``LOCALHOST`` mode Jazzy's rmw_fastrtps adds a UDP transport of its own with no
    interface list, whose two send sockets bind 0.0.0.0 and the host address. Fast DDS reads the
    profile once, at a process's first participant, and ``SYSTEM_DEFAULT`` without it would
    discover by multicast on every interface; so the range changes only for another process's
    environment (``env`` given) or in this process before it holds any UDP socket. Otherwise it
    stays ``LOCALHOST`` (the profile may then be in force or not: both stay on this machine). An
    environment set so (``SYSTEM_DEFAULT`` with this profile) counts as asking for localhost.

    Args:
        env: a child process's environment, changed in place; None for this process's
            ``os.environ``, which rcl and Fast DDS read at rclpy.init.

    Returns:
        The profile applied, or None when the conditions above do not hold.
    """
    this_process = env is None or env is os.environ
    env = os.environ if env is None else env
    profile = loopback_profile()
    named = [env[name] for name in PROFILE_VARIABLES if env.get(name, "")]
    ours = profile is not None and named == [str(profile)]
    discovery = env.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").upper()
    if (
        profile is None
        or env.get("RMW_IMPLEMENTATION", "") not in FAST_DDS_RMWS
        or env.get("ROS_STATIC_PEERS", "")
        or (named and not ours)
        or (not named and Path(DEFAULT_PROFILE_FILE).is_file())
        or not (discovery == "LOCALHOST" or (discovery == "SYSTEM_DEFAULT" and ours))
    ):
        return None
    env["FASTRTPS_DEFAULT_PROFILES_FILE"] = str(profile)
    in_force = not this_process or _profile_in_force()
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "SYSTEM_DEFAULT" if in_force else "LOCALHOST"
    return profile


#: whether this process's first participant was created with the loopback profile in force
_profile_loaded = False


def _profile_in_force() -> bool:
    """True once the loopback profile was applied before this process held a UDP socket."""
    global _profile_loaded
    if not _profile_loaded and not _holds_udp_socket():
        _profile_loaded = True
    return _profile_loaded


def _holds_udp_socket() -> bool:
    """Whether this process holds a UDP socket (every DDS participant does); True where
    ``/proc`` cannot tell."""
    try:
        inodes = set()
        for fd in os.listdir("/proc/self/fd"):
            with contextlib.suppress(OSError):  # closed since the listing
                link = os.readlink(f"/proc/self/fd/{fd}")
                if link.startswith("socket:["):
                    inodes.add(link[len("socket:[") : -1])
        for table in ("/proc/self/net/udp", "/proc/self/net/udp6"):
            with open(table) as rows:
                next(rows)  # header
                if any(row.split()[9] in inodes for row in rows):
                    return True
    except (OSError, IndexError, StopIteration):
        return True
    return False
