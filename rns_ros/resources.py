"""Where the package's data files (URDFs, YAML) are: installed share folder or source checkout."""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

PACKAGE = "rns_ros"


def config_dir() -> Path:
    """The ``config`` folder: ``share/rns_ros/config`` of an install, else the source tree's."""
    candidates = []
    try:
        from ament_index_python.packages import PackageNotFoundError, get_package_share_directory

        # not installed, or no AMENT_PREFIX_PATH: fall through to the other candidates
        with contextlib.suppress(PackageNotFoundError, OSError):
            candidates.append(Path(get_package_share_directory(PACKAGE)) / "config")
    except ImportError:  # plain Python install without the ament index
        pass
    candidates.append(Path(sys.prefix) / "share" / PACKAGE / "config")
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
