"""Simulated user-study cohorts and the declared calibration protocol (docs/reproduction.md).

A *cohort* is a number of independent studies of 18 participants, each participant with a
within-subject speed per session (:class:`bilevel_kit.sim.timing.WithinSubjectModel`) and a
counterbalanced order of the three conditions. The calibration fits on its **own** cohort
(``calibration_seed``), never on the studies that are then reported:

1. ``robot_scale`` and ``kit_overhead_human`` (``o_H``) by least squares to the cohort means of
   **Whole Assembly idle = 270 s** and **Single Task idle = 99 s** (docs/paper-data.md). A
   session's speed has the same distribution whatever ``within_cv`` is, so these means do not
   depend on step 2.
2. ``within_cv`` (the participant x condition SD) so that the cohort's median repeated-measures
   F of the target metric equals the paper's (**F = 57.60, total task time**): the only
   number of the paper that measures how much a participant varies from session to session.

Every other number of the paper is a prediction, evaluated on fresh cohorts (:mod:`.user_study`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..heuristics.cross_entropy import CEParams
from ..instance import Instance
from ..sim import Policy, SimParams, TimingModel, effective_instance, make_policy, run
from ..sim.timing import WithinSubjectModel
from .common import (
    CONDITIONS,
    DEFAULT_FREE,
    DEFAULT_TARGETS,
    F_TARGET,
    METRICS,
    PAPER_N,
    paper_idle,
)
from .stats import anova_rm

#: Stream tags of the cohorts: a calibration cohort and an evaluation cohort never share draws,
#: even with equal seeds.
CALIBRATION, EVALUATION = 1, 2


@dataclass(frozen=True)
class Cohort:
    """Standard normals of ``n_studies`` studies of ``n`` participants (common random numbers:
    the same draws at every parameter value) and the runs' seeds."""

    seed: int
    tag: int
    z_speed: np.ndarray  # (studies, n)
    z_within: np.ndarray  # (studies, n, conditions)
    run_seeds: np.ndarray  # (studies, n)

    @property
    def n_studies(self) -> int:
        return int(self.z_speed.shape[0])

    @property
    def n_participants(self) -> int:
        return int(self.z_speed.shape[1])


def draw_cohort(seed: int, n_studies: int, n: int = PAPER_N, tag: int = EVALUATION) -> Cohort:
    """``n_studies`` studies of ``n`` participants from ``SeedSequence([seed, 15, tag])``."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 15, tag]))
    z_speed = rng.standard_normal((n_studies, n))
    z_within = rng.standard_normal((n_studies, n, len(CONDITIONS)))
    run_seeds = rng.integers(0, 2**31, size=(n_studies, n))
    return Cohort(seed, tag, z_speed, z_within, run_seeds)


def study_params(
    timing: TimingModel,
    trays: int | str | None,
    ce: CEParams | None,
    delivery_time: float | None = None,
) -> SimParams:
    """One table; ``trays``/``delivery_time`` override the instance's (None: keep them).
    The participant's speed comes from the within-subject model, so ``participant_cv = 0``."""
    timing = replace(timing, participant_cv=0.0, session_factor=1.0)
    return SimParams(units=1, trays=trays, delivery_time=delivery_time, timing=timing, ce=ce)


