"""rns_demo: the thesis' scenarios over real DDS, each method on a fresh stack, in one table.

An inspection scenario (default ``satellite_observation``: reactionless ``dls`` and ``sc``
against ``conventional``; :mod:`rns_ros.runs.inspection`), the point-to-point task
(``--scenario ptp_three_phase``: rns_ptp's 3-phase method against JS-C / IJ-C / TJ-C;
:mod:`rns_ros.runs.ptp`) or a motion/force scenario (``--scenario wall_contact``: RNS-C against
OS-C; :mod:`rns_ros.runs.contact`). The table of the recorded figures
(:mod:`rns_ros.runs.report`) is printed; ``--summary PATH`` writes it as JSON.

``--model FILE`` (inspection scenarios) runs every node on another robot model YAML
(docs/own_arm.md): each node gets ``model_config``, the operator's frames are the model's. A
scenario's ``initial_joint_positions_deg`` are used when they give one angle per controlled joint
of the model and lie within its joint limits (a note says so when they differ from the model's
``initial_joint_positions``); otherwise (a scenario written for another arm) the run starts from
the model's ``initial_joint_positions`` and a note says so
(:func:`rns_ros.runs.inspection.start_configuration`).

The runs start only on a domain without another stack (:func:`rns_ros.harness.claim_domain`);
otherwise one line names it, exit code 2.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

from rns_ros.analysis.arm_feasibility import arm_feasibility
from rns_ros.cli import (
    add_domain_id_argument,
    interrupt_exit_code,
    make_output_folder,
    one_line,
    output_file_problem,
    raise_on_sigterm,
    run_main,
    split_ros_args,
)
from rns_ros.control.camera_law import THESIS_SC_GAIN
from rns_ros.core import RnsError, load_model
from rns_ros.ground.link import MAX_DELAY_S
from rns_ros.harness import CLAIM_PREFIX, DomainInUseError, claim_domain
from rns_ros.resources import default_model_config, scenario_path
from rns_ros.runs.clock import clock_text
from rns_ros.runs.contact import (
    CONTACT_METHODS,
    CONTACT_SCENARIOS,
    DEFAULT_CONTACT_METHODS,
    contact_epilogue,
    is_contact_scenario,
    run_contact_method,
)
from rns_ros.runs.inspection import (
    DEFAULT_METHODS,
    MAX_SIM_STEP,
    METHODS,
    MIN_SIM_STEP,
    check_scenarios,
    run_method,
    singular_threshold,
    start_configuration,
)
from rns_ros.runs.link import MAX_LINK_LOSS
from rns_ros.runs.ptp import PTP_METHODS, PTP_SCENARIOS, PtpScenario, run_ptp_method
from rns_ros.runs.recorded import PartialRecordingError
from rns_ros.runs.report import (
    camera_notes,
    contact_summary,
    format_contact_table,
    format_ptp_table,
    format_spread,
    format_table,
    inspection_summary,
    non_finite_figures,
)

ETS_VII_ALLOWED_DEVIATION_DEG = 0.05  # thesis chapter 4, footnote 1
#: Runs again of a method whose recording came out partial (the run in lockstep is repeatable).
PARTIAL_RETRIES = 2


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    argv, ros_args = split_ros_args(sys.argv[1:] if argv is None else list(argv))
    parser = _parser()
    args = parser.parse_args(argv)
    args.ros_args = ros_args
    _check(parser, args)
    return args


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rns_demo",
        usage="%(prog)s [options] [--ros-args -p NAME:=VALUE --params-file FILE -r FROM:=TO]",
        epilog="--ros-args apply to every node of every run (e.g. -p wrist_gain:=10.0, "
        "-r joint_states:=arm/joint_states); the demo's own settings (method, rate, scenario "
        "angles) win where they overlap.",
        description="Thesis satellite-observation scenario over DDS (simulator + controller + "
        "scripted operator + rerun recording): reactionless DLS and SC vs the conventional "
        "baseline, compared in one table.",
    )
    parser.add_argument(
        "--scenario",
        default="satellite_observation",
        help="inspection scenario name or YAML file, a point-to-point scenario "
        f"({', '.join(PTP_SCENARIOS)}: rns_ptp instead of rns_controller), or a motion/force "
        f"scenario ({', '.join(CONTACT_SCENARIOS)}: contact simulator + rns_force_controller)",
    )
    parser.add_argument(
        "--methods",
        default=None,
        help=f"comma-separated; inspection: from {list(METHODS)} (default "
        f"{','.join(DEFAULT_METHODS)}); point-to-point: from {list(PTP_METHODS)} (default all); "
        f"motion/force: from {list(CONTACT_METHODS)} (default "
        f"{','.join(DEFAULT_CONTACT_METHODS)})",
    )
    parser.add_argument(
        "--model",
        type=Path,
        default=None,
        metavar="FILE",
        help="inspection scenarios: robot model YAML for every node (default: the package's "
        "config/model.yaml); a scenario without angles for its joints starts from the model's "
        "initial_joint_positions (docs/own_arm.md)",
    )
    parser.add_argument("--mode", choices=("kinematic", "dynamic"), default="kinematic")
    parser.add_argument("--rate", type=float, default=100.0, help="controller rate [Hz]")
    parser.add_argument(
        "--real-time-factor",
        type=float,
        default=1.0,
        help="simulated s per wall s the simulator keeps to while the machine keeps up (a busy "
        "machine only slows the run down: the nodes are on simulated time, /clock, in "
        "lockstep); 0 = as fast as possible",
    )
    parser.add_argument(
        "--wall-clock",
        action="store_true",
        help="inspection and point-to-point: run the nodes on the wall clock, as hardware and a "
        "human operator do (no /clock, no lockstep; real-time factor 1); the figures then "
        "depend on how promptly this machine schedules the processes",
    )
    parser.add_argument(
        "--output-lead",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="in lockstep: the controller stamps each output one period after its tick, so "
        "simulator and controller compute side by side on two cores (default; about 1.6x "
        "faster than in turn; a twist acts one period later); --no-output-lead: in turn",
    )
    parser.add_argument(
        "--sim-step",
        type=float,
        default=None,
        help="inspection: rns_simulator's RK4 step [s], a divisor of the control period in "
        f"[{MIN_SIM_STEP:g}, {MAX_SIM_STEP:g}]; default 1 ms, but one control period off real "
        "time in kinematic mode without wheels (the joint rate is held over the period, so one "
        "RK4 step gives the same figures, ten times cheaper)",
    )
    parser.add_argument(
        "--output",
        type=Path,
        default=Path("rns_demo_recordings"),
        help="folder for the recordings: rerun .rrd files and ROS 2 bags of the topics",
    )
    parser.add_argument("--no-record", action="store_true", help="no rerun recording")
    parser.add_argument("--viewer", action="store_true", help="live rerun viewer (needs display)")
    parser.add_argument("--summary", type=Path, default=None, help="also write the table as JSON")
    parser.add_argument(
        "--runs",
        type=int,
        default=1,
        help="inspection scenarios: run every method this many times and add the min / median "
        "/ max of the base deviation (in --summary too); [1, 100]",
    )
    parser.add_argument(
        "--link-delay",
        type=float,
        default=None,
        metavar="SECONDS",
        help="inspection: the operator on the ground behind a space link of this one-way delay "
        "(rns_link, time-tagged twists, rns_predictor); the table adds the delay and the "
        "largest prediction error",
    )
    parser.add_argument(
        "--link-jitter",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="with --link-delay: extra delay, uniform in [0, jitter) per message",
    )
    parser.add_argument(
        "--link-loss",
        type=float,
        default=0.0,
        metavar="P",
        help="with --link-delay: probability that a message is lost, each way",
    )
    add_domain_id_argument(parser, 42, "of the runs")
    return parser


def _check(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """``--methods`` as a list of the scenario's methods; every option within its range, else a
    usage error (exit code 2)."""
    if args.scenario in PTP_SCENARIOS:
        allowed, default = list(PTP_METHODS), list(PTP_METHODS)
    elif is_contact_scenario(args.scenario):
        allowed, default = list(CONTACT_METHODS), list(DEFAULT_CONTACT_METHODS)
    else:
        allowed, default = METHODS, DEFAULT_METHODS
    text = ",".join(default) if args.methods is None else args.methods
    args.methods = [m.strip() for m in text.split(",") if m.strip()]
    unknown = [m for m in args.methods if m not in allowed]
    if unknown or not args.methods:
        parser.error(f"--methods for {args.scenario} must be a comma-separated subset of {allowed}")
    if not 1.0 <= args.rate <= 1000.0:
        parser.error(f"--rate must be in [1, 1000] Hz, got {args.rate}")
    if not 0.0 <= args.real_time_factor <= 1000.0:
        parser.error(f"--real-time-factor must be in [0, 1000], got {args.real_time_factor}")
    if args.wall_clock and args.real_time_factor != 1.0:
        parser.error(
            f"--wall-clock runs at real-time factor 1, got --real-time-factor "
            f"{args.real_time_factor:g}"
        )
    if args.wall_clock and is_contact_scenario(args.scenario):
        parser.error("--wall-clock is for the inspection and point-to-point scenarios")
    if not 1 <= args.runs <= 100:
        parser.error(f"--runs must be in [1, 100], got {args.runs}")
    _check_link(parser, args)
    if args.sim_step is not None:
        substeps = 1.0 / (args.rate * args.sim_step)
        if (
            not MIN_SIM_STEP <= args.sim_step <= MAX_SIM_STEP
            or abs(substeps - round(substeps)) > 1e-6
        ):
            parser.error(
                f"--sim-step must divide the control period 1/rate = {1.0 / args.rate:g} s and lie "
                f"in [{MIN_SIM_STEP:g}, {MAX_SIM_STEP:g}] s, got {args.sim_step:g}"
            )
    if args.runs > 1 and (args.scenario in PTP_SCENARIOS or is_contact_scenario(args.scenario)):
        parser.error("--runs is for the inspection scenarios")
    if args.model is not None and (
        args.scenario in PTP_SCENARIOS or is_contact_scenario(args.scenario)
    ):
        parser.error(
            "--model is for the inspection scenarios (the point-to-point and motion/force "
            "scenarios are written for the thesis' arms)"
        )
    # output paths before the runs: a summary or a recording that cannot be written is a
    # usage error now, not a traceback after the task
    if args.summary is not None and (problem := output_file_problem(args.summary)):
        parser.error(f"--summary {str(args.summary)!r} {problem}")
    if not args.no_record and (problem := make_output_folder(args.output)):
        parser.error(f"--output {str(args.output)!r} {problem}")


def _check_link(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """--link-delay, --link-jitter, --link-loss within their ranges, for inspection runs."""
    if args.link_delay is None:
        if args.link_jitter or args.link_loss:
            parser.error("--link-jitter and --link-loss need --link-delay")
        return
    if args.scenario in PTP_SCENARIOS or is_contact_scenario(args.scenario):
        parser.error("--link-delay is for the inspection scenarios")
    for name, value, high in (
        ("--link-delay", args.link_delay, MAX_DELAY_S),
        ("--link-jitter", args.link_jitter, MAX_DELAY_S),
    ):
        if not (math.isfinite(value) and 0.0 <= value <= high):
            parser.error(f"{name} must be in [0, {high:g}] s, got {value:g}")
    if not (math.isfinite(args.link_loss) and 0.0 <= args.link_loss <= MAX_LINK_LOSS):
        parser.error(f"--link-loss must be in [0, {MAX_LINK_LOSS:g}], got {args.link_loss:g}")


def main(argv: list[str] | None = None) -> int:
    """Exit code 2 with one line on stderr for bad options or configuration; Ctrl-C (or
    SIGTERM) once the runs started: the figures so far, the recordings closed, one line, exit
    code 130 (143); during the imports: 0."""
    return run_main("rns_demo", lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    args = parse_args(argv)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    raise_on_sigterm()
    try:
        return _scenario_runs(args)
    except KeyboardInterrupt as exc:  # outside a method's run (claiming the domain, loading)
        print(f"rns_demo: {_interrupt_text(exc)} before a run started", file=sys.stderr)
        return interrupt_exit_code(exc)


def _interrupt_text(error: KeyboardInterrupt) -> str:
    signum = getattr(error, "signum", signal.SIGINT)
    return "interrupted (Ctrl-C)" if signum == signal.SIGINT else f"stopped by {error}"


@dataclass
class Outcome:
    """What a demo's runs came to besides their rows' figures."""

    #: a method that did not finish its task (failed, or ended early): the method and why
    unfinished: list[str] = field(default_factory=list)
    #: a recording that could not be written (removed): why, one line each
    unwritten: list[str] = field(default_factory=list)
    #: the Ctrl-C / SIGTERM that stopped the runs, None when none did
    interruption: KeyboardInterrupt | None = None

    @property
    def exit_code(self) -> int:
        """128 + signal after an interruption, else 2 for an unfinished method, else 1 for a
        lost recording, else 0."""
        if self.interruption is not None:
            return interrupt_exit_code(self.interruption)
        return 2 if self.unfinished else 1 if self.unwritten else 0


def _scenario_runs(args: argparse.Namespace) -> int:
    if args.scenario in PTP_SCENARIOS:
        return _claimed(args, lambda: _main_ptp(args, PTP_SCENARIOS[args.scenario]))
    if is_contact_scenario(args.scenario):
        return _claimed(args, lambda: _main_contact(args))
    return _main_inspection(args)


def _claimed(args: argparse.Namespace, body: Callable[[], int]) -> int:
    """``body()`` with the domain claimed for the demo's runs (:func:`claim_domain`: nothing
    else of a stack on it, and the claim's node shows it taken to a later rns_demo); exit code
    2 and one line naming the other stack when one runs there."""
    try:
        claim = claim_domain(args.domain_id, f"{CLAIM_PREFIX}_{os.getpid()}")
    except DomainInUseError as exc:
        print(f"rns_demo: {exc}: stop it or pass --domain-id N", file=sys.stderr)
        return 2
    with claim:
        return body()


def _main_inspection(args: argparse.Namespace) -> int:
    try:
        scenario_file = scenario_path(args.scenario)
        (scenario,) = check_scenarios([scenario_file])
        args.model = (args.model or default_model_config()).resolve()
        robot = load_model(args.model)
        args.initial_theta, note = start_configuration(scenario, robot)
    except RnsError as exc:
        print(f"rns_demo: {one_line(exc)}", file=sys.stderr)
        return 2
    return _claimed(args, lambda: _inspection_runs(args, scenario, scenario_file, robot, note))


def _inspection_runs(args: argparse.Namespace, scenario, scenario_file, robot, note: str) -> int:
    print(f"scenario: {scenario_file} ({scenario.description})")
    if note:
        print(f"note: {note}")
    for warning in arm_feasibility(robot, args.initial_theta).warnings:
        print(f"warning (rns_model check): {warning}")
    print(
        f"model: {args.model}; {args.mode} simulation, controller at "
        f"{args.rate:g} Hz, {clock_text(args)}, "
        f"ROS domain {args.domain_id} (localhost only)\n",
        flush=True,
    )
    runs, outcome = [], Outcome()
    for run in range(args.runs):
        label = f" (run {run + 1} of {args.runs})" if args.runs > 1 else ""
        rows = _run_methods(
            args, lambda method: run_method(method, args, scenario_file), outcome, label
        )
        if rows:
            runs.append(rows)
        if outcome.unfinished or outcome.interruption is not None or not rows:
            break  # the figures so far; further runs would only repeat the failure
    if not runs:
        return _nothing_to_report(outcome)
    complete = len(runs) > 1 and not outcome.unfinished and outcome.interruption is None
    table = format_table(runs[-1])
    if complete:
        table += "\n\n" + format_spread(runs)
    sc_gain = float(scenario.controller.get("sc_gain", THESIS_SC_GAIN))
    notes = camera_notes(
        runs[-1], singular_threshold(scenario), float(min(robot.velocity_limits)), sc_gain
    )
    return _report(
        args,
        runs[-1],
        table,
        [problem for rows in runs for problem in non_finite_figures(rows)],
        "".join(f"note: {line}\n" for line in notes)
        + f"ETS-VII allowed base attitude deviation: ±{ETS_VII_ALLOWED_DEVIATION_DEG} deg.",
        inspection_summary(runs),
        outcome,
    )


def _run_methods(
    args: argparse.Namespace, run: Callable, outcome: Outcome, label: str = ""
) -> list:
    """``run(method)`` for each of ``--methods`` in turn, announced (``label`` after the method);
    a run whose recording came out partial is run again (up to PARTIAL_RETRIES times). A
    method that fails is said at once on stderr and added to ``outcome.unfinished`` (one line);
    the others still run. Ctrl-C or SIGTERM ends the runs (``outcome.interruption``), with the
    interrupted run's figures so far where it kept them. The rows of the methods that ran."""
    rows = []
    for method in args.methods:
        print(f"running {method}{label} ...", flush=True)
        try:
            row = _run_complete(run, method)
        except RnsError as exc:
            outcome.unfinished.append(one_line(exc))
            print(f"rns_demo: {outcome.unfinished[-1]}", file=sys.stderr, flush=True)
            continue
        except KeyboardInterrupt as exc:
            outcome.interruption = exc
            kept = getattr(exc, "row", None)
            outcome.unwritten += getattr(exc, "unwritten", [])
            if kept is not None:
                rows.append(kept)
            else:
                outcome.unfinished.append(
                    f"{method}: {_interrupt_text(exc)}; no figures of this run"
                )
            break
        rows.append(row)
        outcome.unwritten += list(getattr(row, "unwritten", ()))
    return rows


