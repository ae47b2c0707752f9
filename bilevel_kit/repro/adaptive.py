"""Beyond the paper: how much of the fixed-to-oracle gap a policy that learns the human's pace
closes (``bilevel-kit repro adaptive``; docs/simulation.md, "Adaptive policies").

Policies: ``optimized`` (the paper's, task means), ``optimized-adaptive`` (the posterior mean
of the speed factor, :mod:`bilevel_kit.sim.pace`) and ``optimized-oracle`` (the true factor),
on the same seeds (common random numbers). One participant builds every table of a run (the
within-subject model's way: ``participant_cv = 0`` and the factor as ``session_factor``), each
task with independent lognormal noise ``task_cv``. Participant groups: the 10 %, 50 % and 90 %
quantiles of the factor's distribution (lognormal, mean 1, the paper's CV 61.14 / 374.78:
fast, median, slow) and a sample of the whole population. Supply: none, and one Figure 6 cell
(legs and feet fed at MAT 60 s, MTTF 60 s, 30 s repair, feeders start empty).

Per group and metric (the paper's idle time, makespan - task times, whose differences between
policies equal the makespan's since every policy sees the same task times; the simulator's idle
time, where taking the parts off the tray is work; the makespan), the share of
the gap the adaptive policy closes is ``(fixed - adaptive) / (fixed - oracle)``, reported only
where the oracle beats the fixed policy by more than twice the standard error of the paired
difference (otherwise there is no gap to close, and the row says so).
"""

from __future__ import annotations

import hashlib
import json
import math
import statistics
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic
from ..errors import UsageError
from ..experiments.cells import is_failed, run_cells_counted, write_json
from ..experiments.tables import markdown_lines, write_csv
from ..instance import load
from ..sim import SimParams, TimingModel, effective_instance, make_policy, simulate
from ..sim.timing import PAPER_CV
from .common import FIG6_REPAIR, FIG6_SUPPLIED, FIG6_UNITS, load_instance, paper_idle

FIXED, ADAPTIVE, ORACLE = "optimized", "optimized-adaptive", "optimized-oracle"
POLICIES = (FIXED, ADAPTIVE, ORACLE)
#: Participant groups: name -> quantile of the factor (None: sampled from the population).
GROUPS: dict[str, float | None] = {"fast": 0.1, "median": 0.5, "slow": 0.9, "population": None}
#: The delay cell (MAT, MTTF) of Figure 6's grid; None: no supply process.
DELAYS: tuple[tuple[float, float] | None, ...] = (None, (60.0, 60.0))
#: Per-task noise (assumed): the order of the fitted within-participant CV (0.154).
TASK_CV = 0.15
#: The user study's fitted robot speed and o_H (paper_repro/results/user_study_parameters.csv).
FITTED = {"robot_scale": 1.2469, "kit_overhead_human": 2.6523}
REPS = 10
#: Metrics: the paper's idle time (pickups count as idle; with common random numbers its
#: differences between policies equal the makespan's), the simulator's (pickups are work).
METRICS = {"idle": "idle (s)", "idle_sim": "idle, pickups as work (s)", "makespan": "makespan (s)"}
QUICK_REPS, QUICK_UNITS = 2, 2


def factor_quantile(q: float, cv: float = PAPER_CV) -> float:
    """The ``q`` quantile of a lognormal factor with mean 1 and CV ``cv``."""
    s2 = math.log1p(cv * cv)
    return math.exp(-s2 / 2 + math.sqrt(s2) * statistics.NormalDist().inv_cdf(q))


@dataclass(frozen=True)
class AdaptiveCell:
    """One participant group under one supply setting: every policy on the same runs, run
    ``i`` with speed factor ``factors[i]`` and seed ``seeds[i]``."""

    instance: str
    group: str
    mat: float | None
    mttf: float | None
    factors: tuple[float, ...]
    seeds: tuple[int, ...]
    units: int = FIG6_UNITS
    timing: dict[str, Any] = field(default_factory=dict)
    policies: tuple[str, ...] = POLICIES

    @property
    def delay(self) -> str:
        return "none" if self.mat is None else f"MAT {self.mat:g}, MTTF {self.mttf:g}"

    def key(self) -> str:
        cfg = {k: v for k, v in asdict(self).items() if k != "instance"}
        cfg["instance_sha1"] = hashlib.sha1(Path(self.instance).read_bytes()).hexdigest()[:12]
        blob = json.dumps(cfg, sort_keys=True, default=str).encode()
        label = "nodelay" if self.mat is None else f"mat{self.mat:g}_mttf{self.mttf:g}"
        return f"{label}_{self.group}__{hashlib.sha1(blob).hexdigest()[:10]}"

    def params(self, factor: float) -> SimParams:
        supplied = {t: self.mat for t in FIG6_SUPPLIED} if self.mat is not None else {}
        return SimParams(
            units=self.units,
            mat=supplied,
            mttf=self.mttf,
            repair_time=FIG6_REPAIR,
            use_instance_supply=False,
            timing=TimingModel(**{**self.timing, "session_factor": factor}),
        )


