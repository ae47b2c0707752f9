"""The Markdown tables of the simulation studies (Figure 6, cpsat-rolling against Optimized,
the horizon and the adaptive studies) and of the run times, rendered from the committed CSVs
(:mod:`.report` holds the calibration's and the user study's)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from ..experiments.tables import markdown_lines
from .adaptive import format_markdown as adaptive_markdown
from .adaptive import share_text
from .fig6_stats import BETTER, WORSE
from .fmt import f, yes
from .horizon_tables import planning_markdown, typed_rows, window_markdown
from .robust_facts import ROBUST_TABLES
from .robust_kitbench_facts import ROBUST_KITBENCH_TABLES
from .robust_sim import ROBUST_SIM_TABLES
from .stations_tables import STATION_TABLES

Row = Mapping[str, Any]
#: Table name -> (its CSV file, its renderer).
Tables = dict[str, tuple[str, Callable[[Sequence[Row]], str]]]
#: The paired test's direction after Holm, as a mark in a heatmap cell.
MARKS = {BETTER: "▲", WORSE: "▼"}


def _blank(x: Any) -> bool:
    return x is None or x == ""


def _cell(r: Row) -> str:
    """``8.5 \\*\\* ▲``: the improvement, the paper's stars, the paired test's direction."""
    stars = str(r.get("stars") or "").replace("*", "\\*")
    return " ".join(x for x in (f(r["pct"]), stars, MARKS.get(str(r["dir_paired_holm"]), "")) if x)


def _panels(rows: Sequence[Row], keep: Callable[[str], bool]) -> list[str]:
    """Each kept panel as a MAT x MTTF table of :func:`_cell`, and its no-delay cell."""
    out: list[str] = []
    for panel in dict.fromkeys(str(r["panel"]) for r in rows):
        if not keep(panel):
            continue
        sub = [r for r in rows if r["panel"] == panel]
        grid = [r for r in sub if not _blank(r["mat"])]
        mats = sorted({float(r["mat"]) for r in grid})
        mttfs = sorted({float(r["mttf"]) for r in grid})
        out += [f"**{panel} (%)**", ""]
        table = []
        for a in mats:
            cells = [f"{a:g}"]
            for b in mttfs:
                r = next(x for x in grid if float(x["mat"]) == a and float(x["mttf"]) == b)
                cells.append(_cell(r))
            table.append(cells)
        out += markdown_lines(["MAT \\ MTTF", *(f"{v:g}" for v in mttfs)], table)
        ref = next((r for r in sub if _blank(r["mat"])), None)
        if ref is not None:
            out += ["", f"No delay (reference): {_cell(ref)}"]
        out.append("")
    return out


def fig6_markdown(rows: Sequence[Row]) -> str:
    """The paper's four panels (``fig6_improvements.csv``, long format) as MAT x MTTF tables."""
    return "\n".join(_panels(rows, lambda p: "cpsat" not in p)).rstrip()


def cpsat_markdown(rows: Sequence[Row]) -> str:
    """cpsat-rolling over Optimized (the panels of a ``--with-cpsat`` run)."""
    return "\n".join(_panels(rows, lambda p: "cpsat" in p)).rstrip()


def verdicts_markdown(rows: Sequence[Row]) -> str:
    """Per panel: better / n.s. / worse under each test, the "most scenarios" verdicts, and
    the replications the paper's test would need for 80 % power."""
    body = []
    for r in rows:
        counts = [
            f"{r[f'{t}_better']} / {r[f'{t}_ns']} / {r[f'{t}_worse']}"
            for t in ("tukey", "tukey_holm", "paired_holm")
        ]
        r80 = "-" if _blank(r["r80_median_better"]) else f"{float(r['r80_median_better']):.0f}"
        body.append(
            [
                str(r["panel"]),
                str(r["reps"]),
                *counts,
                f"{r['most_tukey']} / {r['most_paired_holm']}",
                r80,
                f"{r['cells_r80_le_100']}/{r['cells']}",
            ]
        )
    head = [
        "panel",
        "R",
        "paper's test: better / n.s. / worse",
        "paper's + Holm",
        "paired + Holm",
        "most scenarios? (paper's / paired)",
        "R for 80 % power (median, cells ahead)",
        "cells with R80 <= 100",
    ]
    return "\n".join(markdown_lines(head, body))


def cpsat_verdicts_markdown(rows: Sequence[Row]) -> str:
    """:func:`verdicts_markdown` of the cpsat-rolling panels only."""
    return verdicts_markdown([r for r in rows if "cpsat" in str(r["panel"])])


