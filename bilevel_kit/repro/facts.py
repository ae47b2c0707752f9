"""Every number the reproduction's prose quotes, computed from the committed CSVs in
``paper_repro/results/`` (the templates of :mod:`.template` place them as ``{{name}}``).

Names are dotted by source: ``paper.*`` (the paper's published numbers), ``cal.*`` (the
calibration), ``us.*`` (the user study's predictions), ``within.*`` (the participant model),
``sens.*`` (its sensitivity), ``fig6.*``, ``r100.*`` and ``cpsat.*`` (Figure 6 at R = 30,
at R = 100, and cpsat-rolling against Optimized), ``hz.*`` (the horizon study), ``ad.*`` (the
adaptive study) and ``time.*`` (the run times). A fact is text, formatted as the prose
shows it; a phrase that states a verdict is computed from the numbers, never typed.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..instance import DEFAULT_HORIZON
from .adaptive import share_text
from .calibration import WITHIN_CAP
from .common import PAPER_ACTIVE, PAPER_F, READOFF
from .fig6_stats import BETTER, NS, WORSE
from .fmt import f, read_rows, yes
from .horizon_tables import horizon_summary, mean_gap_by_n, paired_gap_difference, typed_rows
from .predictions import PREDICTED, follows, inside_count
from .report_sim import duration
from .stations_facts import stations_facts
from .verdict import CLOSED, GAP, GAP_DIFFERENCE, HALF, LEVEL, meets, verdict

Rows = list[dict[str, str]]
Facts = dict[str, str]


def _num(x: Any) -> float:
    return float(x)


def _range(values: Sequence[float], nd: int = 1, unit: str = "") -> str:
    """``a-b`` (en dash free: a hyphen), or one value when they agree at ``nd`` decimals."""
    lo, hi = f(min(values), nd), f(max(values), nd)
    return f"{lo}{unit}" if lo == hi else f"{lo}{unit} to {hi}{unit}"


def _pct(x: Any, nd: int = 0) -> str:
    return f"{100 * float(x):.{nd}f} %"


def paper_facts() -> Facts:
    """The paper's published numbers and the code's settings the prose names."""
    from ..sim.cpsat_rolling import CPSATRollingOptions

    opts = CPSATRollingOptions()
    return {
        "cfg.cpsat_dtime": f"{opts.deterministic_time:g}",
        "cfg.cpsat_supply_window": str(opts.supply_window),
        "cfg.cpsat_window": str(opts.window),
        "paper.F_total": f"{PAPER_F['total']:.2f}",
        "paper.F_idle": f"{PAPER_F['idle']:.2f}",
        "paper.active_mean": f"{PAPER_ACTIVE[0]:.2f}",
        "paper.active_sd": f"{PAPER_ACTIVE[1]:.2f}",
        "paper.readoff": f"{READOFF:.2f}",
    }


def calibration_facts(params: Rows, targets: Rows, draws: Rows) -> Facts:
    """The calibration's values, the bootstrap's ranges, the targets and the provenance."""
    v = {r["name"]: r for r in params}
    out: Facts = {
        "cal.cap": f"{WITHIN_CAP:g}",
        "cal.draws": str(len(draws)),
        "cal.at_bound_draws": str(sum(yes(d["at_bound"]) for d in draws)),
        "cal.at_bound": "at" if yes(v["at_bound"]["value"]) else "below",
        "cal.reach": "out of the model's reach"
        if yes(v["at_bound"]["value"])
        else "within the model's reach",
        "cal.learning": f(v["learning"]["value"], 2),
        "cal.command": v["command"]["value"],
        "cal.instance_sha1": v["instance_sha1"]["value"],
    }
    for name, key, nd in (
        ("robot_scale", "robot_scale", 4),
        ("kit_overhead_human", "oh", 3),
        ("within_cv", "within", 4),
    ):
        out[f"cal.{key}"] = f(v[name]["value"], nd)
        out[f"cal.{key}_range"] = f"[{f(v[name]['low'], nd)}, {f(v[name]['high'], nd)}]"
    out["cal.within_bound"] = f(v["within_cv_bound"]["value"], 4)
    for t in targets:
        key = f"{t['quantity'].lower()}_{t['metric']}" + (
            f"_{t['condition'].split('-')[0]}" if t["condition"] else ""
        )
        nd = 2 if t["quantity"] == "F" else 1
        out[f"cal.target.{key}.fitted"] = f(t["fitted"], nd)
        out[f"cal.target.{key}.residual"] = f"{float(t['residual']):+.{nd}f}"
        out[f"cal.target.{key}.boot"] = (
            f"[{f(t['bootstrap_low'], nd)}, {f(t['bootstrap_high'], nd)}]"
        )
    return out


#: Slugs of the user study's numbers (``us.<slug>.<field>``).
SLUGS = {
    "mean total task time, Optimized (s)": "opt_total",
    "mean total task time, Single Task (s)": "st_total",
    "mean total task time, Whole Assembly (s)": "wa_total",
    "mean human idle time, Optimized (s)": "opt_idle",
    "mean human idle time, Single Task (s)": "st_idle",
    "mean human idle time, Whole Assembly (s)": "wa_idle",
    "repeated-measures F(2, 34), total task time": "F_total",
    "repeated-measures F(2, 34), human idle time": "F_idle",
    "Tukey 95% CI ST-WA centre, total task time (s)": "st_wa_total",
    "Tukey 95% CI OPT-WA centre, total task time (s)": "opt_wa_total",
    "Tukey 95% CI half-width (every pair), total task time (s)": "half_total",
    "Tukey 95% CI ST-WA centre, human idle time (s)": "st_wa_idle",
    "Tukey 95% CI OPT-WA centre, human idle time (s)": "opt_wa_idle",
    "Tukey 95% CI half-width (every pair), human idle time (s)": "half_idle",
}


def study_facts(pred: Rows, summary: Rows) -> Facts:
    """``us.*``: the counts, each number's median and intervals, the widening, the outliers."""
    s = {r["key"]: r["value"] for r in summary}
    ki, ni = inside_count(pred, independent=True)  # this version's rule, whatever the CSV's
    out: Facts = {
        "us.studies": s["studies"],
        "us.cal_studies": s["cal_studies"],
        "us.predicted": s["predicted"],
        "us.inside": s["predicted_inside"],
        "us.independent": str(ni),
        "us.independent_inside": str(ki),
        "us.implied": s["implied"],
        "us.fitted": s["fitted"],
        "us.opt_st_ns": _pct(s["opt_vs_st_not_significant"]),
    }
    for r in pred:
        slug, nd = SLUGS[r["quantity"]], 2 if r["quantity"].startswith("repeated") else 1
        out[f"us.{slug}.paper"] = f(r["paper"], nd)
        out[f"us.{slug}.median"] = f(r["median"], nd)
        out[f"us.{slug}.pi"] = f"[{f(r['pi_low'], nd)}, {f(r['pi_high'], nd)}]"
        out[f"us.{slug}.cal"] = f"[{f(r['cal_low'], nd)}, {f(r['cal_high'], nd)}]"
        out[f"us.{slug}.implied"] = f(r["implied"], nd)
        out[f"us.{slug}.widened"] = "-" if not r["widened_pct"] else f"{r['widened_pct']} %"
        out[f"us.{slug}.inside"] = meets(r["cal_low"], r["cal_high"], r["paper"], r["readoff"])
    predicted = [r for r in pred if r["kind"] == PREDICTED]
    out["us.independent_list"] = "; ".join(
        r["quantity"].removesuffix(" (s)") for r in predicted if not follows(r)
    )
    # a CSV written before the within-subject Tukey has no check column (issue 38, item 3)
    out["us.tukey"] = (
        "the within-subject Tukey (df 34), with the independent-groups one as the check column"
        if pred and "check_median" in pred[0]
        else "the independent-groups Tukey (`pairwise_tukeyhsd`, df 51): the committed CSVs "
        "predate the within-subject Tukey, and `repro user-study` rewrites them with it"
    )
    widened = [_num(r["widened_pct"]) for r in predicted if r["widened_pct"]]
    out["us.widened_range"] = _range(widened, 0, " %")
    most = max((r for r in predicted if r["widened_pct"]), key=lambda r: _num(r["widened_pct"]))
    out["us.widened_most"] = f"{most['quantity']} ({_num(most['widened_pct']):+.0f} %)"
    out["us.widened_median"] = f"{float(np.median(widened)):.0f} %"
    outside = [r for r in predicted if not yes(r["inside"])]
    out["us.outside"] = (
        "none"
        if not outside
        else "; ".join(
            f"{r['quantity']} (paper {f(r['paper'], 2 if 'F(' in r['quantity'] else 1)}, "
            f"our interval [{f(r['cal_low'])}, {f(r['cal_high'])}])"
            for r in outside
        )
    )
    return out


