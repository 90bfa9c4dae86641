"""rns_ros.cli: --ros-args splitting and the --domain-id option shared by rns_demo and
rns_observer."""

from __future__ import annotations

import argparse
import subprocess
import sys

import pytest

from rns_ros.cli import (
    add_domain_id_argument,
    make_output_folder,
    output_file_problem,
    output_folder_problem,
    split_ros_args,
)

ROS = ["--ros-args", "-r", "x:=y"]


@pytest.mark.parametrize(
    ("argv", "own", "ros"),
    [
        (["--rate", "50"], ["--rate", "50"], []),
        (["--rate", "50", *ROS], ["--rate", "50"], ROS),
        ([*ROS, "--", "--rate", "50"], ["--rate", "50"], ROS),
        (["--ros-args"], [], ["--ros-args"]),
    ],
)
def test_split_ros_args_cuts_out_what_rcl_reads(argv, own, ros):
    assert split_ros_args(argv) == (own, ros)


def _parser(fallback: int = 42) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tool")
    add_domain_id_argument(parser, fallback, "of the runs")
    return parser


def test_domain_id_comes_from_option_then_environment_then_fallback(monkeypatch):
    monkeypatch.delenv("ROS_DOMAIN_ID", raising=False)
    assert _parser(42).parse_args([]).domain_id == 42
    monkeypatch.setenv("ROS_DOMAIN_ID", "17")
    assert _parser(42).parse_args([]).domain_id == 17
    assert _parser(42).parse_args(["--domain-id", "101"]).domain_id == 101


def test_domain_id_takes_what_rcl_takes_with_fast_dds():
    """102-232: Fast DDS maps them to UDP ports (rcl takes them); 233 would not fit."""
    assert _parser().parse_args(["--domain-id", "150"]).domain_id == 150
    assert _parser().parse_args(["--domain-id", "232"]).domain_id == 232


@pytest.mark.parametrize(
    ("argv", "env", "bad"),
    [
        (["--domain-id", "233"], "5", "'233'"),
        (["--domain-id", "-1"], "5", "'-1'"),
        ([], "abc", "'abc'"),
    ],
)
def test_bad_domain_id_is_a_usage_error_naming_the_range(monkeypatch, capsys, argv, env, bad):
    monkeypatch.setenv("ROS_DOMAIN_ID", env)
    with pytest.raises(SystemExit) as exit_info:
        _parser().parse_args(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "--domain-id: must be an integer in [0, 232]" in err
    assert bad in err


@pytest.mark.parametrize("interrupted", [True, False])
def test_an_error_raised_out_of_an_interrupted_import_ends_quietly(interrupted):
    """Ctrl-C while a C extension initializes (rclpy's): the SystemExit of the start-up handler
    reaches the top as an ImportError with a traceback. After a start-up signal the excepthook
    ends the process with code 0 and nothing on stderr; without one, errors print as ever."""
    code = (
        "import sys\n"
        "from rns_ros import cli\n"
        f"{'cli._startup_signals.append(2)' if interrupted else ''}\n"
        "sys.excepthook = cli._quiet_after_startup_signal(sys.excepthook)\n"
        "raise ImportError('initialization failed')\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    if interrupted:
        assert (result.returncode, result.stderr) == (0, "")
    else:
        assert result.returncode == 1
        assert "ImportError: initialization failed" in result.stderr


def test_output_file_problem_names_a_missing_folder_and_a_folder(tmp_path):
    assert output_file_problem(tmp_path / "new.json") is None
    (tmp_path / "old.json").write_text("{}")
    assert output_file_problem(tmp_path / "old.json") is None  # replaced
    assert output_file_problem(tmp_path) == "is a folder, not a file"
    missing = tmp_path / "no" / "x.json"
    assert output_file_problem(missing) == (
        f"cannot be written: its folder {str(missing.parent)!r} does not exist"
    )


def test_output_folder_problem_allows_new_folders_but_not_below_a_file(tmp_path):
    assert output_folder_problem(tmp_path) is None
    assert output_folder_problem(tmp_path / "a" / "b") is None  # made with its parents
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert output_folder_problem(blocker) == f"cannot be a folder: {str(blocker)!r} is a file"
    assert output_folder_problem(blocker / "sub") == (
        f"cannot be a folder: {str(blocker)!r} is a file"
    )


def test_make_output_folder_makes_it_or_says_why_not(tmp_path):
    assert make_output_folder(tmp_path / "a" / "b") is None
    assert (tmp_path / "a" / "b").is_dir()
    assert make_output_folder(tmp_path / ("x" * 300)) == "cannot be made: File name too long"
    (tmp_path / "file").write_text("")
    assert make_output_folder(tmp_path / "file" / "sub") == (
        f"cannot be a folder: {str(tmp_path / 'file')!r} is a file"
    )


@pytest.mark.parametrize(
    ("program", "handler"),
    [("rns_simulator", "_record_startup_signal"), ("rns_my_tool", "default_int_handler")],
)
def test_ctrl_c_is_taken_over_at_import_only_for_our_executables(tmp_path, program, handler):
    """Importing rns_ros takes Ctrl-C over first thing for any program named rns_* (before
    rns_ros.cli's own imports), then keeps it only for one of our executables: a user's
    rns_my_tool importing rns_ros as a library gets Python's KeyboardInterrupt back."""
    script = tmp_path / program
    script.write_text(
        "import signal\nimport rns_ros\nprint(signal.getsignal(signal.SIGINT).__name__)\n"
    )
    result = subprocess.run([sys.executable, str(script)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == handler
