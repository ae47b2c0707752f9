"""Heuristic-vs-exact gap table over instances/generated/ (issue 4).

One compare cell per (instance, method), saved under bench/results/gap_cells/ (resumable);
writes bench/results/gap.md, gap.csv and gap.png. The gap of a method is measured to the best
lower bound of the instance (CP-SAT's proven bound when it has one, else the closed-form
bounds); CP-SAT's own row shows whether it proved optimality within the time limit.

Run: python bench/bench_gap.py [--time-limit 60] [--trays 1] [--jobs N | --scheduler ADDRESS]

``--trays 1`` recomputes the table under the paper's study protocol (one kit tray in circulation)
for every instance and writes ``gap_trays1.*``; without it each instance's own ``trays`` field
holds (unlimited where absent) and the files are ``gap.*``. ``--jobs``/``--scheduler`` run the
cells on N local worker processes or a running Dask cluster (docs/cluster.md).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

from bilevel_kit.atomic import write_text
from bilevel_kit.experiments import (
    CompareCell,
    add_best_bound_gap,
    compare_cell,
    format_markdown,
    run_cells,
    sweep_session,
    write_csv,
)
from bilevel_kit.plots import plot_gaps, save_figure

ROOT = Path(__file__).resolve().parent.parent
METHODS = ("single-task", "whole-assembly", "greedy-ce", "cpsat")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--trays", default=None, help="override every instance's trays (1, 2, ...)")
    ap.add_argument("--jobs", type=int, default=1, help="local worker processes")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler")
    args = ap.parse_args()
    out = ROOT / "bench" / "results"
    files = sorted((ROOT / "instances" / "generated").glob("*.json"))
    overrides = {} if args.trays is None else {"trays": args.trays}
    stem = "gap" if args.trays is None else f"gap_trays{args.trays}"
    cells = [
        CompareCell(str(f.relative_to(ROOT)), m, 0, args.time_limit, {}, overrides)
        for f in files
        for m in METHODS
    ]
    os.chdir(ROOT)
    with sweep_session(args.jobs, args.scheduler, progress=True):
        records = add_best_bound_gap(
            run_cells(cells, compare_cell, cell_dir=out / "gap_cells", desc="gap")
        )
    write_text(out / f"{stem}.md", format_markdown(records))
    write_csv(out / f"{stem}.csv", records)
    ok = [r for r in records if r.get("makespan") is not None]
    save_figure(plot_gaps(ok, methods=METHODS).figure, out / f"{stem}.png")
    print(format_markdown(records))


if __name__ == "__main__":
    main()
