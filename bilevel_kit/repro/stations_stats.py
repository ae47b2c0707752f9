"""The stations study's statistics (docs/stations.md): ``S_max`` per replication, its
distribution with a bootstrap interval on the mean and Clopper-Pearson intervals on the share of
replications that serve k stations, the verdict those intervals give, at several idle
thresholds and for both idle definitions; and the capacity bound the robot's and the humans'
times per unit put on any policy.

``S_max`` of a replication: the largest S whose mean human idle per station, and every smaller
S's, is at most the threshold (0: above it already at S = 1). Its values are small integers, so a
t-interval of their mean is degenerate ([1, 1] when all agree) or crosses the range; the mean's
interval here is the percentile bootstrap over replications, and the verdict is read from the
binomial intervals: ``k`` stations are served when the Clopper-Pearson 95 % interval of the
share of replications with ``S_max >= k`` lies above one half, not served when it lies below;
a k whose interval contains one half leaves the verdict unsettled.

Capacity bound (nominal times, the wait for the first kit left out, which only adds idle): a
station's human needs ``H`` per unit (task times ``W`` plus one pickup ``o_H`` per kit), and the
robot ``R`` per unit of a station (``o_R`` plus the pick times plus ``d`` per kit: the robot
pushes the tray, docs/timeline.md). The station that finishes k-th cannot finish before the robot
has built its own units and those of the stations finished before it, so its reproduction's
idle share (docs/reproduction.md) is at least ``1 - W / max(H, R_own + R of those)``; the least
mean over the orders of finishing is the floor (:func:`idle_floor`), and ``S`` units per
``max(max H, sum R)`` the most throughput. With one kit per unit (Whole Assembly's kits) ``R``
is the least any policy whose kits hold at most one unit can give, so that floor holds for every
policy; Single Task's (one kit per task) is its own.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

THRESHOLDS = (0.05, 0.10, 0.15)
#: The idle definitions: the reproduction's (the paper's idle time: pickups and the wait for
#: the first kit are idle) and the steady state's (from the first kit, pickups as work).
IDLE_DEFS = {"paper": "idle", "steady": "idle_steady"}
BOOTSTRAP = 10_000
LEVEL = 0.95


def s_max(idle: Mapping[int, float], threshold: float) -> int:
    """One replication's ``S_max`` from its idle share at each S (the module docstring)."""
    ok = 0
    for s in sorted(idle):
        if s != ok + 1 or idle[s] > threshold:
            break
        ok = s
    return ok


def bootstrap_mean(x: Sequence[float], seed: int = 0) -> tuple[float, float, float]:
    """The mean and its 95 % percentile-bootstrap interval (:data:`BOOTSTRAP` resamples of the
    replications, a fixed seed: the same data give the same interval)."""
    a = np.asarray(x, float)
    rng = np.random.default_rng(seed)
    means = rng.choice(a, size=(BOOTSTRAP, len(a)), replace=True).mean(axis=1)
    lo, hi = np.quantile(means, [(1 - LEVEL) / 2, (1 + LEVEL) / 2])
    return float(a.mean()), float(lo), float(hi)


def clopper_pearson(k: int, n: int) -> tuple[float, float]:
    """The exact (Clopper-Pearson) 95 % interval of a share ``k`` of ``n``."""
    from scipy.stats import beta

    alpha = 1 - LEVEL
    lo = 0.0 if k == 0 else float(beta.ppf(alpha / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1 - alpha / 2, k + 1, n - k))
    return lo, hi


def verdict(shares: Sequence[tuple[float, float]]) -> str:
    """The stations served, from the intervals of the shares with ``S_max >= k`` (k = 1, 2,
    ...): the largest k whose interval lies above one half; ``"k-j unsettled"`` when the
    intervals of k + 1 .. j contain one half."""
    served = 0
    open_ = []
    for k, (lo, hi) in enumerate(shares, start=1):
        if lo > 0.5:
            served = k
        elif hi >= 0.5:
            open_.append(k)
    return f"{served}-{max(open_)} unsettled" if open_ else str(served)


