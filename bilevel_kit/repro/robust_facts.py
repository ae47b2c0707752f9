"""The robust study's sentences for docs/robust.md, computed from the committed ``robust.csv``
(:mod:`.robust`) and, for the CVaR paragraph, ``bench/results/cvar.csv`` (bench/bench_cvar.py),
so that no verdict and no number in the page's prose is typed by hand (:mod:`.template`).

The verdicts follow the 95 % paired intervals of the VSS, never a threshold on its size: a
cell whose interval lies above 0 is one where planning for the spread pays, one whose interval
meets 0 is no evidence either way, one below 0 is one where it did worse; the sizes are given
beside the verdicts (s and % of the mean-value plan's expected makespan) for the reader to
weigh.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..experiments.tables import fill_blocks, marked_blocks, read_csv
from .robust import SCENARIOS, detail_markdown, vss_markdown

Row = Mapping[str, Any]


def yes(x: Any) -> bool:
    """A CSV's boolean field (written as ``True``/``False``)."""
    return str(x) in ("True", "true")


def _pays(r: Row) -> bool:
    return float(r["vss_low"]) > 0


def _worse(r: Row) -> bool:
    return float(r["vss_high"]) < 0


def _cell(r: Row) -> str:
    trays = str(r["trays"])
    return (
        f"{r['instance']} with {trays} tray{'' if trays == '1' else 's'} at CV {float(r['cv']):g}"
    )


def _size(r: Row) -> str:
    """The VSS of ``r`` in s and in % of the mean-value plan's expected makespan."""
    pct = float(r["vss_pct"])
    return f"{float(r['vss']):.2f} s ({pct:.2f} % of the expected makespan; {_cell(r)})"


def _where(mine: Sequence[Row]) -> str:
    """Per instance, the CVs at which planning for the spread pays."""
    parts = []
    for name in dict.fromkeys(str(r["instance"]) for r in mine):
        cvs = sorted(float(r["cv"]) for r in mine if r["instance"] == name)
        paid = sorted(float(r["cv"]) for r in mine if r["instance"] == name and _pays(r))
        if not paid:
            parts.append(f"on {name} at no CV studied")
        elif paid == cvs:
            parts.append(f"on {name} at every CV studied")
        elif paid == cvs[len(cvs) - len(paid) :]:
            parts.append(f"on {name} from CV {paid[0]:g}")
        else:
            parts.append(f"on {name} at CV {', '.join(f'{c:g}' for c in paid)}")
    return "; ".join(parts)


def _tray_sentence(trays: str, mine: Sequence[Row]) -> str:
    """One tray count's verdict (module docstring)."""
    label = f"With {trays} tray{'' if trays == '1' else 's'}"
    pays = [r for r in mine if _pays(r)]
    if not pays:
        top = max(mine, key=lambda r: float(r["vss"]))
        return (
            f"{label}, planning for the spread showed no gain at any CV studied (no 95 % paired "
            f"VSS interval above 0; the largest VSS: {_size(top)}): planning for the mean is "
            "enough as far as these intervals tell."
        )
    best = max(pays, key=lambda r: float(r["vss_pct"]))
    if len(pays) == len(mine):
        low = min(float(r["vss_pct"]) for r in mine)
        return (
            f"{label}, planning for the spread pays in every cell, at every CV studied on every "
            f"instance (each 95 % paired VSS interval above 0): the SAA plan saves {low:.2f} % "
            f"to {float(best['vss_pct']):.2f} % of the expected makespan, at most "
            f"{float(best['vss']):.2f} s ({_cell(best)})."
        )
    rest = [r for r in mine if not _pays(r)]
    kept = [r for r in rest if float(r["vss"]) == 0.0 and yes(r["same_plan"])]
    proven = [r for r in kept if yes(r["saa_proven"])]
    if len(proven) == len(rest):
        why = "the SAA solve proved the mean-value plan optimal on its scenarios (VSS 0)"
    else:
        why = "the 95 % paired VSS interval meets 0"
        if proven:
            why += f" ({len(proven)} of them: the mean-value plan proven optimal, VSS 0)"
    return (
        f"{label}, planning for the spread pays in {len(pays)} of {len(mine)} cells "
        f"(95 % paired VSS interval above 0: {_where(mine)}), up to {_size(best)}; in the other "
        f"{len(rest)} {why}."
    )


