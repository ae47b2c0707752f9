"""Beyond the paper: how many assembly stations one kitting robot keeps busy
(``bilevel-kit repro stations``; docs/stations.md).

Lines: every station builds the table (``table``), the stool (``stool``) or the chair
(``chair``) of the mixed-model family (:func:`bilevel_kit.generate.mixed`), or station k builds
the table, the stool and the chair in turn (``mix``). ``S`` = 1..6 stations per robot, each
building ``units`` units with one tray (the paper's protocol) and its own human
(docs/timeline.md#several-stations). Supply: none (every part in stock), or the large parts
(legs, feet, connectors, stool tops and legs; not screws) each fed by a feeder with MAT
:data:`DELAY_MAT`, MTTF :data:`DELAY_MTTF` and a 30 s repair, starting empty: the feeders are
shared, so their rate caps what more stations can build.

Times are sampled (:class:`bilevel_kit.sim.TimingModel`: a speed factor per unit with the
paper's CV, and per-task noise :data:`TASK_CV`); the robot and ``o_H`` are the instance's
(uncalibrated). Each replication's seed is common to every policy and S (common random
numbers). Per run: throughput (units per hour: units built / makespan), human idle per station
(the reproduction's idle time, docs/reproduction.md: a station's completion less its sampled
task times over its completion, the mean over the stations; and, named apart, ``idle_steady``
from its first kit's arrival with pickups as work), robot utilisation (robot busy picking and
delivering / makespan). ``S_max`` per replication, its statistics at several thresholds and
the capacity bound: :mod:`.stations_stats`.

Policies: the baselines and cpsat-rolling (one policy per station, the station of earliest
need first: :mod:`bilevel_kit.sim.stations`), and ``optimized``, greedy-ce planning stations
(:func:`bilevel_kit.sim.stations.station_policies`).
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic
from ..errors import UsageError
from ..experiments.cells import is_failed, run_cells_counted, write_json
from ..experiments.tables import markdown_lines, read_csv, write_csv
from ..generate import mixed
from ..instance import Instance, from_dict
from ..plan import Kit, Timeline
from ..sim import SimParams, TimingModel, simulate
from ..sim.stations import station_policies
from .stations_plots import LABELS, draw_figures, rows_from_csv
from .stations_stats import capacity, idle_floor, per_unit, served_rows
from .stats import t_interval

#: The product each station builds, station k taking entry (k - 1) mod len.
LINES: dict[str, tuple[str, ...]] = {
    "table": ("table",),
    "stool": ("stool",),
    "chair": ("chair",),
    "mix": ("table", "stool", "chair"),
}
#: Task id prefix of each product in :func:`bilevel_kit.generate.mixed`.
_PREFIX = {"table": "T", "stool": "S", "chair": "C"}
#: The parts fed by feeders in the supply-delay setting (screws come in bulk).
FED = ("leg", "foot", "connector", "seat", "stool_leg")
DELAY_MAT, DELAY_MTTF, DELAY_REPAIR = 60.0, 60.0, 30.0
DELAYS = ("none", "feeders")
TASK_CV = 0.1
THRESHOLD = 0.10
#: S = 1..3, 4 units per station, 20 replications (docs/stations.md#the-experiment: the
#: capacity bound rules out S = 3 on every line at every threshold, and 20 replications give a
#: Clopper-Pearson interval narrower than one half whenever the replications agree)
STATIONS = (1, 2, 3)
BOUND_STATIONS = (1, 2, 3, 4, 5, 6)
UNITS, REPS = 4, 20
QUICK_UNITS, QUICK_REPS, QUICK_STATIONS = 2, 2, (1, 2, 4)
#: cpsat-rolling's options in the study: a window of 8 tasks and 0.05 deterministic seconds
#: per decision (a run of 6 stations makes about 100 decisions).
CPSAT_OPTIONS: dict[str, Any] = {"window": 8, "deterministic_time": 0.05}
#: The planning policies, whose cells take ten to a hundred times the baselines' CPU: they run
#: the first :data:`PLANNING_REPS` seeds, with parts in stock only (with the shared feeders the
#: columns measure the feeders, not the robot: docs/stations.md#the-experiment). Six is the
#: fewest replications whose Clopper-Pearson interval excludes one half when they all agree.
PLANNING = ("cpsat-rolling", "optimized")
PLANNING_REPS = 6
PLANNING_DELAYS = ("none",)


def line_document(line: str, stations: int, units: int) -> dict[str, Any]:
    """An instance document: ``stations`` stations of ``line`` (the module docstring), each
    building ``units`` units of its product with one tray; station ``Sk``'s tasks are the
    product's with ids prefixed ``sk_`` and product ``<product>k``."""
    if line not in LINES:
        raise UsageError(f"unknown line {line!r}; lines are {', '.join(LINES)}")
    base = mixed(1)
    tasks: list[dict[str, Any]] = []
    edges: list[list[str]] = []
    doc_stations = []
    for k in range(1, stations + 1):
        product = LINES[line][(k - 1) % len(LINES[line])]
        own = [t for t in base["tasks"] if t["product"] == product]
        ids = {t["id"] for t in own}
        tasks += [
            dict(copy.deepcopy(t), id=f"s{k}_{t['id']}", product=f"{product}{k}") for t in own
        ]
        edges += [[f"s{k}_{a}", f"s{k}_{b}"] for a, b in base["precedence"] if a in ids]
        doc_stations.append({"id": f"S{k}", "serves": [f"{product}{k}"]})
    used = {p["type"] for t in tasks for p in t["parts"]}
    return {
        **{k: v for k, v in base.items() if k not in ("tasks", "precedence", "assumptions")},
        "name": f"{line}_s{stations}_u{units}",
        "description": f"{stations} assembly station(s) of the '{line}' line, {units} unit(s) "
        "each, one robot (bilevel-kit repro stations; docs/stations.md).",
        "part_types": [p for p in base["part_types"] if p["id"] in used],
        "tasks": tasks,
        "precedence": edges,
        "units": units,
        "trays": 1,
        "stations": doc_stations,
    }


