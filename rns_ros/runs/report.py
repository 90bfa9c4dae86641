"""What the rows of rns_demo's runs show: the tables, the JSON summary, the spread over runs, the
non-finite figures that fail a run."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import asdict
from typing import NamedTuple, Protocol

import numpy as np

from rns_ros.analysis.reproduce.chapter4_ptp import THESIS_TABLE
from rns_ros.control.camera_law import THESIS_SC_GAIN
from rns_ros.runs.contact import ContactDemoRow
from rns_ros.runs.inspection import DemoRow
from rns_ros.runs.ptp import PtpDemoRow
from rns_ros.runs.recorded import EnergyFigures


class CheckedRow(Protocol):
    """A row whose figures :func:`non_finite_figures` checks."""

    @property
    def label(self) -> str: ...

    def checked_figures(self) -> dict[str, float]: ...


def non_finite_figures(rows: Iterable[CheckedRow]) -> list[str]:
    """One text per run with a NaN or infinite figure ("sc: final_camera_error_deg = nan, ...");
    empty when every figure is finite."""
    problems = []
    for row in rows:
        values = row.checked_figures()
        bad = [f"{name} = {value}" for name, value in values.items() if not math.isfinite(value)]
        if bad:
            problems.append(f"{row.label}: " + ", ".join(bad))
    return problems


#: Marks a row whose run ended before the task's end (figures so far; the cause follows).
ENDED_MARK = " *"


def _row_name(row: DemoRow) -> str:
    return row.method + (ENDED_MARK if row.ended else "")


def format_table(rows: list[DemoRow]) -> str:
    """The comparison table of inspection ``rows``; a row marked ``*`` ended early (a joint at
    its limit), its figures those up to then."""
    columns = (
        ("method", max(14, 2 + max((len(_row_name(row)) for row in rows), default=0))),
        ("max base dev [deg]", 20),
        ("camera err [deg]", 18),
        ("RMS ω err [rad/s]", 19),
        ("wrist drift [m]", 17),
        ("max |θ̇| [rad/s]", 17),
        ("Δl [kg m²/s]", 14),
        ("min σ(J̄)", 11),
        ("sing. [s]", 11),
        ("C_max [J]", 11),
        ("C_sum [J s]", 13),
        ("wheel KE [J]", 14),
        ("wheel sat [s]", 15),
        ("wall [s]", 10),
        ("task [s]", 10),
        ("× real time", 13),
    )
    linked = any(row.link_delay_s is not None for row in rows)
    if linked:
        columns += (("link [s]", 10), ("pred. err [deg]", 17))
    header = "".join(
        f"{title:<{width}}" if i == 0 else f"{title:>{width}}"
        for i, (title, width) in enumerate(columns)
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        f = row.figures
        lines.append(
            f"{_row_name(row):<{columns[0][1]}}{f.max_base_deviation_deg:>20.3e}"
            f"{f.final_camera_error_deg:>18.4g}"
            f"{f.rms_tracking_error:>19.3e}{f.max_wrist_drift_m:>17.3f}{f.max_joint_speed:>17.3f}"
            f"{f.angular_momentum_drift:>14.2e}{f.min_sigma:>11.3g}{f.singular_time_s:>11.2f}"
            f"{_energy_columns(row.energy)}"
            f"{row.wall_time_s:>10.1f}{_task_columns(row)}" + (_link_columns(row) if linked else "")
        )
    if any(row.ended for row in rows):
        lines.append(f"{ENDED_MARK.strip()} ended before the task's end: the figures up to then")
    return "\n".join(lines)


def _link_columns(row: DemoRow) -> str:
    """The link's one-way delay [s] and the largest prediction error [deg], or dashes."""
    delay = "-" if row.link_delay_s is None else f"{row.link_delay_s:g}"
    error = row.prediction_error_deg
    return f"{delay:>10}" + (f"{'-':>17}" if error is None else f"{error:>17.3g}")


def _task_columns(row: DemoRow) -> str:
    """Wall time of the task [s] and its real-time factor, or dashes."""
    factor = row.real_time_factor
    if factor is None:
        return f"{'-':>10}{'-':>13}"
    return f"{row.task_wall_s:>10.2f}{factor:>13.2f}"


def _energy_columns(energy: EnergyFigures | None) -> str:
    if energy is None:
        return f"{'-':>11}{'-':>13}{'-':>14}{'-':>15}"
    saturation = "-" if energy.wheel_saturation_s is None else f"{energy.wheel_saturation_s:.2f}"
    return (
        f"{energy.c_max:>11.3g}{energy.c_sum:>13.3g}{energy.peak_wheel_energy:>14.3g}"
        f"{saturation:>15}"
    )


#: A camera that ends farther than this from the scenario's target [deg] gets a line saying why.
CAMERA_OFF_DEG = 1.0
#: Share of a velocity limit at which a run counts as speed-limited [-].
SPEED_LIMIT_REACHED = 0.99


