"""One gap (issue 40, item 1): on the paper's table, the lead figure of ``compare``'s table
(``above best bound (%)``), the label of the comparison chart and the README's "greedy-ce is
6.6 % above it" are the same number under the same definition (docs/timeline.md#terms)."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

from bilevel_kit import plots
from bilevel_kit.experiments import CompareCell, add_best_bound_gap, compare_cell
from bilevel_kit.experiments.compare import instance_fields
from bilevel_kit.experiments.tables import table_rows

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "instances" / "hrc_table.json"


def _readme_figure() -> str:
    """The README's percentage for greedy-ce above the optimum of the table."""
    text = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    found = re.search(r"`greedy-ce` is (\d+\.\d) % above it", text)
    assert found, "the README no longer states greedy-ce's distance above the optimum"
    return found.group(1)


def test_table_chart_and_readme_show_the_same_lead_figure():
    fields = instance_fields(TABLE)
    cells = [CompareCell(str(TABLE), m, 0, 60.0, {}, {}, *fields) for m in ("greedy-ce", "cpsat")]
    records = add_best_bound_gap(compare_cell(c) for c in cells)
    header, rows = table_rows(records)
    # the lead figure comes first of the table's relative columns; the others are named
    assert header.index("above best bound (%)") < header.index("own gap (%)")
    assert not any(h.startswith("gap") for h in header)
    row = next(r for r in rows if r[header.index("method")] == "greedy-ce")
    table = float(row[header.index("above best bound (%)")])
    ax = plots.plot_comparison(records)
    labels = [t.get_text() for t in ax.texts]
    plt.close("all")
    chart = re.search(r"463\.8 s\n\+(\d+\.\d) %", "\n".join(labels))
    assert chart, labels
    assert f"{table:.1f}" == chart.group(1) == _readme_figure() == "6.6"