def line_instance(line: str, stations: int, units: int) -> Instance:
    return from_dict(line_document(line, stations, units), f"<stations study {line}>")


@dataclass(frozen=True)
class StationsCell:
    """One run: a line with ``stations`` stations under one supply setting, one policy, one
    seed (a pure function of these)."""

    line: str
    stations: int
    delay: str
    policy: str
    seed: int
    units: int = UNITS
    policy_options: dict[str, Any] = field(default_factory=dict)

    def key(self) -> str:
        blob = json.dumps(asdict(self), sort_keys=True).encode()
        digest = hashlib.sha1(blob).hexdigest()[:10]
        return f"{self.line}_s{self.stations}_{self.delay}_{self.policy}_{self.seed}__{digest}"

    def params(self, inst: Instance) -> SimParams:
        fed = [t for t in FED if t in inst.part_types] if self.delay == "feeders" else []
        return SimParams(
            mat=dict.fromkeys(fed, DELAY_MAT),
            mttf=DELAY_MTTF if fed else None,
            repair_time=DELAY_REPAIR,
            timing=TimingModel(task_cv=TASK_CV),
            policy_options=self.policy_options,
        )


def stations_cell(cell: StationsCell) -> dict[str, Any]:
    """Simulate one run: throughput, human idle per station, robot utilisation."""
    inst = line_instance(cell.line, cell.stations, cell.units)
    t0 = time.perf_counter()
    res = simulate(inst, cell.policy, params=cell.params(inst), seed=cell.seed)
    idle = station_idle_paper(res.timeline, res.plan.kits, res.times.human)
    steady = station_idle(res.timeline)
    units = cell.stations * cell.units
    return {
        "key": cell.key(),
        "cell": asdict(cell),
        "makespan": res.makespan,
        "throughput": 3600.0 * units / res.makespan,
        "idle": float(np.mean(idle)),
        "idle_max": max(idle),
        "idle_steady": float(np.mean(steady)),
        "robot_utilisation": res.robot_work / res.makespan,
        "robot_wait": res.robot_wait,
        "n_kits": res.n_kits,
        "safety_nets": res.safety_nets,  # decisions cut by the wall clock: not reproducible
        "wall_s": time.perf_counter() - t0,
    }