def within_facts(rows: Rows) -> Facts:
    """``within.*``: shares, the bound, the correlations, the F decomposition per metric."""
    out: Facts = {}
    by = {(r["quantity"], r["metric"]): r for r in rows}
    for part, key in (
        ("participant", "p"),
        ("participant x condition", "pc"),
        ("learning", "learn"),
    ):
        out[f"within.share_{key}"] = _pct(
            by[(f"share of a session's log-variance: {part}", "")]["ours"], 1
        )
    corr = [r for r in rows if r["quantity"].startswith("correlation")]
    out["within.corr_range"] = _range([_num(r["ours"]) for r in corr], 3)
    out["within.corr_list"] = ", ".join(
        f"{r['quantity'].split(', ')[1]} {f(r['ours'], 3)}" for r in corr
    )
    out["within.corr_bounds"] = _range(
        [_num(r["low"]) for r in corr] + [_num(r["high"]) for r in corr], 2
    )
    fit = by[("calibration cohort's median F of total time at the fit", "total")]
    out["within.F_fit"] = f(fit["ours"], 2)
    for m in ("total", "idle"):
        q = {r["quantity"]: r for r in rows if r["metric"] == m}
        share = _num(q["share of log(F ours / F paper) from the condition means"]["ours"])
        out[f"within.{m}.F"] = f(q["F from the medians"]["ours"], 1)
        out[f"within.{m}.F_paper_means"] = f(
            q["F with the paper's means and our residual"]["ours"], 1
        )
        out[f"within.{m}.F_paper_residual"] = f(
            q["F with our means and the paper's residual"]["ours"], 1
        )
        out[f"within.{m}.ms_cond"] = (
            f"{_num(q['MS conditions (median over studies)']['ours']):,.0f}"
        )
        out[f"within.{m}.ms_cond_paper"] = (
            f"{_num(q['MS conditions (median over studies)']['paper']):,.0f}"
        )
        sd = q["residual SD (s)"]
        out[f"within.{m}.sd"] = f(sd["ours"], 1)
        out[f"within.{m}.sd_paper"] = f(sd["paper"], 1)
        out[f"within.{m}.share_means"] = _pct(share)
        out[f"within.{m}.source"] = (
            "the condition means" if share > 0.5 else "the residual (participant x condition)"
        )
        ours = _num(q["F from the medians"]["ours"]) - PAPER_F[m]
        out[f"within.{m}.direction"] = verdict(ours, ours, LEVEL)
    return out


