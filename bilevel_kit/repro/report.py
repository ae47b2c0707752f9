"""The Markdown tables of the reproduction's documents, rendered from the committed CSVs in
``paper_repro/results/`` (docs/reproduction.md), so no document can drift from the files.

:data:`TABLES` maps a table's name to its CSV and renderer; the templates
(:mod:`.template`) place a table with ``{{table:NAME}}``. This module holds the calibration's
and the user study's tables; :mod:`.report_sim` the simulation studies'.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ..experiments.tables import markdown_lines
from .fmt import f, nd_of, read_rows, yes
from .predictions import FITTED, IMPLIED, PREDICTED, follows
from .report_sim import SIM_TABLES, Row, Tables


def _kind(r: Row) -> str:
    """``fitted``, ``implied (644.8)``, ``predicted`` or ``predicted, follows ...``."""
    kind = str(r["kind"])
    if kind == IMPLIED:
        return f"implied ({f(r['implied'], nd_of(str(r['quantity'])))})"
    what = follows(r)
    return f"predicted, follows {what}" if kind == PREDICTED and what else kind


def _paper(r: Row) -> str:
    nd = nd_of(str(r["quantity"]))
    h = float(r.get("readoff") or 0.0)
    return f"{f(r['paper'], nd)} ± {f(h, 1)}" if h > 0 else f(r["paper"], nd)


def _inside(r: Row) -> str:
    word = "yes" if yes(r["inside"]) else "**no**"
    return word if r["kind"] == PREDICTED else f"{word.strip('*')} (not counted)"


def _interval(r: Row, lo: str, hi: str) -> str:
    nd = nd_of(str(r["quantity"]))
    return f"[{f(r[lo], nd)}, {f(r[hi], nd)}]"


def predictions_markdown(rows: Sequence[Row]) -> str:
    """The Goal table: paper value (± its read-off), kind, our median, the interval of the
    participants alone and with the calibration's uncertainty, how much wider, inside."""
    body = [
        [
            str(r["quantity"]),
            _kind(r),
            _paper(r),
            f(r["median"], nd_of(str(r["quantity"]))),
            _interval(r, "pi_low", "pi_high"),
            _interval(r, "cal_low", "cal_high"),
            "-" if r.get("widened_pct") in (None, "") else f"{float(r['widened_pct']):+.0f} %",
            _inside(r),
        ]
        for r in rows
    ]
    head = [
        "paper number",
        "kind",
        "paper",
        "our median",
        "95 % interval, participants",
        "95 % interval, with calibration",
        "width change with calibration",
        "inside?",
    ]
    from .predictions import inside_count

    k, n = inside_count(rows)
    ki, ni = inside_count(rows, independent=True)
    kinds = [str(r["kind"]) for r in rows]
    lines = markdown_lines(head, body)
    lines += [
        "",
        f"**{k} of {n} predicted paper numbers lie inside our 95 % prediction intervals with "
        f"the calibration's uncertainty** ({ki} of the {ni} independent ones; "
        f"{kinds.count(FITTED)} fitted and {kinds.count(IMPLIED)} implied numbers shown, not "
        "counted).",
    ]
    return "\n".join(lines)


def parameters_markdown(rows: Sequence[Row]) -> str:
    body = [
        [
            str(r["parameter"]),
            f(r["value"], 4) if "." in str(r["value"]) else str(r["value"]),
            str(r["role"]),
            str(r["source"]),
        ]
        for r in rows
    ]
    return "\n".join(markdown_lines(["parameter", "value", "role", "source"], body))


def calibration_markdown(rows: Sequence[Row]) -> str:
    """``calibration.csv``: the values with the bootstrap's 95 % range, then the provenance."""
    body, prov = [], []
    for r in rows:
        if r["role"] == "provenance":
            prov.append(f"{r['name']} `{r['value']}`")
            continue
        value = str(r["value"])
        num = value.replace(".", "", 1).replace("-", "", 1).isdigit() and "." in value
        boot = f"[{f(r['low'], 4)}, {f(r['high'], 4)}]" if r.get("low") not in (None, "") else ""
        body.append(
            [
                str(r["name"]),
                f(value, 4) if num else value,
                str(r["role"]),
                boot,
                str(r.get("source", "")),
            ]
        )
    head = ["name", "value", "role", "bootstrap 95 % range", "source"]
    lines = markdown_lines(head, body)
    return "\n".join([*lines, "", "Provenance: " + "; ".join(prov) + "."])


def calibration_targets_markdown(rows: Sequence[Row]) -> str:
    """``calibration_targets.csv``: the three targets, the model's value at the fit, and the
    spread of the bootstrap's synthetic targets."""
    body = []
    for r in rows:
        nd = 2 if r["quantity"] == "F" else 1
        name = (
            f"mean {r['metric']} time, {r['condition']}"
            if r["condition"]
            else f"F(2, 34), {r['metric']} time"
        )
        h = float(r["readoff"] or 0)
        paper = f"{f(r['paper'], nd)} ± {f(h, 1)}" if h > 0 else f(r["paper"], nd)
        body.append(
            [
                name,
                paper,
                f(r["fitted"], nd),
                f(r["residual"], nd),
                f"[{f(r['bootstrap_low'], nd)}, {f(r['bootstrap_high'], nd)}]",
            ]
        )
    head = ["target", "paper", "model at the fit", "residual", "bootstrap targets, 95 % range"]
    return "\n".join(markdown_lines(head, body))


