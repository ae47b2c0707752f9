"""The stations study's tables in docs/stations.md, rendered from its committed CSVs
(``stations.csv``, ``stations_served.csv``) so that no number there is typed by hand
(:mod:`.template`)."""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

from ..experiments.tables import markdown_lines
from .stations import LABELS

Row = Mapping[str, Any]


def _ci(r: Row, metric: str, nd: int) -> str:
    m, lo, hi = (float(r[k]) for k in (metric, f"{metric}_low", f"{metric}_high"))
    return f"{m:.{nd}f} [{lo:.{nd}f}, {hi:.{nd}f}]"


def per_rep(r: Row) -> list[int]:
    """A row's per-replication ``S_max`` (a list, or its text in the CSV)."""
    v = r["per_rep"]
    return [int(x) for x in (json.loads(v) if isinstance(v, str) else v)]


def _distribution(r: Row) -> str:
    """How many replications gave each ``S_max``: ``"0: 3, 1: 17"``."""
    counts = Counter(per_rep(r))
    return ", ".join(f"{k}: {counts[k]}" for k in sorted(counts))


def _share(r: Row, k: int) -> str:
    n, lo, hi = (float(r[f"served_{k}{x}"]) for x in ("", "_low", "_high"))
    return f"{n:.0f}/{r['reps']} [{100 * lo:.0f}, {100 * hi:.0f} %]"


def _main(rows: Sequence[Row]) -> list[Row]:
    """The rows the headline table shows: the reproduction's idle at 10 %."""
    return [r for r in rows if r["idle_def"] == "paper" and int(r["threshold"]) == 10]


def served_markdown(rows: Sequence[Row]) -> str:
    """``stations_served.csv`` at the reproduction's idle and 10 %: per line, policy and
    supply, the replications' ``S_max`` values, the share serving one and two stations with
    its Clopper-Pearson interval, the mean with its bootstrap interval, the verdict and the
    capacity bound."""
    head = ["line", "policy", "supply", "S_max: replications per value"]
    head += ["serve 1 [95 % CI]", "serve 2 [95 % CI]", "mean [95 % bootstrap CI]"]
    head += ["stations served", "capacity bound"]
    body = [
        [
            str(r["line"]),
            LABELS.get(str(r["policy"]), str(r["policy"])),
            _supply(str(r["delay"])),
            _distribution(r),
            _share(r, 1),
            _share(r, 2),
            _ci(r, "s_max", 2),
            str(r["verdict"]),
            str(r["bound"]),
        ]
        for r in _main(rows)
    ]
    return "\n".join(markdown_lines(head, body))


def sweep_markdown(rows: Sequence[Row]) -> str:
    """``stations_served.csv`` with parts in stock: the verdict at each threshold, for both
    idle definitions, and the capacity bound of the reproduction's."""
    mine = [r for r in rows if r["delay"] == "none"]
    ths = sorted({int(r["threshold"]) for r in mine})
    by = {(r["line"], r["policy"], r["idle_def"], int(r["threshold"])): r for r in mine}
    keys = list(dict.fromkeys((r["line"], r["policy"]) for r in mine))
    head = ["line", "policy", *(f"idle <= {t} %: reproduction's / steady (bound)" for t in ths)]
    body = []
    for line, p in keys:
        cells = []
        for t in ths:
            a, b = by[(line, p, "paper", t)], by[(line, p, "steady", t)]
            cells.append(f"{a['verdict']} / {b['verdict']} ({a['bound']})")
        body.append([str(line), LABELS.get(str(p), str(p)), *cells])
    return "\n".join(markdown_lines(head, body))


def _supply(delay: str) -> str:
    return "in stock" if delay == "none" else "shared feeders"


def by_stations_markdown(rows: Sequence[Row], delay: str) -> str:
    """``stations.csv`` for one supply: per line and policy, at each S, the throughput (units
    per hour), the human idle per station (the reproduction's, then from the first kit with
    pickups as work) and the robot's busy share (means)."""
    mine = [r for r in rows if r["delay"] == delay]
    grid = sorted({int(r["stations"]) for r in mine})
    by = {(str(r["line"]), str(r["policy"]), int(r["stations"])): r for r in mine}
    keys = list(dict.fromkeys((str(r["line"]), str(r["policy"])) for r in mine))
    head = ["line", "policy", *(f"S = {s}" for s in grid)]
    body = []
    for line, p in keys:
        cells = []
        for s in grid:
            r = by.get((line, p, s))
            cells.append(
                "-"
                if r is None
                else f"{float(r['throughput']):.1f} / {float(r['idle']):.0f} % / "
                f"{float(r['idle_steady']):.0f} % / {float(r['robot_utilisation']):.0f} %"
            )
        body.append([line, LABELS.get(p, p), *cells])
    return "\n".join(markdown_lines(head, body))


def in_stock_markdown(rows: Sequence[Row]) -> str:
    return by_stations_markdown(rows, "none")


def feeders_markdown(rows: Sequence[Row]) -> str:
    return by_stations_markdown(rows, "feeders")


#: Table name -> (its CSV file, its renderer), merged into :data:`.report_sim.SIM_TABLES`.
STATION_TABLES = {
    "stations_served": ("stations_served.csv", served_markdown),
    "stations_sweep": ("stations_served.csv", sweep_markdown),
    "stations_in_stock": ("stations.csv", in_stock_markdown),
    "stations_feeders": ("stations.csv", feeders_markdown),
}

__all__ = [
    "STATION_TABLES",
    "by_stations_markdown",
    "per_rep",
    "served_markdown",
    "sweep_markdown",
]