def sensitivity_facts(model: Rows, delivery: Rows) -> Facts:
    """``sens.*``: what the learning effect and the weights move, what the delivery time does."""
    out: Facts = {}
    ref = [r for r in model if r["group"] == "reference"]
    ref_med = {r["quantity"]: r["median"] for r in ref}
    settings = list(dict.fromkeys(r["setting"] for r in model))
    opt_idle = "mean human idle time, Optimized (s)"
    for group in ("learning", "weights"):
        rows = [r for r in model if r["group"] == group]
        vals = [_num(r["median"]) for r in rows if r["quantity"] == opt_idle]
        out[f"sens.{group}.opt_idle"] = _range(vals, 1, " s")
        counts = sorted({r["inside_count"] for r in rows}, key=lambda c: int(c.split("/")[0]))
        out[f"sens.{group}.inside"] = " to ".join(dict.fromkeys([counts[0], counts[-1]]))
    inert = [
        s
        for s in settings
        if s.startswith(("W1 ", "W7 "))
        and all(r["median"] == ref_med[r["quantity"]] for r in model if r["setting"] == s)
    ]
    out["sens.inert"] = f"{len(inert)} of the 4 W1/W7 settings"
    weights = [r for r in model if r["group"] == "weights" and r["quantity"] == opt_idle]
    worst = min(weights, key=lambda r: int(r["inside_count"].split("/")[0]))
    out["sens.weights.worst"] = (
        f"{worst['setting']}: {worst['inside_count']} inside, Optimized's idle time "
        f"{f(worst['median'], 1)} s"
    )
    out["sens.ref_inside"] = ref[0]["inside_count"] if ref else "-"
    first: dict[str, dict[str, str]] = {}
    for r in delivery:
        first.setdefault(r["setting"], r)
    for key, r in zip(("d0", "d2", "d5", "unlimited"), first.values(), strict=False):
        out[f"sens.{key}.inside"] = r["inside_count"]
        out[f"sens.{key}.oh"] = f(r["kit_overhead_human"], 2)
        idle = next(
            x for x in delivery if x["setting"] == r["setting"] and x["quantity"] == opt_idle
        )
        out[f"sens.{key}.opt_idle"] = f(idle["median"], 1)
    return out


