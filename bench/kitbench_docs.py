"""Rewrite the KitBench tables of docs/kitbench.md, instances/kitbench/README.md and README.md from
instances/kitbench/index.csv, and the profile prose of docs/kitbench.md from the passes'
committed rows (bench/results/kitbench_LABEL.csv), and the exact models against lns (the
kitbench-versus blocks of docs/kitbench.md and bench/results/kitbench_cmp*_10s.md and
kitbench_cmp*_60s.md) and the side-by-side runs of two code versions
(bench/kitbench_before_after.py) likewise;
with --figures, also redraw a run's profile and gap-versus-size figures into docs/figures/;
with --profiles, redraw the profile figures of the committed passes
(docs/figures/kitbench-profile-60s.png and -10s.png) from their rows.

python bench/kitbench_docs.py [--check] [--figures RUN_DIR LABEL] [--profiles] [--gap-size]

--check: exit 1 when a page disagrees with the index (tests/experiments/test_kitbench_library.py
checks the same). --figures out/kitbench-10s 10s: docs/figures/kitbench-profile-10s.png and
docs/figures/kitbench-gap-size-10s.png from that run's cells and the current records.
--gap-size: the gap-versus-size figure of each committed pass (docs/figures/kitbench-gap-size-
60s.png and -10s.png) from its rows, graded against the current records (a record proven or
raised later lowers a certified gap without a rerun; the plans and bounds are the pass's own).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import kitbench_before_after as before_after  # noqa: E402

from bilevel_kit.experiments.kitbench import Library, read_cells, render_blocks  # noqa: E402
from bilevel_kit.experiments.kitbench.profiles import (  # noqa: E402
    profile_figure,
    read_rows,
    render_profile_blocks,
)
from bilevel_kit.experiments.kitbench.run import result_rows, write_figures  # noqa: E402
from bilevel_kit.experiments.kitbench.versus import number, render_versus_blocks  # noqa: E402

PAGES = (
    ROOT / "docs" / "kitbench.md",
    ROOT / "instances" / "kitbench" / "README.md",
    ROOT / "README.md",
)
RESULTS = ROOT / "bench" / "results"
#: The committed tables with a per-instance block of the exact models against lns.
VERSUS_PAGES = tuple(
    sorted(p for s in ("10s", "60s") for p in RESULTS.glob(f"kitbench_cmp*_{s}.md"))
)
#: The committed passes drawn by --profiles: label -> (its rows, a separate pass's rows).
PASSES = {"60s": ("kitbench_60s.csv", None), "10s": ("kitbench_10s.csv", "kitbench_10s_lns.csv")}


def profiles(library: Library) -> list[Path]:
    """The profile figure of each committed pass (:data:`PASSES`), from its rows."""
    from bilevel_kit.plots import save_figure

    out = []
    for label, (own, extra) in PASSES.items():
        rows = read_rows(RESULTS / own)
        more = read_rows(RESULTS / extra) if extra else []
        fig = profile_figure(rows, library.read(), f"{label.removesuffix('s')} s per solve", more)
        out.append(save_figure(fig, ROOT / "docs" / "figures" / f"kitbench-profile-{label}.png"))
    return out


def cells_of(rows: list[dict]) -> list[dict]:
    """The cell records a pass's committed rows were made from: what each solve found, without
    the gaps, which :func:`result_rows` computes again against the current records."""
    return [
        {
            "instance": r["instance"],
            "tasks": int(r["tasks"]),
            "method": r["method"],
            "status": r["status"],
            "makespan": r["makespan"],
            "bound": number(r["bound"]),
            "wall_time_s": number(r["wall_time_s"]),
            "valid": r["valid"],
            "error": r["error"] or None,
        }
        for r in rows
    ]


def gap_size(library: Library) -> list[Path]:
    """The gap-versus-size figure of each committed pass (:data:`PASSES`), from its rows and
    its run's method list and limit, against the current records."""
    from bilevel_kit.plots import plot_gap_vs_size, save_figure

    out = []
    for label, (own, _) in PASSES.items():
        run = json.loads((RESULTS / own.replace(".csv", "_run.json")).read_text())
        rows = result_rows(library.read(), cells_of(read_rows(RESULTS / own)))
        ax = plot_gap_vs_size(rows, methods=run["methods"])
        ax.set_title(f"KitBench: certified gap against size ({run['time_limit']:g} s per solve)")
        out.append(
            save_figure(ax.figure, ROOT / "docs" / "figures" / f"kitbench-gap-size-{label}.png")
        )
    return out


def figures(run: Path, label: str, library: Library) -> list[Path]:
    """The run's two figures against the current records, as docs/figures/kitbench-*-LABEL."""
    manifest = json.loads((run / "run.json").read_text())
    rows = result_rows(library.read(), read_cells(run))
    out = ROOT / "docs" / "figures"
    paths = write_figures(rows, manifest["methods"], out, manifest["time_limit"], "tmp-")
    final = []
    for path in paths:  # a figure with nothing to draw is not written
        kind = "profile" if path.name.endswith("profile.png") else "gap-size"
        target = out / f"kitbench-{kind}-{label}.png"
        path.replace(target)
        final.append(target)
    return final


def rewrite(library: Library, check: bool = False) -> list[Path]:
    """Render every generated block of the pages (:data:`PAGES`, :data:`VERSUS_PAGES` and the
    before-and-after tables); the pages that disagreed, rewritten unless ``check``."""
    records = library.read()
    stale = []
    for page in (*PAGES, *VERSUS_PAGES, *before_after.tables()):
        text = page.read_text(encoding="utf-8")
        new = render_profile_blocks(render_blocks(text, records), records, RESULTS)
        new = before_after.render(render_versus_blocks(new, RESULTS), RESULTS)
        if new != text:
            stale.append(page)
            if not check:
                page.write_text(new, encoding="utf-8")
    return stale


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--figures", nargs=2, metavar=("RUN_DIR", "LABEL"))
    ap.add_argument("--profiles", action="store_true")
    ap.add_argument("--gap-size", action="store_true")
    args = ap.parse_args()
    library = Library.at(ROOT / "instances" / "kitbench")
    stale = rewrite(library, args.check)
    if args.check and stale:
        raise SystemExit(f"out of date: {', '.join(str(p) for p in stale)}")
    if args.figures:
        for path in figures(Path(args.figures[0]), args.figures[1], library):
            print(f"wrote {path}")
    if args.profiles:
        for path in profiles(library):
            print(f"wrote {path}")
    if args.gap_size:
        for path in gap_size(library):
            print(f"wrote {path}")