def served_rows(
    runs: Mapping[tuple[str, str, str], Mapping[int, Mapping[int, Mapping[str, float]]]],
    grid: Sequence[int],
    bounds: Mapping[tuple[str, str], Mapping[float, int]] | None = None,
) -> list[dict[str, Any]]:
    """Rows of ``stations_served.csv``: per line, supply, policy, idle definition and
    threshold, the per-replication ``S_max``, its mean with the bootstrap interval, the share
    of replications serving k = 1..max(grid) stations with its binomial interval, the verdict
    and the capacity bound (``runs``: (line, supply, policy) -> seed -> S -> record)."""
    rows = []
    for (line, delay, policy), by_seed in runs.items():
        for name, key in IDLE_DEFS.items():
            for th in THRESHOLDS:
                best = [
                    s_max({s: float(r[key]) for s, r in by_s.items()}, th)
                    for by_s in by_seed.values()
                ]
                m, lo, hi = bootstrap_mean(best)
                row: dict[str, Any] = {
                    "line": line,
                    "delay": delay,
                    "policy": policy,
                    "idle_def": name,
                    "threshold": round(100 * th),
                    "reps": len(best),
                    "s_max": round(m, 2),
                    "s_max_low": round(lo, 2),
                    "s_max_high": round(hi, 2),
                    "per_rep": best,
                }
                shares = []
                for k in range(1, max(grid) + 1):
                    n_k = sum(b >= k for b in best)
                    shares.append(clopper_pearson(n_k, len(best)))
                    row[f"served_{k}"] = n_k
                    row[f"served_{k}_low"] = round(shares[-1][0], 3)
                    row[f"served_{k}_high"] = round(shares[-1][1], 3)
                row["verdict"] = verdict(shares)
                bound = (bounds or {}).get((line, policy), {})
                row["bound"] = bound.get(th, "") if name == "paper" else ""
                rows.append(row)
    return rows


def per_unit(inst: Any, kits: Sequence[Sequence[str]]) -> dict[str, float]:
    """Nominal seconds per unit of a one-station, one-unit instance with these kits: the
    robot's (``o_R`` + pick times + ``d`` per kit), the human's with pickups (``o_H`` per
    kit) and the task time alone."""
    task = sum(inst.human_time(t.id) for t in inst.tasks)
    robot = sum(inst.robot_time(t.id) for t in inst.tasks)
    n, one = len(kits), inst.params_of()  # one station (docstring)
    return {
        "robot": robot + n * (inst.kit_overhead_robot + one.delivery_time),
        "human": task + n * one.kit_overhead_human,
        "task": task,
    }


def idle_floor(products: Sequence[Mapping[str, float]]) -> float:
    """The least mean idle share (the reproduction's) of stations building ``products`` (one
    :func:`per_unit` each) sharing one robot, the wait for the first kit left out (the module
    docstring): the station that finishes k-th waited at least for the robot's work on its own
    units and on those of the k - 1 stations finished before it, so its completion per unit is
    at least ``max(H, R_own + sum of theirs)``; the least over the orders of finishing."""
    best = 1.0
    for order in itertools.permutations(range(len(products))):
        robot, idle = 0.0, []
        for i in order:
            p = products[i]
            robot += p["robot"]
            idle.append(1.0 - p["task"] / max(p["human"], robot))
        best = min(best, float(np.mean(idle)))
    return best


def capacity(products_at: Mapping[int, Sequence[Mapping[str, float]]]) -> dict[float, int]:
    """Per threshold, the largest S whose idle floor, and every smaller S's, is at most the
    threshold (``products_at``: S -> each station's :func:`per_unit`): no policy with these
    kits serves more in a steady state."""
    floors = {s: idle_floor(p) for s, p in products_at.items()}
    return {th: s_max(floors, th) for th in THRESHOLDS}


__all__ = [
    "IDLE_DEFS",
    "THRESHOLDS",
    "bootstrap_mean",
    "capacity",
    "clopper_pearson",
    "idle_floor",
    "per_unit",
    "s_max",
    "served_rows",
    "verdict",
]
