"""``rns_model check``: the feasibility numbers against an independent computation, the warning of
a 6-joint arm, and one-line errors (exit 2) for bad input, alias bombs and oversized URDFs among
them (the console script, in a subprocess, within its memory bound).

Independent route: the reaction null space is the kernel of the base angular rows of
M_b^-1 M_bm (CRBA, eq. 2.7: zero momentum, M_b V_b + M_bm theta_dot = 0, so the base does not
turn iff those rows annihilate theta_dot), found here by an SVD; the restricted Jacobian is
J_omega_e times an orthonormal basis N of that kernel (J_omega_e P_RNS = J_omega_e N N^T has the
same singular values as J_omega_e N).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from rns_testing import BOMB_KEYS, alias_bomb_model, chain_urdf, six_joint_model

from rns_ros.analysis.arm_feasibility import NEAR_SINGULAR, arm_feasibility
from rns_ros.apps import model_check
from rns_ros.core import load_model
from rns_ros.core.config import load_model_config
from rns_ros.core.urdf_tree import MAX_URDF_LINKS
from rns_ros.core.yaml_input import MAX_YAML_NODES
from rns_ros.resources import config_dir

RELATIVE_RANK = 1e-9


def _independent(robot, theta):
    """(null-space dimension, rank of [kernel rows; J_omega_e], J-bar singular values)."""
    model = robot.model
    data = model.createData()
    q = robot.configuration(theta)
    mass = pin.crba(model, data, q)
    mass = np.triu(mass) + np.triu(mass, 1).T  # crba fills the upper triangle
    base_rows = np.linalg.solve(mass[:6, :6], mass[:6, 6:])[3:]  # base angular velocity rows
    _, sigma, vt = np.linalg.svd(base_rows)
    rank = int(np.sum(sigma > RELATIVE_RANK * sigma[0]))
    kernel = vt[rank:].T  # (n, n - rank), orthonormal
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    camera = pin.getFrameJacobian(model, data, robot.camera_frame_id, pin.LOCAL_WORLD_ALIGNED)
    j_omega = camera[3:, 6:]
    restricted = np.linalg.svd(j_omega @ kernel, compute_uv=False)
    stacked = np.vstack((base_rows / sigma[0], j_omega / np.linalg.norm(j_omega, 2)))
    stacked_sigma = np.linalg.svd(stacked, compute_uv=False)
    stacked_rank = int(np.sum(stacked_sigma > RELATIVE_RANK * stacked_sigma[0]))
    return robot.n - rank, stacked_rank, restricted


def _check(capsys, *args: str) -> tuple[int, str, str]:
    code = model_check.main(["check", *args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _value(out: str, pattern: str) -> str:
    match = re.search(pattern, out)
    assert match, f"{pattern!r} not in:\n{out}"
    return match.group(1)


@pytest.mark.parametrize(
    "degrees", [None, [-90, -30, 0, -70, 180, -30, 0], [20, 40, -30, 60, 10, -50, 30]]
)
def test_feasibility_numbers_match_an_independent_computation(robot, degrees):
    theta = np.zeros(robot.n) if degrees is None else np.deg2rad(degrees)
    result = arm_feasibility(robot, theta)
    dimension, stacked_rank, restricted = _independent(robot, theta)
    assert result.null_space_dimension == dimension == 4
    assert result.stacked_rank == stacked_rank == 6
    np.testing.assert_allclose(result.restricted_singular_values, restricted, rtol=1e-9)
    assert result.pointing_feasible
    assert result.wrist_feasible
    assert result.wrist_null_space_dimension == 1
    assert result.total_mass == pytest.approx(sum(i.mass for i in robot.model.inertias))
    # the thesis' satellite: 2550 kg (ETS-VII class) carrying the arm
    assert result.base_mass == pytest.approx(robot.model.inertias[1].mass)
    assert result.mass_ratio == pytest.approx(
        result.base_mass / (result.total_mass - result.base_mass)
    )
    near = restricted[-1] < NEAR_SINGULAR
    assert any("sigma_min" in w for w in result.warnings) == near
    assert len(result.warnings) == int(near)


def test_check_prints_the_default_arm(capsys):
    path = config_dir() / "model.yaml"
    robot = load_model(path)
    code, out, err = _check(capsys, str(path))
    assert code == 0
    assert err == ""
    theta = robot.initial_theta
    dimension, _stacked_rank, restricted = _independent(robot, theta)
    assert _value(out, r"controlled joints \((\d+)\)") == "7"
    assert int(_value(out, r"reaction null space: dimension (\d+)")) == dimension
    assert _value(out, r"camera pointing.*?: (\w+)") == "yes"
    assert _value(out, r"wrist holding: (\w+) \((\d+)-dim") == "yes"
    assert _value(out, r"wrist holding: \w+ \((\d+)-dim") == "1"
    sigma = float(_value(out, r"restricted Jacobian J_omega_e P_RNS: ([0-9.e+-]+)"))
    assert sigma == pytest.approx(restricted[-1], rel=1e-3)
    total = float(_value(out, r"mass: total ([0-9.e+]+) kg"))
    assert total == pytest.approx(sum(i.mass for i in robot.model.inertias), rel=1e-6)


def test_six_joints_warn_that_no_redundancy_is_left_for_the_wrist(tmp_path, capsys):
    model = six_joint_model(tmp_path)
    robot = load_model(model)
    assert robot.n == 6
    theta = np.deg2rad([-90, -30, 0, -70, 180, -30])  # away from the singularities
    dimension, stacked_rank, restricted = _independent(robot, theta)
    result = arm_feasibility(robot, theta)
    assert result.null_space_dimension == dimension == 3
    assert result.stacked_rank == stacked_rank == 6
    assert result.pointing_feasible
    assert not result.wrist_feasible
    np.testing.assert_allclose(result.restricted_singular_values, restricted, rtol=1e-9)
    wrist = [w for w in result.warnings if w.startswith("wrist holding cannot be reactionless")]
    assert len(wrist) == 1
    assert "3-dimensional reaction null space" in wrist[0]

    code, out, err = _check(capsys, str(model))
    assert code == 0
    assert err == ""
    assert _value(out, r"wrist holding: (\w+)") == "NO"
    assert "warning: wrist holding cannot be reactionless: 6 controlled joints" in out


def test_six_joints_without_a_wrist_frame_have_nothing_to_warn_about_the_wrist(tmp_path):
    robot = load_model(six_joint_model(tmp_path, wrist_frame=None))
    result = arm_feasibility(robot, np.deg2rad([-90, -30, 0, -70, 180, -30]))
    assert result.pointing_feasible
    assert result.wrist_null_space_dimension == 0
    assert not any("wrist" in w for w in result.warnings)


def test_five_joints_cannot_point_reactionlessly(tmp_path):
    """5 joints: a 2-dimensional null space for 3 camera rows."""
    model = six_joint_model(tmp_path)
    urdf = tmp_path / "arm6.urdf"
    urdf.write_text(
        urdf.read_text().replace(
            '<joint name="joint_6" type="revolute">', '<joint name="joint_6" type="fixed">'
        )
    )
    robot = load_model(model)
    theta = np.deg2rad([-90, -30, 0, -70, 180])
    result = arm_feasibility(robot, theta)
    dimension, stacked_rank, _restricted = _independent(robot, theta)
    assert result.null_space_dimension == dimension == 2
    assert not result.pointing_feasible
    assert stacked_rank == 5
    assert any("fewer than the 3 camera rows" in w for w in result.warnings)


def test_held_joint_makes_a_six_joint_arm(tmp_path, capsys):
    """With the model YAML's held_joints: joint_7 held."""
    urdf, _ = load_model_config(config_dir() / "model.yaml")
    model = tmp_path / "held.yaml"
    model.write_text(
        f"urdf: {urdf}\ncamera_frame: camera\nwrist_frame: wrist\nheld_joints: {{joint_7: 0.3}}\n"
    )
    code, out, err = _check(capsys, str(model))
    assert code == 0
    assert err == ""
    assert "held joints (1): joint_7 = 0.3" in out
    assert "warning: wrist holding cannot be reactionless" in out


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("rns_model: ")
    return lines[0]


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    bad_yaml = tmp_path / "bad.yaml"
    bad_yaml.write_text("urdf: [unclosed\n")
    code, _out, err = _check(capsys, str(bad_yaml))
    assert code == 2
    assert "not valid YAML" in _one_error_line(err)

    code, _out, err = _check(capsys, str(tmp_path / "missing.yaml"))
    assert code == 2
    assert "not found" in _one_error_line(err)

    urdf, _ = load_model_config(config_dir() / "model.yaml")
    unknown = tmp_path / "unknown.yaml"
    unknown.write_text(f"urdf: {urdf}\ncamera_frame: no_such_frame\n")
    code, _out, err = _check(capsys, str(unknown))
    assert code == 2
    assert "'no_such_frame' is not a frame" in _one_error_line(err)

    code, _out, err = _check(capsys, str(urdf))
    assert code == 2
    assert "give the model YAML" in _one_error_line(err)

    code = model_check.main([])
    assert code == 2
    assert "rns_model --help" in _one_error_line(capsys.readouterr().err)