def advice_markdown(rows: Sequence[Row]) -> str:
    """The practitioner's sentences: the study's answer over every cell, then one verdict per
    tray count (module docstring) and the cells where the SAA plan did worse."""
    pays, worse = [r for r in rows if _pays(r)], [r for r in rows if _worse(r)]
    best = max(rows, key=lambda r: float(r["vss_pct"]))
    out = [
        f"Over the {len(rows)} cells the VSS interval lies above 0 in {len(pays)} and below 0 "
        f"in {len(worse)}; the largest VSS is {_size(best)}."
    ]
    if pays and not worse:
        out.append(
            "In no cell did planning for the spread do worse out of sample: where human times "
            "vary, plan for it (`-p objective=expected_makespan`), and expect a gain of the "
            f"order found here, at most {float(best['vss_pct']):.2f} % of the expected makespan."
        )
    for trays in dict.fromkeys(str(r["trays"]) for r in rows):
        out.append(_tray_sentence(trays, [r for r in rows if str(r["trays"]) == trays]))
    if worse:
        out.append(
            f"In {len(worse)} of {len(rows)} cells the SAA plan was worse out of sample "
            f"(paired interval below 0: {', '.join(_cell(r) for r in worse)}): {SCENARIOS} "
            "scenarios can overfit, which is why every plan is judged on the independent "
            "evaluation sample."
        )
    return " ".join(out)


def solves_markdown(rows: Sequence[Row]) -> str:
    """How the cells' solves ended: the wall-clock safety net (``safety_net_fired``), the SAA
    solves' proofs, and what a VSS of exactly zero means where it occurs."""
    cut = [r for r in rows if int(r["safety_net_fired"]) > 0]
    if not cut:
        out = [
            "Every solve of every cell stopped on its deterministic time limit or on a proof "
            f"(`safety_net_fired` is 0 in all {len(rows)} cells): each row is a pure function of "
            "its configuration and seed."
        ]
    else:
        out = [
            f"The wall-clock safety net cut {sum(int(r['safety_net_fired']) for r in cut)} "
            f"solves in {len(cut)} of {len(rows)} cells, even computed again "
            f"({', '.join(_cell(r) for r in cut)}): those rows are not a pure function of "
            "their configuration and seed, the others are."
        ]
    open_ = [r for r in rows if not yes(r["saa_proven"])]
    sentence = (
        f"The SAA solve is proven optimal on its {SCENARIOS} scenarios in "
        f"{len(rows) - len(open_)} of {len(rows)} cells"
    )
    if open_:
        sentence += (
            f" (not in {', '.join(_cell(r) for r in open_)}: there the VSS is a lower estimate "
            "of the exact SAA plan's)"
        )
    out.append(sentence + ".")
    kept = [r for r in rows if float(r["vss"]) == 0.0 and yes(r["same_plan"])]
    if kept:
        unproven = [r for r in kept if not yes(r["saa_proven"])]
        out.append(
            f"A VSS of exactly zero ({len(kept)} cells) means the SAA solve kept the mean-value "
            + (
                "plan, proven optimal on its scenarios: the mean-value plan is an exact SAA "
                "optimum there."
                if not unproven
                else f"plan, in {len(unproven)} of them without a proof: zero there is not "
                "evidence that no better plan exists."
            )
        )
    return " ".join(out)


def _versus(low: float, high: float, what: str) -> str:
    """The verdict of a paired interval of (CVaR plan - sample-average plan) on ``what``."""
    if low > 0:
        return f"the CVaR plan is worse on {what}"
    if high < 0:
        return f"the CVaR plan is better on {what}"
    return f"no evidence of a difference on {what}"


def _model(r: Row, p: str, name: str, what: str) -> str:
    """What ``lns`` with one objective (column prefix ``p``) returned, against the mean-value
    plan of its own mean-time step, on its in-sample objective ``what``."""
    improved, proven = yes(r[f"{p}_improved"]), r[f"{p}_status"] == "optimal"
    if proven:
        did = "proves its plan optimal" if improved else "proves the mean-value plan optimal"
    else:
        did = (
            "improves on the mean-value plan, without a proof,"
            if improved
            else ("does not improve on the mean-value plan in the time left")
        )
    return (
        f"the {name} model {did} on the {r['scenarios']} scenarios (in-sample {what} "
        f"{float(r[f'{p}_objective']):.1f} s against the mean-value plan's "
        f"{float(r[f'{p}_mean_value_plan_objective']):.1f} s)"
    )


