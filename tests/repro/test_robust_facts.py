"""docs/robust.md's verdict sentences (:mod:`bilevel_kit.repro.robust_facts`): they follow the
VSS intervals, on the committed CSV and on rows made to take each branch."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

from bilevel_kit.repro.report import read_rows
from bilevel_kit.repro.robust_facts import (
    CVAR_CSV,
    CVAR_PAGE,
    advice_markdown,
    cvar_markdown,
    cvar_page,
    solves_markdown,
)
from bilevel_kit.repro.template import ROOT

CSV = ROOT / "paper_repro" / "results" / "robust.csv"


def _row(trays: str, cv: float, vss: float, half: float, **kw: Any) -> dict[str, Any]:
    base = {"instance": "table", "trays": trays, "cv": cv, "vss": vss, "vss_low": vss - half}
    base |= {"vss_high": vss + half, "vss_pct": vss / 4.4, "same_plan": vss == 0.0}
    return base | {"saa_proven": "True", "safety_net_fired": 0} | kw


def test_the_committed_advice_says_the_spread_pays_with_two_trays() -> None:
    text = advice_markdown(read_rows(CSV))
    assert text.startswith(
        "Over the 24 cells the VSS interval lies above 0 in 21 and below 0 in 0; the largest VSS "
        "is 6.34 s (1.42 % of the expected makespan; table with unlimited trays at CV 0.5)."
    )
    assert "at most 1.42 % of the expected makespan." in text
    assert (
        "With 1 tray, planning for the spread pays in 5 of 8 cells (95 % paired VSS interval "
        "above 0: on table at every CV studied; on sp12 from CV 0.5), up to 3.72 s" in text
    )
    assert "in the other 3 the SAA solve proved the mean-value plan optimal" in text
    assert (
        "With 2 trays, planning for the spread pays in every cell, at every CV studied on every "
        "instance (each 95 % paired VSS interval above 0): the SAA plan saves 0.08 % to 1.03 %"
        in text
    )
    assert "planning for the mean is enough" not in text and "worse out of sample (" not in text


def test_the_committed_solves_sentence_counts_proofs_and_no_cut_solve() -> None:
    text = solves_markdown(read_rows(CSV))
    assert "(`safety_net_fired` is 0 in all 24 cells)" in text
    assert (
        "proven optimal on its 10 scenarios in 23 of 24 cells (not in table with 1 tray at CV "
        "0.5: there the VSS is a lower estimate" in text
    )
    assert "A VSS of exactly zero (3 cells)" in text and "exact SAA optimum there" in text


def test_the_verdict_follows_the_interval_not_the_size() -> None:
    # a tiny VSS whose interval lies above 0 pays; a large one whose interval meets 0 does not
    tiny = advice_markdown([_row("2", 0.1, 0.05, 0.04), _row("2", 0.5, 0.1, 0.05)])
    assert "With 2 trays, planning for the spread pays in every cell" in tiny
    loud = advice_markdown([_row("2", 0.1, 5.0, 6.0), _row("2", 0.5, 0.0, 0.0)])
    assert "With 2 trays, planning for the spread showed no gain at any CV studied" in loud
    assert "the largest VSS: 5.00 s" in loud and "pays" not in loud
    mixed = advice_markdown([_row("1", 0.1, 1.0, 2.0), _row("1", 0.3, 2.0, 1.0)])
    assert "pays in 1 of 2 cells (95 % paired VSS interval above 0: on table from CV 0.3)" in mixed
    assert "in the other 1 the 95 % paired VSS interval meets 0." in mixed


def test_a_worse_cell_a_cut_cell_and_an_unproven_zero_are_named() -> None:
    rows = [
        _row("1", 0.5, -1.9, 0.6),
        _row("1", 0.1, 0.0, 0.0, saa_proven="False", safety_net_fired=2),
    ]
    advice = advice_markdown(rows)
    assert (
        "In 1 of 2 cells the SAA plan was worse out of sample (paired interval below 0: "
        "table with 1 tray at CV 0.5): 10 scenarios can overfit" in advice
    )
    assert "never did worse" not in advice and "In no cell" not in advice
    solves = solves_markdown(rows)
    assert solves.startswith(
        "The wall-clock safety net cut 2 solves in 1 of 2 cells, even computed again (table "
        "with 1 tray at CV 0.1): those rows are not a pure function"
    )
    assert "in 1 of them without a proof: zero there is not evidence" in solves


def _cvar_row(**kw: Any) -> dict[str, Any]:
    """A bench/results/cvar.csv row (bench/bench_cvar.py): both models improved, unproven."""
    row: dict[str, Any] = {"time_limit": 30.0, "load": 3.04, "cpus": 2, "alpha": 0.9}
    row |= {"scenarios": 20, "evaluation": 1000, "same_plan": "False"}
    for p, obj in (("sa", 440.0), ("cvar", 480.0)):
        row |= {f"{p}_status": "feasible", f"{p}_objective": obj, f"{p}_improved": "True"}
        row |= {f"{p}_mean_value_plan_objective": obj + 5, f"{p}_eval_half": 1.8}
    row |= {"sa_eval_mean": 441.6, "sa_eval_cvar": 495.6, "cvar_eval_mean": 444.3}
    row |= {"cvar_eval_cvar": 497.8, "diff_mean": 2.7, "diff_low": 2.1, "diff_high": 3.3}
    return row | {"diff_cvar": 2.2, "diff_cvar_low": 0.8, "diff_cvar_high": 3.7} | kw


def test_the_cvar_verdicts_follow_the_intervals() -> None:
    text = cvar_markdown([_cvar_row(cvar_status="optimal")])
    assert text.startswith(
        "With `lns -t 30` (load average 3.0 on 2 cores), the CVaR model proves its plan optimal "
        "on the 20 scenarios (in-sample CVaR(0.9) 480.0 s against the mean-value plan's 485.0 s)"
        "; the sample-average model improves on the mean-value plan, without a proof, on the 20"
    )
    assert (
        "(paired difference 2.7 s, 95 % interval [2.1, 3.3]: the CVaR plan is worse on the " in text
    )
    assert "[0.8, 3.7] s: the CVaR plan is worse on CVaR(0.9))." in text
    assert "rests on the 2 worst ones, and the CVaR plan fits them:" in text
    meets = cvar_markdown([_cvar_row(diff_cvar_low=-0.5, diff_low=-1.0)])
    assert "no evidence of a difference on the mean" in meets and "fits them" not in meets
    assert "no evidence of a difference on CVaR(0.9)" in meets
    same = cvar_markdown([_cvar_row(same_plan="True", sa_improved="False")])
    assert "Both return the same plan: mean 441.6 ± 1.8 s and CVaR(0.9) 495.6 s" in same
    assert "the sample-average model does not improve on the mean-value plan" in same


def test_the_cvar_paragraph_is_rendered_from_the_csv(tmp_path: Path) -> None:
    now, want = cvar_page(ROOT)
    assert now == want, "docs/robust.md's CVaR block: run python bench/bench_cvar.py --render"
    assert "<!-- robust:cvar -->\nWith `lns -t 30`" in now
    for rel in (CVAR_CSV, CVAR_PAGE):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / rel, tmp_path / rel)
    csv = tmp_path / CVAR_CSV
    head, first, *rest = csv.read_text().splitlines()
    cells = first.split(",")
    cells[head.split(",").index("sa_eval_mean")] = "123.45"
    csv.write_text("\n".join([head, ",".join(cells), *rest]) + "\n")
    now, want = cvar_page(tmp_path)
    assert now != want and "123.5 ±" in want
