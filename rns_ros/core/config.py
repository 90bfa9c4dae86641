"""Model configuration files (``config/model.yaml``): which URDF, which frames/joints play the
thesis roles, which joints are held, the satellite body and the initial joint angles. Unknown
keys and wrong types raise :class:`ConfigError` naming the key.

Keys (all but ``urdf`` optional): ``urdf`` (path relative to the YAML file; a ``.xacro`` is
expanded, :mod:`rns_ros.core.description`), ``xacro_args`` ({name: value}), ``packages``
({package: share folder relative to the YAML file}, for ``$(find pkg)``), ``camera_frame``,
``wrist_frame`` (null: no wrist term), ``positioning_joints``, ``wrist_joints``,
``controlled_joints`` (list), ``held_joints`` ({name: position [rad or m]}),
``initial_joint_positions`` ({name: angle [rad]}), ``base`` ({mass [kg], inertia: 3 principal
moments or 6 values ixx ixy ixz iyy iyz izz [kg m^2], mount_xyz [m], mount_rpy [rad]}).
"""

from __future__ import annotations

import math
from pathlib import Path

from rns_ros.core.errors import ConfigError
from rns_ros.core.model import FreeFloatingModel, ModelSpec
from rns_ros.core.urdf_prep import BaseBody
from rns_ros.core.validation import short_repr
from rns_ros.core.yaml_input import read_yaml_file

_KEYS = {
    "urdf",
    "camera_frame",
    "wrist_frame",
    "positioning_joints",
    "wrist_joints",
    "controlled_joints",
    "held_joints",
    "initial_joint_positions",
    "base",
    "xacro_args",
    "packages",
}
_BASE_KEYS = {"mass", "inertia", "mount_xyz", "mount_rpy"}
#: Longest ``urdf`` path accepted [characters] (Linux's PATH_MAX).
MAX_PATH_LENGTH = 4096
#: How many unknown keys an error message lists.
SHOWN_KEYS = 10


def read_yaml_mapping(path: str | Path, keys: set[str] | None, what: str) -> tuple[Path, dict]:
    """Read a YAML file holding one mapping whose keys are all in ``keys`` (None: the caller
    checks them, e.g. once it knows which kind of file it is).

    Returns (path, mapping). A missing file, invalid YAML, a file or document over the limits of
    :mod:`rns_ros.core.yaml_input`, a non-mapping or an unknown key raise :class:`ConfigError`
    naming the file (and the key).
    """
    path = Path(path)
    content = read_yaml_file(path, what)
    if not isinstance(content, dict):
        expected = "a mapping" if keys is None else f"a mapping with keys {sorted(keys)}"
        raise ConfigError(f"{path}: expected {expected}, got {short_repr(content)}")
    if keys is not None:
        check_keys(content, keys, str(path))
    return path, content


def check_keys(mapping: dict, keys: set[str], where: str) -> None:
    """Raise :class:`ConfigError` naming any key of ``mapping`` not in ``keys`` (the first
    :data:`SHOWN_KEYS`, each cut to 40 characters)."""
    unknown = sorted(str(key) for key in set(mapping) - keys)
    if unknown:
        shown = [key if len(key) <= 40 else key[:37] + "..." for key in unknown[:SHOWN_KEYS]]
        more = f" and {len(unknown) - SHOWN_KEYS} more" if len(unknown) > SHOWN_KEYS else ""
        raise ConfigError(f"{where}: unknown key(s) {shown}{more}; valid keys: {sorted(keys)}")


