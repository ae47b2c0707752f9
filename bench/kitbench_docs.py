"""Rewrite the KitBench tables of docs/kitbench.md, instances/kitbench/README.md and README.md from
instances/kitbench/index.csv, and the profile prose of docs/kitbench.md from the passes'
committed rows (bench/results/kitbench_LABEL.csv); with --figures, also redraw a run's profile
and gap-versus-size figures into docs/figures/; with --profiles, redraw the profile figures of
the committed passes (docs/figures/kitbench-profile-60s.png and -10s.png) from their rows.

python bench/kitbench_docs.py [--check] [--figures RUN_DIR LABEL] [--profiles]

--check: exit 1 when a page disagrees with the index (tests/experiments/test_kitbench_library.py
checks the same). --figures out/kitbench-10s 10s: docs/figures/kitbench-profile-10s.png and
docs/figures/kitbench-gap-size-10s.png from that run's cells and the current records.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bilevel_kit.experiments.kitbench import Library, read_cells, render_blocks  # noqa: E402
from bilevel_kit.experiments.kitbench.profiles import (  # noqa: E402
    profile_figure,
    read_rows,
    render_profile_blocks,
)
from bilevel_kit.experiments.kitbench.run import result_rows, write_figures  # noqa: E402

PAGES = (
    ROOT / "docs" / "kitbench.md",
    ROOT / "instances" / "kitbench" / "README.md",
    ROOT / "README.md",
)
RESULTS = ROOT / "bench" / "results"
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


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--figures", nargs=2, metavar=("RUN_DIR", "LABEL"))
    ap.add_argument("--profiles", action="store_true")
    args = ap.parse_args()
    library = Library.at(ROOT / "instances" / "kitbench")
    records = library.read()
    stale = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        new = render_profile_blocks(render_blocks(text, records), records, RESULTS)
        if new != text:
            stale.append(page)
            if not args.check:
                page.write_text(new, encoding="utf-8")
    if args.check and stale:
        raise SystemExit(f"out of date: {', '.join(str(p) for p in stale)}")
    if args.figures:
        for path in figures(Path(args.figures[0]), args.figures[1], library):
            print(f"wrote {path}")
    if args.profiles:
        for path in profiles(library):
            print(f"wrote {path}")