#: Figure 6's panels by short key.
PANELS = {
    "st_total": "total task time, Optimized over Single Task",
    "st_idle": "human idle time, Optimized over Single Task",
    "wa_total": "total task time, Optimized over Whole Assembly",
    "wa_idle": "human idle time, Optimized over Whole Assembly",
    "cpsat_total": "total task time, cpsat-rolling over Optimized",
    "cpsat_idle": "human idle time, cpsat-rolling over Optimized",
}


def _cells_text(cells: Sequence[Mapping[str, str]]) -> str:
    """``MAT 90 / MTTF 30, MAT 120 / MTTF 30, ...`` or ``none``."""
    if not cells:
        return "none"
    return ", ".join(f"MAT {_num(c['mat']):g} / MTTF {_num(c['mttf']):g}" for c in cells)


def fig6_facts(prefix: str, imp: Rows, ver: Rows, trends: Rows) -> Facts:
    """``<prefix>.<panel>.*``: counts by direction, verdicts, power, the trend test, the cells
    where Optimized is significantly behind and its significant gains at MAT >= 90 s."""
    out: Facts = {}
    inv = {v: k for k, v in PANELS.items()}
    for r in ver:
        k = f"{prefix}.{inv[r['panel']]}"
        for t in ("tukey", "tukey_holm", "paired_holm"):
            out[f"{k}.{t}"] = (
                f"{r[f'{t}_better']} better, {r[f'{t}_ns']} n.s., {r[f'{t}_worse']} worse"
            )
            out[f"{k}.{t}_better"] = r[f"{t}_better"]
        out[f"{k}.most_tukey"] = r["most_tukey"]
        out[f"{k}.most_paired"] = r["most_paired_holm"]
        out[f"{k}.r80"] = f(r["r80_median_better"], 0)
        out[f"{k}.r80_le_100"] = f"{r['cells_r80_le_100']} of {r['cells']}"
        out[f"{prefix}.reps"] = r["reps"]
    for panel, key in inv.items():
        grid = [r for r in imp if r["panel"] == panel and r["mat"]]
        if not grid:
            continue
        k = f"{prefix}.{key}"
        worse = [r for r in grid if r["dir_paired_holm"] == WORSE]
        out[f"{k}.worse_cells"] = _cells_text(worse)
        out[f"{k}.worse_range"] = _range([_num(r["pct"]) for r in worse], 1, " %") if worse else "-"
        hi_mat = [r for r in grid if _num(r["mat"]) >= 90 and r["dir_paired_holm"] == BETTER]
        out[f"{k}.better_hi_mat"] = _cells_text(hi_mat)
        out[f"{k}.better_hi_mat_range"] = (
            _range([_num(r["pct"]) for r in hi_mat], 2, " %") if hi_mat else "-"
        )
        r80 = [int(_num(r["r80"])) for r in grid if r["r80"] and _num(r["pct"]) > 0]
        out[f"{k}.r80_range"] = _range(r80, 0) if r80 else "-"
        mat30 = [r for r in grid if _num(r["mat"]) == min(_num(x["mat"]) for x in grid)]
        out[f"{k}.low_mat_range"] = _range([_num(r["pct"]) for r in mat30], 1, " %")
        ns = [r for r in grid if r["dir_paired_holm"] == NS]
        out[f"{k}.ns_cells"] = _cells_text(ns)
        ref = next((r for r in imp if r["panel"] == panel and not r["mat"]), None)
        if ref is not None:
            out[f"{k}.ref"] = f"{_num(ref['pct']):.1f} %"
    for r in trends:
        k = f"{prefix}.{inv[r['panel']]}.trend"
        out[f"{k}.slope"] = f"{_num(r['slope_per_30s']):+.2f}"
        out[f"{k}.ci"] = f"[{f(r['ci_low'], 2)}, {f(r['ci_high'], 2)}]"
        out[f"{k}.tau"] = f(r["kendall_tau"], 2)
        out[f"{k}.verdict"] = r["verdict"]
        out[f"{k}.tau_p"] = f"{_num(r['kendall_p']):.3f}".lstrip("0")
        peak = r.get("peak_mat")
        out[f"{k}.peak"] = f"{_num(peak):g} s" if peak not in (None, "") else "-"
    return out


