r"""An online estimate of the human's pace: the conjugate Bayesian update of the participant's
speed factor from the observed task durations (docs/simulation.md#adaptive-policies).

Model (the participant model of :mod:`.timing`): the human takes ``d_t = f * mu_t * e_t`` for
task ``t`` of mean ``mu_t``, with one speed factor ``f`` for the run and independent per-task
noise ``e_t``, both lognormal with mean 1:

.. math::

    x = \log f \sim N(m_0, s_0^2),\quad s_0^2 = \log(1 + c_f^2),\quad m_0 = -s_0^2 / 2

    y_t = \log(d_t / \mu_t) + \sigma^2 / 2 = x + \varepsilon_t,\quad
    \varepsilon_t \sim N(0, \sigma^2),\quad \sigma^2 = \log(1 + c_e^2)

with ``c_f`` the factor's CV (the prior) and ``c_e`` the per-task noise CV. A normal prior and
normal observations of ``x`` give a normal posterior after ``n`` observed tasks:

.. math::

    P_n = 1 / s_0^2 + n / \sigma^2,\qquad
    m_n = (m_0 / s_0^2 + \sum_t y_t / \sigma^2) / P_n,\qquad v_n = 1 / P_n

and the posterior mean of the factor ``E[f | d] = exp(m_n + v_n / 2)``. Limits: ``c_e = 0``
(no per-task noise, the default timing model's) makes every observation exact,
``m_n = mean(y_t)``, ``v_n = 0``; ``c_f = 0`` makes the prior exact, ``f = 1``.

The policies plan with the **posterior mean** of ``f``, not its median ``exp(m_n)``: the fixed
policy plans with the expected task time ``mu_t`` (``E[f] = 1`` under the prior), and the
posterior mean keeps that meaning, the expected duration given what was observed. With no
observation it is exactly 1, so an adaptive policy decides exactly as the fixed one until the
first task is finished.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from ..instance import Instance
from ..options import option
from .timing import PAPER_CV, TimingModel


@dataclass(frozen=True)
class PaceOptions:
    """The prior of the pace estimate (``-p key=value``; None: from the run's timing model)."""

    prior_cv: float | None = option(
        None,
        "CV of the speed factor's lognormal prior (mean 1); default: the run's "
        "participant CV, or the paper's 61.14/374.78 when the run draws none",
        min=0.0,
    )
    task_cv: float | None = option(
        None,
        "CV of the per-task lognormal noise around factor x mean; default: the run's task_cv",
        min=0.0,
    )

    def resolve(self, instance: Instance, timing: TimingModel) -> tuple[float, float]:
        """``(c_f, c_e)``: the options, else the run's timing model (module docstring). A run
        whose participants all have factor 1 (``participant_cv = 0``, e.g. the within-subject
        model, whose ``session_factor`` the policies do not know) gets the paper's CV, the SD
        of a session's speed over participants and sessions."""
        cf = self.prior_cv
        if cf is None:
            cf = timing.cv_for(instance) or PAPER_CV
        ce = self.task_cv if self.task_cv is not None else timing.task_cv
        return float(cf), float(ce)


@dataclass(frozen=True)
class Posterior:
    """The normal posterior ``N(mean, var)`` of ``log f`` after ``n`` observed tasks."""

    mean: float
    var: float
    n: int

    @property
    def factor(self) -> float:
        """The posterior mean of the speed factor, ``exp(mean + var / 2)``."""
        return math.exp(self.mean + self.var / 2)

    @property
    def median(self) -> float:
        return math.exp(self.mean)


def posterior(prior_cv: float, task_cv: float, log_ratios: list[float]) -> Posterior:
    """The posterior of ``log f`` given ``log(d_t / mu_t)`` of the observed tasks (module
    docstring: the conjugate normal update)."""
    s2 = math.log1p(prior_cv * prior_cv)
    m0 = -s2 / 2
    n = len(log_ratios)
    if n == 0 or s2 == 0:
        return Posterior(m0, s2, n)
    sigma2 = math.log1p(task_cv * task_cv)
    ys = [y + sigma2 / 2 for y in log_ratios]
    if sigma2 == 0:  # exact observations: the prior no longer matters
        return Posterior(math.fsum(ys) / n, 0.0, n)
    precision = 1 / s2 + n / sigma2
    return Posterior((m0 / s2 + math.fsum(ys) / sigma2) / precision, 1 / precision, n)


class PaceEstimator:
    """The posterior of one run's speed factor from ``SimState.observed`` (tasks with a
    positive mean and duration; the per-kit pickup ``o_H`` is not a task and not scaled)."""

    def __init__(self, instance: Instance, prior_cv: float, task_cv: float) -> None:
        self.instance = instance
        self.prior_cv = prior_cv
        self.task_cv = task_cv

    def posterior(self, observed: Mapping[str, float]) -> Posterior:
        ys = []
        for t in observed:  # (math.fsum: the order does not matter)
            mu, d = self.instance.human_time(t), observed[t]
            if mu > 0 and d > 0:
                ys.append(math.log(d / mu))
        return posterior(self.prior_cv, self.task_cv, ys)
