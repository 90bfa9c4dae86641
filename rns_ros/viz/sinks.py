"""Where a recording goes: a spawned viewer, a running viewer, a local web viewer, or a file.

=========  ===========================================================================
sink       what happens
=========  ===========================================================================
spawn      start the native viewer ``rerun --bind 127.0.0.1 --port <grpc_port>`` (or reuse
           one already listening there) and stream to it
connect    stream to a viewer or server at ``connect_url`` (``rerun+http://host:port/proxy``)
serve      host a gRPC server on 127.0.0.1:<grpc_port> in this process and a web viewer on
           http://127.0.0.1:<web_port> (a ``rerun --serve-web`` child process)
save       write an ``.rrd`` file; open it later with ``rerun <file>``
auto       spawn when a display exists (``DISPLAY`` / ``WAYLAND_DISPLAY``), else save; a failed
           spawn falls back to save
=========  ===========================================================================

Everything listens on the loopback interface only. The SDK's own ``spawn``, ``serve_grpc`` and
``serve_web_viewer`` would bind 0.0.0.0 in rerun 0.41, so the viewer processes are started here
with ``--bind 127.0.0.1`` and the in-process server is a ``GrpcServerSink(bind_ip="127.0.0.1")``.

Each sink belongs to one ``RecordingStream`` (never the global one), so several recordings can be
open in one process.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import socket
import subprocess
import tempfile
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO
from urllib.parse import quote

import rerun as rr
import rerun.blueprint as rrb

from rns_ros.core.errors import ConfigError, RnsError
from rns_ros.core.validation import Choice

LOCALHOST = "127.0.0.1"
#: How long a starting viewer process may take to listen [s].
START_TIMEOUT = 10.0
#: A native viewer listens before it opens its window (and exits ~10 ms later when there is no
#: display): it must still run this long after listening to count as started [s].
WINDOW_GRACE = 0.5
CONNECT_SCHEMES = ("rerun://", "rerun+http://", "rerun+https://")
_ANSI = re.compile(r"\x1b\[[0-9;]*m")


class SinkError(RnsError, RuntimeError):
    """A viewer could not be started or a port is taken."""


class SinkKind(Choice):
    """Where the recording goes (see the module docstring)."""

    __label__ = "sink"

    AUTO = "auto"
    SPAWN = "spawn"
    CONNECT = "connect"
    SERVE = "serve"
    SAVE = "save"


@dataclass(frozen=True)
class SinkSettings:
    """Sink choice and its addresses.

    Attributes:
        kind: :class:`SinkKind` (or its value).
        rrd_path: file for ``save`` (relative: to the working directory); its folder must exist.
        connect_url: viewer/server URL for ``connect``: ``rerun+http://HOST:PORT/proxy``.
        grpc_port: port of the spawned viewer (``spawn``) or of the in-process server (``serve``).
        web_port: HTTP port of the web viewer (``serve``).

    Raises:
        ConfigError: unknown kind, a URL of the wrong form, a port outside [1, 65535], or (for
            ``save``) an ``rrd_path`` that is a directory or whose folder does not exist.
    """

    kind: SinkKind | str = SinkKind.AUTO
    rrd_path: Path | str = Path("rns_ros.rrd")
    connect_url: str = f"rerun+http://{LOCALHOST}:9876/proxy"
    grpc_port: int = 9876
    web_port: int = 9090

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", SinkKind.parse(self.kind))
        path = Path(self.rrd_path).expanduser()
        object.__setattr__(self, "rrd_path", path)
        for name in ("grpc_port", "web_port"):
            port = getattr(self, name)
            if not 1 <= port <= 65535:
                raise ConfigError(f"{name} must be in [1, 65535], got {port}")
        url = self.connect_url
        if not url.startswith(CONNECT_SCHEMES) or not url.rstrip("/").endswith("/proxy"):
            raise ConfigError(
                f"connect_url must look like rerun+http://HOST:PORT/proxy (schemes "
                f"{list(CONNECT_SCHEMES)}), got {url!r}"
            )
        if self.kind is SinkKind.SAVE:
            _check_rrd_path(path)


def has_display(env: Mapping[str, str] | None = None) -> bool:
    """True when a graphical session is reachable (``DISPLAY`` or ``WAYLAND_DISPLAY`` set)."""
    env = os.environ if env is None else env
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def resolve_kind(kind: SinkKind | str, env: Mapping[str, str] | None = None) -> SinkKind:
    """``auto`` -> ``spawn`` with a display, else ``save``; other kinds unchanged."""
    kind = SinkKind.parse(kind)
    if kind is SinkKind.AUTO:
        return SinkKind.SPAWN if has_display(env) else SinkKind.SAVE
    return kind


def rerun_executable() -> str:
    """The ``rerun`` CLI of this environment: on PATH, else the binary in the rerun_cli wheel."""
    found = shutil.which("rerun")
    if found:
        return found
    import rerun_cli

    binary = Path(rerun_cli.__file__).parent / "rerun"
    if not binary.is_file():
        raise SinkError(f"no rerun executable on PATH nor at {binary}")
    return str(binary)


@dataclass
class OpenSink:
    """A sink attached to a recording.

    Attributes:
        kind: the resolved kind (never ``auto``).
        description: where the data goes and how to look at it (for the node's log).
        rrd_path: absolute file path for ``save``, else None.
        viewer_pid: pid of a viewer process started here (spawn: left running for the user;
            serve: the web viewer, stopped by :meth:`close`).
    """

    kind: SinkKind
    description: str
    rrd_path: Path | None = None
    viewer_pid: int | None = None
    _process: subprocess.Popen | None = field(default=None, repr=False)
    _stop_process: bool = field(default=False, repr=False)
    _stderr: IO[bytes] | None = field(default=None, repr=False)

    def close(self) -> None:
        """Stop the web viewer started for ``serve`` (a spawned native viewer stays open)."""
        process, self._process = self._process, None
        if process is not None and self._stop_process and process.poll() is None:
            process.terminate()
            try:
                process.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=5.0)
        if self._stderr is not None:
            self._stderr.close()
            self._stderr = None


def open_sink(
    rec: rr.RecordingStream,
    settings: SinkSettings,
    blueprint: rrb.Blueprint | None = None,
    env: Mapping[str, str] | None = None,
) -> OpenSink:
    """Attach the sink of ``settings`` to ``rec``; ``blueprint`` becomes its default layout.

    Call before logging anything. Raises :class:`SinkError` when a viewer cannot be started or a
    port is taken (``auto`` falls back to ``save`` instead).
    """
    kind = resolve_kind(settings.kind, env)
    if kind is SinkKind.SPAWN:
        try:
            return _spawn(rec, settings, blueprint)
        except SinkError as exc:
            if settings.kind is not SinkKind.AUTO:
                raise
            sink = _save(rec, settings, blueprint)
            sink.description = f"could not spawn a viewer ({exc}); {sink.description}"
            return sink
    if kind is SinkKind.CONNECT:
        rec.connect_grpc(settings.connect_url, default_blueprint=blueprint)
        return OpenSink(kind, f"streaming to the viewer at {settings.connect_url}")
    if kind is SinkKind.SERVE:
        return _serve(rec, settings, blueprint)
    return _save(rec, settings, blueprint)


def _check_rrd_path(path: Path) -> None:
    """ConfigError unless ``path`` can be a recording file: its folder exists, it is no folder."""
    path = path.absolute()
    if path.is_dir():
        raise ConfigError(f"rrd_path {str(path)!r} is a directory; give a file name like run.rrd")
    if not path.parent.is_dir():
        raise ConfigError(f"rrd_path {str(path)!r}: folder {str(path.parent)!r} does not exist")


def _save(rec, settings: SinkSettings, blueprint) -> OpenSink:
    path = Path(settings.rrd_path).absolute()
    _check_rrd_path(path)  # again: ``auto`` falls back to save without the settings check
    try:
        rec.save(path, default_blueprint=blueprint)
    except RuntimeError as exc:  # rerun's "Failed to create file: Permission denied ..."
        raise ConfigError(f"rrd_path {str(path)!r} cannot be written: {exc}") from None
    return OpenSink(
        SinkKind.SAVE, f"recording to {path}; open it with: rerun {path}", rrd_path=path
    )


def _spawn(rec, settings: SinkSettings, blueprint) -> OpenSink:
    port = settings.grpc_port
    url = f"rerun+http://{LOCALHOST}:{port}/proxy"
    if _accepts_connections(port):
        rec.connect_grpc(url, default_blueprint=blueprint)
        return OpenSink(SinkKind.SPAWN, f"streaming to the viewer already running at {url}")
    process, stderr = _start(
        ["--bind", LOCALHOST, "--port", str(port), "--expect-data-soon", "--memory-limit", "75%"],
        port,
        detach=True,
        grace=WINDOW_GRACE,
    )
    rec.connect_grpc(url, default_blueprint=blueprint)
    return OpenSink(
        SinkKind.SPAWN,
        f"spawned a rerun viewer (pid {process.pid}) listening on {url}",
        viewer_pid=process.pid,
        _process=process,
        _stderr=stderr,
    )


def _serve(rec, settings: SinkSettings, blueprint) -> OpenSink:
    for name in ("grpc_port", "web_port"):
        port = getattr(settings, name)
        if not _port_is_free(port):
            raise SinkError(f"{name} {port} on {LOCALHOST} is already in use; choose another")
    server = rr.GrpcServerSink(bind_ip=LOCALHOST, port=settings.grpc_port)
    rec.set_sinks(server, default_blueprint=blueprint)
    uri = server.uri
    web_port = settings.web_port
    process, stderr = _start(
        ["--serve-web", "--bind", LOCALHOST, "--web-viewer-port", str(web_port), uri],
        web_port,
        detach=False,
    )
    page = f"http://{LOCALHOST}:{web_port}/?url={quote(uri, safe='')}"
    return OpenSink(
        SinkKind.SERVE,
        f"serving on {uri}; open {page} in a browser, or run: rerun --connect {uri}",
        viewer_pid=process.pid,
        _process=process,
        _stop_process=True,
        _stderr=stderr,
    )


def _start(
    args: list[str], port: int, *, detach: bool, grace: float = 0.0
) -> tuple[subprocess.Popen, IO[bytes]]:
    """Run ``rerun <args>``, wait until it listens on ``port`` and is still running ``grace``
    seconds later; SinkError if it does not."""
    stderr = tempfile.TemporaryFile()  # noqa: SIM115 - lives as long as the viewer process
    process = subprocess.Popen(
        [rerun_executable(), *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=stderr,
        # RERUN_APP_ONLY: what the SDK's spawn sets (no analytics banner / opt-in prompt).
        env={**os.environ, "RERUN_APP_ONLY": "true"},
        start_new_session=detach,  # a spawned viewer outlives this node, like rr.spawn's
    )
    deadline = time.monotonic() + START_TIMEOUT
    listening_since = None
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise SinkError(
                f"'rerun {' '.join(args)}' exited with code {process.returncode}"
                f"{_tail(stderr)} (no display? use sink save)"
            )
        if listening_since is None and _accepts_connections(port):
            listening_since = time.monotonic()
        if listening_since is not None and time.monotonic() - listening_since >= grace:
            return process, stderr
        time.sleep(0.02)
    process.kill()
    process.wait(timeout=5.0)
    stderr.close()
    raise SinkError(f"'rerun {' '.join(args)}' did not listen on {LOCALHOST}:{port} in time")


def _tail(stream: IO[bytes]) -> str:
    """The last line the process wrote to ``stream`` (its error), without colour codes."""
    with contextlib.suppress(OSError):
        stream.seek(0)
        text = _ANSI.sub("", stream.read().decode(errors="replace"))
        stream.close()
        lines = [line.strip() for line in text.splitlines() if line.strip()]
        if lines:
            return f": {lines[-1]}"
    return ""


def _accepts_connections(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.settimeout(0.2)
        return probe.connect_ex((LOCALHOST, port)) == 0


def _port_is_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            probe.bind((LOCALHOST, port))
        except OSError:
            return False
    return True