def camera_notes(
    rows: list[DemoRow],
    threshold: float,
    speed_limit: float = math.inf,
    sc_gain: float = THESIS_SC_GAIN,
) -> list[str]:
    """One line per completed run whose camera ends more than :data:`CAMERA_OFF_DEG` off its
    target, saying whether the singular region (sigma_min of J-bar below ``threshold``), the
    joint speed limit (the lowest URDF velocity limit, ``speed_limit`` [rad/s], reached) or, for
    SC, its speed scale b prod(sigma) below 1 (eq. 4.13, b = ``sc_gain``) is why."""
    notes = []
    for row in rows:
        f = row.figures
        if row.ended or not f.final_camera_error_deg > CAMERA_OFF_DEG:
            continue
        head = f"{row.method}: the camera ends {f.final_camera_error_deg:.3g} deg off its target"
        if f.singular_time_s > 0.0:
            notes.append(
                f"{head}: {f.singular_time_s:.2f} s in the singular region (sigma_min of J-bar "
                f"down to {f.min_sigma:.2g} < {threshold:g}), where the method gives up rate "
                "accuracy to keep the joint rates bounded (section 4.3)"
            )
        elif row.method == "sc" and (scale := _sc_scales(f, sc_gain)) is not None:
            low, high = scale
            notes.append(
                f"{head}: SC scales the commanded rate by b prod(sigma of J-bar) (eq. 4.13), "
                f"{low:.2g} to {high:.2g} here (1: as commanded), so the camera turns "
                f"{'faster' if low >= 1.0 else 'slower' if high <= 1.0 else 'at another speed'}"
                f" than commanded; not a singular region (sigma_min of J-bar >= {f.min_sigma:.2g})"
            )
        elif f.max_joint_speed >= SPEED_LIMIT_REACHED * speed_limit:
            notes.append(
                f"{head}: the joint rates reached their speed limit (max |θ̇| "
                f"{f.max_joint_speed:.3g} rad/s), which scales the commanded rate down; not a "
                f"singular region (sigma_min of J-bar >= {f.min_sigma:.2g})"
            )
        elif (
            f.commanded_camera_error_deg is not None
            and f.commanded_camera_error_deg < COMMANDED_SHARE * f.final_camera_error_deg
        ):
            notes.append(
                f"{head} but {f.commanded_camera_error_deg:.3g} deg off what the recorded "
                "cmd_twist samples add up to: the operator's stream fell short of the scenario "
                "(samples late or missing: on the wall clock, an operator that waited for a core)"
            )
        else:
            notes.append(
                f"{head} with sigma_min of J-bar >= {f.min_sigma:.2g} (never below {threshold:g}):"
                " not a singular region; see the RMS ω error and the controller's warnings"
            )
    return notes


#: A camera this much closer to what the recorded twists add up to than to the scenario's
#: target [-, share] puts the error on the operator's stream.
COMMANDED_SHARE = 0.5

#: An SC speed scale this far from 1 [-] explains a camera off its target.
SC_SCALE_OFF = 0.1


def _sc_scales(figures, sc_gain: float) -> tuple[float, float] | None:
    """SC's smallest and largest speed scale b prod(sigma) over a run, when either is more than
    :data:`SC_SCALE_OFF` from 1 (None otherwise, or when not computed)."""
    low, high = figures.min_singular_product, figures.max_singular_product
    if low is None or high is None:
        return None
    low, high = sc_gain * low, sc_gain * high
    return (low, high) if low < 1.0 - SC_SCALE_OFF or high > 1.0 + SC_SCALE_OFF else None


class Spread(NamedTuple):
    """One figure of one method over the runs: min, median, max, and each run."""

    min: float
    median: float
    max: float
    values: list[float]


def _base_deviation(row: DemoRow) -> float:
    return row.figures.max_base_deviation_deg


def spread(
    runs: list[list[DemoRow]],
    method: str,
    figure: Callable[[DemoRow], float | None] = _base_deviation,
) -> Spread:
    """:class:`Spread` of ``figure(row)`` (default: the max base deviation [deg]) of
    ``method``'s rows over ``runs`` (rows per run); runs without the figure are left out."""
    values = [
        value
        for rows in runs
        for row in rows
        if row.method == method and (value := figure(row)) is not None
    ]
    if not values:
        return Spread(np.nan, np.nan, np.nan, [])
    return Spread(min(values), float(np.median(values)), max(values), values)


def _task_wall(row: DemoRow) -> float | None:
    return row.task_wall_s