def _nothing_to_report(outcome: Outcome) -> int:
    """No method produced figures: the lines already said why; one more after an interruption
    or a lost recording."""
    for line in outcome.unwritten:
        print(f"rns_demo: {line}", file=sys.stderr)
    if outcome.interruption is not None:
        print(f"rns_demo: {_interrupt_text(outcome.interruption)}: no figures", file=sys.stderr)
    return outcome.exit_code or 2


def _run_complete(run: Callable, method: str):
    """``run(method)``, again after a :class:`PartialRecordingError` (at most PARTIAL_RETRIES)."""
    retries = 0
    while True:
        try:
            return run(method)
        except PartialRecordingError as exc:
            retries += 1
            if retries > PARTIAL_RETRIES:
                raise
            print(f"  {one_line(exc)}: running {method} again", flush=True)


def _report(
    args, rows, table: str, problems: list[str], epilogue: str, summary: list, outcome: Outcome
) -> int:
    """The end of every demo: the table; exit 1 on non-finite figures (a run that produced NaN
    / inf failed, whatever the table shows); else the epilogue, the recordings and the JSON
    ``summary`` to ``--summary``; then one line per method that did not finish its task (the
    method and why; its figures above are those so far), per recording that could not be
    written, and for an interruption; the exit code :attr:`Outcome.exit_code`."""
    print()
    print(table)
    if problems:
        print(f"rns_demo: non-finite figures: {'; '.join(problems)}", file=sys.stderr)
        return 1
    print(f"\n{epilogue}")
    recordings = [row.recording for row in rows if row.recording]
    if recordings:
        print("rerun recordings (open with `rerun <file>`): " + ", ".join(recordings))
    mcaps = [row.mcap for row in rows if row.mcap]
    if mcaps:
        print("ROS 2 bags (rns_bag, ros2 bag; their .mcap in Foxglove, PlotJuggler): "
              + ", ".join(mcaps))  # fmt: skip
    if args.summary:
        try:
            args.summary.write_text(json.dumps(summary, indent=2) + "\n")
        except OSError as exc:  # checked at start-up; the folder went away, the disk filled
            print(f"rns_demo: cannot write --summary {str(args.summary)!r}: {exc.strerror}",
                  file=sys.stderr)  # fmt: skip
            return 2
        print(f"summary written to {args.summary}")
    outcome.unfinished += [line for row in rows if (line := row_ended(row))]
    for line in outcome.unfinished + outcome.unwritten:
        print(f"rns_demo: {line}", file=sys.stderr)
    if outcome.interruption is not None:
        print(f"rns_demo: {_interrupt_text(outcome.interruption)}", file=sys.stderr)
    return outcome.exit_code


