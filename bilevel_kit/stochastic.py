r"""Stochastic human times: scenarios, the expected makespan of a plan and honest estimates
(docs/formulations.md#stochastic-human-times-sample-average-approximation).

**Scenarios.** Scenario ``s`` gives task ``i`` the human time ``h_i^s = mean_i * e_i^s`` with
``e_i^s`` independent lognormal factors of mean 1 and coefficient of variation ``c_i`` (the
shop-floor simulation's law for its per-task noise, docs/simulation.md): ``c_i`` is the
task's own ``sd_i / mean_i`` from the instance, or one ``cv`` for every task. So the
scenarios have each task's mean and standard deviation. Robot times, the overheads and the
delivery time stay deterministic. Every draw comes from a :class:`numpy.random.Generator`
seeded by ``(seed, stream)``: :data:`OPTIMISE` for the scenarios a method optimises on,
:data:`EVALUATE` for the independent sample an estimate is made on, so the two never share a
draw.

**The expected makespan** of a plan is the sample average of its makespan under the scenarios,
each evaluated by the one timeline evaluator :func:`bilevel_kit.plan.evaluate` with that
scenario's ``human_times`` (docs/timeline.md). In-sample values of a plan optimised on the
same scenarios are biased low; :func:`estimate` on the :data:`EVALUATE` stream is the honest
number, :func:`paired` the interval of a difference on common random numbers.

**The CVaR of the makespan** at level ``alpha`` (:func:`cvar`, the objective ``cvar_makespan``)
is the mean of the worst ``(1 - alpha)`` share of the scenarios' makespans, the boundary
scenario counted fractionally (docs/formulations.md#cvar-of-the-makespan).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .instance import Instance
from .plan import Plan, evaluate

#: The seed stream of the scenarios a method optimises on.
OPTIMISE = 0
#: The seed stream of the independent evaluation sample (never optimised on).
EVALUATE = 1
#: The seed stream of the wait-and-see sample (per-scenario optima).
WAIT_AND_SEE = 2


def task_cvs(instance: Instance, cv: float | None = None) -> np.ndarray:
    """Each task's coefficient of variation (file order): ``cv`` for every task, or (None)
    the instance's ``sd_i / mean_i`` (0 for a task of mean 0)."""
    if cv is not None:
        if not math.isfinite(cv) or cv < 0:
            raise ValueError(f"cv must be finite and >= 0, got {cv!r}")
        return np.full(instance.n_tasks, float(cv))
    return np.array(
        [t.human_sd / t.human_mean if t.human_mean > 0 else 0.0 for t in instance.tasks]
    )


def rng_for(seed: int, stream: int) -> np.random.Generator:
    """The generator of ``stream`` (:data:`OPTIMISE`, :data:`EVALUATE`, ...) for ``seed``."""
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(int(stream),)))


def sample(
    instance: Instance, n: int, seed: int, *, cv: float | None = None, stream: int = OPTIMISE
) -> np.ndarray:
    """``n`` scenarios (rows) of every task's human time (columns, file order): the module
    docstring's lognormal law with mean ``mean_i`` and coefficient of variation ``c_i``."""
    if n < 1:
        raise ValueError(f"the number of scenarios must be >= 1, got {n}")
    means = np.array([t.human_mean for t in instance.tasks])
    sigma2 = np.log1p(task_cvs(instance, cv) ** 2)
    factors = rng_for(seed, stream).lognormal(-sigma2 / 2, np.sqrt(sigma2), (n, len(means)))
    return means * factors


def makespans(instance: Instance, plan: Plan, scenarios: np.ndarray) -> np.ndarray:
    """The makespan of ``plan`` under every scenario (the one evaluator, docs/timeline.md)."""
    ids = [t.id for t in instance.tasks]
    return np.array(
        [
            evaluate(instance, plan, human_times=dict(zip(ids, row.tolist(), strict=True))).makespan
            for row in scenarios
        ]
    )


def expected_makespan(instance: Instance, plan: Plan, scenarios: np.ndarray) -> float:
    """The sample average of the makespan of ``plan`` under ``scenarios``."""
    return float(makespans(instance, plan, scenarios).mean())


def cvar(values: Sequence[float] | np.ndarray, alpha: float) -> float:
    r"""CVaR at level ``alpha`` of equally weighted ``values``
    (docs/formulations.md#cvar-of-the-makespan), Rockafellar-Uryasev's

    .. math:: \min_\eta\; \eta + \frac{1}{(1-\alpha) S} \sum_s \max(0, C_s - \eta),

    in closed form: with the values sorted worst first and ``m = (1 - alpha) S``, value ``j``
    (0-based) has weight ``min(1, max(0, m - j))`` and CVaR is the weighted sum over ``m``:
    the mean of the worst ``m`` values, exact also when ``m`` is not an integer. ``alpha = 0``
    returns the plain mean (the same float as ``np.mean``, so it equals the sample average)."""
    if not (math.isfinite(alpha) and 0 <= alpha < 1):
        raise ValueError(f"alpha must be in [0, 1), got {alpha!r}")
    v = np.asarray(values, dtype=float)
    if len(v) == 0:
        raise ValueError("CVaR of no values")
    if alpha == 0:
        return float(v.mean())
    worst = np.sort(v)[::-1]
    mass = (1 - alpha) * len(v)
    weights = np.clip(mass - np.arange(len(v)), 0.0, 1.0)
    return float(weights @ worst / weights.sum())


def cvar_makespan(instance: Instance, plan: Plan, scenarios: np.ndarray, alpha: float) -> float:
    """The CVaR at level ``alpha`` of the makespan of ``plan`` under ``scenarios``."""
    return cvar(makespans(instance, plan, scenarios), alpha)


def mean_times(scenarios: np.ndarray, instance: Instance) -> dict[str, float]:
    """Each task's average human time over ``scenarios`` (the times whose deterministic
    optimum bounds the sample average from below: Jensen, docs/formulations.md)."""
    return dict(zip((t.id for t in instance.tasks), scenarios.mean(axis=0).tolist(), strict=True))


@dataclass(frozen=True)
class Estimate:
    """A sample mean with its 95 % confidence half-width (Student t, ``n - 1`` degrees)."""

    mean: float
    half: float
    n: int

    @property
    def low(self) -> float:
        return self.mean - self.half

    @property
    def high(self) -> float:
        return self.mean + self.half


def estimate(values: Sequence[float] | np.ndarray) -> Estimate:
    """The mean of ``values`` and its 95 % interval (half-width 0 for one value)."""
    from scipy import stats

    v = np.asarray(values, dtype=float)
    if len(v) < 2:
        return Estimate(float(v.mean()), 0.0, len(v))
    half = float(stats.t.ppf(0.975, len(v) - 1) * v.std(ddof=1) / math.sqrt(len(v)))
    return Estimate(float(v.mean()), half, len(v))


def paired(a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray) -> Estimate:
    """The mean of ``a - b`` on the same scenarios (common random numbers) and its interval."""
    return estimate(np.asarray(a, dtype=float) - np.asarray(b, dtype=float))
