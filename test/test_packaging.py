"""Packaging checks for the ament_python package rns_ros.

* ``package.xml`` is a valid format-3 manifest that agrees with ``setup.py`` and with what the
  Python code imports;
* a real ``colcon build`` (run by the interpreter running pytest, into a temporary directory,
  from a copy of the source tree so nothing is written into the repository) installs the
  layout ``ros2 run`` / ``ament_index_python`` rely on, and the installed console scripts run.
"""

from __future__ import annotations

import ast
import fnmatch
import json
import os
import pty
import re
import shutil
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from catkin_pkg.package import parse_package

pytestmark = pytest.mark.packaging

REPO = Path(__file__).resolve().parents[1]
PKG = "rns_ros"
BUILD_TIMEOUT_S = 300
RUN_TIMEOUT_S = 60

# Not part of the source tree: never copied into the build, never expected to be installed.
TOP_LEVEL_EXCLUDES = {".venv", ".git", "build", "install", "log"}
ANYWHERE_EXCLUDES = (
    "__pycache__",
    "*.pyc",
    "*.egg-info",
    ".pytest_cache",
    ".ruff_cache",
    ".hypothesis",
    "*.rrd",
)
# Repository paths a build must never create (colcon's defaults, setuptools' egg-info).
BUILD_ARTEFACTS = ("build", "install", "log", "*.egg-info")

# rosdep keys of system Python packages -> the PyPI distribution pinned in requirements*.txt.
ROSDEP_TO_PYPI = {
    "python3-numpy": "numpy",
    "python3-yaml": "pyyaml",
    "python3-pytest": "pytest",
    "xacro": "xacro",  # a ROS package whose Python code PyPI carries under the same name
}


def _ros_env(**extra: str) -> dict[str, str]:
    """Environment for subprocesses that may start ROS nodes: localhost-only discovery."""
    env = dict(os.environ)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.setdefault("ROS_DOMAIN_ID", "43")
    env.update(extra)
    return env


def _ignore(root: Path):
    """``shutil.copytree`` ignore callable for the source-tree copy."""

    def ignore(directory: str, names: list[str]) -> set[str]:
        ignored = {
            name for name in names if any(fnmatch.fnmatch(name, p) for p in ANYWHERE_EXCLUDES)
        }
        if Path(directory).resolve() == root:
            ignored |= TOP_LEVEL_EXCLUDES & set(names)
        return ignored

    return ignore


def _source_files(directory: Path) -> list[Path]:
    """Files under ``directory`` (relative to it) that belong to the source tree."""
    if not directory.is_dir():
        return []
    files = []
    for path in sorted(directory.rglob("*")):
        rel = path.relative_to(directory)
        if path.is_file() and not any(
            fnmatch.fnmatch(part, p) for part in rel.parts for p in ANYWHERE_EXCLUDES
        ):
            files.append(rel)
    return files


def _build_artefacts_in_repo() -> set[str]:
    return {
        entry.name
        for entry in REPO.iterdir()
        if any(fnmatch.fnmatch(entry.name, p) for p in BUILD_ARTEFACTS)
    }


def _run(cmd: list[str], *, timeout: float, what: str, **kwargs) -> subprocess.CompletedProcess:
    """Run ``cmd`` in its own process group; on timeout kill the whole group and fail clearly."""
    with subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        text=True,
        start_new_session=True,
        **kwargs,
    ) as proc:
        try:
            out, _ = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out, _ = proc.communicate()
            pytest.fail(
                f"{what} did not finish within {timeout:.0f} s and was killed.\n"
                f"command: {' '.join(cmd)}\n--- output ---\n{out}"
            )
    return subprocess.CompletedProcess(cmd, proc.returncode, out, None)


# --- static metadata --------------------------------------------------------------------------


@pytest.fixture(scope="module")
def manifest():
    warnings: list[str] = []
    package = parse_package(str(REPO), warnings=warnings)
    assert not warnings, f"catkin_pkg warnings for package.xml: {warnings}"
    return package


