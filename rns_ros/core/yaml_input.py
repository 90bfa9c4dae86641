"""YAML read from users (model, scenario and fixed-base model files, command-line values) with
bounded size, so that no input can exhaust memory or time.

YAML aliases (``*name`` repeating an ``&name`` anchor) are normal YAML, and a few are accepted.
Nested, they multiply: nine aliases of nine aliases of ... (a "billion laughs") stand for
billions of values, which any code walking the value (a check, an error message) would visit.
So the document is measured while it is composed, before any Python value is built:

* at most :data:`MAX_YAML_ALIASES` aliases;
* at most :data:`MAX_YAML_NODES` nodes (scalars, lists, mappings), every alias counted as the
  nodes it repeats; an alias inside its own anchor (a recursive structure) is refused;
* at most :data:`MAX_YAML_BYTES` of text.

Each refusal is a :class:`~rns_ros.core.errors.ConfigError` naming the input, the limit and the
value found. The text is scanned by libyaml when PyYAML has it (as ``yaml.CSafeLoader``), the
nodes are composed and counted here, and built as :func:`yaml.safe_load` builds them.
"""

from __future__ import annotations

import os
from pathlib import Path

import yaml
from yaml.composer import Composer
from yaml.constructor import ConstructorError, SafeConstructor
from yaml.nodes import Node, ScalarNode
from yaml.resolver import Resolver

from rns_ros.core.errors import ConfigError

#: Largest YAML text read [bytes]: model and scenario files are a few kB.
MAX_YAML_BYTES = 1_000_000
#: Most aliases (``*name``) in one document: a hand-written file uses a few.
MAX_YAML_ALIASES = 100
#: Most nodes in one document, every alias counted as the nodes it repeats; a model or
#: scenario file has about a hundred.
MAX_YAML_NODES = 20_000

try:
    from yaml._yaml import CParser as _CParser
except ImportError:  # pragma: no cover - PyYAML built without libyaml
    _CParser = None

if _CParser is not None:
    _EVENT_SOURCES: tuple[type, ...] = (_CParser,)
else:  # pragma: no cover
    from yaml.parser import Parser
    from yaml.reader import Reader
    from yaml.scanner import Scanner

    _EVENT_SOURCES = (Reader, Scanner, Parser)


class _BoundedLoader(Composer, *_EVENT_SOURCES, SafeConstructor, Resolver):
    """A safe loader whose composer (first in the MRO, ahead of libyaml's own) counts the
    document's nodes, aliases expanded, as it goes (module docstring)."""

    def __init__(self, stream: str, where: str) -> None:
        if _CParser is not None:
            _CParser.__init__(self, stream)
        else:  # pragma: no cover
            Reader.__init__(self, stream)
            Scanner.__init__(self)
            Parser.__init__(self)
        Composer.__init__(self)
        SafeConstructor.__init__(self)
        Resolver.__init__(self)
        self.where = where
        self.aliases = 0
        self.total = 0  # nodes so far, aliases expanded
        self.sizes: dict[int, int] = {}  # id(anchored node) -> nodes it stands for

    def compose_node(self, parent: Node | None, index) -> Node:
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            line = event.start_mark.line + 1
            self.aliases += 1
            if self.aliases > MAX_YAML_ALIASES:
                raise ConfigError(
                    f"{self.where}: more than {MAX_YAML_ALIASES} YAML aliases (*name), the "
                    f"limit (one more: *{event.anchor} at line {line})"
                )
            target = self.anchors.get(event.anchor)
            if target is not None:  # else the composer reports the undefined alias
                if id(target) not in self.sizes:
                    raise ConfigError(
                        f"{self.where}: alias *{event.anchor} at line {line} is inside its "
                        "own anchor (a recursive structure)"
                    )
                self._count(self.sizes[id(target)], line)
            return super().compose_node(parent, index)
        event = self.peek_event()
        self._count(1, event.start_mark.line + 1)
        before = self.total
        node = super().compose_node(parent, index)
        if event.anchor is not None:
            self.sizes[id(node)] = 1 + self.total - before
        return node

    def _count(self, nodes: int, line: int) -> None:
        self.total += nodes
        if self.total > MAX_YAML_NODES:
            raise ConfigError(
                f"{self.where}: more than {MAX_YAML_NODES} YAML nodes with the aliases "
                f"expanded, the limit ({self.total} by line {line})"
            )

    def construct_yaml_int(self, node: ScalarNode) -> int:
        try:
            return super().construct_yaml_int(node)
        except ValueError:  # Python's limit on the digits of a decimal integer
            raise ConstructorError(
                None,
                None,
                f"integer of {len(node.value)} characters is too long",
                node.start_mark,
            ) from None


_BoundedLoader.add_constructor("tag:yaml.org,2002:int", _BoundedLoader.construct_yaml_int)


def load_yaml(text: str, where: str):
    """The Python value of the YAML document ``text`` (scalars, lists and dicts only, as
    :func:`yaml.safe_load`); ``where`` names the input in errors.

    Raises:
        ConfigError: ``text`` is over :data:`MAX_YAML_BYTES` or the document over a limit of
            the module docstring.
        yaml.YAMLError: ``text`` is not YAML (the caller says what to do about it).
    """
    size = len(text.encode(errors="replace"))
    if size > MAX_YAML_BYTES:
        raise ConfigError(f"{where}: {size} bytes of YAML, over the limit of {MAX_YAML_BYTES}")
    loader = _BoundedLoader(text, where)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def read_head(path: Path, limit: int) -> tuple[bytes, int]:
    """The first ``limit + 1`` bytes of the file ``path`` and its size [bytes] (what was read,
    or more where the file system says so): a file over ``limit`` is told without reading it
    all.

    Raises:
        OSError: the file cannot be read.
    """
    with Path(path).open("rb") as stream:
        data = stream.read(limit + 1)
        return data, max(len(data), os.fstat(stream.fileno()).st_size)


def read_yaml_file(path: str | Path, what: str):
    """The Python value of the YAML file ``path`` (see :func:`load_yaml`); ``what`` names the
    kind of file in errors ("model config").

    Raises:
        ConfigError: the file is missing, unreadable, larger than :data:`MAX_YAML_BYTES`, not
            YAML, or over a limit of the module docstring (one line naming the file).
    """
    path = Path(path)
    try:
        if not path.is_file():
            raise ConfigError(f"{what} not found: {path}")
        data, size = read_head(path, MAX_YAML_BYTES)
        if size > MAX_YAML_BYTES:
            raise ConfigError(
                f"{path}: {size} bytes, over the limit of {MAX_YAML_BYTES} bytes for a {what}"
            )
        text = data.decode()
    except OSError as exc:  # the message without the file name, given once in front
        raise ConfigError(f"{path}: cannot read the {what}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: cannot read the {what}: {exc}") from None
    try:
        return load_yaml(text, str(path))
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML: {exc}") from exc