def row_ended(row) -> str | None:
    """``method: why`` for a row whose run ended before its task's end, else None."""
    ended = getattr(row, "ended", None)
    return f"{row.method}: {ended}" if ended else None


def _main_ptp(args: argparse.Namespace, scenario: PtpScenario) -> int:
    print(f"scenario: {scenario.name} ({scenario.description})")
    print(
        f"model: {default_model_config()}; {args.mode} simulation, rns_ptp at {args.rate:g} Hz, "
        f"{clock_text(args)}, ROS domain {args.domain_id} "
        "(localhost only)\n",
        flush=True,
    )
    outcome = Outcome()
    rows = _run_methods(args, lambda method: run_ptp_method(method, scenario, args), outcome)
    if not rows:
        return _nothing_to_report(outcome)
    return _report(
        args,
        rows,
        format_ptp_table(rows),
        non_finite_figures(rows),
        "ratio: max base deviation / that of the 3-phase method. The thesis' arm geometry is "
        "not printed (ours is identified, docs/arm_identification.md): compare the ranking.",
        [asdict(row) for row in rows],
        outcome,
    )


def _main_contact(args: argparse.Namespace) -> int:
    print(f"scenario: {scenario_path(args.scenario)} (thesis Part II, chapter 6)")
    print(
        "contact simulation at 1 kHz in lockstep with "
        f"rns_force_controller, real-time factor {args.real_time_factor:g}, ROS domain "
        f"{args.domain_id} (localhost only)\n",
        flush=True,
    )
    outcome = Outcome()
    rows = _run_methods(
        args, lambda method: run_contact_method(method, args.scenario, args), outcome
    )
    if not rows:
        return _nothing_to_report(outcome)
    return _report(
        args,
        rows,
        format_contact_table(rows),
        non_finite_figures(rows),
        contact_epilogue(args.scenario),
        contact_summary(rows),
        outcome,
    )


if __name__ == "__main__":
    sys.exit(main())
