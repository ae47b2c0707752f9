"""Redraw the stations study's committed figures (docs/figures/stations-LINE.png) from its
committed rows, results/stations.csv, in seconds: the study itself
(``bilevel-kit repro stations``, about an hour) draws the same figures from the same CSV
(docs/stations.md).

python paper_repro/draw_stations.py [--csv results/stations.csv] [--out docs/figures]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))  # a plain checkout works too

from bilevel_kit.experiments.tables import read_csv  # noqa: E402
from bilevel_kit.repro.stations import THRESHOLD, capacity_curves  # noqa: E402
from bilevel_kit.repro.stations_plots import draw_figures, rows_from_csv  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--csv", type=Path, default=HERE / "results" / "stations.csv")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures")
    args = ap.parse_args(argv)
    rows = rows_from_csv(read_csv(args.csv))
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=args.out) as tmp:  # each file replaced whole
        files = draw_figures(rows, Path(tmp), capacity_curves, threshold=THRESHOLD)
        for path in files.values():
            target = args.out / path.name.replace("stations_", "stations-")
            path.replace(target)
            print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
