"""Start-up contract of every installed executable: a bad argument, params file,
parameter or model is one line ``<executable>: <problem>`` on stderr and exit code 2, never a
traceback; Ctrl-C during start-up (imports included) is exit code 0; an unknown ``-p`` name is a
warning naming the closest valid one.

The executables run as subprocesses from ``.venv/bin`` (~1 s each: the imports take ~0.4 s).
"""

from __future__ import annotations

import contextlib
import os
import pty
import re
import select
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from rns_testing import alias_bomb_model, chain_urdf

from rns_ros.cli import EXECUTABLES, describe_ros_error, one_line
from rns_ros.core.config import load_model_config
from rns_ros.core.urdf_tree import MAX_URDF_LINKS
from rns_ros.core.yaml_input import MAX_YAML_NODES
from rns_ros.resources import default_model_config

REPO = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
TIMEOUT_S = 20.0  # a start-up failure takes ~1 s; a node that does not fail runs until killed
#: The executables with the start-up contract (rns_param / rns_topic have their own tests).
CHECKED = (
    "rns_attitude_control",
    "rns_controller",
    "rns_demo",
    "rns_force_controller",
    "rns_link",
    "rns_predictor",
    "rns_observer",
    "rns_operator",
    "rns_rerun_logger",
    "rns_simulator",
    "rns_teleop_keyboard",
)


