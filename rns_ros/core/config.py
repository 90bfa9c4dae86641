"""Model configuration files (``config/model.yaml``): which URDF, and which frames/joints play the
thesis roles. Unknown keys and wrong types raise :class:`ConfigError` naming the key."""

from __future__ import annotations

from pathlib import Path

import yaml

from rns_ros.core.errors import ConfigError
from rns_ros.core.model import FreeFloatingModel, ModelSpec

_KEYS = {"urdf", "camera_frame", "wrist_frame", "positioning_joints", "wrist_joints"}


def read_yaml_mapping(path: str | Path, keys: set[str] | None, what: str) -> tuple[Path, dict]:
    """Read a YAML file holding one mapping whose keys are all in ``keys`` (None: the caller
    checks them, e.g. once it knows which kind of file it is).

    Returns (path, mapping). A missing file, invalid YAML, a non-mapping or an unknown key raise
    :class:`ConfigError` naming the file (and the key).
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{what} not found: {path}")
    try:
        content = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML: {exc}") from exc
    if not isinstance(content, dict):
        expected = "a mapping" if keys is None else f"a mapping with keys {sorted(keys)}"
        raise ConfigError(f"{path}: expected {expected}, got {content!r}")
    if keys is not None:
        check_keys(content, keys, str(path))
    return path, content


def check_keys(mapping: dict, keys: set[str], where: str) -> None:
    """Raise :class:`ConfigError` naming any key of ``mapping`` not in ``keys``."""
    unknown = sorted(str(key) for key in set(mapping) - keys)
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {unknown}; valid keys: {sorted(keys)}")


def load_model_config(path: str | Path) -> tuple[Path, ModelSpec]:
    """Read a model YAML file; returns (absolute URDF path, :class:`ModelSpec`).

    A relative ``urdf`` path is taken relative to the YAML file's folder.
    """
    path, content = read_yaml_mapping(path, _KEYS, "model config")
    if not isinstance(content.get("urdf"), str):
        raise ConfigError(f"{path}: 'urdf' must be a file path string, got {content.get('urdf')!r}")
    for key in ("camera_frame", "wrist_frame"):
        if key in content and content[key] is not None and not isinstance(content[key], str):
            raise ConfigError(f"{path}: '{key}' must be a frame name, got {content[key]!r}")
    joints = {}
    for key in ("positioning_joints", "wrist_joints"):
        value = content.get(key, [])
        if not isinstance(value, list) or not all(isinstance(name, str) for name in value):
            raise ConfigError(f"{path}: '{key}' must be a list of joint names, got {value!r}")
        joints[key] = tuple(value)
    spec = ModelSpec(
        camera_frame=content.get("camera_frame", "camera"),
        wrist_frame=content.get("wrist_frame", "wrist"),
        **joints,
    )
    return (path.parent / content["urdf"]).resolve(), spec


def load_model(path: str | Path) -> FreeFloatingModel:
    """Load the :class:`FreeFloatingModel` described by a model YAML file."""
    urdf, spec = load_model_config(path)
    return FreeFloatingModel.from_urdf(urdf, spec)
