"""docs/robust.md's verdict sentences (:mod:`bilevel_kit.repro.robust_facts`): they follow the
VSS intervals, on the committed CSV and on rows made to take each branch."""

from __future__ import annotations

from typing import Any

from bilevel_kit.repro.report import read_rows
from bilevel_kit.repro.robust_facts import advice_markdown, solves_markdown
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