def _configs(rows: Sequence[Row]) -> list[str]:
    return list(dict.fromkeys(str(r["setting"]) for r in rows))


def sensitivity_markdown(rows: Sequence[Row]) -> str:
    """What-if fits (``user_study_sensitivity.csv``): one column per setting; the refitted
    robot speed and ``o_H``, the predicted count inside and every predicted median ("(in)":
    inside our participants-only interval)."""
    configs = _configs(rows)
    first = {c: next(r for r in rows if r["setting"] == c) for c in configs}
    by = {(str(r["setting"]), str(r["quantity"])): r for r in rows}
    body = [
        ["robot_scale (refitted)", *(f(first[c]["robot_scale"], 3) for c in configs)],
        ["o_H (s, refitted)", *(f(first[c]["kit_overhead_human"], 2) for c in configs)],
        ["predicted inside", *(str(first[c]["inside_count"]) for c in configs)],
    ]
    quantities = dict.fromkeys(str(r["quantity"]) for r in rows if r["kind"] == PREDICTED)
    for q in quantities:
        cells = [
            f(by[(c, q)]["median"], nd_of(q)) + (" (in)" if yes(by[(c, q)]["inside"]) else "")
            for c in configs
        ]
        body.append([q, *cells])
    return "\n".join(markdown_lines(["", *configs], body))


#: Short column names of the predicted numbers (model sensitivity table).
SHORT_Q = {
    "mean total task time, Optimized (s)": "OPT total (s)",
    "mean human idle time, Optimized (s)": "OPT idle (s)",
    "repeated-measures F(2, 34), human idle time": "F idle",
    "Tukey 95% CI OPT-WA centre, total task time (s)": "OPT-WA total centre",
    "Tukey 95% CI OPT-WA centre, human idle time (s)": "OPT-WA idle centre",
    "Tukey 95% CI half-width (every pair), total task time (s)": "half-width total",
    "Tukey 95% CI half-width (every pair), human idle time (s)": "half-width idle",
}


def model_sensitivity_markdown(rows: Sequence[Row]) -> str:
    """Model sensitivity (``user_study_model_sensitivity.csv``): one row per setting, the
    predicted medians ("(in)" as above) and the count inside."""
    quantities = list(dict.fromkeys(str(r["quantity"]) for r in rows))
    by = {(str(r["setting"]), str(r["quantity"])): r for r in rows}
    body = []
    for c in _configs(rows):
        r0 = by[(c, quantities[0])]
        cells = [
            f(by[(c, q)]["median"], nd_of(q)) + (" (in)" if yes(by[(c, q)]["inside"]) else "")
            for q in quantities
        ]
        body.append([c, f(r0["within_cv"], 3), *cells, str(r0["inside_count"])])
    head = ["setting", "within_cv", *(SHORT_Q.get(q, q) for q in quantities), "inside"]
    return "\n".join(markdown_lines(head, body))


def within_markdown(rows: Sequence[Row]) -> str:
    """``user_study_within.csv``: quantity | metric | ours (95 % range) | paper."""
    body = []
    for r in rows:
        ours = str(r["ours"])
        if r.get("low") not in (None, ""):
            ours += f" [{r['low']}, {r['high']}]"
        elif r.get("high") not in (None, ""):
            ours += f" (bound {r['high']})"
        body.append([str(r["quantity"]), str(r["metric"]) or "-", ours, str(r["paper"] or "-")])
    return "\n".join(markdown_lines(["quantity", "metric", "ours", "paper"], body))


def _tables() -> Tables:
    own: Tables = {
        "calibration": ("calibration.csv", calibration_markdown),
        "calibration_targets": ("calibration_targets.csv", calibration_targets_markdown),
        "user_study_predictions": ("user_study_predictions.csv", predictions_markdown),
        "user_study_parameters": ("user_study_parameters.csv", parameters_markdown),
        "user_study_within": ("user_study_within.csv", within_markdown),
        "user_study_sensitivity": ("user_study_sensitivity.csv", sensitivity_markdown),
        "user_study_model_sensitivity": (
            "user_study_model_sensitivity.csv",
            model_sensitivity_markdown,
        ),
    }
    return {**own, **SIM_TABLES}


def render_table(name: str, results_dir: str | Path) -> str:
    """The table ``name`` (:func:`tables`) rendered from its CSV in ``results_dir``."""
    known = _tables()
    if name not in known:
        raise KeyError(f"unknown table {name!r}; tables are {', '.join(sorted(known))}")
    file, fn = known[name]
    return fn(read_rows(Path(results_dir) / file))


def tables() -> dict[str, str]:
    """Table name -> its CSV file."""
    return {k: v[0] for k, v in _tables().items()}


__all__ = ["f", "read_rows", "render_table", "tables", "yes"]