def test_fixed_base_model_is_refused_by_name(capsys):
    code, _out, err = _check(capsys, str(config_dir() / "lwr_7dof.yaml"))
    assert code == 2
    assert "is a fixed-base arm" in _one_error_line(err)


def test_help_and_module_entry_point():
    done = subprocess.run(
        [sys.executable, "-m", "rns_ros.apps.model_check", "check", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0
    assert "MODEL.yaml" in done.stdout


def test_without_a_wrist_frame_ok_claims_only_camera_pointing(tmp_path, capsys):
    """wrist_frame: null requests no wrist holding, so `ok` does not claim it."""
    model = six_joint_model(tmp_path, wrist_frame=None)
    angles = {
        "joint_1": -1.57,
        "joint_2": -0.52,
        "joint_4": -1.22,
        "joint_5": 3.14,
        "joint_6": -0.52,
    }
    with model.open("a") as stream:
        stream.write(f"initial_joint_positions: {angles}\n")  # away from singularities
    assert model_check.main(["check", str(model)]) == 0
    out = capsys.readouterr().out
    assert "ok: reactionless camera pointing is feasible (wrist holding not requested)" in out
    assert "wrist holding are feasible" not in out


# --- bounded input, as the console script meets it ----------------------------------------------
#: Peak resident memory of ``rns_model check`` refusing a file [MB] (~80: the imports).
REFUSAL_RSS_MB = 200
BIN = Path(sys.executable).parent


#: Runs a command and prints its peak resident memory [kB]: a small process of its own, since a
#: child's peak counts the image it was forked from (the test process, hundreds of MB).
_MEASURE = (
    "import resource, subprocess, sys\n"
    "code = subprocess.call(sys.argv[1:], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL)\n"
    "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n"
    "sys.exit(code)\n"
)


def _console_check(path: Path, tmp_path: Path) -> tuple[int, str, float]:
    """Run ``.venv/bin/rns_model check path``: (exit code, stderr, peak resident memory [MB])."""
    done = subprocess.run(
        [sys.executable, "-c", _MEASURE, str(BIN / "rns_model"), "check", str(path)],
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=60.0,
    )
    return done.returncode, done.stderr, int(done.stdout) / 1024


@pytest.mark.parametrize("key", BOMB_KEYS)
def test_console_script_refuses_an_alias_bomb_in_one_line(key, tmp_path):
    urdf, _ = load_model_config(config_dir() / "model.yaml")
    model = tmp_path / "bomb.yaml"
    model.write_text(alias_bomb_model(key, urdf))
    code, err, rss = _console_check(model, tmp_path)
    assert code == 2, err[-3000:]
    assert "Traceback" not in err
    assert re.fullmatch(
        rf"rns_model: {re.escape(str(model))}: more than {MAX_YAML_NODES} YAML nodes .*\n", err
    )
    assert rss < REFUSAL_RSS_MB


def test_console_script_refuses_a_1000_link_urdf_in_one_line(tmp_path):
    (tmp_path / "chain.urdf").write_text(chain_urdf(1000))
    model = tmp_path / "chain.yaml"
    model.write_text("urdf: chain.urdf\ncamera_frame: l999\nwrist_frame: null\n")
    code, err, rss = _console_check(model, tmp_path)
    assert code == 2, err[-3000:]
    assert "Traceback" not in err
    assert err == (
        f"rns_model: chain: 1000 <link> elements, over the limit of {MAX_URDF_LINKS} for a "
        "robot description\n"
    )
    assert rss < REFUSAL_RSS_MB
