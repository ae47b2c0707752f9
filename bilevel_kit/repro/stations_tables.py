"""The stations study's tables in docs/stations.md, rendered from its committed CSVs
(``stations.csv``, ``stations_served.csv``) so that no number there is typed by hand
(:mod:`.template`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from ..experiments.tables import markdown_lines
from .stations import LABELS

Row = Mapping[str, Any]


def _ci(r: Row, metric: str, nd: int) -> str:
    m, lo, hi = (float(r[k]) for k in (metric, f"{metric}_low", f"{metric}_high"))
    return f"{m:.{nd}f} [{lo:.{nd}f}, {hi:.{nd}f}]"


def served_markdown(rows: Sequence[Row]) -> str:
    """``stations_served.csv``: S_max with its interval, one row per line and policy, one
    column per supply."""
    delays = list(dict.fromkeys(str(r["delay"]) for r in rows))
    by = {(str(r["line"]), str(r["policy"]), str(r["delay"])): r for r in rows}
    keys = list(dict.fromkeys((str(r["line"]), str(r["policy"])) for r in rows))
    head = ["line", "policy", *(f"S_max, {_supply(d)} [95 % CI]" for d in delays)]
    body = [
        [line, LABELS.get(p, p), *(_ci(by[(line, p, d)], "s_max", 2) for d in delays)]
        for line, p in keys
    ]
    return "\n".join(markdown_lines(head, body))


def _supply(delay: str) -> str:
    return "parts in stock" if delay == "none" else delay


def by_stations_markdown(rows: Sequence[Row], delay: str) -> str:
    """``stations.csv`` for one supply: per line and policy, at each S, the throughput (units
    per hour), the human idle per station and the robot's busy share (means)."""
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
                f"{float(r['robot_utilisation']):.0f} %"
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
    "stations_in_stock": ("stations.csv", in_stock_markdown),
    "stations_feeders": ("stations.csv", feeders_markdown),
}

__all__ = ["STATION_TABLES", "by_stations_markdown", "served_markdown"]