def horizon_facts(plan: Rows, window: Rows) -> Facts:
    """``hz.*``: the mean gap by N, the closure at the default N and at the best N, and the
    window study's gains and verdicts."""
    rows = typed_rows(plan)
    summ = horizon_summary(rows)
    mean = mean_gap_by_n(rows)
    ns = sorted(mean)
    d = DEFAULT_HORIZON
    closed_d = [s["closed_default_pct"] for s in summ if s["closed_default_pct"] is not None]
    closed_b = [s["closed_pct"] for s in summ if s["closed_pct"] is not None]
    out: Facts = {
        "hz.instances": str(len(summ)),
        "hz.n_first": str(ns[0]),
        "hz.n_last": str(ns[-1]),
        "hz.default_n": str(d),
        "hz.gap_first": f"{mean[ns[0]]:.1f} %",
        "hz.gap_default": f"{mean[d]:.1f} %",
        "hz.gap_last": f"{mean[ns[-1]]:.1f} %",
        "hz.closed_default_mean": f"{100 * (mean[ns[0]] - mean[d]) / mean[ns[0]]:.0f} %",
        "hz.closed_default_range": _range(closed_d, 0, " %"),
        "hz.closed_default_median": f"{float(np.median(closed_d)):.0f} %",
        "hz.default_worse": str(sum(c < 0 for c in closed_d)),
        "hz.closed_best_range": _range(closed_b, 0, " %"),
        "hz.closed_best_median": f"{float(np.median(closed_b)):.0f} %",
        "hz.best_n_range": _range([s["best_n"] for s in summ], 0),
        "hz.reference": _reference_phrase({s["instance"]: s["reference"] for s in summ}),
        "hz.plans_valid": str(sum(bool(r["valid"]) for r in rows)),
        "hz.plans": str(len(rows)),
    }
    for m, key in ((d - 1, "prev"), (d + 1, "next")):
        diff = paired_gap_difference(rows, d, m)
        out[f"hz.n_{key}"] = str(m)
        out[f"hz.gap_{key}"] = f"{mean[m]:.2f} %"
        out[f"hz.diff_{key}"] = (
            f"{diff['mean']:+.2f} points [{diff['low']:+.2f}, {diff['high']:+.2f}]"
        )
        out[f"hz.diff_{key}.verdict"] = verdict(diff["low"], diff["high"], GAP_DIFFERENCE)
    out["hz.gap_default_2"] = f"{mean[d]:.2f} %"
    win = typed_rows(window)
    roll = [r for r in win if r["window"] is not None]
    out["hz.reps"] = str(win[0]["reps"]) if win else "-"
    nodelay = [r for r in roll if r["mat"] is None]
    if nodelay:
        best = max(nodelay, key=lambda r: (round(r["total_pct_over_optimized"], 9), -r["window"]))
        out["hz.nodelay_best_window"] = str(best["window"])
        out["hz.nodelay_best_gain"] = f"{best['total_pct_over_optimized']:.1f} %"
    delay = [r for r in roll if r["mat"] is not None]
    for name in (BETTER, NS, WORSE):
        out[f"hz.delay_{name.replace('.', '')}"] = str(sum(r["direction"] == name for r in delay))
    out["hz.delay_cells"] = str(len(delay))
    out["hz.delay_gain_range"] = _range([r["total_pct_over_optimized"] for r in delay], 2, " %")
    return out