def study_runs(
    instance: Instance,
    params: SimParams,
    design: WithinSubjectModel,
    cohort: Cohort,
    conditions: Sequence[str] = CONDITIONS,
    policies: dict[str, Policy] | None = None,
) -> list[dict[str, Any]]:
    """One row per study x participant x condition. Participant ``p`` of study ``j`` has the
    session factors ``design.session_factors`` of the cohort's draws (the same person in every
    condition, with a counterbalanced order). ``policies`` caches one policy object per
    condition (the optimized policy's layout cache is then shared by every run)."""
    policies = {} if policies is None else policies
    inst = effective_instance(instance, params)
    rows: list[dict[str, Any]] = []
    for j in range(cohort.n_studies):
        f = design.session_factors(cohort.z_speed[j], cohort.z_within[j])
        orders = _positions(cohort.n_participants)
        for cond in conditions:
            ci = CONDITIONS.index(cond)
            if cond not in policies:
                policies[cond] = make_policy(
                    cond, inst, seed=params.policy_seed or 0, params=params
                )
            for p in range(cohort.n_participants):
                tm = replace(params.timing, session_factor=float(f[p, ci]))
                rec = run(
                    instance,
                    policies[cond],
                    params=replace(params, timing=tm),
                    seed=int(cohort.run_seeds[j, p]),
                )
                rows.append(
                    {
                        "study": j,
                        "participant": p + 1,
                        "condition": cond,
                        "session": int(orders[p][ci]) + 1,
                        "session_factor": round(float(f[p, ci]), 9),
                        "total_time": rec["makespan"],
                        "human_idle": paper_idle(rec),
                        "human_idle_sim": rec["human_idle"],
                        "active_time": float(sum(rec["human_times"].values())),
                        "n_kits": rec["n_kits"],
                        "robot_idle": rec["robot_idle"],
                        "robot_blocked": rec["robot_blocked"],
                        "kits": rec["kits"],
                    }
                )
    return rows


def _positions(n: int) -> list[tuple[int, ...]]:
    """Session position (0-based) of each condition for participant 0..n-1."""
    from ..sim.timing import counterbalanced_orders

    orders = counterbalanced_orders(len(CONDITIONS))
    return [
        tuple(orders[p % len(orders)].index(c) for c in range(len(CONDITIONS))) for p in range(n)
    ]


def condition_means(rows: Sequence[Mapping[str, Any]]) -> dict[str, dict[str, float]]:
    """Mean of each metric per condition."""
    out: dict[str, dict[str, float]] = {}
    for m, col in METRICS.items():
        out[m] = {}
        for cond in dict.fromkeys(r["condition"] for r in rows):
            out[m][cond] = float(np.mean([r[col] for r in rows if r["condition"] == cond]))
    return out


def median_f(rows: Sequence[Mapping[str, Any]], metric: str) -> float:
    """Median over the studies of the repeated-measures F of ``metric``."""
    col = METRICS[metric]
    fs = []
    for j in sorted({r["study"] for r in rows}):
        f = anova_rm([r for r in rows if r["study"] == j], col)["F"]
        fs.append(math.inf if f is None else f)
    return float(np.median(fs))


def fit_means(
    instance: Instance,
    cohort: Cohort,
    design: WithinSubjectModel,
    *,
    base: TimingModel,
    trays: int | str | None = None,
    delivery_time: float | None = None,
    targets: Sequence[tuple[str, str, float]] = DEFAULT_TARGETS,
    free: Mapping[str, tuple[float, float]] = DEFAULT_FREE,
    grid: int = 5,
) -> dict[str, Any]:
    """Step 1: least squares of the ``free`` TimingModel fields to the mean ``targets``.

    Why this way: each evaluation simulates the cohort in the target conditions only (fast
    policies), so a coarse grid over the whole box and a finite-difference least-squares
    polish (:func:`scipy.optimize.least_squares`; the residuals are piecewise linear) is cheap
    and cannot get stuck in a far local minimum.
    """
    from scipy.optimize import least_squares

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
            params = study_params(tm, trays, None, delivery_time)
            means = condition_means(study_runs(instance, params, design, cohort, conds))
            hit = np.array([means[m][c] for m, c, _ in targets])
            cache[key] = hit
        return hit

    def sse(x: np.ndarray) -> float:
        return float(np.sum((model(x) - goal) ** 2))

    axes = [np.linspace(lo[i], hi[i], grid) for i in range(len(names))]
    pts = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(names), -1).T
    best = min(pts, key=sse)
    res = least_squares(
        lambda x: model(x) - goal, best, bounds=(lo, hi), x_scale="jac", max_nfev=60
    )
    if sse(res.x) < sse(best):
        best = res.x
    # 6 decimals: stable across platforms (Figure 6's cell keys hash the timing), and far
    # below the noise of any reported number.
    best = np.clip(np.round(best, 6), lo, hi)
    fitted = model(best)
    return {
        "values": {n: float(v) for n, v in zip(names, best, strict=True)},
        "targets": [
            {
                "quantity": f"mean {m}, {c}",
                "metric": m,
                "condition": c,
                "paper": float(v),
                "fitted": float(f),
                "residual": float(f - v),
            }
            for (m, c, v), f in zip(targets, fitted, strict=True)
        ],
        "evaluations": len(cache),
    }


