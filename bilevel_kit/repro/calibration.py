"""Simulated user-study runs and the calibration of the timing model to the paper's numbers.

The instance's robot pick times and the human's per-kit pickup time are guesses;
:func:`calibrate` fits ``robot_scale`` and ``kit_overhead_human`` by least squares to two of the
paper's numbers (Whole Assembly idle 270 s and Single Task idle 99 s, docs/paper-data.md);
every other number of the study is a prediction (docs/reproduction.md).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ..instance import Instance
from ..layout.cross_entropy import CEParams
from ..sim import SimParams, TimingModel, replicate
from .common import CONDITIONS, DEFAULT_FREE, DEFAULT_TARGETS, METRICS, paper_idle


def study_params(timing: TimingModel, trays: int | str | None, ce: CEParams | None) -> SimParams:
    """One table; ``trays`` overrides the instance's (None: keep it, the study's table has 1)."""
    return SimParams(units=1, trays=trays, timing=timing, ce=ce)


def study_runs(
    instance: Instance,
    params: SimParams,
    seeds: Sequence[int],
    conditions: Sequence[str] = CONDITIONS,
) -> list[dict[str, Any]]:
    """One row per participant x condition (participant p = run seed ``seeds[p]``, so every
    condition sees the same participant: a within-subjects design)."""
    rows: list[dict[str, Any]] = []
    for cond in conditions:
        for p, rec in enumerate(replicate(instance, cond, params, seeds=seeds), start=1):
            active = float(sum(rec["human_times"].values()))
            rows.append(
                {
                    "participant": p,
                    "seed": rec["seed"],
                    "condition": cond,
                    "speed": rec["speed"][0],
                    "total_time": rec["makespan"],
                    "human_idle": paper_idle(rec),
                    "human_idle_sim": rec["human_idle"],
                    "active_time": active,
                    "n_kits": rec["n_kits"],
                    "robot_idle": rec["robot_idle"],
                    "robot_blocked": rec["robot_blocked"],
                    "kits": rec["kits"],
                }
            )
    return rows


def condition_means(rows: Sequence[Mapping[str, Any]]) -> dict[str, dict[str, float]]:
    """Mean of each metric per condition."""
    out: dict[str, dict[str, float]] = {}
    for m, col in METRICS.items():
        out[m] = {}
        for cond in dict.fromkeys(r["condition"] for r in rows):
            out[m][cond] = float(np.mean([r[col] for r in rows if r["condition"] == cond]))
    return out


def calibrate(
    instance: Instance,
    seeds: Sequence[int],
    *,
    base: TimingModel | None = None,
    trays: int | str | None = None,
    targets: Sequence[tuple[str, str, float]] = DEFAULT_TARGETS,
    free: Mapping[str, tuple[float, float]] = DEFAULT_FREE,
    grid: int = 11,
    refine: Sequence[int] = (7,),
    polish: bool = True,
) -> dict[str, Any]:
    """Least-squares fit of the ``free`` TimingModel fields to the paper's ``targets``.

    Why this way: each evaluation simulates the study's participants (common random numbers:
    the same seeds at every point) in the target conditions only, which takes ~10 ms, so a
    coarse grid over the whole box (``grid`` points per axis), grids of ``refine[i]`` points
    over +-1 step around the best point, and a finite-difference least-squares polish
    (:func:`scipy.optimize.least_squares`, the residuals are piecewise linear) is cheap and
    cannot get stuck in a far local minimum.

    Returns the fitted values (``values``), the model's value of each target (``fitted``), the
    residuals, the number of evaluations and the wall time.
    """
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    base = base or TimingModel()
    names = list(free)
    lo = np.array([free[n][0] for n in names], float)
    hi = np.array([free[n][1] for n in names], float)
    conds = list(dict.fromkeys(c for _, c, _ in targets))
    goal = np.array([v for _, _, v in targets], float)
    cache: dict[tuple[float, ...], np.ndarray] = {}

    def model(x: np.ndarray) -> np.ndarray:
        key = tuple(round(float(v), 12) for v in x)
        hit = cache.get(key)
        if hit is None:
            changes: dict[str, Any] = dict(zip(names, key, strict=True))
            tm = replace(base, **changes)
            means = condition_means(
                study_runs(instance, study_params(tm, trays, None), seeds, conds)
            )
            hit = np.array([means[m][c] for m, c, _ in targets])
            cache[key] = hit
        return hit

    def sse(x: np.ndarray) -> float:
        return float(np.sum((model(x) - goal) ** 2))

    def grid_search(a: np.ndarray, b: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
        axes = [np.linspace(a[i], b[i], n) for i in range(len(names))]
        pts = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(names), -1).T
        best = min(pts, key=sse)
        step = (b - a) / max(n - 1, 1)
        return best, step

    best, step = grid_search(lo, hi, grid)
    for n in refine:
        best, step = grid_search(np.maximum(lo, best - step), np.minimum(hi, best + step), n)
    if polish:
        res = least_squares(
            lambda x: model(x) - goal, best, bounds=(lo, hi), x_scale="jac", max_nfev=100
        )
        if sse(res.x) < sse(best):
            best = res.x
    # 6 decimals: stable across platforms (Figure 6's cell keys hash the timing), and far
    # below the noise of any reported number.
    best = np.clip(np.round(best, 6), lo, hi)
    fitted = model(best)
    return {
        "free": {n: list(free[n]) for n in names},
        "values": {n: float(v) for n, v in zip(names, best, strict=True)},
        "targets": [
            {
                "metric": m,
                "condition": c,
                "paper": float(v),
                "fitted": float(f),
                "residual": float(f - v),
            }
            for (m, c, v), f in zip(targets, fitted, strict=True)
        ],
        "rmse": float(math.sqrt(sse(best) / len(goal))),
        "evaluations": len(cache),
        "participants": len(seeds),
        "wall_s": time.perf_counter() - t0,
    }
