"""The stations study's figures (docs/stations.md): drawn from the committed CSV by
``paper_repro/draw_stations.py`` as by the study, intervals as error bars at the CSV's bounds,
one colour per policy in every figure, one y scale per row."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from bilevel_kit.experiments.tables import read_csv
from bilevel_kit.repro.stations import THRESHOLD, capacity_curves
from bilevel_kit.repro.stations_plots import plot_stations, rows_from_csv

ROOT = Path(__file__).resolve().parents[2]
CSV = ROOT / "paper_repro" / "results" / "stations.csv"


@pytest.fixture(scope="module")
def rows():
    return rows_from_csv(read_csv(CSV))


def _figure(rows, line):
    grid = sorted({r["stations"] for r in rows if r["line"] == line})
    return plot_stations(rows, line, capacity_curves(line, grid), threshold=THRESHOLD)


def test_rows_read_back_typed(rows) -> None:
    first = rows[0]
    assert (first["line"], first["delay"], first["policy"]) == ("table", "none", "single-task")
    assert (first["stations"], first["reps"]) == (1, 20)
    assert (first["idle"], first["idle_low"], first["idle_high"]) == (17.08, 15.95, 18.2)


def test_intervals_are_error_bars_at_the_csvs_bounds_and_nothing_is_shaded(rows) -> None:
    """Table, parts in stock, idle panel: Single Task at S = 1 has its bar from 15.95 to
    18.2 %; no filled band (their overlaps mixed colours no policy has)."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection

    fig = _figure(rows, "table")
    idle = fig.axes[2]
    assert not [c for c in idle.collections if isinstance(c, PolyCollection)]
    bars = [c for c in idle.containers if c.get_label().startswith("Single Task")]
    assert len(bars) == 1
    segments = [
        s for c in bars[0].lines[2] if isinstance(c, LineCollection) for s in c.get_segments()
    ]
    first = min(segments, key=lambda s: s[0][0])  # S = 1 (set slightly left of it)
    assert first[0][0] == pytest.approx(1 - 1.5 * 0.07)
    assert sorted(p[1] for p in first) == pytest.approx([15.95, 18.2])
    plt.close(fig)


def test_a_policy_keeps_its_colour_and_each_row_one_y_scale(rows) -> None:
    import matplotlib.pyplot as plt

    colours = {}
    for line in ("table", "mix"):
        fig = _figure(rows, line)
        top, idle = fig.axes[0], fig.axes[2]
        assert top.get_shared_y_axes().joined(top, fig.axes[1])
        assert idle.get_ylim() == fig.axes[3].get_ylim()
        for c in idle.containers:
            colours.setdefault(c.get_label(), set()).add(c.lines[0].get_color())
        plt.close(fig)
    assert all(len(v) == 1 for v in colours.values()), colours
    assert len({next(iter(v)) for v in colours.values()}) == len(colours)


def test_the_script_redraws_every_line(tmp_path) -> None:
    """``python paper_repro/draw_stations.py --out DIR`` writes one figure per line, named as
    committed, and nothing else (its temporary folder is gone)."""
    script = ROOT / "paper_repro" / "draw_stations.py"
    done = subprocess.run(
        [sys.executable, str(script), "--out", str(tmp_path)], capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [f"stations-{x}.png" for x in ("chair", "mix", "stool", "table")]
