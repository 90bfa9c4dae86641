"""``rns_model``: can my arm do reactionless camera pointing on its satellite?

``rns_model check MODEL.yaml`` loads and validates a model YAML (docs/model.md) as every node
does, then prints, at the model's initial configuration (``initial_joint_positions``, zeros by
default): the controlled and held joints, total / base / arm mass and the base-to-arm mass ratio,
the dimension of the reaction null space (n - rank M~_omega_m, eq. 2.34), whether reactionless
camera pointing (3 constraint rows + 3 camera rows) and wrist holding (a null space left after
them) are feasible, the smallest singular value of the restricted Jacobian J_omega_e P_RNS
(eq. 4.5), and one warning per task that cannot be reactionless, with the reason and what to do
(:mod:`rns_ros.analysis.arm_feasibility`).

Exit codes: 0 once the model loads (feasible or with warnings: read them); 2 with one line
``rns_model: <problem>`` on stderr for a bad command line, a missing or invalid file, or a model
that does not load (naming the link, joint or frame and the reason).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from rns_ros.cli import OneLineParser, run_main

PROGRAM = "rns_model"


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog=PROGRAM,
        description="Check a robot model (a model YAML naming a URDF, docs/own_arm.md) for "
        "reactionless control on a free-floating satellite.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    check = commands.add_parser(
        "check",
        help="load and validate MODEL; print joints, masses, the reaction null space and which "
        "reactionless tasks are feasible at its initial configuration",
        description="Exit 0 when the model loads (read the warnings), 2 when it does not.",
    )
    check.add_argument("model", metavar="MODEL.yaml", type=Path, help="model YAML file")
    return parser


def _load(path: Path):
    """The free-floating model of ``path``; a URDF or a fixed-base (Part II) model YAML is a
    ConfigError saying what to give instead."""
    from rns_ros.core import load_model
    from rns_ros.core.config import read_yaml_mapping
    from rns_ros.core.errors import ConfigError

    if path.suffix.lower() in (".urdf", ".xacro", ".xml"):
        raise ConfigError(
            f"{path} is a robot description; give the model YAML that names it "
            "(urdf:, camera_frame:, ...; docs/own_arm.md)"
        )
    _, content = read_yaml_mapping(path, None, "model config")
    if "ee_frame" in content:
        raise ConfigError(
            f"{path} is a fixed-base arm (ee_frame: Part II, docs/part2.md); rns_model checks a "
            "free-floating model (camera_frame:, docs/own_arm.md)"
        )
    return load_model(path)


def report_lines(path: Path, robot, feasibility) -> list[str]:
    """The report of ``rns_model check`` as lines (without the warnings)."""
    import numpy as np

    f = feasibility
    held = (
        ", ".join(f"{name} = {value:g}" for name, value in f.held_joints.items())
        if f.held_joints
        else "none"
    )
    theta_deg = np.array2string(
        np.rad2deg(f.theta), precision=1, separator=" ", suppress_small=True
    )
    yes_no = {True: "yes", False: "NO"}
    wrist = (
        f"{yes_no[f.wrist_feasible]} ({f.wrist_null_space_dimension}-dimensional null space left "
        f"for wrist frame '{f.wrist_frame}')"
        if f.wrist_frame is not None
        else f"not requested (wrist_frame: null; {f.wrist_null_space_dimension}-dimensional null "
        "space left)"
    )
    return [
        f"model: {path}",
        f"controlled joints ({f.n}): {', '.join(f.controlled_joints)}",
        f"held joints ({len(f.held_joints)}): {held}",
        f"mass: total {f.total_mass:.6g} kg, base {f.base_mass:.6g} kg, arm {f.arm_mass:.6g} kg; "
        f"base-to-arm ratio {f.mass_ratio:.4g}",
        f"initial configuration [deg]: {theta_deg}",
        f"reaction null space: dimension {f.null_space_dimension} "
        f"(n {f.n} - rank M~_omega_m {f.coupling_rank})",
        f"reactionless camera pointing (3 constraint + 3 camera rows): "
        f"{yes_no[f.pointing_feasible]} (rank of [M~_omega_m; J_omega_e] {f.stacked_rank})",
        f"reactionless wrist holding: {wrist}",
        f"smallest singular value of the restricted Jacobian J_omega_e P_RNS: "
        f"{f.restricted_sigma_min:.4g}",
    ]


def _check(path: Path) -> int:
    from rns_ros.analysis.arm_feasibility import arm_feasibility
    from rns_ros.core.link_tree import link_edges

    robot = _load(path)
    feasibility = arm_feasibility(robot)
    print("\n".join(report_lines(path, robot, feasibility)))
    edges = link_edges(robot)  # what rns_simulator publishes on /tf: the nodes build it too
    moving = sum(not edge.static for edge in edges)
    print(f"/tf link tree: {len(edges)} transforms ({moving} moving, {len(edges) - moving} static)")
    for note in robot.loading_notes:
        print(f"note: {note}")
    for warning in feasibility.warnings:
        print(f"warning: {warning}")
    if not feasibility.warnings:
        if feasibility.wrist_frame is None:
            print("ok: reactionless camera pointing is feasible (wrist holding not requested)")
        else:
            print("ok: reactionless camera pointing and wrist holding are feasible")
    return 0


def _body(argv: Sequence[str]) -> int:
    args = _parser().parse_args(list(argv))
    if args.command == "check":
        return _check(args.model)
    raise AssertionError(args.command)  # argparse allows only the commands above


def main(argv: Sequence[str] | None = None) -> int:
    """Exit code 0 (checked), 2 (bad usage or model, one line on stderr)."""
    return run_main(PROGRAM, lambda: _body(sys.argv[1:] if argv is None else argv))


if __name__ == "__main__":
    sys.exit(main())
