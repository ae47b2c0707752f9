"""Beyond the paper: how much of the fixed-to-oracle gap a policy that learns the human's pace
closes (``bilevel-kit repro adaptive``; docs/simulation.md, "Adaptive policies").

Policies: ``optimized`` (the paper's, task means), ``optimized-adaptive`` (the posterior mean
of the speed factor, :mod:`bilevel_kit.sim.pace`) and ``optimized-oracle`` (the true factor),
on the same seeds (common random numbers). One participant builds every table of a run (the
within-subject model's way: ``participant_cv = 0`` and the factor as ``session_factor``), each
task with independent lognormal noise ``task_cv`` (the calibration's ``within_cv``). The robot's
speed and ``o_H`` are the one calibration's (:mod:`.calibrated`). Participant groups: the
10 %, 50 % and 90 % quantiles of the factor's distribution (lognormal, mean 1, the paper's CV:
fast, median, slow) and a sample of the whole population. Supply: none, and one Figure 6 cell
(legs and feet fed at MAT 60 s, MTTF 60 s, 30 s repair, feeders start empty).

Per group and metric (the paper's idle time, makespan - task times, whose differences between
policies equal the makespan's since every policy sees the same task times; the simulator's idle
time, where taking the parts off the tray is work; the makespan), the share of
the gap the adaptive policy closes is ``(fixed - adaptive) / (fixed - oracle)`` with a 95 %
bootstrap interval over the runs, reported only where the oracle beats the fixed policy
significantly (the 95 % t-interval of the paired gap above 0; otherwise there is no gap to
close, and the row gives the gap's verdict from its interval, :mod:`.verdict`). "Fixed -
adaptive" carries its 95 % t-interval: an interval containing 0 is "no significant
difference", never "no loss".
"""

from __future__ import annotations

import math
import statistics
import time
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic
from ..errors import UsageError
from ..experiments.cells import write_json
from ..experiments.tables import markdown_lines, write_csv
from ..instance import load
from ..sim import SimParams, TimingModel, effective_instance, make_policy, simulate
from ..sim.timing import PAPER_CV
from .calibrated import load_calibration
from .common import (
    FIG6_REPAIR,
    FIG6_SUPPLIED,
    FIG6_UNITS,
    config_digest,
    load_instance,
    paper_idle,
    run_study_cells,
)
from .stats import t_interval
from .verdict import GAP, side, verdict

FIXED, ADAPTIVE, ORACLE = "optimized", "optimized-adaptive", "optimized-oracle"
POLICIES = (FIXED, ADAPTIVE, ORACLE)
#: Participant groups: name -> quantile of the factor (None: sampled from the population).
GROUPS: dict[str, float | None] = {"fast": 0.1, "median": 0.5, "slow": 0.9, "population": None}
#: The delay cell (MAT, MTTF) of Figure 6's grid; None: no supply process.
DELAYS: tuple[tuple[float, float] | None, ...] = (None, (60.0, 60.0))
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
        label = "nodelay" if self.mat is None else f"mat{self.mat:g}_mttf{self.mttf:g}"
        return f"{label}_{self.group}__{config_digest(self)}"

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


#: Bootstrap resamples of the runs for the share's 95 % interval.
BOOTSTRAP = 2000


def share_interval(
    gap: np.ndarray, closed: np.ndarray, rng: np.random.Generator, resamples: int = BOOTSTRAP
) -> tuple[float | None, float | None]:
    """95 % percentile bootstrap interval of ``mean(closed) / mean(gap)`` over resampled runs
    (pairs kept); None when more than 2.5 % of the resamples have no positive gap (the ratio
    is then unbounded)."""
    idx = rng.integers(0, len(gap), (resamples, len(gap)))
    g, c = gap[idx].mean(axis=1), closed[idx].mean(axis=1)
    ok = g > 1e-9
    if ok.mean() < 0.975:
        return None, None
    ratio = c[ok] / g[ok]
    return float(np.quantile(ratio, 0.025)), float(np.quantile(ratio, 0.975))