def station_idle_paper(
    timeline: Timeline, kits: Sequence[Kit], human: Mapping[str, float]
) -> list[float]:
    """Per station, the reproduction's idle share (docs/reproduction.md, the paper's idle
    time): its completion less its sampled task times ``human``, over its completion, from
    time 0; taking parts off the tray and the wait for the first kit count as idle."""
    end: dict[str, float] = {}
    work: dict[str, float] = {}
    for kt, kit, s in zip(timeline.kits, kits, timeline.kit_stations, strict=True):
        end[s] = max(end.get(s, 0.0), kt.human_end)
        work[s] = work.get(s, 0.0) + sum(human[t] for t in kit.tasks)
    return [max(0.0, 1.0 - work[s] / end[s]) for s in end]


def station_idle(timeline: Timeline) -> list[float]:
    """Per station, the steady-state idle share (``idle_steady``, a second view named apart):
    the share of its human's time from its first kit to its completion spent waiting for a
    kit (the wait for the first kit is start-up; taking parts off the tray is work)."""
    first: dict[str, float] = {}
    end: dict[str, float] = {}
    work: dict[str, float] = {}
    for kt, s in zip(timeline.kits, timeline.kit_stations, strict=True):
        first.setdefault(s, kt.human_start)
        end[s] = max(end.get(s, 0.0), kt.human_end)
        work[s] = work.get(s, 0.0) + kt.human_end - kt.human_start
    return [max(0.0, 1.0 - work[s] / (end[s] - first[s])) for s in first]


#: each metric of ``stations.csv``: its scale to the reported unit and its largest value
_METRICS = (
    ("throughput", 1.0, math.inf),
    ("idle", 100.0, 100.0),
    ("idle_steady", 100.0, 100.0),
    ("robot_utilisation", 100.0, 100.0),
)


