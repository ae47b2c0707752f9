"""The robust study's sentences for docs/robust.md, computed from the committed ``robust.csv``
(:mod:`.robust`), so that no verdict and no number in the page's prose is typed by hand
(:mod:`.template`).

The verdicts follow the 95 % paired intervals of the VSS, never a threshold on its size: a
cell whose interval lies above 0 is one where planning for the spread pays, one whose interval
meets 0 is no evidence either way, one below 0 is one where it did worse; the sizes are given
beside the verdicts (s and % of the mean-value plan's expected makespan) for the reader to
weigh.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from .robust import SCENARIOS, detail_markdown, vss_markdown

Row = Mapping[str, Any]


def _yes(x: Any) -> bool:
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
    kept = [r for r in rest if float(r["vss"]) == 0.0 and _yes(r["same_plan"])]
    proven = [r for r in kept if _yes(r["saa_proven"])]
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
    open_ = [r for r in rows if not _yes(r["saa_proven"])]
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
    kept = [r for r in rows if float(r["vss"]) == 0.0 and _yes(r["same_plan"])]
    if kept:
        unproven = [r for r in kept if not _yes(r["saa_proven"])]
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


#: Table name -> (its CSV file, its renderer), merged into :data:`.report_sim.SIM_TABLES`.
ROBUST_TABLES = {
    "robust_vss": ("robust.csv", vss_markdown),
    "robust_detail": ("robust.csv", detail_markdown),
    "robust_advice": ("robust.csv", advice_markdown),
    "robust_solves": ("robust.csv", solves_markdown),
}