def summarize(record: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Rows of ``adaptive.csv``: per metric, the three means, the gap (fixed - oracle) and what
    the adaptive policy closes of it (fixed - adaptive), each with its 95 % t-interval, and
    the share closed with its 95 % bootstrap interval where the gap is significant (its
    interval above 0)."""
    cell, runs = record["cell"], record["runs"]
    factors = cell["factors"]
    delay = "none" if cell["mat"] is None else f"MAT {cell['mat']:g}, MTTF {cell['mttf']:g}"
    out = []
    for metric in METRICS:
        v = {p: np.asarray(runs[p][metric], float) for p in POLICIES}
        gap_runs, closed_runs = v[FIXED] - v[ORACLE], v[FIXED] - v[ADAPTIVE]
        n = len(gap_runs)
        gap, gap_lo, gap_hi = t_interval(gap_runs)
        closed, closed_lo, closed_hi = t_interval(closed_runs)
        rng = np.random.default_rng(zlib.crc32(f"{delay}|{cell['group']}|{metric}".encode()))
        share = closed / gap if side(gap_lo, gap_hi) > 0 else None
        lo, hi = share_interval(gap_runs, closed_runs, rng) if share is not None else (None, None)
        out.append(
            {
                "delay": delay,
                "group": cell["group"],
                "factor": "sampled" if cell["group"] == "population" else round(factors[0], 4),
                "runs": n,
                "metric": metric,
                **{f"mean_{p}": round(float(v[p].mean()), 2) for p in POLICIES},
                "gap_fixed_minus_oracle": round(gap, 2),
                "se_gap": round(_se(gap_runs), 2),
                "gap_low": round(gap_lo, 2),
                "gap_high": round(gap_hi, 2),
                "fixed_minus_adaptive": round(closed, 2),
                "se_fixed_minus_adaptive": round(_se(closed_runs), 2),
                "closed_low": round(closed_lo, 2),
                "closed_high": round(closed_hi, 2),
                "share_closed": None if share is None else round(share, 3),
                "share_low": None if lo is None else round(lo, 3),
                "share_high": None if hi is None else round(hi, 3),
                **{f"kits_{p}": round(float(np.mean(runs[p]["n_kits"])), 1) for p in POLICIES},
            }
        )
    return out


def _se(x: np.ndarray) -> float:
    return float(x.std(ddof=1) / math.sqrt(len(x))) if len(x) > 1 else 0.0


def calibrated(calibration: str | Path | None, instance: str) -> dict[str, float]:
    """The one calibration's robot speed and ``o_H``, and its participant x condition SD as
    the per-task noise ``task_cv`` (assumed: a task varies around the participant's pace as a
    session varies around the participant's speed)."""
    cal = load_calibration(calibration, instance)
    return {
        "robot_scale": cal.robot_scale,
        "kit_overhead_human": cal.kit_overhead_human,
        "task_cv": round(cal.within_cv, 6),
    }


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


def _blank(x: Any) -> bool:
    return x is None or x == ""


def share_text(r: Mapping[str, Any]) -> str:
    """``90 % [81, 97]``, or why there is no share: the gap's verdict from its interval (no
    significant gap, or the oracle significantly slower), or an unbounded interval."""
    if _blank(r["share_closed"]):
        return f"no share: {verdict(r['gap_low'], r['gap_high'], GAP)}"
    share = f"{100 * float(r['share_closed']):.0f} %"
    if _blank(r.get("share_low")):
        return f"{share} [unbounded]"
    return f"{share} [{100 * float(r['share_low']):.0f}, {100 * float(r['share_high']):.0f}]"


def format_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """One table: per supply setting and group, the metrics of the three policies, the gap and
    what the adaptive policy closes (mean [95 % t-interval]) and the share closed (its 95 %
    bootstrap interval); rows as :func:`summarize` returns them or as read back from
    ``adaptive.csv`` (the README renders its table from the committed file)."""
    head = ["supply", "group (factor)", "metric", "fixed", "adaptive", "oracle",
            "gap [95 % CI]", "closed [95 % CI]", "share [95 % bootstrap]"]  # fmt: skip
    body = []
    for r in rows:
        num = {k: float(r[k]) for k in r if k.startswith(("mean_", "gap_", "closed_", "fixed_"))}
        body.append(
            [
                r["delay"],
                f"{r['group']} ({r['factor']})",
                METRICS[r["metric"]],
                *(f"{num[f'mean_{p}']:.1f}" for p in POLICIES),
                f"{num['gap_fixed_minus_oracle']:.1f} [{num['gap_low']:.1f}, "
                f"{num['gap_high']:.1f}]",
                f"{num['fixed_minus_adaptive']:.1f} [{num['closed_low']:.1f}, "
                f"{num['closed_high']:.1f}]",
                share_text(r),
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
    calibration: str | Path | None = None,
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
    tm = {"participant_cv": 0.0, **calibrated(calibration, path), **(timing or {})}
    cells = _cells(path, reps, 3 * reps, units, seed, tm)
    out = Path(out_dir)
    ok, failed, computed = run_study_cells(
        cells, adaptive_cell, out, jobs=jobs, progress=progress, desc="adaptive cells"
    )
    rows = [row for r in ok for row in summarize(r)]
    files = {"csv": write_csv(out / "adaptive.csv", rows, exclude=(), line_end="\n")}
    head = (
        f"Adaptive pace{' (QUICK: a reduced run)' if quick else ''}: {units} tables per run, "
        f"{reps} runs per fixed group, {3 * reps} sampled participants; task_cv {tm['task_cv']}."
        " Idle: the paper's (makespan - task times). gap = fixed - oracle, closed = fixed - "
        "adaptive (mean and 95 % t-interval over paired runs); share = closed / gap (95 % "
        "bootstrap interval) where the gap is significant.\n\n"
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
        "simulation_wall_s": {p: sum(r["wall_s"].get(p, 0.0) for r in ok) for p in POLICIES},
        "rows": rows,
        "wall_s": time.perf_counter() - t0,
    }
    result["files"] = {k: str(v) for k, v in {**files, "json": out / "adaptive.json"}.items()}
    write_json(out / "adaptive.json", result)
    return result
