"""The text of a robot description file: a URDF as it is, or a xacro expanded to URDF.

Most published descriptions are xacro. They are expanded with the PyPI ``xacro`` package (the
one ROS uses), with no ROS install needed:

* ``xacro_args`` are the ``<xacro:arg>`` values, as ``xacro file.xacro name:=value`` gives them;
* ``$(find pkg)`` resolves to ``packages[pkg]`` when the model YAML names the package's folder,
  else through the ament index (``AMENT_PREFIX_PATH``), as on a ROS install.

A file, or an expanded xacro, over :data:`~rns_ros.core.urdf_tree.MAX_URDF_BYTES` is refused.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Mapping
from pathlib import Path

from rns_ros.core.errors import ModelError
from rns_ros.core.urdf_tree import MAX_URDF_BYTES, check_urdf_size
from rns_ros.core.yaml_input import read_head

#: File name endings read as xacro.
XACRO_SUFFIXES = (".xacro", ".urdf.xacro")


def is_xacro(path: str | Path) -> bool:
    """Whether ``path`` names a xacro file (by its ending)."""
    return str(path).endswith(XACRO_SUFFIXES)


def read_description(
    path: str | Path,
    xacro_args: Mapping[str, str] | None = None,
    packages: Mapping[str, str | Path] | None = None,
) -> str:
    """The URDF text of ``path``: read as it is, or, for a ``.xacro`` file, expanded.

    Args:
        path: the URDF or xacro file.
        xacro_args: ``<xacro:arg>`` values (xacro only).
        packages: package name -> its share folder, for ``$(find pkg)`` (xacro only).

    Raises:
        ModelError: the file is missing or unreadable, over
            :data:`~rns_ros.core.urdf_tree.MAX_URDF_BYTES` (as a file or expanded), or xacro
            cannot expand it (one line: the file and the reason).
    """
    path = Path(path)
    try:
        if not path.is_file():
            raise ModelError(f"URDF file not found: {path}")
        data, size = read_head(path, MAX_URDF_BYTES)
        check_urdf_size(size, str(path))
        if not is_xacro(path):
            return data.decode().replace("\r\n", "\n").replace("\r", "\n")  # as read_text
    except OSError as exc:  # the message without the file name, given once in front
        raise ModelError(f"{path}: cannot read the URDF: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ModelError(f"{path}: cannot read the URDF: {exc}") from None
    text = _expand(path, dict(xacro_args or {}), {k: Path(v) for k, v in (packages or {}).items()})
    check_urdf_size(len(text.encode()), f"{path} (expanded)")
    return text


def _expand(path: Path, args: dict[str, str], packages: dict[str, Path]) -> str:
    try:
        import xacro
    except ImportError:  # pragma: no cover - a dependency of the package
        raise ModelError(
            f"{path}: a xacro file needs the xacro package (pip install xacro)"
        ) from None
    missing: list[str] = []  # a package $(find ...) could not resolve (xacro wraps the error)
    try:
        with _finding(packages, missing):
            document = xacro.process_file(str(path), mappings=args)
    except Exception as exc:  # xacro raises its own and XML errors
        reason = missing[0] if missing else " ".join(str(exc).split()) or type(exc).__name__
        raise ModelError(f"{path}: xacro could not expand it: {reason}") from None
    return document.toprettyxml(indent="  ")


@contextlib.contextmanager
def _finding(packages: dict[str, Path], missing: list[str]) -> Iterator[None]:
    """``$(find pkg)`` answers from ``packages`` first, then the ament index, while xacro
    runs (xacro 2.1 resolves it in ``substitution_args._eval_find``); a package found in
    neither is said in ``missing``."""
    from xacro import substitution_args

    ament = substitution_args._eval_find

    def find(package: str) -> str:
        if package in packages:
            return str(packages[package])
        try:
            return ament(package)
        except Exception:
            missing.append(
                f"$(find {package}): package not found (name its folder under 'packages' in "
                "the model YAML, or set AMENT_PREFIX_PATH)"
            )
            raise

    substitution_args._eval_find = find
    try:
        yield
    finally:
        substitution_args._eval_find = ament