def adaptive_facts(rows: Rows) -> Facts:
    """``ad.<delay>.<group>.*``: the share with its interval, the gap and what is closed (95 %
    t-intervals), per supply setting and group (the paper's idle time)."""
    out: Facts = {}
    for r in rows:
        if r["metric"] != "idle":
            continue
        d = "none" if r["delay"] == "none" else "delay"
        k = f"ad.{d}.{r['group']}"
        out[f"{k}.factor"] = r["factor"]
        out[f"{k}.gap"] = (
            f"{f(r['gap_fixed_minus_oracle'], 0)} s [{f(r['gap_low'], 0)}, {f(r['gap_high'], 0)}]"
        )
        out[f"{k}.closed"] = (
            f"{f(r['fixed_minus_adaptive'], 0)} s [{f(r['closed_low'], 0)}, "
            f"{f(r['closed_high'], 0)}]"
        )
        out[f"{k}.closed_verdict"] = verdict(r["closed_low"], r["closed_high"], CLOSED)
        gap_word = verdict(r["gap_low"], r["gap_high"], GAP)
        out[f"{k}.gap_verdict"] = gap_word
        out[f"{k}.share"] = share_text(r)
        out[f"{k}.half"] = (
            verdict(r["share_low"], r["share_high"], HALF, at=0.5)
            if r["share_closed"]
            else f"no share to judge ({gap_word})"
        )
        out["ad.runs"] = r["runs"] if r["group"] != "population" else out.get("ad.runs", "")
        if r["group"] == "population":
            out["ad.population"] = r["runs"]
    return out


def timing_facts(rows: Rows) -> Facts:
    """``time.<run>`` (wall time), ``time.<run>.load``, and ``time.four`` (the four studies)."""
    out: Facts = {}
    by = {r["run"]: r for r in rows}
    for r in rows:
        out[f"time.{r['run']}"] = duration(r["wall_s"])
        out[f"time.{r['run']}.load"] = f"{r['load_start']}-{r['load_end']}"
        out[f"time.{r['run']}.jobs"] = r["jobs"]
        detail = json.loads(r["detail"]) if r.get("detail") else {}
        for pol, s in detail.get("sim_s", {}).items():
            tables = detail.get("tables", 0)
            if tables and s:
                out[f"time.{r['run']}.{pol}.tables_per_s"] = f"{tables / s:.1f}"
    four = ("user_study", "fig6", "horizon", "adaptive")
    if all(k in by for k in four):
        out["time.four"] = duration(sum(_num(by[k]["wall_s"]) for k in four))
        out["time.measured"] = max(by[k]["measured"] for k in four)
    return out


#: fact family -> (its CSVs, the function of their rows).
SOURCES: tuple[tuple[tuple[str, ...], Callable[..., Facts]], ...] = (
    (
        ("calibration.csv", "calibration_targets.csv", "calibration_bootstrap.csv"),
        calibration_facts,
    ),
    (("user_study_predictions.csv", "user_study_summary.csv"), study_facts),
    (("user_study_within.csv",), within_facts),
    (("user_study_model_sensitivity.csv", "user_study_sensitivity.csv"), sensitivity_facts),
    (("horizon.csv", "horizon_window.csv"), horizon_facts),
    (("adaptive.csv",), adaptive_facts),
    (("timing.csv",), timing_facts),
    (("stations.csv", "stations_served.csv"), stations_facts),
)
FIG6_RUNS = (("fig6", "fig6"), ("r100", "fig6_r100"), ("cpsat", "fig6_cpsat"))


def facts(results_dir: str | Path) -> Facts:
    """Every fact, from the CSVs in ``results_dir`` (a family whose CSV is missing is left
    out: a template that uses it then fails naming the fact)."""
    base = Path(results_dir)
    out = paper_facts()
    for files, fn in SOURCES:
        if all((base / x).is_file() for x in files):
            out.update(fn(*(read_rows(base / x) for x in files)))
    for prefix, stem in FIG6_RUNS:
        paths = [base / f"{stem}_{x}.csv" for x in ("improvements", "verdicts", "trends")]
        if all(p.is_file() for p in paths[:2]):
            trends = read_rows(paths[2]) if paths[2].is_file() else []
            out.update(fig6_facts(prefix, read_rows(paths[0]), read_rows(paths[1]), trends))
    return out


__all__ = ["facts"]


def _reference_phrase(kinds: Mapping[str, str]) -> str:
    """What the horizon study's reference is, from each instance's kind: the proven optimum on
    every instance, or on k of n and CP-SAT's best lower bound on the others, named (their
    gaps are then upper bounds on the true gaps, docs/reproduction.md)."""
    bound = [name for name, kind in kinds.items() if kind != "optimum"]
    if not bound:
        return "the proven optimum on every instance"
    return (
        f"the proven optimum on {len(kinds) - len(bound)} of {len(kinds)} instances and CP-SAT's "
        f"best lower bound on {', '.join(bound)} (not proven within the limit on this run: "
        "its gaps are upper bounds on the true gaps)"
    )
