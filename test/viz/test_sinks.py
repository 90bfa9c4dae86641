"""Sink selection and the local viewers: everything listens on 127.0.0.1 only."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import time
import urllib.request
import warnings
from pathlib import Path

import numpy as np
import pytest
import rerun as rr

from rns_ros.core import ConfigError, load_model_config
from rns_ros.resources import default_model_config
from rns_ros.viz import TelemetryRecorder, paths
from rns_ros.viz.readback import recording_summary
from rns_ros.viz.sinks import (
    SinkError,
    SinkKind,
    SinkSettings,
    has_display,
    open_sink,
    rerun_executable,
    resolve_kind,
)


def _free_ports(count: int = 1) -> list[int]:
    """Distinct free TCP ports on 127.0.0.1 (held together while choosing, so never equal)."""
    probes = [socket.socket() for _ in range(count)]
    try:
        for probe in probes:
            probe.bind(("127.0.0.1", 0))
        return [probe.getsockname()[1] for probe in probes]
    finally:
        for probe in probes:
            probe.close()


def _listening_addresses(port: int) -> set[str]:
    """IPv4/IPv6 addresses (hex, as in /proc/net/tcp*) with a socket listening on ``port``."""
    addresses = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        if not Path(table).exists():
            continue
        for line in Path(table).read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, hex_port = local.split(":")
            if state == "0A" and int(hex_port, 16) == port:  # 0A = LISTEN
                addresses.add(address)
    return addresses


@pytest.mark.parametrize(
    ("env", "kind"),
    [
        ({}, SinkKind.SAVE),
        ({"DISPLAY": ""}, SinkKind.SAVE),
        ({"DISPLAY": ":0"}, SinkKind.SPAWN),
        ({"WAYLAND_DISPLAY": "wayland-0"}, SinkKind.SPAWN),
    ],
)
def test_auto_spawns_only_with_a_display(env, kind):
    assert has_display(env) is (kind is SinkKind.SPAWN)
    assert resolve_kind("auto", env) is kind
    assert resolve_kind("connect", env) is SinkKind.CONNECT


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"kind": "viewer"}, "sink must be one of .*'viewer'"),
        ({"connect_url": "http://127.0.0.1:9876"}, "connect_url must look like"),
        ({"grpc_port": 70000}, "grpc_port must be in \\[1, 65535\\], got 70000"),
        ({"kind": "save", "rrd_path": "/no/such/folder/x.rrd"}, "'/no/such/folder' does not"),
    ],
)
def test_bad_sink_settings_name_the_value(settings, message):
    with pytest.raises(ConfigError, match=message):
        SinkSettings(**settings)


def test_save_resolves_a_relative_path_against_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rec = rr.RecordingStream("rns_ros_test")
    sink = open_sink(rec, SinkSettings(kind="save", rrd_path="out.rrd"))
    rec.log("x", rr.Scalars(1.0))
    rec.disconnect()
    assert sink.rrd_path == tmp_path / "out.rrd"
    assert sink.rrd_path.stat().st_size > 0
    assert f"rerun {tmp_path / 'out.rrd'}" in sink.description


def test_serve_hosts_grpc_and_web_viewer_on_loopback_only():
    grpc_port, web_port, other_port = _free_ports(3)
    rec = rr.RecordingStream("rns_ros_test")
    sink = open_sink(rec, SinkSettings(kind="serve", grpc_port=grpc_port, web_port=web_port))
    try:
        assert _listening_addresses(grpc_port) == {"0100007F"}  # 127.0.0.1
        assert _listening_addresses(web_port) == {"0100007F"}
        with urllib.request.urlopen(f"http://127.0.0.1:{web_port}/", timeout=5) as page:
            assert page.status == 200
        assert f"http://127.0.0.1:{web_port}/?url=rerun%2Bhttp%3A%2F%2F" in sink.description
        # a second server on the same ports is refused with a clear error
        with pytest.raises(SinkError, match=f"grpc_port {grpc_port} .* already in use"):
            open_sink(
                rr.RecordingStream("rns_ros_test"),
                SinkSettings(kind="serve", grpc_port=grpc_port, web_port=other_port),
            )
    finally:
        rec.disconnect()
        sink.close()
    assert _listening_addresses(web_port) == set()  # the web viewer process was stopped


def test_spawn_without_a_display_fails_clearly_and_auto_falls_back_to_save(tmp_path, monkeypatch):
    # Make sure no real window can open, whatever the developer's session has.
    monkeypatch.setenv("DISPLAY", ":987654")
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    (port,) = _free_ports()
    with pytest.raises(SinkError, match="exited with code"):
        open_sink(rr.RecordingStream("rns_ros_test"), SinkSettings(kind="spawn", grpc_port=port))
    rec = rr.RecordingStream("rns_ros_test")
    settings = SinkSettings(kind="auto", grpc_port=port, rrd_path=tmp_path / "fallback.rrd")
    sink = open_sink(rec, settings)
    rec.disconnect()
    assert sink.kind is SinkKind.SAVE
    assert sink.description.startswith("could not spawn a viewer")
    assert sink.rrd_path == tmp_path / "fallback.rrd"


def test_connect_streams_to_a_running_rerun_server(robot, tmp_path):
    """A headless ``rerun --save`` server stands in for a viewer: what it receives is on disk."""
    (port,) = _free_ports()
    received = tmp_path / "received.rrd"
    server = subprocess.Popen(
        [rerun_executable(), "--bind", "127.0.0.1", "--port", str(port), "--save", str(received)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env={**os.environ, "RERUN_APP_ONLY": "true"},
    )
    try:
        # hang-sized bounds: the server's start and exit take seconds on a loaded machine
        deadline = time.monotonic() + 60.0
        while _listening_addresses(port) != {"0100007F"} and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _listening_addresses(port) == {"0100007F"}, "rerun server not listening after 60 s"
        urdf, _ = load_model_config(default_model_config())
        url = f"rerun+http://127.0.0.1:{port}/proxy"
        recorder = TelemetryRecorder(robot, urdf, SinkSettings(kind="connect", connect_url=url))
        assert recorder.sink.description == f"streaming to the viewer at {url}"
        for k in range(20):
            recorder.joint_state(k * 10_000_000, np.zeros(7), np.zeros(7))
        recorder.close()  # flushes the gRPC stream
        # spawn finds something listening on its port and streams there instead of starting one
        other = rr.RecordingStream("rns_ros_test")
        reused = open_sink(other, SinkSettings(kind="spawn", grpc_port=port))
        other.disconnect()
        assert reused.viewer_pid is None
        assert reused.description == f"streaming to the viewer already running at {url}"
        time.sleep(0.5)
    finally:
        server.send_signal(signal.SIGINT)  # the server writes what it received and exits
        try:
            server.wait(timeout=60.0)
        finally:
            if server.poll() is None:  # never left running past the test
                server.kill()
                server.wait()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # an interrupted `rerun --save` writes no footer
        summary = recording_summary(received)
    assert summary[paths.joint_transform("joint_1")] == 20
    assert summary[paths.ACHIEVED_ANGULAR_VELOCITY_AXES[2]] == 20
