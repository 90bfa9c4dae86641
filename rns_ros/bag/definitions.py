"""Message definitions as rosbag2 stores them: the complete ``ros2msg`` text, the type hash, and
the fields each type lays out in CDR.

The ``.msg`` files come from the installed interface packages' ``share/<pkg>/msg/``
(:func:`rns_ros.resources.share_folders`: the ament index, else the Python environment's prefix,
where the PyPI wheels install them); the type hash (``RIHS01_...``) from the ``<Type>.json``
type description installed next to each ``.msg``.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from pathlib import Path

from rns_ros.core import RnsError
from rns_ros.resources import share_folders

#: The line that separates the definitions of a ros2msg schema.
SEPARATOR = "=" * 80
#: .msg field types that are not messages.
PRIMITIVE_TYPES = frozenset(
    {"bool", "byte", "char", "float32", "float64", "string", "wstring"}
    | {f"{sign}int{bits}" for sign in ("", "u") for bits in (8, 16, 32, 64)}
)


class DefinitionError(RnsError):
    """A message type whose definition is not installed or cannot be read."""


def _parts(type_name: str) -> tuple[str, str]:
    """(package, name) of ``'pkg/Type'`` or ``'pkg/msg/Type'``."""
    package, *_, name = type_name.split("/")
    return package, name


def full_type_name(type_name: str) -> str:
    """``'pkg/msg/Type'`` of ``'pkg/Type'`` or ``'pkg/msg/Type'``."""
    package, name = _parts(type_name)
    return f"{package}/msg/{name}"


def msg_file(type_name: str) -> Path:
    """The installed ``.msg`` file of ``'pkg/Type'`` or ``'pkg/msg/Type'``.

    Raises:
        DefinitionError: no package share folder holds it.
    """
    package, name = _parts(type_name)
    shares = share_folders(package)
    for share in shares:
        path = share / "msg" / f"{name}.msg"
        if path.is_file():
            return path
    where = ", ".join(str(share) for share in shares) or f"no share/{package} folder found"
    raise DefinitionError(f"no .msg definition of {type_name} installed ({where})")


def msg_dependencies(text: str, package: str) -> list[str]:
    """The message types (``'pkg/Type'``) the fields of the ``.msg`` ``text`` use, sorted;
    a type without a package is ``package``'s."""
    found = set()
    for line in text.splitlines():
        words = line.split("#", 1)[0].split()
        if len(words) < 2 or "=" in words[0]:
            continue
        kind = words[0].split("[", 1)[0].split("<=", 1)[0]
        if kind in PRIMITIVE_TYPES:
            continue
        found.add(kind if "/" in kind else f"{package}/{kind}")
    return sorted(found)


@functools.cache
def message_definition(type_name: str) -> str:
    """rosbag2's complete ``ros2msg`` definition of ``'pkg/msg/Type'``: its ``.msg`` text, then
    each type it uses, depth first, once, after the separator and a ``MSG: pkg/Type`` line.

    Raises:
        DefinitionError: a ``.msg`` file of the closure is not installed.
    """
    seen: set[str] = set()

    def text_of(name: str) -> str:
        text = msg_file(name).read_text()
        for dependency in msg_dependencies(text, name.split("/")[0]):
            if dependency not in seen:
                seen.add(dependency)
                text += f"\n{SEPARATOR}\nMSG: {dependency}\n{text_of(dependency)}"
        return text

    return text_of(type_name)


@functools.cache
def type_description_hash(type_name: str) -> str:
    """The type hash ``RIHS01_<sha256>`` of ``'pkg/msg/Type'`` from its installed type
    description (``share/<pkg>/msg/<Type>.json``), or ``''`` when none is installed (rosbag2
    stores ``''`` then too)."""
    package, name = _parts(type_name)
    wanted = full_type_name(type_name)
    for share in share_folders(package):
        path = share / "msg" / f"{name}.json"
        try:
            hashes = json.loads(path.read_text())["type_hashes"]
        except (OSError, ValueError, KeyError, TypeError):
            continue
        for entry in hashes:
            if isinstance(entry, dict) and entry.get("type_name") == wanted:
                return str(entry.get("hash_string", ""))
    return ""


@dataclass(frozen=True)
class Field:
    """One field of a message as CDR lays it out.

    Attributes:
        kind: a primitive (``float64``, ``string``, ...) or a message ``'pkg/Type'``.
        length: elements of a fixed-size array; None for a single value or a sequence.
        sequence: a sequence (``T[]`` or ``T[<=N]``: a uint32 count, then the elements).
    """

    name: str
    kind: str
    length: int | None = None
    sequence: bool = False


def _field(words: list[str], package: str) -> Field:
    """A field from the words ``[type, name, ...]`` of a .msg line."""
    spec, name = words[0], words[1]
    kind, length, sequence = spec, None, False
    if "[" in spec:
        kind, bracket = spec.split("[", 1)
        bound = bracket.rstrip("]")
        if bound == "" or bound.startswith("<="):
            sequence = True
        else:
            length = int(bound)
    kind = kind.split("<=", 1)[0]  # a bounded string is a string
    if kind not in PRIMITIVE_TYPES and "/" not in kind:
        kind = f"{package}/{kind}"
    elif kind not in PRIMITIVE_TYPES:
        kind = "/".join(_parts(kind))
    return Field(name, kind, length, sequence)


def parse_definition(type_name: str, text: str) -> dict[str, tuple[Field, ...]]:
    """The fields of every type of a complete ros2msg definition ``text`` of ``type_name``:
    ``{'pkg/Type': fields}`` (constants left out).

    Raises:
        DefinitionError: a line that is not a field, a constant or a comment.
    """
    sections = text.split(f"{SEPARATOR}\n")
    types: dict[str, tuple[Field, ...]] = {}
    for index, section in enumerate(sections):
        lines = section.splitlines()
        name = "/".join(_parts(type_name))
        if index > 0:
            if not lines or not lines[0].startswith("MSG: "):
                raise DefinitionError(f"{type_name}: a definition section without 'MSG: pkg/Type'")
            name = "/".join(_parts(lines.pop(0)[5:].strip()))
        package = name.split("/")[0]
        fields = []
        for line in lines:
            words = line.split("#", 1)[0].split()
            if not words:
                continue
            if len(words) < 2:
                raise DefinitionError(f"{name}: cannot read the definition line {line.strip()!r}")
            if "=" in words[1] or (len(words) > 2 and words[2].startswith("=")):
                continue  # a constant (NAME=VALUE): not serialized
            try:
                fields.append(_field(words, package))
            except ValueError:
                raise DefinitionError(f"{name}: bad array bound in {line.strip()!r}") from None
        types[name] = tuple(fields)
    return types
