"""Policies that plan with the human's pace: learnt online (``*-adaptive``) or known
(``*-oracle``, a reference); docs/simulation.md#adaptive-policies.

``optimized`` and ``cpsat-rolling`` plan with the instance's mean task times. Their variants
here plan every decision with ``factor * mean`` for every task the human has not finished, in
the decision's model (greedy-ce's ``H`` in terms (5)-(6); the CP-SAT window's human times) and
in the human's remaining work ``H_rem``, recomputed from the observed progress
(:class:`~.state.HumanProgress`) with the same scaled durations:

* ``optimized-adaptive``, ``cpsat-rolling-adaptive``: ``factor`` is the posterior mean of the
  participant's speed factor given the durations of the tasks finished so far
  (``SimState.observed``), the conjugate update of :mod:`.pace` under the participant model's
  lognormal prior. Before the first task is finished it is exactly 1: the fixed policy's
  decision. One factor for the whole run (one participant, as in the within-subject model and
  the adaptive study); under the default timing model with several units, where every unit is
  a new participant, this pools different people (a misspecification, documented).
* ``optimized-oracle``, ``cpsat-rolling-oracle``: ``factor`` is the participant's true speed
  factor of each task's unit. The simulator hands it over in ``SimState.true_speed`` only to
  policies whose class sets ``sees_true_speed = True``, so no other policy can read it; the
  oracle still does not know the per-task noise (``task_cv``) or the future supply.

With ``human_estimate="oracle"`` (``SimParams``) the state's ``human_remaining`` uses the sampled
durations; these policies ignore it and recompute ``H_rem`` with their own factor.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ..errors import UsageError
from ..instance import Instance
from ..plan import Kit
from .cpsat_rolling import CPSATRollingOptions, CPSATRollingPolicy
from .pace import PaceEstimator, PaceOptions, Posterior
from .policies import OptimizedPolicy
from .state import PolicyBase, SimState
from .timing import TimingModel

if TYPE_CHECKING:
    from .params import SimParams

#: One factor for every task, or one per task in instance order.
Scale = float | np.ndarray


class Pace:
    """The factor a paced policy plans with at each decision (module docstring)."""

    def __init__(
        self, instance: Instance, params: SimParams | None, options: PaceOptions, oracle: bool
    ) -> None:
        self.instance = instance
        self.oracle = oracle
        timing = params.timing if params is not None else TimingModel()
        self.estimator = PaceEstimator(instance, *options.resolve(instance, timing))
        self._unit = np.array([t.unit - 1 for t in instance.tasks], dtype=np.int64)
        #: the posterior at each decision of the current run (adaptive only)
        self.posteriors: list[Posterior] = []

    def reset(self) -> None:
        self.posteriors = []

    def scale(self, state: SimState) -> Scale:
        if self.oracle:
            if len(state.true_speed) != self.instance.units:
                raise UsageError(
                    "an oracle policy needs the participant's true speed, which only the "
                    "simulator gives (SimState.true_speed)"
                )
            return np.asarray(state.true_speed, dtype=float)[self._unit]
        post = self.estimator.posterior(state.observed)
        self.posteriors.append(post)
        return post.factor

    def duration(self, scale: Scale) -> Callable[[str], float]:
        """A task's planned human time: its mean times its factor (exactly the mean at 1)."""
        inst = self.instance
        if isinstance(scale, np.ndarray):
            per_task = scale
            return lambda t: inst.human_time(t) * float(per_task[inst.index[t]])
        return lambda t: inst.human_time(t) * scale

    def apply(self, state: SimState) -> tuple[SimState, Scale, Callable[[str], float]]:
        """The state with ``human_remaining`` recomputed at the planned pace, the scale and the
        planned duration of a task."""
        scale = self.scale(state)
        dur = self.duration(scale)
        return replace(state, human_remaining=state.progress.remaining(dur)), scale, dur


def _pace_options(options: object) -> PaceOptions:
    """The pace options among a policy's options (the oracles take none: defaults)."""
    return options if isinstance(options, PaceOptions) else PaceOptions()


class OptimizedAdaptivePolicy(PolicyBase):
    """``optimized`` planning with the posterior mean of the participant's speed factor."""

    name: ClassVar[str] = "optimized-adaptive"
    sees_true_speed: ClassVar[bool] = False

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        self.base = OptimizedPolicy(instance, seed=seed, params=params)
        self.pace = Pace(instance, params, _pace_options(options), self.sees_true_speed)

    def reset(self) -> None:
        self.base.reset()
        self.pace.reset()
        self.base.greedy.set_human_scale(1.0)

    def decide(self, state: SimState) -> Kit | None:
        paced, scale, _ = self.pace.apply(state)
        self.base.greedy.set_human_scale(scale)
        return self.base.greedy.decide(paced.policy_state())


class OptimizedOraclePolicy(OptimizedAdaptivePolicy):
    """``optimized`` planning with the participant's true speed factor (a reference)."""

    name: ClassVar[str] = "optimized-oracle"
    sees_true_speed: ClassVar[bool] = True


@dataclass(frozen=True)
class CPSATRollingAdaptiveOptions(CPSATRollingOptions, PaceOptions):
    """``cpsat-rolling``'s options plus the pace prior's (:class:`~.pace.PaceOptions`)."""


class CPSATRollingAdaptivePolicy(CPSATRollingPolicy):
    """``cpsat-rolling`` planning each window with the posterior mean of the speed factor."""

    name: ClassVar[str] = "cpsat-rolling-adaptive"
    sees_true_speed: ClassVar[bool] = False

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        super()._setup(instance, seed, params, options)
        self.pace = Pace(instance, params, _pace_options(options), self.sees_true_speed)

    def reset(self) -> None:
        super().reset()
        self.pace.reset()
        self.human_time = self.instance.human_time

    def decide(self, state: SimState) -> Kit | None:
        paced, _, self.human_time = self.pace.apply(state)
        return super().decide(paced)


class CPSATRollingOraclePolicy(CPSATRollingAdaptivePolicy):
    """``cpsat-rolling`` planning with the participant's true speed factor (a reference)."""

    name: ClassVar[str] = "cpsat-rolling-oracle"
    sees_true_speed: ClassVar[bool] = True
