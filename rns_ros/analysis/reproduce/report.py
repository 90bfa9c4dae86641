"""docs/reproduction.md: the headline table, the counts, then every result's rows and figure.

The counts follow the verdict rule of :mod:`~rns_ros.analysis.reproduce.registry`: only the
thesis' own claims with a result verdict (exact, close, different, qualitative, not reproduced)
are counted; *by construction* rows, inputs and extensions are counted apart, never as agreement.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

from rns_ros.analysis.reproduce.registry import (
    COUNTED,
    VERDICT_RULE,
    Comparison,
    RunRecord,
    Verdict,
    cell_text,
)
from rns_ros.core.errors import ConfigError


@dataclass(frozen=True)
class Headline:
    """One claim a reader of the thesis' summaries (§8.1) remembers, and the rows that judge it.

    Attributes:
        claim: the claim in a few words, with where the thesis makes it.
        rows: ``(result id, comparison key)`` pairs, the first being the claim's own verdict.
    """

    claim: str
    rows: tuple[tuple[str, str], ...]


#: The headline table, in the thesis' order.
HEADLINES = (
    Headline(
        "Planar arm: the reactionless field bifurcates at r ≈ 0.945 m (§3.2.2)",
        (("sec3.2.2", "r_star_m"),),
    ),
    Headline(
        "Inspection: conventional control turns the base past ETS-VII's ±0.05 deg "
        "allowance; reactionless control does not turn it (§4.2.2, Fig. 4.4)",
        (
            ("fig4.4", "max_base_deviation_conventional_deg"),
            ("fig4.4", "max_base_deviation_dls_deg"),
        ),
    ),
    Headline(
        "DLS: singular region 1.71 s ≤ t ≤ 4.18 s, joint speed suppressed (Fig. 4.7)",
        (("fig4.7", "singular_region_end_s"), ("fig4.7", "peak_joint_speed_rad_s")),
    ),
    Headline(
        "SC: the camera follows the commanded direction, only the speed errs (Fig. 4.8)",
        (("fig4.8", "max_axis_error_deg"), ("fig4.8", "speed_scale_range")),
    ),
    Headline(
        "Point-to-point: the 3-phase method's base deviation is about two times smaller "
        "(Table 4.2)",
        (("table4.2", "deviation_ratio_baselines_over_3_phase"),),
    ),
    Headline(
        "Partial reactionless deployment: 28.5 % less base deviation (§4.5.2)",
        (("sec4.5.2", "reduction_percent"),),
    ),
    Headline(
        "Reactionless ≈ minimum-energy motion: mean C_ratio 1.002 (planar, Fig. 5.1) and "
        "1.14 (7-DoF, Fig. 5.3)",
        (("fig5.1", "c_ratio_mean"), ("fig5.3", "c_ratio_mean")),
    ),
    Headline(
        "Inspection energy: almost 10³ times less than with reaction wheels (Fig. 5.5)",
        (("fig5.5", "energy_ratio"),),
    ),
    Headline(
        "Planar arc: peak joint speed 4.22 rad/s (OS-C) against 0.73 rad/s (RNS-C) (Fig. 6.4)",
        (("fig6.4", "peak_ratio_osc_over_rns_c"),),
    ),
    Headline(
        "7-DoF wall: OS-C's joint motion differs from RNS-C's (Fig. 6.8)",
        (("fig6.8", "peak_ratio_osc_over_rns_c"),),
    ),
    Headline(
        "RNS-C tends to resolved-acceleration control as the virtual mass grows (Fig. 7.3)",
        (("fig7.3", "rms_delta_theta_rad"),),
    ),
    Headline(
        "Joint damper k_d = 2770 1/s, the highest without instability (Fig. 7.4)",
        (("fig7.4", "damper_rk4_limit"),),
    ),
)


def _rows(records: list[RunRecord]) -> list[tuple[RunRecord, Comparison, bool]]:
    """Every row with whether it is an extension (its own flag or its result's)."""
    return [
        (record, c, c.extension or record.reproduction.extension)
        for record in records
        for c in record.outcome.comparisons
    ]


def counts_text(records: list[RunRecord]) -> list[str]:
    """The counts: thesis claims judged (by verdict), then by construction, inputs and
    extensions apart."""
    rows = _rows(records)
    claims = Counter(c.verdict for _, c, ext in rows if not ext and c.verdict in COUNTED)
    listed = Counter(c.verdict for _, c, ext in rows if not ext and c.verdict not in COUNTED)
    extensions = Counter(c.verdict for _, c, ext in rows if ext)
    agreeing = claims[Verdict.EXACT] + claims[Verdict.CLOSE] + claims[Verdict.QUALITATIVE]
    return [
        f"**Thesis claims judged: {sum(claims.values())}**: "
        + ", ".join(f"{claims[v]} {v.value}" for v in COUNTED)
        + f" ({agreeing} agree).",
        "",
        f"Listed apart, never counted as agreement: {listed[Verdict.BY_CONSTRUCTION]} by "
        f"construction (identities and results our set-up forces), {listed[Verdict.INPUT]} "
        f"input (values we set or fitted, statements of the set-up); "
        f"{sum(extensions.values())} extension rows (conditions the thesis never ran: "
        + ", ".join(f"{extensions[v]} {v.value}" for v in Verdict if extensions[v])
        + f"). {len(records)} results, {sum(r.seconds for r in records):.0f} s of computing.",
    ]


def headline_table(records: list[RunRecord]) -> list[str]:
    """The headline table: each claim of :data:`HEADLINES` with the thesis' value, ours and
    the verdict; a result not in ``records`` shows as not run.

    Raises:
        ConfigError: a headline names a row its result does not have.
    """
    by_id = {record.reproduction.id: record for record in records}
    lines = ["| claim | thesis | ours | verdict | result |", "|---|---|---|---|---|"]
    for headline in HEADLINES:
        for index, (identifier, key) in enumerate(headline.rows):
            claim = headline.claim if index == 0 else "″"
            record = by_id.get(identifier)
            if record is None:
                lines.append(f"| {claim} | | not run | | `{identifier}` |")
                continue
            row = next((c for c in record.outcome.comparisons if c.key == key), None)
            if row is None:
                raise ConfigError(f"the headline row {key!r} is not in the result {identifier!r}")
            unit = f" {row.unit}" if row.unit and not isinstance(row.ours, dict) else ""
            lines.append(
                f"| {claim} | {cell_text(row.thesis)} | {cell_text(row.ours)}{unit} | "
                f"{row.verdict.value} | [`{identifier}`](#{anchor(identifier)}) `{key}` |"
            )
    return lines


def report_markdown(records: list[RunRecord], figure_dir: str) -> str:
    """docs/reproduction.md: the headline table, the verdict rule and counts, then per result a
    table thesis | ours | verdict and its figure.

    Args:
        figure_dir: path of the PNGs relative to the report (e.g. "reproduction").
    """
    lines = [
        "# Reproduction of the thesis",
        "",
        "Generated by `rns_reproduce all` (do not edit by hand). Each section is one registered",
        "result: the numbers the thesis reports next to ours, the settings and our choices.",
        "The JSON of each result, with every value, is written next to its figure.",
        "",
        "## Headline",
        "",
        "The claims a reader of the thesis' chapter summaries and §8.1 remembers, ours beside",
        "them (the first row of each claim carries its verdict; the rule is below).",
        "",
        *headline_table(records),
        "",
        "## Counts",
        "",
        *counts_text(records),
        "",
        f"One verdict rule for every comparison: {VERDICT_RULE}",
        "",
        "| id | thesis | title |",
        "|---|---|---|",
    ]
    lines += [
        f"| [`{r.reproduction.id}`](#{anchor(r.reproduction.id)}) | {r.reproduction.figure} | "
        f"{r.reproduction.title}{' (extension)' if r.reproduction.extension else ''} |"
        for r in records
    ]
    for record in records:
        rep, outcome = record.reproduction, record.outcome
        kind = " An extension: ours only, reported apart." if rep.extension else ""
        lines += [
            "",
            f"## {rep.id}",
            "",
            f"{rep.figure}: {rep.title}. Computed in {record.seconds:.1f} s.{kind}",
            "",
            "| quantity | thesis | ours | verdict | note |",
            "|---|---|---|---|---|",
        ]
        for c in outcome.comparisons:
            unit = f" [{c.unit}]" if c.unit else ""
            verdict = f"{c.verdict.value} (extension)" if c.extension else c.verdict.value
            lines.append(
                f"| `{c.key}`{unit} | {cell_text(c.thesis)} | {cell_text(c.ours)} | {verdict} | "
                f"{cell_text(c.note)} |"
            )
        if outcome.settings:
            settings = "; ".join(f"{k} = {cell_text(v)}" for k, v in outcome.settings.items())
            lines += ["", f"Settings: {settings}."]
        if outcome.choices:
            lines += ["", "Choices:", ""] + [f"* {choice}" for choice in outcome.choices]
        lines += ["", f"![{rep.figure}]({figure_dir}/{rep.id}.png)"]
    return "\n".join(lines) + "\n"


def anchor(identifier: str) -> str:
    """The markdown anchor of a result's section (``## <id>``)."""
    return identifier.replace(".", "").lower()
