"""The Markdown tables of ``paper_repro/README.md``, rendered from the committed CSVs in
``paper_repro/results/`` (docs/reproduction.md), so the README cannot drift from the files.

``python paper_repro/render_readme.py`` rewrites every block between
``<!-- results:NAME -->`` and ``<!-- /results:NAME -->``; :func:`render_readme` is what the
test compares the README with.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ..experiments.tables import markdown_lines
from .adaptive import format_markdown as adaptive_markdown
from .horizon_tables import planning_markdown, typed_rows, window_markdown

Row = Mapping[str, Any]


def _f(x: Any, nd: int = 1) -> str:
    """A number as text with ``nd`` decimals (CSV strings and Python values alike)."""
    if x is None or x == "":
        return "-"
    try:
        return f"{float(x):.{nd}f}"
    except (TypeError, ValueError):
        return str(x)


def _yes(x: Any) -> str:
    return "yes" if str(x).lower() in ("true", "1", "yes") else "no"


def _nd(quantity: str) -> int:
    return 2 if quantity.startswith("repeated") else 1


def predictions_markdown(rows: Sequence[Row]) -> str:
    """The Goal table: paper value | fitted or predicted | our median | 95 % interval | inside."""
    body = [
        [
            r["quantity"],
            _f(r["paper"], _nd(r["quantity"])),
            r["role"],
            _f(r["median"], _nd(r["quantity"])),
            f"[{_f(r['pi_low'], _nd(r['quantity']))}, {_f(r['pi_high'], _nd(r['quantity']))}]",
            _yes(r["inside"]),
        ]
        for r in rows
    ]
    pred = [r for r in rows if r["role"] == "predicted"]
    k = sum(_yes(r["inside"]) == "yes" for r in pred)
    n_studies = rows[0].get("studies", "?") if rows else "?"
    lines = markdown_lines(
        [
            "paper number",
            "paper",
            "fitted or predicted",
            "our median",
            "our 95 % interval",
            "inside?",
        ],
        body,
    )
    lines += [
        "",
        f"**{k} of {len(pred)} predicted paper numbers lie inside our 95 % prediction "
        f"intervals** ({n_studies} simulated studies of 18 participants; fitted rows not "
        "counted).",
    ]
    return "\n".join(lines)


def parameters_markdown(rows: Sequence[Row]) -> str:
    body = [
        [
            r["parameter"],
            _f(r["value"], 4) if "." in str(r["value"]) else str(r["value"]),
            r["role"],
            r["source"],
        ]
        for r in rows
    ]
    return "\n".join(markdown_lines(["parameter", "value", "role", "source"], body))


def sensitivity_markdown(rows: Sequence[Row]) -> str:
    """One column per (d, trays): robot_scale, o_H and every predicted median (inside: *)."""
    configs = list(dict.fromkeys((str(r["delivery_time"]), str(r["trays"])) for r in rows))
    quantities = list(dict.fromkeys(r["quantity"] for r in rows if r["role"] == "predicted"))
    by = {(str(r["delivery_time"]), str(r["trays"]), r["quantity"]): r for r in rows}
    first = {
        c: next(r for r in rows if (str(r["delivery_time"]), str(r["trays"])) == c) for c in configs
    }
    header = ["", *(f"d = {_f(d, 0)} s, trays {t}" for d, t in configs)]
    body = [
        ["robot_scale (refitted)", *(_f(first[c]["robot_scale"], 3) for c in configs)],
        ["o_H (s, refitted)", *(_f(first[c]["kit_overhead_human"], 2) for c in configs)],
        ["predicted inside", *(str(first[c]["inside_count"]) for c in configs)],
    ]
    for q in quantities:
        cells = []
        for c in configs:
            r = by[(*c, q)]
            cells.append(_f(r["median"], _nd(q)) + (" (in)" if _yes(r["inside"]) == "yes" else ""))
        body.append([q, *cells])
    return "\n".join(markdown_lines(header, body))


def fig6_markdown(rows: Sequence[Row]) -> str:
    """Each panel as a MAT x MTTF table of ``% stars`` (long-format rows of
    ``fig6_improvements.csv``)."""
    out: list[str] = []
    for panel in dict.fromkeys(r["panel"] for r in rows):
        sub = [r for r in rows if r["panel"] == panel]
        grid = [r for r in sub if r["mat"] not in ("", None)]
        mats = sorted({float(r["mat"]) for r in grid})
        mttfs = sorted({float(r["mttf"]) for r in grid})
        out += [f"**{panel} (%)**", ""]
        table = []
        for a in mats:
            cells = [f"{a:g}"]
            for b in mttfs:
                r = next(x for x in grid if float(x["mat"]) == a and float(x["mttf"]) == b)
                cells.append(f"{_f(r['pct'])} {r['stars'] or ''}".strip().replace("*", "\\*"))
            table.append(cells)
        out += markdown_lines(["MAT \\ MTTF", *(f"{v:g}" for v in mttfs)], table)
        ref = next((r for r in sub if r["mat"] in ("", None)), None)
        if ref is not None:
            stars = (ref["stars"] or "").replace("*", "\\*")
            out += ["", f"No delay (reference): {_f(ref['pct'])} {stars}".rstrip()]
        out.append("")
    return "\n".join(out).rstrip()


def verdicts_markdown(rows: Sequence[Row]) -> str:
    body = [
        [
            r["panel"],
            f"{r['significant']}/{r['cells']}",
            f"{r['significant_holm']}/{r['cells']}",
            f"{r['significant_paired']}/{r['cells']}",
            r["verdict"],
        ]
        for r in rows
    ]
    return "\n".join(
        markdown_lines(
            [
                "panel",
                "significant (ANOVA + Tukey, p < .05)",
                "after Holm over the cells",
                "paired t-test (not the paper's)",
                "'significant for most scenarios'?",
            ],
            body,
        )
    )


def horizon_markdown(rows: Sequence[Row]) -> str:
    """The horizon study's planning tables (``horizon.csv``)."""
    return planning_markdown(typed_rows(rows))