def summarize(records: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Rows of ``stations.csv``: per line, supply, policy and S, each metric's mean and 95 %
    t-interval over the replications."""
    groups: dict[tuple[str, str, str, int], list[Mapping[str, Any]]] = {}
    for r in records:
        c = r["cell"]
        groups.setdefault((c["line"], c["delay"], c["policy"], c["stations"]), []).append(r)
    rows = []
    for (line, delay, policy, s), rs in groups.items():
        row: dict[str, Any] = {"line": line, "delay": delay, "policy": policy, "stations": s}
        row["reps"] = len(rs)
        for metric, scale, top in _METRICS:
            m, lo, hi = t_interval([scale * float(r[metric]) for r in rs], 0.0, top)
            row.update({metric: round(m, 2), f"{metric}_low": round(lo, 2)})
            row[f"{metric}_high"] = round(hi, 2)
        row["wall_s"] = round(sum(float(r["wall_s"]) for r in rs), 2)
        rows.append(row)
    return rows


def served(records: Sequence[Mapping[str, Any]]) -> list[dict]:
    """Rows of ``stations_served.csv``: per line, supply, policy, idle definition and threshold,
    ``S_max`` per replication with its statistics and the capacity bound
    (:func:`.stations_stats.served_rows`)."""
    runs: dict[tuple[str, str, str], dict[int, dict[int, Mapping[str, Any]]]] = {}
    for r in records:
        c = r["cell"]
        by_seed = runs.setdefault((c["line"], c["delay"], c["policy"]), {})
        by_seed.setdefault(c["seed"], {})[c["stations"]] = r
    grid = sorted({int(r["cell"]["stations"]) for r in records})
    bounds = {(line, policy): capacity_bound(line, policy) for line, _, policy in runs}
    return served_rows(runs, grid, bounds)


def products_per_unit(line: str, policy: str, stations: int) -> list[dict[str, float]]:
    """Each station's nominal seconds per unit (:func:`.stations_stats.per_unit`) with the
    kits of ``policy``: one per task for Single Task, one per unit otherwise (Whole Assembly's,
    the least robot and pickup time of any policy whose kits hold at most one unit)."""
    out = []
    for k in range(stations):
        inst = line_instance(LINES[line][k % len(LINES[line])], 1, 1)
        ids = [t.id for t in inst.tasks]
        kits = [[t] for t in ids] if policy == "single-task" else [ids]
        out.append(per_unit(inst, kits))
    return out


def capacity_bound(line: str, policy: str) -> dict[float, int]:
    """Per threshold, the stations no policy with ``policy``'s kits serves in a steady state
    (:func:`.stations_stats.capacity`), over S = 1..max(:data:`BOUND_STATIONS`)."""
    return capacity({s: products_per_unit(line, policy, s) for s in BOUND_STATIONS})


def _ci(r: Mapping[str, Any], metric: str, fmt: str = ".1f") -> str:
    return f"{r[metric]:{fmt}} [{r[f'{metric}_low']:{fmt}}, {r[f'{metric}_high']:{fmt}}]"


def format_markdown(rows: Sequence[Mapping[str, Any]], best: Sequence[Mapping[str, Any]]) -> str:
    """The study's tables: ``S_max`` per line, supply, policy, idle definition and threshold
    (docs/stations.md), then every metric."""
    head = ["line", "supply", "policy", "idle", "threshold %", "S_max per replication"]
    head += ["mean [95 % bootstrap CI]", "stations served", "capacity bound"]
    body = [
        [
            b["line"],
            b["delay"],
            LABELS.get(b["policy"], b["policy"]),
            b["idle_def"],
            str(b["threshold"]),
            " ".join(map(str, b["per_rep"])),
            _ci(b, "s_max", ".2f"),
            b["verdict"],
            str(b["bound"]),
        ]
        for b in best
    ]
    out = [*markdown_lines(head, body), ""]
    head = [
        "line",
        "supply",
        "policy",
        "S",
        "units/h [95 % CI]",
        "idle per station % [95 % CI]",
        "idle from the first kit % [95 % CI]",
        "robot busy % [95 % CI]",
    ]
    body = [
        [
            r["line"],
            r["delay"],
            LABELS.get(r["policy"], r["policy"]),
            str(r["stations"]),
            _ci(r, "throughput"),
            _ci(r, "idle"),
            _ci(r, "idle_steady"),
            _ci(r, "robot_utilisation"),
        ]
        for r in rows
    ]
    return "\n".join(out + markdown_lines(head, body))


def capacity_curves(line: str, grid: Sequence[int]) -> dict[str, list[float]]:
    """At each S of ``grid``, the least idle share (%) and the most units per hour any policy
    whose kits hold at most one unit can give in a steady state (the capacity bound,
    :mod:`.stations_stats`)."""
    idle, rate = [], []
    for s in grid:
        products = products_per_unit(line, "whole-assembly", s)
        idle.append(100.0 * idle_floor(products))
        cycle = max(max(p["human"] for p in products), sum(p["robot"] for p in products))
        rate.append(3600.0 * s / cycle)
    return {"idle": idle, "throughput": rate}


def _check_options(
    lines: Sequence[str],
    delays: Sequence[str],
    policies: Sequence[str],
    reps: int,
    units: int,
    grid: Sequence[int],
) -> None:
    """Refuse (exit 2) an unknown line, supply or policy without stations, or a count < 1."""
    allowed = station_policies()
    bad = [p for p in policies if p not in allowed] + [x for x in lines if x not in LINES]
    bad += [d for d in delays if d not in DELAYS]
    if bad or reps < 1 or units < 1 or min(grid) < 1:
        raise UsageError(
            f"bad stations study options {bad or (reps, units, grid)}: policies from "
            f"{', '.join(allowed)}, lines from {', '.join(LINES)}, supply from "
            f"{', '.join(DELAYS)}, reps, units and S >= 1"
        )


def _cells(
    lines: Sequence[str],
    grid: Sequence[int],
    delays: Sequence[str],
    policies: Sequence[str],
    seeds: Sequence[int],
    units: int,
) -> list[StationsCell]:
    """Every (line, supply, policy, seed, S), S varying fastest within a replication; the
    :data:`PLANNING` policies take the first :data:`PLANNING_REPS` seeds and
    :data:`PLANNING_DELAYS`."""
    return [
        StationsCell(
            line, s, delay, policy, seed, units, CPSAT_OPTIONS if policy == "cpsat-rolling" else {}
        )
        for line in lines
        for delay in delays
        for policy in policies
        for planning in [policy in PLANNING]
        if not planning or delay in PLANNING_DELAYS
        for seed in (seeds[:PLANNING_REPS] if planning else seeds)
        for s in grid
    ]


def _write_outputs(
    out: Path,
    rows: Sequence[Mapping[str, Any]],
    best: Sequence[Mapping[str, Any]],
    head: str,
    quick: bool,
) -> dict[str, Path]:
    """The CSVs, the Markdown tables and one figure per line (module docstring)."""
    files: dict[str, Path] = {
        "csv": write_csv(out / "stations.csv", rows, exclude=(), line_end="\n"),
        "served_csv": write_csv(out / "stations_served.csv", best, exclude=(), line_end="\n"),
        "markdown": out / "stations.md",
    }
    atomic.write_text(files["markdown"], head + format_markdown(rows, best) + "\n")
    # drawn from the CSV as written, as paper_repro/draw_stations.py redraws the committed one
    drawn = rows_from_csv(read_csv(files["csv"]))
    return {**files, **draw_figures(drawn, out, capacity_curves, threshold=THRESHOLD, quick=quick)}


def run_stations(
    out_dir: str | Path = "out/repro/stations",
    quick: bool = False,
    reps: int | None = None,
    jobs: int = 1,
    seed: int = 0,
    *,
    lines: Sequence[str] | None = None,
    stations: Sequence[int] | None = None,
    delays: Sequence[str] | None = None,
    units: int | None = None,
    policies: Sequence[str] | None = None,
    progress: bool | None = None,
    **_: Any,
) -> dict[str, Any]:
    """The stations study (module docstring): ``reps`` replications (5; 2 with ``quick``) of
    ``units`` units per station (2; at least 2 for the idle to mean anything: with one unit
    Whole Assembly delivers one kit per station, never idle after it) for S in ``stations``
    (1..6; 1, 2, 4 with ``quick``). Cells are saved under ``out_dir/cells/`` (a rerun
    computes only the missing ones). Writes ``stations.csv``, ``stations_served.csv``,
    ``stations.md``, one figure per line and ``stations.json``; returns the summary."""
    t0 = time.perf_counter()
    reps = reps if reps is not None else (QUICK_REPS if quick else REPS)
    units = units if units is not None else (QUICK_UNITS if quick else UNITS)
    grid = tuple(stations) if stations else (QUICK_STATIONS if quick else STATIONS)
    lines = tuple(lines) if lines else tuple(LINES)
    delays = tuple(delays) if delays else DELAYS
    policies = tuple(policies) if policies else station_policies()
    _check_options(lines, delays, policies, reps, units, grid)
    seeds = [seed * 1_000_000 + i for i in range(reps)]
    cells = _cells(lines, grid, delays, policies, seeds, units)
    out = Path(out_dir)
    records, computed = run_cells_counted(
        cells,
        stations_cell,
        cell_dir=out / "cells",
        jobs=jobs,
        progress=progress,
        desc="stations cells",
    )
    failed = [{"key": r["key"], "error": r["error"]} for r in records if is_failed(r)]
    ok = [r for r in records if not is_failed(r)]
    rows, best = summarize(ok), served(ok)
    head = (
        f"Stations per robot{' (QUICK: a reduced run)' if quick else ''}: {units} unit(s) per "
        f"station, {reps} replication(s), S = {', '.join(map(str, grid))}. Mean [95 % "
        "t-interval over replications].\n\n"
    )
    files = _write_outputs(out, rows, best, head, quick)
    result = {
        "quick": quick,
        "reps": reps,
        "units": units,
        "stations": list(grid),
        "lines": list(lines),
        "delays": list(delays),
        "policies": list(policies),
        "seed": seed,
        "cells": len(cells),
        "computed": computed,
        "failed": failed,
        "rows": rows,
        "served": best,
        "wall_s": time.perf_counter() - t0,
    }
    result["files"] = {k: str(v) for k, v in {**files, "json": out / "stations.json"}.items()}
    write_json(out / "stations.json", result)
    return result