@pytest.fixture(scope="module")
def setup_info() -> dict:
    """The arguments ``setup.py`` passes to ``setup()``, captured the way colcon does it."""
    code = textwrap.dedent(
        """
        import json
        import setuptools  # noqa: F401  (must precede distutils)
        from distutils.core import run_setup

        dist = run_setup('setup.py', script_args=('--dry-run',), stop_after='config')
        print(json.dumps({
            'name': dist.get_name(),
            'version': dist.get_version(),
            'license': dist.get_license(),
            'description': dist.get_description(),
            'packages': dist.packages or [],
            'data_files': dist.data_files or [],
            'entry_points': dist.entry_points or {},
        }))
        """
    )
    result = _run(
        [sys.executable, "-c", code],
        timeout=RUN_TIMEOUT_S,
        what="reading setup.py",
        cwd=REPO,
        env=_ros_env(PYTHONDONTWRITEBYTECODE="1"),
    )
    assert result.returncode == 0, result.stdout
    return json.loads(result.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def console_scripts(setup_info) -> dict[str, str]:
    """``{script name: 'module:function'}`` from setup.py's console_scripts."""
    scripts = {}
    for spec in setup_info["entry_points"].get("console_scripts", []):
        name, _, target = (part.strip() for part in spec.partition("="))
        assert name not in scripts, f"duplicate console script {name!r}"
        scripts[name] = target
    return scripts


def test_manifest_is_format3_ament_python(manifest):
    assert manifest.package_format == 3
    assert manifest.name == PKG
    assert manifest.get_build_type() == "ament_python"
    manifest.validate()


def test_manifest_matches_setup_py(manifest, setup_info):
    assert setup_info["name"] == manifest.name
    assert setup_info["version"] == manifest.version
    assert setup_info["license"] == manifest.licenses[0]
    assert " ".join(setup_info["description"].split()) == " ".join(manifest.description.split())
    assert PKG in setup_info["packages"]
    assert not any(p == "test" or p.startswith("test.") for p in setup_info["packages"])


def test_setup_py_installs_index_marker_manifest_and_config(setup_info):
    installed = {
        os.path.join(dest, os.path.basename(src))
        for dest, sources in setup_info["data_files"]
        for src in sources
    }
    assert f"share/ament_index/resource_index/packages/{PKG}" in installed
    assert f"share/{PKG}/package.xml" in installed
    for rel in _source_files(REPO / "config"):
        assert f"share/{PKG}/config/{rel.as_posix()}" in installed, rel
    for _, sources in setup_info["data_files"]:
        for src in sources:
            assert not os.path.isabs(src), f"data_files source must be relative: {src}"
            assert (REPO / src).is_file(), src
    assert (REPO / "resource" / PKG).is_file()


def _ament_packages_of_this_interpreter() -> set[str]:
    index = Path(sys.prefix) / "share" / "ament_index" / "resource_index" / "packages"
    return {p.name for p in index.iterdir()} if index.is_dir() else set()


def _pinned_requirements() -> set[str]:
    names = set()
    for req in ("requirements.txt", "requirements-dev.txt"):
        for line in (REPO / req).read_text().splitlines():
            line = line.split("#", 1)[0].strip()
            if line and not line.startswith("-"):
                match = re.fullmatch(r"([A-Za-z0-9_.\-]+)==\S+", line)
                assert match, f"{req}: not pinned exactly: {line!r}"
                names.add(match.group(1).lower().replace("_", "-"))
    return names


def test_exec_depends_resolve(manifest):
    """Every ROS exec_depend is provided by the pinned wheels; system keys are pinned on PyPI."""
    ros_packages = _ament_packages_of_this_interpreter()
    pinned = _pinned_requirements()
    for dep in [*manifest.exec_depends, *manifest.test_depends]:
        if dep.name in ROSDEP_TO_PYPI:
            assert ROSDEP_TO_PYPI[dep.name] in pinned, f"{dep.name} not pinned in requirements"
        else:
            assert dep.name in ros_packages, (
                f"exec_depend {dep.name!r} is not a ROS package installed by requirements.txt "
                f"(not in {sys.prefix}/share/ament_index)"
            )


def _imported_top_level_modules(package_dir: Path) -> set[str]:
    modules = set()
    for path in package_dir.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                modules |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                modules.add(node.module.split(".")[0])
    return modules


def test_imported_ros_packages_are_exec_depends(manifest):
    """A ROS package imported by rns_ros must be declared in package.xml."""
    declared = {dep.name for dep in manifest.exec_depends}
    ros_packages = _ament_packages_of_this_interpreter() - {PKG}
    imported = _imported_top_level_modules(REPO / PKG) & ros_packages
    assert imported <= declared, f"missing <exec_depend> for {sorted(imported - declared)}"


def test_console_scripts_are_consistent(console_scripts):
    assert "rns_demo" in console_scripts
    for name, target in console_scripts.items():
        assert re.fullmatch(r"[a-z][a-z0-9_]*", name), f"bad script name {name!r}"
        module, _, func = target.partition(":")
        assert module.split(".")[0] == PKG, f"{name}: bad target {target!r}"
        assert func, f"{name}: bad target {target!r}"
        module_file = REPO.joinpath(*module.split(".")).with_suffix(".py")
        assert module_file.is_file(), f"{name}: {module_file} does not exist"
        tree = ast.parse(module_file.read_text(encoding="utf-8"))
        functions = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
        assert func in functions, f"{name}: {module} defines no top-level {func}()"


def test_setup_cfg_installs_scripts_where_ros2_run_looks():
    text = (REPO / "setup.cfg").read_text()
    assert re.search(r"^script_dir\s*=\s*\$base/lib/rns_ros\s*$", text, re.M)
    assert re.search(r"^install_scripts\s*=\s*\$base/lib/rns_ros\s*$", text, re.M)


# --- colcon build -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def colcon_install(tmp_path_factory) -> Path:
    """Build a copy of the repository with colcon; return ``<install-base>/rns_ros``."""
    tmp = tmp_path_factory.mktemp("colcon")
    src = tmp / "src" / PKG
    shutil.copytree(REPO, src, ignore=_ignore(REPO))
    artefacts_before = _build_artefacts_in_repo()

    cmd = [
        sys.executable,
        "-m",
        "colcon",
        "build",
        "--base-paths",
        str(src),
        "--build-base",
        str(tmp / "build"),
        "--install-base",
        str(tmp / "install"),
        "--event-handlers",
        "console_cohesion+",
        "desktop_notification-",
        "terminal_title-",
    ]
    env = _ros_env(
        COLCON_LOG_PATH=str(tmp / "log"),
        COLCON_HOME=str(tmp / "colcon_home"),  # ignore the user's defaults.yaml / mixins
        PYTHONDONTWRITEBYTECODE="1",
    )
    result = _run(cmd, timeout=BUILD_TIMEOUT_S, what="colcon build", cwd=tmp, env=env)
    assert result.returncode == 0, f"colcon build failed:\n{result.stdout}"

    created = _build_artefacts_in_repo() - artefacts_before
    assert not created, f"colcon build wrote into the repository: {sorted(created)}"
    prefix = tmp / "install" / PKG
    assert prefix.is_dir(), result.stdout
    return prefix


def _site_packages(prefix: Path) -> Path:
    matches = sorted(prefix.glob("lib/python3*/site-packages"))
    assert matches, f"no lib/python3*/site-packages under {prefix}"
    return matches[0]


def _installed_env(prefix: Path) -> dict[str, str]:
    """What sourcing install/setup.bash would add, restricted to this package."""
    site = str(_site_packages(prefix))
    return _ros_env(
        PYTHONPATH=os.pathsep.join(filter(None, [site, os.environ.get("PYTHONPATH")])),
        AMENT_PREFIX_PATH=os.pathsep.join(
            filter(None, [str(prefix), sys.prefix, os.environ.get("AMENT_PREFIX_PATH")])
        ),
        PYTHONDONTWRITEBYTECODE="1",
    )


def test_installs_ament_index_marker_and_manifest(colcon_install):
    marker = colcon_install / "share/ament_index/resource_index/packages" / PKG
    assert marker.is_file()
    installed = colcon_install / "share" / PKG / "package.xml"
    assert installed.read_bytes() == (REPO / "package.xml").read_bytes()


def test_installs_every_config_file(colcon_install):
    share_config = colcon_install / "share" / PKG / "config"
    for rel in _source_files(REPO / "config"):
        installed = share_config / rel
        assert installed.is_file(), f"config/{rel} not installed to {installed}"
        assert installed.read_bytes() == (REPO / "config" / rel).read_bytes()


def test_installs_python_packages(colcon_install, setup_info):
    site = _site_packages(colcon_install)
    for package in setup_info["packages"]:
        assert (site.joinpath(*package.split(".")) / "__init__.py").is_file(), package
    assert not (site / "test").exists()


def test_installs_executable_console_scripts(colcon_install, console_scripts):
    for name in console_scripts:
        script = colcon_install / "lib" / PKG / name
        assert script.is_file(), f"{name} not installed to {script}"
        assert os.access(script, os.X_OK), f"{script} is not executable"


def test_ament_index_resolves_installed_package(colcon_install):
    code = (
        "from ament_index_python.packages import get_package_prefix, "
        "get_package_share_directory; "
        f"print(get_package_prefix('{PKG}')); print(get_package_share_directory('{PKG}'))"
    )
    result = _run(
        [sys.executable, "-c", code],
        timeout=RUN_TIMEOUT_S,
        what="ament index lookup",
        cwd=colcon_install,
        env=_installed_env(colcon_install),
    )
    assert result.returncode == 0, result.stdout
    prefix, share = result.stdout.strip().splitlines()[-2:]
    assert Path(prefix) == colcon_install
    assert Path(share) == colcon_install / "share" / PKG


def test_installed_package_is_imported_from_install_space(colcon_install):
    result = _run(
        [sys.executable, "-c", f"import {PKG}; print({PKG}.__file__)"],
        timeout=RUN_TIMEOUT_S,
        what=f"import {PKG}",
        cwd=colcon_install,
        env=_installed_env(colcon_install),
    )
    assert result.returncode == 0, result.stdout
    assert Path(result.stdout.strip().splitlines()[-1]).is_relative_to(colcon_install)


def test_every_installed_console_script_answers_help(colcon_install, console_scripts):
    for name in console_scripts:
        script = colcon_install / "lib" / PKG / name
        result = _run(
            [str(script), "--help"],
            timeout=RUN_TIMEOUT_S,
            what=f"{name} --help",
            cwd=colcon_install,
            env=_installed_env(colcon_install),
        )
        assert result.returncode == 0, f"{script} --help failed:\n{result.stdout}"
        assert "usage:" in result.stdout


def test_installed_rns_demo_runs_from_the_install_space(colcon_install, tmp_path):
    """As `ros2 run rns_ros rns_demo` would: the installed script finds the installed model and
    scenarios, runs the stack over DDS and records with the installed rerun logger. Its
    --ros-args reach every node: a global remap moves joint_states for the whole stack."""
    from sensor_msgs.msg import JointState

    from rns_ros.harness import Harness

    script = colcon_install / "lib" / PKG / "rns_demo"
    scenario = tmp_path / "short.yaml"
    scenario.write_text(
        "initial_joint_positions_deg: [-90, -30, 0, -70, 180, -30, 0]\n"
        "axis: [1, 0, 0]\nangle_deg: 10.0\nduration: 1.0\n"
    )
    command = [
        str(script),
        "--scenario",
        str(scenario),
        "--methods",
        "dls",
        "--output",
        str(tmp_path / "rec"),
        "--ros-args",
        "-r",
        "joint_states:=arm/joint_states",
    ]
    env = _installed_env(colcon_install)
    with Harness(int(env["ROS_DOMAIN_ID"])) as ros:
        arm = ros.record(JointState, "arm/joint_states")
        unmapped = ros.record(JointState, "joint_states")
        log = tmp_path / "demo.log"
        with log.open("w") as out:
            demo = subprocess.Popen(
                command, cwd=colcon_install, env=env, stdout=out, stderr=subprocess.STDOUT
            )
            try:
                ros.spin_until(lambda: demo.poll() is not None, timeout=RUN_TIMEOUT_S)
            finally:
                if demo.poll() is None:
                    demo.kill()
                demo.wait(timeout=10)
    output = log.read_text()
    assert demo.returncode == 0, output
    model_line = next(line for line in output.splitlines() if line.startswith("model:"))
    model = model_line.split(":", 1)[1].split(";")[0].strip()
    assert Path(model).is_relative_to(colcon_install / "share" / PKG)
    assert (tmp_path / "rec" / "dls.rrd").is_file()
    # the stream moved: our probe (which may match the demo's participant a few seconds late)
    # saw it on the remapped topic only, and the demo's own logger, remapped too, recorded it
    # (how many of the states a logger keeps up with depends on the machine's load)
    assert len(arm) > 0, output
    assert len(unmapped) == 0
    closed = re.search(r"recording closed \(joints (\d+),", output)
    assert closed is not None, output
    assert int(closed.group(1)) > 0, output


def test_installed_rns_demo_rejects_bad_ros_args(colcon_install):
    result = _run(
        [str(colcon_install / "lib" / PKG / "rns_demo"), "--ros-args", "-p", "no_value"],
        timeout=RUN_TIMEOUT_S,
        what="rns_demo with bad --ros-args",
        cwd=colcon_install,
        env=_installed_env(colcon_install),
    )
    assert result.returncode == 2, result.stdout
    assert "rns_demo: invalid ROS arguments" in result.stdout
    assert "Traceback" not in result.stdout


# --- ros2-run parity --------------------------------------------------------------------------


def _colcon_environment(install_prefix: Path) -> dict[str, str]:
    """The environment of a shell that sourced ``install/setup.bash``, from a minimal base (no
    virtualenv on PATH, no PYTHONPATH): what ``ros2 run`` hands to the executable it starts."""
    base = {
        "HOME": os.environ.get("HOME", "/root"),
        "PATH": "/usr/local/bin:/usr/bin:/bin",
        "PYTHONUNBUFFERED": "1",
        "PYTHONDONTWRITEBYTECODE": "1",
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
    }
    setup = install_prefix.parent / "setup.bash"
    result = subprocess.run(
        ["bash", "-c", f'source "{setup}" && env -0'],
        env=base,
        capture_output=True,
        timeout=RUN_TIMEOUT_S,
        check=True,
    )
    env = dict(item.split("=", 1) for item in result.stdout.decode().split("\0") if "=" in item)
    assert str(_site_packages(install_prefix)) in env["PYTHONPATH"].split(os.pathsep)
    return env


PARITY_PARAMS = """\
rns_simulator:
  ros__parameters:
    publish_rate: 50.0
rns_controller:
  ros__parameters:
    rate: 50.0
    method: sc
"""


def _stamp_s(message) -> float:
    """A message's header stamp [s]."""
    return message.header.stamp.sec + 1e-9 * message.header.stamp.nanosec


def test_ros2_run_parity_installed_executables_with_ros_args(colcon_install, tmp_path):
    """Each executable started from install/rns_ros/lib/rns_ros with the colcon environment, as
    `ros2 run rns_ros <exe> --ros-args ...` would, comes up, honours -p / --params-file / -r, and
    publishes; together they close the loop. SIGINT stops each with exit code 0."""
    from geometry_msgs.msg import TwistStamped
    from rclpy.qos import DurabilityPolicy, QoSProfile
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String
    from trajectory_msgs.msg import JointTrajectory

    from rns_ros.harness import Harness, ProcessStack
    from rns_ros.viz import paths
    from rns_ros.viz.readback import recording_summary

    domain = int(os.environ.get("ROS_DOMAIN_ID", "43"))
    params = tmp_path / "stack.yaml"
    params.write_text(PARITY_PARAMS)
    scenario = tmp_path / "yaw.yaml"
    scenario.write_text(
        "initial_joint_positions_deg: [-90, -30, 0, -70, 180, -30, 0]\n"
        "frame: camera\naxis: [0, 0, 1]\nangle_deg: 30.0\nduration: 60.0\n"
        "time_scaling: constant\n"
    )
    rrd = tmp_path / "parity.rrd"
    arm_states = {"joint_states": "arm/joint_states"}
    processes = ProcessStack(
        domain, bin_dir=colcon_install / "lib" / PKG, base_env=_colcon_environment(colcon_install)
    )
    with Harness(domain) as ros, processes:
        arm = ros.record(JointState, "arm/joint_states")
        unmapped = ros.record(JointState, "joint_states")
        commands = ros.record(TwistStamped, "cmd_vel")
        references = ros.record(JointTrajectory, "joint_references")
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        description = ros.record(String, "robot_description", qos=latched)
        started = {
            "rns_simulator": processes.start(
                "rns_simulator", params_file=params, remappings=arm_states
            ),
            "rns_controller": processes.start(
                "rns_controller",
                {"wrist_gain": 0.0},
                params_file=params,
                remappings={**arm_states, "cmd_twist": "cmd_vel"},
            ),
            "rns_operator": processes.start(
                "rns_operator",
                {"scenario": str(scenario), "rate": 25.0, "start_delay": 0.0},
                remappings={"cmd_twist": "cmd_vel"},
            ),
            "rns_rerun_logger": processes.start(
                "rns_rerun_logger",
                {"sink": "save", "rrd_path": str(rrd)},
                remappings={**arm_states, "cmd_twist": "cmd_vel"},
            ),
        }
        # the keyboard teleop needs a terminal: a pseudo-terminal stands in for the user's
        teleop_twists = ros.record(TwistStamped, "teleop_twist")
        user, terminal = pty.openpty()
        teleop = subprocess.Popen(
            processes.command(
                "rns_teleop_keyboard",
                {"rate": 25.0},
                remappings={"cmd_twist": "teleop_twist"},
            ),
            env=processes.env,
            stdin=terminal,
            stdout=terminal,
            stderr=terminal,
            start_new_session=True,
        )
        os.close(terminal)
        probe = ros.probe()

        def everyone_up() -> bool:
            for name, process in started.items():
                assert process.poll() is None, f"{name} exited:\n{processes.output(process)}"
            return set(started) <= set(probe.get_node_names()) and len(references) > 5

        assert ros.spin_until(everyone_up, timeout=40.0), {
            name: processes.output(p) for name, p in started.items()
        }
        ros.spin_for(2.0)
        # the rates the params file sets, from the stamps (what the nodes publish at), not from
        # arrivals (how this machine schedules them)
        arm_rate = 1.0 / np.median(np.diff(arm.array(_stamp_s)))
        reference_rate = 1.0 / np.median(np.diff(references.array(_stamp_s)))
        exit_codes = processes.stop(timeout=10.0)
        outputs = {name: processes.output(p) for name, p in started.items()}

        def rolling() -> bool:
            os.write(user, b"q")  # roll +, as auto-repeat would send it
            ros.spin_for(0.05)
            return any(m.twist.angular.x > 0.0 for m in teleop_twists.messages)

        try:
            teleop_rolled = ros.spin_until(rolling, timeout=20.0)
            os.write(user, b"Q")  # quit
            # a bound only a hang exceeds: beside other work the exit took over 10 s once
            ros.spin_until(lambda: teleop.poll() is not None, timeout=30.0)
        finally:
            if teleop.poll() is None:
                teleop.kill()
            teleop.wait(timeout=5)
            os.close(user)

    assert teleop_rolled, "rns_teleop_keyboard published no roll twist on the remapped topic"
    assert teleop.returncode == 0
    assert teleop_twists.latest().twist.angular.x == 0.0  # quitting sends a zero

    assert exit_codes == [0, 0, 0, 0], outputs
    assert arm_rate == pytest.approx(50.0, rel=0.2), "simulator --params-file publish_rate: 50"
    assert reference_rate == pytest.approx(50.0, rel=0.2), "controller --params-file rate: 50"
    assert len(unmapped) == 0, "-r joint_states:=arm/joint_states"
    assert "sc reactionless control" in outputs["rns_controller"]  # method from the file
    assert commands.latest().header.frame_id == "camera"  # the operator's remapped output
    assert max(m.twist.angular.z for m in commands.messages) > 0.0
    assert commands.latest().twist.angular.z == 0.0  # stopped by SIGINT: it sends zeros
    moved = np.ptp(arm.array(lambda m: m.position), axis=0).max()
    assert moved > 1e-3, "the remapped loop moved the arm"
    assert description.latest().data.lstrip().startswith("<")
    # the logger is a best-effort observer: how much it logs before the stop depends on how it
    # is scheduled; the joints it logged came through the remapped joint_states
    summary = recording_summary(rrd)
    assert summary, "the logger's recording is empty"
    joints = [path for path in summary if path.startswith(paths.JOINTS)]
    assert not joints or summary.get(paths.joint_transform("joint_4"), 0) >= 1, joints