def _env(**extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env.update(
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        ROS_DOMAIN_ID="65",
        AMENT_PREFIX_PATH=str(BIN.parent),
        PATH=f"{BIN}{os.pathsep}{env.get('PATH', '')}",
    )
    env.pop("DISPLAY", None)  # rns_rerun_logger's sink auto: save, never a viewer
    env.pop("WAYLAND_DISPLAY", None)
    env.update(extra)
    return env


def _run(executable: str, *args: str, cwd: Path, **env: str) -> subprocess.CompletedProcess:
    """Run an executable that must fail at start-up; killed (and the test failed) if it runs on."""
    with subprocess.Popen(
        [str(BIN / executable), *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(**env),
        cwd=cwd,
        start_new_session=True,
    ) as proc:
        try:
            out, err = proc.communicate(timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out, err = proc.communicate()
            pytest.fail(f"{executable} {list(args)} still ran after {TIMEOUT_S} s:\n{err[-2000:]}")
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def _assert_one_line_error(result: subprocess.CompletedProcess, executable: str, pattern: str):
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.returncode == 2, result.stderr[-3000:]
    assert "Traceback" not in result.stderr
    assert len(lines) == 1, result.stderr[-3000:]
    assert lines[0].startswith(f"{executable}: ")
    assert re.search(pattern, lines[0]), lines[0]


def test_executables_match_the_console_scripts_of_setup_py():
    setup = (REPO / "setup.py").read_text()
    scripts = set(re.findall(r'"(rns_\w+) = rns_ros\.', setup))
    assert set(CHECKED) <= scripts
    # every console script gets the start-up Ctrl-C handling (rns_ros.cli)
    assert scripts <= EXECUTABLES


# --- bad ROS arguments ------------------------------------------------------------------------
@pytest.mark.parametrize("executable", CHECKED)
def test_garbage_params_file_is_one_line_and_exit_2(executable, tmp_path):
    params = tmp_path / "params.yaml"
    params.write_text("garbage: [\n")  # not even YAML
    result = _run(executable, "--ros-args", "--params-file", str(params), cwd=tmp_path)
    _assert_one_line_error(result, executable, r"Couldn't parse params file: .*params\.yaml")
    assert "/project/src" not in result.stderr  # rcl's C source locations are cut


@pytest.mark.parametrize(
    ("executable", "args", "pattern", "env"),
    [
        ("rns_operator", ["--ros-args", "-p"], r"trailing -p flag", {}),
        ("rns_demo", ["--ros-args", "-p"], r"trailing -p flag", {}),
        ("rns_controller", ["--ros-args", "--bogus"], r"unknown ROS arguments \['--bogus'\]", {}),
        # a params file for another program: valid YAML, not ROS parameters
        ("rns_simulator", ["--ros-args", "--params-file", "{tmp}/p.yaml"], r"ros__parameters", {}),
        # rclpy's own parameter, checked inside Node.__init__
        (
            "rns_teleop_keyboard",
            ["--ros-args", "-p", "use_sim_time:=maybe"],
            r"'use_sim_time' to 'maybe'",
            {},
        ),
        ("rns_operator", [], r"ROS_DOMAIN_ID is not an integral number", {"ROS_DOMAIN_ID": "x"}),
        # Fast DDS would end the process from C++ (exit code 1, RTPS errors) at node creation
        ("rns_controller", [], r"ROS_DOMAIN_ID=300 is out of range", {"ROS_DOMAIN_ID": "300"}),
    ],
    ids=[
        "trailing-p",
        "demo-trailing-p",
        "unknown-flag",
        "foreign-yaml",
        "sim-time",
        "domain",
        "domain-300",
    ],
)
def test_bad_ros_arguments_are_one_line_and_exit_2(executable, args, pattern, env, tmp_path):
    (tmp_path / "p.yaml").write_text("a: 1\n")
    args = [arg.format(tmp=tmp_path) for arg in args]
    _assert_one_line_error(_run(executable, *args, cwd=tmp_path, **env), executable, pattern)


# --- bad configuration ------------------------------------------------------------------------
@pytest.mark.parametrize("sink", ["save", "auto"])  # auto without a display falls back to save
def test_rrd_path_that_is_a_directory_is_one_line_and_exit_2(sink, tmp_path):
    result = _run(
        "rns_rerun_logger",
        "--ros-args",
        "-p",
        f"sink:={sink}",
        "-p",
        f"rrd_path:={tmp_path}",
        cwd=tmp_path,
    )
    _assert_one_line_error(result, "rns_rerun_logger", rf"rrd_path '{tmp_path}' is a directory")


def test_model_with_a_nan_inertia_is_one_line_naming_the_link_and_exit_2(tmp_path):
    urdf, _ = load_model_config(default_model_config())
    root = ET.fromstring(urdf.read_text())
    root.find("link[@name='base_link']/inertial/inertia").set("ixx", "nan")
    (tmp_path / "arm.urdf").write_text(ET.tostring(root, encoding="unicode"))
    config = tmp_path / "model.yaml"
    config.write_text("urdf: arm.urdf\ncamera_frame: camera\nwrist_frame: wrist\n")
    result = _run("rns_simulator", "--ros-args", "-p", f"model_config:={config}", cwd=tmp_path)
    _assert_one_line_error(result, "rns_simulator", r"link 'base_link' <inertia>: ixx='nan'")


@pytest.mark.parametrize("kind", ["alias-bomb", "1000-links"])
def test_model_over_the_input_limits_is_one_line_and_exit_2(kind, tmp_path):
    config = tmp_path / "model.yaml"
    if kind == "alias-bomb":
        urdf, _ = load_model_config(default_model_config())
        config.write_text(alias_bomb_model("held_joints", urdf))
        pattern = rf"model\.yaml: more than {MAX_YAML_NODES} YAML nodes with the aliases expanded"
    else:
        (tmp_path / "chain.urdf").write_text(chain_urdf(1000))
        config.write_text("urdf: chain.urdf\ncamera_frame: l999\nwrist_frame: null\n")
        pattern = rf"chain: 1000 <link> elements, over the limit of {MAX_URDF_LINKS}"
    result = _run("rns_simulator", "--ros-args", "-p", f"model_config:={config}", cwd=tmp_path)
    _assert_one_line_error(result, "rns_simulator", pattern)


# --- Ctrl-C during start-up ------------------------------------------------------------------
def _interrupt_after(executable: str, delay: float, tmp_path) -> tuple[int, str]:
    """Start ``executable``, send SIGINT after ``delay`` [s]; (exit code, stderr)."""
    master, slave = pty.openpty()
    stdin = slave if executable == "rns_teleop_keyboard" else subprocess.DEVNULL
    args = ["--no-record"] if executable == "rns_demo" else []
    proc = subprocess.Popen(
        [str(BIN / executable), *args],
        stdin=stdin,
        stdout=slave,
        stderr=subprocess.PIPE,
        env=_env(TERM="xterm"),
        cwd=tmp_path,
        start_new_session=True,
    )
    os.close(slave)
    try:
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        deadline = time.monotonic() + TIMEOUT_S
        while proc.poll() is None and time.monotonic() < deadline:
            if select.select([master], [], [], 0.1)[0]:
                try:
                    os.read(master, 65536)  # keep the terminal drained
                except OSError:
                    # the terminal closed as the process exits, which takes a while longer
                    # on a loaded machine
                    with contextlib.suppress(subprocess.TimeoutExpired):
                        proc.wait(timeout=max(0.0, deadline - time.monotonic()))
                    break
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
        return proc.wait(), proc.stderr.read().decode(errors="replace")
    finally:
        os.close(master)
        proc.stderr.close()


@pytest.mark.parametrize("executable", CHECKED)
def test_ctrl_c_during_start_up_exits_0_without_a_traceback(executable, tmp_path):
    """0.3 s: still importing numpy / Pinocchio / rclpy (~0.4 s), where Python's own handler
    would raise KeyboardInterrupt. The keyboard teleop needs a terminal to get that far. On a
    loaded machine the interpreter itself may still be starting at 0.3 s: an interrupt whose
    traceback holds no frame of an rns_ros/ file, or one that killed the process before Python
    installed its handler (exit by SIGINT, nothing printed), landed before any of our code ran
    (nothing of ours can handle it), so that attempt is repeated later, up to 1.2 s."""
    for delay in (0.3, 0.6, 1.2):
        code, err = _interrupt_after(executable, delay, tmp_path)
        killed_early = code == -signal.SIGINT and not err.strip()
        before_our_code = killed_early or (
            code != 0 and "Traceback" in err and "rns_ros/" not in err
        )
        if not before_our_code:
            break
    assert code == 0, err[-3000:]
    assert "Traceback" not in err, err[-3000:]
    assert "KeyboardInterrupt" not in err, err[-3000:]


# --- unknown -p names --------------------------------------------------------------------------
def test_unknown_parameter_is_a_warning_naming_the_closest_valid_one(tmp_path):
    proc = subprocess.Popen(
        [str(BIN / "rns_operator"), "--ros-args", "-p", "ratee:=20.0", "-p", "use_sim_time:=false"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=_env(),
        cwd=tmp_path,
        start_new_session=True,
    )
    fd = proc.stderr.fileno()  # raw reads: a buffered readline would hide what follows
    text = ""

    def read_until(done) -> None:
        nonlocal text
        deadline = time.monotonic() + TIMEOUT_S
        while time.monotonic() < deadline and not done():
            if select.select([fd], [], [], 0.1)[0]:
                chunk = os.read(fd, 65536)
                if not chunk:  # the process closed stderr
                    return
                text += chunk.decode(errors="replace")

    try:
        read_until(lambda: "unknown parameter" in text)
        proc.send_signal(signal.SIGINT)
        read_until(lambda: False)
        code = proc.wait(timeout=TIMEOUT_S)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        proc.stderr.close()
    warnings = [line for line in text.splitlines() if "unknown parameter" in line]
    assert len(warnings) == 1, text  # not use_sim_time: rclpy's own
    assert "unknown parameter 'ratee' is ignored; did you mean 'rate'?" in warnings[0]
    assert code == 0, text


# --- message formatting -------------------------------------------------------------------------
def test_one_line_drops_rcl_source_locations():
    message = (
        "Failed to parse ROS arguments: Couldn't parse params file: '--params-file x.yaml'. "
        "Error: Sequences can only be values and not keys in params. Error at line 1\n"
        ", at /project/src/parse.c:841, at /project/src/rcl/arguments.c:415"
    )
    assert one_line(message) == (
        "Failed to parse ROS arguments: Couldn't parse params file: '--params-file x.yaml'. "
        "Error: Sequences can only be values and not keys in params. Error at line 1"
    )


def test_unknown_ros_arguments_are_explained():
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
    from rclpy.utilities import remove_ros_args

    with pytest.raises(_rclpy.UnknownROSArgsError) as caught:
        remove_ros_args(["x", "--ros-args", "--bogus"])
    assert describe_ros_error(caught.value).startswith("unknown ROS arguments ['--bogus']; ")


def _shell_env() -> dict[str, str]:
    """A new shell's environment: no AMENT_PREFIX_PATH, no activated venv, no PYTHONPATH."""
    return {"HOME": os.environ.get("HOME", "/tmp"), "PATH": "/usr/bin:/bin", "LANG": "C.UTF-8"}


@pytest.mark.parametrize("executable", sorted(EXECUTABLES))
def test_every_console_script_runs_from_the_venv_alone(executable, tmp_path):
    done = subprocess.run(
        [str(BIN / executable), "--help"],
        env=_shell_env(),
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.startswith(f"usage: {executable}")
    assert "Traceback" not in done.stderr


def test_the_shipped_files_are_found_from_the_venv_alone(tmp_path):
    """Without AMENT_PREFIX_PATH the package's config files (the reproduction list, the
    default model) come from the venv's share folder."""
    listing = subprocess.run(
        [str(BIN / "rns_reproduce"), "list"],
        env=_shell_env(),
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert listing.returncode == 0, listing.stderr[-2000:]
    assert "table4.2" in listing.stdout
    model = subprocess.run(
        [str(BIN / "rns_model"), "check", str(default_model_config())],
        env=_shell_env(),
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert model.returncode == 0, model.stderr[-2000:]
    assert "Traceback" not in model.stderr