def load_model_config(path: str | Path) -> tuple[Path, ModelSpec]:
    """Read a model YAML file; returns (absolute URDF path, :class:`ModelSpec`).

    A relative ``urdf`` path is taken relative to the YAML file's folder. An absent
    ``positioning_joints`` / ``wrist_joints`` means the default split (ModelSpec: None).
    """
    path, content = read_yaml_mapping(path, _KEYS, "model config")
    if not isinstance(content.get("urdf"), str) or len(content["urdf"]) > MAX_PATH_LENGTH:
        raise ConfigError(
            f"{path}: 'urdf' must be a file path string, got {short_repr(content.get('urdf'))}"
        )
    for key in ("camera_frame", "wrist_frame"):
        if key in content and content[key] is not None and not isinstance(content[key], str):
            raise ConfigError(
                f"{path}: '{key}' must be a frame name, got {short_repr(content[key])}"
            )
    joints = {
        key: _names(content[key], f"{path}: '{key}'") if key in content else None
        for key in ("positioning_joints", "wrist_joints", "controlled_joints")
    }
    spec = ModelSpec(
        camera_frame=content.get("camera_frame", "camera"),
        wrist_frame=content.get("wrist_frame", "wrist"),
        held_joints=_positions(content.get("held_joints", {}), f"{path}: 'held_joints'"),
        initial_joint_positions=_positions(
            content.get("initial_joint_positions", {}), f"{path}: 'initial_joint_positions'"
        ),
        base=None if content.get("base") is None else _base(content["base"], f"{path}: 'base'"),
        xacro_args=_strings(content.get("xacro_args", {}), f"{path}: 'xacro_args'"),
        packages={
            package: (path.parent / folder).resolve()
            for package, folder in _strings(
                content.get("packages", {}), f"{path}: 'packages'"
            ).items()
        },
        **joints,
    )
    return (path.parent / content["urdf"]).resolve(), spec


def load_model(path: str | Path) -> FreeFloatingModel:
    """Load the :class:`FreeFloatingModel` described by a model YAML file."""
    urdf, spec = load_model_config(path)
    return FreeFloatingModel.from_urdf(urdf, spec)


def _strings(value, where: str) -> dict[str, str]:
    """A mapping of names to scalar values, as text (``xacro_args``, ``packages``)."""
    if not isinstance(value, dict) or not all(isinstance(key, str) for key in value):
        raise ConfigError(f"{where} must be a mapping of names to values, got {short_repr(value)}")
    scalars = (str, int, float, bool)
    bad = [key for key, item in value.items() if not isinstance(item, scalars)]
    if bad:
        raise ConfigError(
            f"{where}: '{bad[0]}' must be a single value, got {short_repr(value[bad[0]])}"
        )
    return {
        key: ("true" if item else "false") if isinstance(item, bool) else str(item)
        for key, item in value.items()
    }


def _names(value, where: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(name, str) for name in value):
        raise ConfigError(f"{where} must be a list of joint names, got {short_repr(value)}")
    return tuple(value)


def _number(value, where: str) -> float:
    finite = False
    if isinstance(value, int | float) and not isinstance(value, bool):
        try:
            finite = math.isfinite(value)
        except OverflowError:  # an integer beyond float
            finite = False
    if not finite:
        raise ConfigError(f"{where} must be a finite number, got {short_repr(value)}")
    return float(value)


def _numbers(value, sizes: tuple[int, ...], where: str) -> tuple[float, ...]:
    if not isinstance(value, list) or len(value) not in sizes:
        raise ConfigError(f"{where} must be a list of {' or '.join(map(str, sizes))} numbers")
    return tuple(_number(item, where) for item in value)


def _positions(value, where: str) -> dict[str, float]:
    if not isinstance(value, dict) or not all(isinstance(name, str) for name in value):
        raise ConfigError(
            f"{where} must be a mapping joint name: position, got {short_repr(value)}"
        )
    return {name: _number(position, f"{where} '{name}'") for name, position in value.items()}


def _base(value, where: str) -> BaseBody:
    """The satellite body of the ``base`` key (:class:`BaseBody`)."""
    if not isinstance(value, dict):
        raise ConfigError(f"{where} must be a mapping with keys {sorted(_BASE_KEYS)}")
    check_keys(value, _BASE_KEYS, where)
    for key in ("mass", "inertia"):
        if key not in value:
            raise ConfigError(f"{where}: '{key}' is required")
    moments = _numbers(value["inertia"], (3, 6), f"{where} 'inertia'")
    if len(moments) == 3:
        xx, yy, zz = moments
        xy = xz = yz = 0.0
    else:
        xx, xy, xz, yy, yz, zz = moments
    return BaseBody(
        mass=_number(value["mass"], f"{where} 'mass'"),
        inertia=((xx, xy, xz), (xy, yy, yz), (xz, yz, zz)),
        mount_xyz=_numbers(value.get("mount_xyz", [0.0] * 3), (3,), f"{where} 'mount_xyz'"),
        mount_rpy=_numbers(value.get("mount_rpy", [0.0] * 3), (3,), f"{where} 'mount_rpy'"),
    )