def fit_within(
    instance: Instance,
    cohort: Cohort,
    design: WithinSubjectModel,
    params: SimParams,
    *,
    target: tuple[str, float] = F_TARGET,
    xtol: float = 2e-3,
) -> dict[str, Any]:
    """Step 2: ``within_cv`` so that the cohort's median repeated-measures F of ``target``'s
    metric equals the paper's (bisection on log F, which falls as ``within_cv`` grows; the
    boundary when the target is out of reach)."""
    metric, goal = target
    policies: dict[str, Policy] = {}
    vmax = (
        math.sqrt(
            max(
                math.log1p(design.total_cv**2) - float(np.var(np.log(design.learning_factors))), 0.0
            )
        )
        * 0.98
    )
    seen: dict[float, float] = {}

    def f_of(w: float) -> float:
        w = round(w, 6)
        if w not in seen:
            rows = study_runs(
                instance, params, replace(design, within_cv=w), cohort, policies=policies
            )
            seen[w] = median_f(rows, metric)
        return seen[w]

    a, b = 0.0, vmax
    if f_of(a) <= goal:
        w = a
    elif f_of(b) >= goal:
        w = b
    else:
        while b - a > xtol:
            mid = (a + b) / 2
            if f_of(mid) > goal:
                a = mid
            else:
                b = mid
        w = round((a + b) / 2, 6)
    f = f_of(w)
    return {
        "values": {"within_cv": float(w)},
        "targets": [
            {
                "quantity": f"F {metric}",
                "metric": metric,
                "condition": "",
                "paper": float(goal),
                "fitted": float(f),
                "residual": float(f - goal),
            }
        ],
        "evaluations": len(seen),
        "max_within_cv": vmax,
    }


def calibrate(
    instance: Instance,
    cohort: Cohort,
    *,
    design: WithinSubjectModel | None = None,
    base: TimingModel | None = None,
    trays: int | str | None = None,
    delivery_time: float | None = None,
    targets: Sequence[tuple[str, str, float]] = DEFAULT_TARGETS,
    f_target: tuple[str, float] | None = F_TARGET,
    free: Mapping[str, tuple[float, float]] = DEFAULT_FREE,
    grid: int = 5,
    ce: CEParams | None = None,
) -> dict[str, Any]:
    """The declared protocol (module docstring) on the calibration ``cohort``: step 1 (means),
    then step 2 (``within_cv`` on ``f_target``; skipped when None, keeping ``design``'s).

    Returns the fitted values (``values``: the TimingModel fields and ``within_cv``), every
    target with the model's value and residual, the cohort, the evaluations and the wall time.
    """
    t0 = time.perf_counter()
    design = design or WithinSubjectModel()
    base = base or TimingModel()
    step1 = fit_means(
        instance,
        cohort,
        design,
        base=base,
        trays=trays,
        delivery_time=delivery_time,
        targets=targets,
        free=free,
        grid=grid,
    )
    values = dict(step1["values"])
    out_targets = list(step1["targets"])
    evaluations = step1["evaluations"]
    within = design.within_cv
    if f_target is not None:
        params = study_params(replace(base, **values), trays, ce, delivery_time)
        step2 = fit_within(instance, cohort, design, params, target=f_target)
        within = step2["values"]["within_cv"]
        out_targets += step2["targets"]
        evaluations += step2["evaluations"]
    return {
        "free": {n: list(free[n]) for n in free},
        "values": values,
        "within_cv": within,
        "targets": out_targets,
        "cohort": {
            "seed": cohort.seed,
            "studies": cohort.n_studies,
            "participants": cohort.n_participants,
        },
        "evaluations": evaluations,
        "wall_s": time.perf_counter() - t0,
    }