def trends_markdown(rows: Sequence[Row]) -> str:
    """The trend claims: the MAT slope per 30 s with its 95 % interval, Kendall's tau, the
    verdict."""
    body = [
        [
            str(r["panel"]),
            str(r["claim"]),
            f"{f(r['slope_per_30s'], 2)} [{f(r['ci_low'], 2)}, {f(r['ci_high'], 2)}]",
            f"{_p(r['p'])} (t, df {r.get('df', '-')})",
            f"{f(r['kendall_tau'], 2)} (p {_p(r['kendall_p'])})",
            _num_text(r.get("peak_mat")),
            str(r["verdict"]),
        ]
        for r in rows
    ]
    head = [
        "panel",
        "claim",
        "MAT slope, points per 30 s [95 % CI]",
        "p (t-test of the replications' slopes)",
        "Kendall's tau of the cells",
        "largest at MAT (s)",
        "verdict",
    ]
    return "\n".join(markdown_lines(head, body))


def _num_text(x: Any) -> str:
    """``90`` for 90.0 or "90.0"; ``-`` when missing."""
    return "-" if x in (None, "") else f"{float(x):g}"


def _p(p: Any) -> str:
    if _blank(p):
        return "-"
    v = float(p)
    return "< .001" if v < 0.001 else f"{v:.3f}".lstrip("0")


def horizon_markdown(rows: Sequence[Row]) -> str:
    """The horizon study's planning tables (``horizon.csv``)."""
    return planning_markdown(typed_rows(rows))


def horizon_window_markdown(rows: Sequence[Row]) -> str:
    """The horizon study's window table (``horizon_window.csv``)."""
    return window_markdown(typed_rows(rows))


def adaptive_shares_markdown(rows: Sequence[Row]) -> str:
    """The share of the fixed-to-oracle gap the adaptive policy closes (the paper's idle time),
    with its 95 % bootstrap interval, per group and supply setting."""
    idle = [r for r in rows if r["metric"] == "idle"]
    delays = list(dict.fromkeys(str(r["delay"]) for r in idle))
    groups = list(dict.fromkeys(str(r["group"]) for r in idle))
    by = {(str(r["group"]), str(r["delay"])): r for r in idle}
    body = []
    for g in groups:
        cells = []
        for d in delays:
            r = by[(g, d)]
            gap = (
                f"{f(r['gap_fixed_minus_oracle'], 0)} s [{f(r['gap_low'], 0)}, "
                f"{f(r['gap_high'], 0)}]"
            )
            cells.append(f"{share_text(r)}; gap {gap}")
        factor = by[(g, delays[0])]["factor"]
        body.append([f"{g} ({factor})", *cells])
    head = ["participants (factor)", *(f"supply: {d}" for d in delays)]
    return "\n".join(markdown_lines(head, body))


def timing_markdown(rows: Sequence[Row]) -> str:
    """``timing.csv``: one row per run."""
    body = [
        [
            str(r["run"]),
            f"`{r['command']}`",
            _duration(float(r["wall_s"])),
            str(r["jobs"]),
            f"{r['load_start']} / {r['load_end']}",
            str(r["measured"]),
        ]
        for r in rows
    ]
    head = ["run", "command", "wall time", "jobs", "load average (start / end)", "measured"]
    return "\n".join(markdown_lines(head, body))


def _duration(s: float) -> str:
    if s < 120:
        return f"{s:.1f} s"
    whole = round(s)
    return f"{whole // 60} min {whole % 60:02d} s"


def duration(s: Any) -> str:
    """A wall time as ``67.5 s`` or ``12 min 04 s``."""
    return _duration(float(s))


SIM_TABLES: Tables = {
    "fig6_improvements": ("fig6_improvements.csv", fig6_markdown),
    "fig6_verdicts": ("fig6_verdicts.csv", verdicts_markdown),
    "fig6_trends": ("fig6_trends.csv", trends_markdown),
    "fig6_r100_improvements": ("fig6_r100_improvements.csv", fig6_markdown),
    "fig6_r100_verdicts": ("fig6_r100_verdicts.csv", verdicts_markdown),
    "fig6_r100_trends": ("fig6_r100_trends.csv", trends_markdown),
    "fig6_cpsat": ("fig6_cpsat_improvements.csv", cpsat_markdown),
    "fig6_cpsat_verdicts": ("fig6_cpsat_verdicts.csv", cpsat_verdicts_markdown),
    "horizon": ("horizon.csv", horizon_markdown),
    "horizon_window": ("horizon_window.csv", horizon_window_markdown),
    "adaptive": ("adaptive.csv", adaptive_markdown),
    "adaptive_shares": ("adaptive.csv", adaptive_shares_markdown),
    **STATION_TABLES,
    **ROBUST_TABLES,
    **ROBUST_KITBENCH_TABLES,
    **ROBUST_SIM_TABLES,
    "timing": ("timing.csv", timing_markdown),
}

__all__ = ["SIM_TABLES", "Row", "Tables", "duration", "yes"]