def _cvar_sentence(r: Row) -> str:
    """One time limit of ``bench/bench_cvar.py``: what each model returned, then both plans on
    the evaluation scenarios, with the paired intervals' verdicts."""
    f = {k: float(v) for k, v in r.items() if k.endswith(_NUMERIC)}
    head = f"With `lns -t {f['time_limit']:g}` (load average {f['load']:.1f} on {r['cpus']} cores)"
    level = f"CVaR({r['alpha']})"
    models = (
        f"{head}, {_model(r, 'cvar', 'CVaR', level)}; {_model(r, 'sa', 'sample-average', 'mean')}."
    )
    sa = f"{f['sa_eval_mean']:.1f} ± {f['sa_eval_half']:.1f} s"
    if yes(r["same_plan"]):
        return (
            f"{models} Both return the same plan: mean {sa} and {level} "
            f"{f['sa_eval_cvar']:.1f} s on {r['evaluation']} independent evaluation scenarios."
        )
    if not yes(r["sa_improved"]) and not yes(r["cvar_improved"]):
        models += (
            " Neither improved on its own mean-time step's plan, so the plans differ as the two "
            "mean-time `lns` runs did."
        )
    mean = _versus(f["diff_low"], f["diff_high"], "the mean")
    tail = _versus(f["diff_cvar_low"], f["diff_cvar_high"], level)
    return (
        f"{models} On {r['evaluation']} independent evaluation scenarios the CVaR plan's mean "
        f"is {f['cvar_eval_mean']:.1f} ± {f['cvar_eval_half']:.1f} s against the "
        f"sample-average plan's {sa} (paired difference {f['diff_mean']:.1f} s, 95 % interval "
        f"[{f['diff_low']:.1f}, {f['diff_high']:.1f}]: {mean}) and its {level} "
        f"{f['cvar_eval_cvar']:.1f} s against {f['sa_eval_cvar']:.1f} s (paired bootstrap "
        f"interval of the difference [{f['diff_cvar_low']:.1f}, {f['diff_cvar_high']:.1f}] s: "
        f"{tail})."
    )


#: The columns of bench/results/cvar.csv read as numbers (by name or suffix).
_NUMERIC: tuple[str, ...] = ("time_limit", "load", "_eval_mean", "_eval_half", "_eval_cvar")
_NUMERIC += ("_objective", "diff_mean", "_low", "_high", "diff_cvar")


def cvar_markdown(rows: Sequence[Row]) -> str:
    """docs/robust.md's CVaR paragraph from ``bench/results/cvar.csv`` (bench/bench_cvar.py):
    one sentence per time limit, then how many scenarios the tail rests on and, where the
    CVaR plan did worse in the tail out of sample, why."""
    out = [_cvar_sentence(r) for r in rows]
    r = rows[0]
    tail = round((1 - float(r["alpha"])) * int(r["scenarios"]))
    overfit = [x for x in rows if not yes(x["same_plan"]) and float(x["diff_cvar_low"]) > 0]
    out.append(
        f"With {r['scenarios']} scenarios CVaR({r['alpha']}) rests on the {tail} worst ones"
        + (", and the CVaR plan fits them" if overfit else "")
        + ": to plan for the tail, use many more scenarios than for the mean (at least ten in "
        "the tail), and judge the plan on the evaluation sample."
    )
    return " ".join(out)


#: Table name -> (its CSV file, its renderer), merged into :data:`.report_sim.SIM_TABLES`.
ROBUST_TABLES = {
    "robust_vss": ("robust.csv", vss_markdown),
    "robust_detail": ("robust.csv", detail_markdown),
    "robust_advice": ("robust.csv", advice_markdown),
    "robust_solves": ("robust.csv", solves_markdown),
}

#: docs/robust.md's CVaR paragraph: the block ``<!-- robust:cvar -->`` ...
#: ``<!-- /robust:cvar -->``, rendered from bench/bench_cvar.py's CSV (outside the reproduction's
#: rendered section: a benchmark's output, not a study's).
CVAR_CSV, CVAR_PAGE = "bench/results/cvar.csv", "docs/robust.md"
_BLOCK = marked_blocks("robust")


def cvar_page(root: Path) -> tuple[str, str]:
    """(docs/robust.md now, what it must be: its CVaR block rendered from the CSV)."""
    now = (root / CVAR_PAGE).read_text()
    body = cvar_markdown(read_csv(root / CVAR_CSV)) + "\n"
    return now, fill_blocks(_BLOCK, now, lambda name: body if name == "cvar" else None)