def format_spread(runs: list[list[DemoRow]]) -> str:
    """The max base deviation and the task's wall time of each method over the runs (the table
    above is the last run)."""
    lines = [
        f"over {len(runs)} runs (the table: the last run)",
        f"{'method':<22}{'max base dev [deg]: min':>26}{'median':>12}{'max':>12}"
        f"{'task [s]: min':>16}{'median':>10}{'max':>10}",
    ]
    for row in runs[-1]:
        base, task = spread(runs, row.method), spread(runs, row.method, _task_wall)
        lines.append(
            f"{row.method:<22}{base.min:>26.3e}{base.median:>12.3e}{base.max:>12.3e}"
            f"{task.min:>16.2f}{task.median:>10.2f}{task.max:>10.2f}"
        )
    return "\n".join(lines)


def format_ptp_table(rows: list[PtpDemoRow]) -> str:
    """Table 4.2 style: deviation and ratio to the 3-phase run, next to the thesis'."""
    reference = next((r.max_base_deviation_deg for r in rows if r.method == "three_phase"), None)
    thesis_reference = THESIS_TABLE["3-phase"]
    header = (
        f"{'method':<10}{'max base dev [deg]':>20}{'ratio':>8}{'thesis [deg]':>14}"
        f"{'thesis ratio':>14}{'end error':>16}{'max |θ̇| [rad/s]':>18}{'T [s]':>8}"
        f"{'wall [s]':>10}  folds reached (θ4)"
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        ratio = row.max_base_deviation_deg / reference if reference else math.nan
        thesis = THESIS_TABLE[row.label]
        if row.final_camera_error_m is None:
            end = f"{row.final_joint_error_deg:.2g} deg"
        else:
            end = f"{1e3 * row.final_camera_error_m:.3g} mm cam"
        lines.append(
            f"{row.label:<10}{row.max_base_deviation_deg:>20.4f}{ratio:>8.2f}{thesis:>14.2f}"
            f"{thesis / thesis_reference:>14.2f}{end:>16}"
            f"{row.max_joint_speed:>18.3f}{row.duration_s:>8.2f}{row.wall_time_s:>10.1f}"
            f"  {row.fold_reached}"
        )
    return "\n".join(lines)


def format_contact_table(rows: list[ContactDemoRow]) -> str:
    """One line per controller: errors, joint speeds (DDS and in-process), loop timing."""
    header = (
        f"{'controller':<16}{'max pos err [mm]':>18}{'max |f err| [N]':>17}{'held [N]':>10}"
        f"{'peak |θ̇| [rad/s]':>18}{'in-process':>12}{'final |θ̇|':>11}{'loop [Hz]':>11}"
        f"{'step med/p99 [µs]':>19}{'wall [s]':>10}"
    )
    lines = [header, "-" * len(header)]
    for row in rows:
        f = row.figures
        lines.append(
            f"{row.label:<16}{1e3 * f.max_position_error_m:>18.4f}{f.max_force_error_n:>17.3g}"
            f"{f.held_force_error_n:>10.3g}{f.peak_joint_speed:>18.3f}"
            f"{row.core_peak_joint_speed:>12.3f}{f.final_joint_speed:>11.2g}"
            f"{row.loop_rate_hz:>11.0f}"
            f"{f'{row.step_time_median_us:.0f}/{row.step_time_p99_us:.0f}':>19}"
            f"{row.wall_time_s:>10.1f}"
        )
    return "\n".join(lines)


def inspection_summary(runs: list[list[DemoRow]]) -> list[dict]:
    """The JSON summary of the last run's rows; over several ``runs`` (rows per run) with the
    spread of the base deviation and of the task's wall time."""
    return [
        {"method": row.method, **asdict(row.figures), "wall_time_s": row.wall_time_s}
        | {"task_wall_s": row.task_wall_s, "task_sim_s": row.task_sim_s}
        | {"recording": row.recording, "mcap": row.mcap, "ended": row.ended}
        | (
            {"link_delay_s": row.link_delay_s, "prediction_error_deg": row.prediction_error_deg}
            if row.link_delay_s is not None
            else {}
        )
        | {"energy": None if row.energy is None else asdict(row.energy)}
        | (
            {
                "runs": spread(runs, row.method)._asdict(),
                "task_wall_runs": spread(runs, row.method, _task_wall)._asdict(),
            }
            if len(runs) > 1
            else {}
        )
        for row in runs[-1]
    ]


def contact_summary(rows: list[ContactDemoRow]) -> list[dict]:
    """The JSON summary of motion/force rows."""
    return [
        {
            "method": row.method,
            "label": row.label,
            **asdict(row.figures),
            "core_peak_joint_speed": row.core_peak_joint_speed,
            "loop_rate_hz": row.loop_rate_hz,
            "step_time_median_us": row.step_time_median_us,
            "step_time_p99_us": row.step_time_p99_us,
            "final_state": row.final_state,
            "wall_time_s": row.wall_time_s,
            "recording": row.recording,
            "mcap": row.mcap,
        }
        for row in rows
    ]