def horizon_window_markdown(rows: Sequence[Row]) -> str:
    """The horizon study's window table (``horizon_window.csv``)."""
    return window_markdown(typed_rows(rows))


#: README block name -> (CSV file in the results folder, renderer).
BLOCKS: dict[str, tuple[str, Callable[[Sequence[Row]], str]]] = {
    "user_study_predictions": ("user_study_predictions.csv", predictions_markdown),
    "user_study_parameters": ("user_study_parameters.csv", parameters_markdown),
    "user_study_sensitivity": ("user_study_sensitivity.csv", sensitivity_markdown),
    "fig6_improvements": ("fig6_improvements.csv", fig6_markdown),
    "fig6_verdicts": ("fig6_verdicts.csv", verdicts_markdown),
    "horizon": ("horizon.csv", horizon_markdown),
    "horizon_window": ("horizon_window.csv", horizon_window_markdown),
    "adaptive": ("adaptive.csv", adaptive_markdown),
}

_BLOCK = re.compile(r"(<!-- results:(\w+) -->\n)(.*?)(<!-- /results:\2 -->)", re.S)


def read_rows(path: str | Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def render_readme(text: str, results_dir: str | Path) -> str:
    """``text`` with every results block re-rendered from its CSV (unknown blocks: error)."""

    def sub(m: re.Match[str]) -> str:
        name = m.group(2)
        if name not in BLOCKS:
            raise KeyError(f"unknown results block {name!r}")
        file, fn = BLOCKS[name]
        return f"{m.group(1)}{fn(read_rows(Path(results_dir) / file))}\n{m.group(4)}"

    return _BLOCK.sub(sub, text)


def blocks_in(text: str) -> list[str]:
    return [m.group(2) for m in _BLOCK.finditer(text)]
