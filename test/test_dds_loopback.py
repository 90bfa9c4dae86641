"""DDS on the loopback interface: the profile the programs apply where localhost is asked for.

The rule (``rns_ros.resources.apply_loopback_profile``) is checked on environments; the effect on
a running node by its sockets, read from ``/proc`` as ``ss -uanp`` shows them: with the profile
every UDP socket of the node is bound to 127.0.0.1, and the node is still reached by a
participant of this process. A user's own profile is left in force, and with it (Fast DDS's
defaults) the node binds sockets beyond 127.0.0.1: the check can fail.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from sensor_msgs.msg import JointState

from rns_ros import resources
from rns_ros.harness import Harness, ros_environment
from rns_ros.resources import apply_loopback_profile, loopback_profile

ROOT = Path(__file__).resolve().parents[1]
DOMAIN = int(os.environ.get("ROS_DOMAIN_ID", "44"))
FILE = "FASTRTPS_DEFAULT_PROFILES_FILE"
RANGE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
SIMULATOR = "import sys; from rns_ros.nodes.simulator import main; sys.exit(main())"


def _localhost(**extra: str) -> dict[str, str]:
    return {RANGE: "LOCALHOST", "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", **extra}


def test_the_shipped_profile_binds_127_0_0_1_only_and_sends_no_multicast():
    profile = loopback_profile()
    assert profile is not None
    assert profile.is_file()
    root = ET.parse(profile).getroot()
    ns = {"p": root.tag.split("}")[0].strip("{")}
    addresses = [e.text for e in root.iter() if e.tag.endswith("}address")]
    assert addresses
    assert set(addresses) == {"127.0.0.1"}
    assert root.find(".//p:metatrafficMulticastLocatorList", ns) is None
    assert root.find(".//p:defaultMulticastLocatorList", ns) is None
    assert root.find(".//p:useBuiltinTransports", ns).text == "false"


def test_a_child_asking_for_localhost_gets_the_profile_and_a_range_rmw_adds_nothing_to():
    env = _localhost()
    assert apply_loopback_profile(env) == loopback_profile()
    assert env[FILE] == str(loopback_profile())
    assert env[RANGE] == "SYSTEM_DEFAULT"
    # applied once, it stays applied (a program's children inherit it)
    again = dict(env)
    assert apply_loopback_profile(again) == loopback_profile()
    assert again == env


@pytest.mark.parametrize(
    "env",
    [
        _localhost(FASTRTPS_DEFAULT_PROFILES_FILE="/home/me/my_profile.xml"),
        _localhost(FASTDDS_DEFAULT_PROFILES_FILE="/home/me/my_profile.xml"),
        _localhost(ROS_STATIC_PEERS="192.168.1.7"),
        _localhost(RMW_IMPLEMENTATION="rmw_cyclonedds_cpp"),
        {RANGE: "SUBNET"},
        {RANGE: "SYSTEM_DEFAULT"},
        {},
    ],
    ids=[
        "own profile",
        "own profile (Fast DDS 3 name)",
        "static peers",
        "cyclone",
        "subnet",
        "system default",
        "nothing asked",
    ],
)
def test_the_profile_is_left_out_where_the_user_decides_otherwise(env):
    before = dict(env)
    assert apply_loopback_profile(env) is None
    assert env == before


def test_a_profile_file_in_the_working_folder_is_the_users(tmp_path, monkeypatch):
    (tmp_path / "DEFAULT_FASTRTPS_PROFILES.xml").write_text("<profiles/>")
    monkeypatch.chdir(tmp_path)
    env = _localhost()
    assert apply_loopback_profile(env) is None
    assert FILE not in env


def test_this_process_keeps_localhost_once_it_holds_a_udp_socket(monkeypatch):
    """Fast DDS reads the profile at a process's first participant only: after that the range
    must stay LOCALHOST (SYSTEM_DEFAULT without the profile would discover by multicast)."""
    monkeypatch.setattr(resources, "_profile_loaded", False)
    for name in (RANGE, FILE, "FASTDDS_DEFAULT_PROFILES_FILE", "ROS_STATIC_PEERS"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv(RANGE, "LOCALHOST")
    monkeypatch.setenv("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as held:
        held.bind(("127.0.0.1", 0))
        assert apply_loopback_profile() == loopback_profile()
    assert os.environ[RANGE] == "LOCALHOST"
    assert os.environ[FILE] == str(loopback_profile())


def _udp_addresses(pid: int) -> list[str]:
    """Local addresses ``ip:port`` of the UDP sockets process ``pid`` holds."""
    inodes = set()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        try:
            link = os.readlink(f"/proc/{pid}/fd/{fd}")
        except OSError:
            continue
        if link.startswith("socket:["):
            inodes.add(link[len("socket:[") : -1])
    addresses = []
    with open(f"/proc/{pid}/net/udp") as rows:
        next(rows)
        for row in rows:
            fields = row.split()
            if fields[9] in inodes:
                ip_hex, port_hex = fields[1].split(":")
                ip = socket.inet_ntoa(int(ip_hex, 16).to_bytes(4, "little"))
                addresses.append(f"{ip}:{int(port_hex, 16)}")
    return addresses


def _simulator_sockets(env: dict[str, str], domain: int) -> list[str]:
    """Start rns_simulator with ``env``; once its joint_states reach this process, its UDP
    sockets (IPv4)."""
    env = {**env, "PYTHONPATH": str(ROOT), "ROS_DOMAIN_ID": str(domain)}
    with Harness(domain) as ros:
        states = ros.record(JointState, "joint_states")
        proc = subprocess.Popen(
            [sys.executable, "-c", SIMULATOR],
            cwd=ROOT,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        try:
            reached = ros.spin_until(lambda: len(states.messages) >= 3, timeout=60.0)
            assert proc.poll() is None, proc.stderr.read()
            assert reached, "the simulator's joint_states never reached this process"
            time.sleep(0.2)  # participants are matched: every socket is open
            return _udp_addresses(proc.pid)
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            proc.stderr.close()


@pytest.mark.skipif(not Path("/proc/self/net/udp").exists(), reason="reads sockets from /proc")
def test_a_node_asking_for_localhost_binds_every_udp_socket_to_127_0_0_1():
    env = ros_environment(DOMAIN)  # LOCALHOST, Fast DDS, no static peers
    for name in (FILE, "FASTDDS_DEFAULT_PROFILES_FILE"):
        env.pop(name, None)
    addresses = _simulator_sockets(env, DOMAIN)
    assert addresses, "the node holds no UDP socket"
    assert all(a.startswith("127.0.0.1:") for a in addresses), addresses


@pytest.mark.skipif(not Path("/proc/self/net/udp").exists(), reason="reads sockets from /proc")
def test_with_a_profile_of_the_users_own_the_node_uses_it(tmp_path):
    """An empty profile of the user's: Fast DDS's defaults, which bind beyond 127.0.0.1."""
    own = tmp_path / "mine.xml"
    own.write_text(
        '<?xml version="1.0" encoding="UTF-8" ?>\n'
        '<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"/>\n'
    )
    env = {**ros_environment(DOMAIN), FILE: str(own)}
    addresses = _simulator_sockets(env, DOMAIN)
    assert any(not a.startswith("127.0.0.1:") for a in addresses), addresses