def adaptive_cell(cell: AdaptiveCell) -> dict[str, Any]:
    """Simulate one cell: per policy and run, the paper's idle time, the makespan, the kits.
    One policy object per policy serves every run (the factor is not part of its
    construction: the prior comes from ``task_cv`` and the paper's CV)."""
    inst = load(cell.instance)
    base = cell.params(1.0)
    runs: dict[str, dict[str, list[float]]] = {}
    wall: dict[str, float] = {}
    for pol in cell.policies:
        t0 = time.perf_counter()
        obj = make_policy(pol, effective_instance(inst, base), params=base)
        recs = [
            simulate(inst, obj, params=cell.params(f), seed=s).record()
            for f, s in zip(cell.factors, cell.seeds, strict=True)
        ]
        wall[pol] = time.perf_counter() - t0
        runs[pol] = {
            "idle": [paper_idle(r) for r in recs],
            "idle_sim": [r["human_idle"] for r in recs],
            "makespan": [r["makespan"] for r in recs],
            "n_kits": [r["n_kits"] for r in recs],
        }
    return {"key": cell.key(), "cell": asdict(cell), "runs": runs, "wall_s": wall}


def summarize(record: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Rows of ``adaptive.csv``: per metric, the three means, the gap, the share closed."""
    cell, runs = record["cell"], record["runs"]
    factors = cell["factors"]
    out = []
    for metric in METRICS:
        v = {p: np.asarray(runs[p][metric], float) for p in POLICIES}
        gap_runs = v[FIXED] - v[ORACLE]
        closed_runs = v[FIXED] - v[ADAPTIVE]
        n = len(gap_runs)
        se = float(gap_runs.std(ddof=1) / math.sqrt(n)) if n > 1 else 0.0
        se_closed = float(closed_runs.std(ddof=1) / math.sqrt(n)) if n > 1 else 0.0
        gap, closed = float(gap_runs.mean()), float(closed_runs.mean())
        share = closed / gap if gap > max(2 * se, 1e-9) else None
        out.append(
            {
                "delay": "none"
                if cell["mat"] is None
                else f"MAT {cell['mat']:g}, MTTF {cell['mttf']:g}",
                "group": cell["group"],
                "factor": "sampled" if cell["group"] == "population" else round(factors[0], 4),
                "runs": n,
                "metric": metric,
                **{f"mean_{p}": round(float(v[p].mean()), 2) for p in POLICIES},
                "gap_fixed_minus_oracle": round(gap, 2),
                "se_gap": round(se, 2),
                "fixed_minus_adaptive": round(closed, 2),
                "se_fixed_minus_adaptive": round(se_closed, 2),
                "share_closed": None if share is None else round(share, 3),
                **{f"kits_{p}": round(float(np.mean(runs[p]["n_kits"])), 1) for p in POLICIES},
            }
        )
    return out


def _cells(
    path: str, reps: int, population: int, units: int, seed: int, timing: Mapping[str, Any]
) -> list[AdaptiveCell]:
    rng = np.random.default_rng(np.random.SeedSequence([seed, 18, 1]))
    s2 = math.log1p(PAPER_CV**2)
    sampled = tuple(float(f) for f in rng.lognormal(-s2 / 2, math.sqrt(s2), population))
    cells = []
    for delay in DELAYS:
        mat, mttf = delay if delay is not None else (None, None)
        for group, q in GROUPS.items():
            n = population if q is None else reps
            factors = sampled if q is None else (factor_quantile(q),) * n
            seeds = tuple(seed * 1_000_000 + i for i in range(n))
            cells.append(AdaptiveCell(path, group, mat, mttf, factors, seeds, units, dict(timing)))
    return cells


def format_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """One table: per supply setting and group, the metrics of the three policies and the
    share of the gap closed (rows as :func:`summarize` returns them or as read back from
    ``adaptive.csv``: the README renders its table from the committed file)."""
    head = ["supply", "group (factor)", "metric", "fixed", "adaptive", "oracle", "gap",
            "closed", "share"]  # fmt: skip
    body = []
    for r in rows:
        share = r["share_closed"]
        num = {k: float(r[k]) for k in r if k.startswith(("mean_", "gap_", "se_", "fixed_"))}
        body.append(
            [
                r["delay"],
                f"{r['group']} ({r['factor']})",
                METRICS[r["metric"]],
                *(f"{num[f'mean_{p}']:.1f}" for p in POLICIES),
                f"{num['gap_fixed_minus_oracle']:.1f} ± {num['se_gap']:.1f}",
                f"{num['fixed_minus_adaptive']:.1f} ± {num['se_fixed_minus_adaptive']:.1f}",
                "no gap" if share in (None, "") else f"{100 * float(share):.0f} %",
            ]
        )
    return "\n".join(markdown_lines(head, body))


def run_adaptive(
    out_dir: str | Path = "out/repro/adaptive",
    quick: bool = False,
    reps: int | None = None,
    jobs: int = 1,
    seed: int = 0,
    *,
    instance: str | Path | None = None,
    units: int | None = None,
    timing: Mapping[str, Any] | None = None,
    progress: bool | None = None,
) -> dict[str, Any]:
    """The adaptive-policy study (module docstring). ``reps`` runs per fixed-factor group
    (default 10; 2 with ``quick``), ``3 * reps`` sampled participants for the population;
    10 tables per run (2 with ``quick``). Cells are saved under ``out_dir/cells/`` (a rerun
    computes only the missing ones). Writes ``adaptive.csv``, ``adaptive.md`` and
    ``adaptive.json``; returns the summary."""
    t0 = time.perf_counter()
    inst, path = load_instance(instance)
    reps = reps if reps is not None else (QUICK_REPS if quick else REPS)
    units = units if units is not None else (QUICK_UNITS if quick else FIG6_UNITS)
    if reps < 2 or units < 1 or jobs < 1:
        raise UsageError(f"need reps >= 2, units >= 1, jobs >= 1; got {reps}, {units}, {jobs}")
    tm = {"participant_cv": 0.0, "task_cv": TASK_CV, **FITTED, **(timing or {})}
    cells = _cells(path, reps, 3 * reps, units, seed, tm)
    out = Path(out_dir)
    records, computed = run_cells_counted(
        cells, adaptive_cell, cell_dir=out / "cells", jobs=jobs, progress=progress,
        desc="adaptive cells",
    )  # fmt: skip
    failed = [{"key": r["key"], "error": r["error"]} for r in records if is_failed(r)]
    rows = [row for r in records if not is_failed(r) for row in summarize(r)]
    files = {"csv": write_csv(out / "adaptive.csv", rows, exclude=(), line_end="\n")}
    head = (
        f"Adaptive pace{' (QUICK: a reduced run)' if quick else ''}: {units} tables per run, "
        f"{reps} runs per fixed group, {3 * reps} sampled participants; task_cv {tm['task_cv']}."
        " Idle: the paper's (makespan - task times). gap = fixed - oracle, closed = fixed - "
        "adaptive (mean ± SE over paired runs); share = closed / gap where the gap exceeds "
        "2 SE.\n\n"
    )
    files["markdown"] = out / "adaptive.md"
    atomic.write_text(files["markdown"], head + format_markdown(rows) + "\n")
    result = {
        "instance": inst.name,
        "units": units,
        "reps": reps,
        "population": 3 * reps,
        "quick": quick,
        "seed": seed,
        "timing": tm,
        "computed": computed,
        "cells": len(cells),
        "failed": failed,
        "simulation_wall_s": {
            p: sum(r["wall_s"].get(p, 0.0) for r in records if not is_failed(r)) for p in POLICIES
        },
        "rows": rows,
        "wall_s": time.perf_counter() - t0,
    }
    result["files"] = {k: str(v) for k, v in {**files, "json": out / "adaptive.json"}.items()}
    write_json(out / "adaptive.json", result)
    return result
