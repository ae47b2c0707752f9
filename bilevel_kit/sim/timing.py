"""Task-time model of the shop-floor simulation: sampled participants and robot pick times.

Why a model at all: the paper samples "a participant's task times and the robot's task times as
recorded from the user study" (Section V-B), but publishes only the per-table summary of the
human's active time, 374.78 s mean and 61.14 s SD. We therefore draw *participants*:

* Human. Per unit one participant with speed factor ``s`` (mean 1, SD ``participant_cv``;
  lognormal by default, or a normal truncated to ``s > 0`` by resampling). Every task of that
  unit takes ``mean_i * s * e_i`` where ``e_i`` is independent per-task noise (lognormal, mean
  1, SD ``task_cv``; **0 by default**). With ``task_cv = 0`` the per-unit total is
  ``s * sum(mean_i)``, so for the table (means summing to 374.78 s) it has mean 374.78 s and SD
  374.78 * cv = 61.14 s, exactly the paper's numbers. The instance's per-task ``human_sd``
  fields are *not* used by default: for the table they are ``mean_i * 61.14 / 374.78``, i.e.
  this same perfectly correlated model; ``participant_cv=None`` derives the factor's SD from
  the instance instead (``sum(sd_i) / sum(mean_i)`` over one unit's tasks).
  The per-kit overhead ``o_H`` (taking the parts off the tray) is not scaled by ``s``.
  ``session_factor`` multiplies every sampled human time of a run on top of that: a
  within-subject study (:class:`WithinSubjectModel`) draws one factor per participant and
  session and runs with ``participant_cv = 0``; the policies plan without it (as a real policy,
  they do not know the participant's speed).
* Robot. Each part's pick time is the instance's ``pick_time`` (after ``robot_scale``), times
  independent lognormal noise of SD ``robot_cv`` (0 by default: deterministic picks). A task
  with a ``robot_time`` override spreads it evenly over its parts, or is one block when it has
  no parts.

Calibration knobs (``human_scale``, ``robot_scale``, ``kit_overhead_*``) are applied to the
instance itself (:func:`bilevel_kit.sim.params.effective_instance`), so the policies plan with
the same expected times the simulation samples around.

All times for a run are drawn up front from dedicated random streams, so they do not depend on
the policy: two policies run with the same seed see the same participants (common random
numbers, which makes paired comparisons between policies much sharper).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import UsageError
from ..instance import Instance

#: The paper's per-table human active time (Section VI): mean and SD in seconds.
PAPER_TABLE_MEAN = 374.78
PAPER_TABLE_SD = 61.14
#: Coefficient of variation of a participant's speed implied by those two numbers.
PAPER_CV = PAPER_TABLE_SD / PAPER_TABLE_MEAN

_DISTS = ("lognormal", "normal")


@dataclass(frozen=True)
class TimingModel:
    """How task times are drawn, plus the calibration knobs ``paper_repro`` may fit.

    Fields:
        participant_cv: SD of the per-unit participant speed factor (mean 1). Default: the
            paper's 61.14 / 374.78. ``None``: from the instance, ``sum(sd_i) / sum(mean_i)``.
        participant_dist: ``"lognormal"`` (default) or ``"normal"`` (truncated to > 0).
        task_cv: SD of independent per-task multiplicative noise (mean 1); default 0.
        human_scale: multiplies every task's mean human time (calibration).
        robot_scale: multiplies every pick time and robot-time override (calibration).
        robot_cv: SD of independent multiplicative noise per pick (mean 1); default 0.
        kit_overhead_robot: overrides the instance's ``o_R`` when not None (s per kit).
        kit_overhead_human: overrides the instance's ``o_H`` when not None (the human's
            per-kit pickup time).
        session_factor: multiplies every sampled human task time of the run (not the
            instance's means, so the policies do not see it); default 1. The within-subject
            participant model (:class:`WithinSubjectModel`) sets it per participant x session.
    """

    participant_cv: float | None = PAPER_CV
    participant_dist: str = "lognormal"
    task_cv: float = 0.0
    human_scale: float = 1.0
    robot_scale: float = 1.0
    robot_cv: float = 0.0
    kit_overhead_robot: float | None = None
    kit_overhead_human: float | None = None
    session_factor: float = 1.0

    def __post_init__(self) -> None:
        if self.participant_dist not in _DISTS:
            raise UsageError(
                f"participant_dist must be one of {', '.join(_DISTS)}, "
                f"got {self.participant_dist!r}"
            )
        for name in ("task_cv", "robot_cv", "participant_cv"):
            v = getattr(self, name)
            if v is not None and (not math.isfinite(v) or v < 0):
                raise UsageError(f"{name} must be finite and >= 0, got {v!r}")
        for name in ("human_scale", "robot_scale", "session_factor"):
            v = getattr(self, name)
            if not math.isfinite(v) or v <= 0:
                raise UsageError(f"{name} must be finite and > 0, got {v!r}")
        for name in ("kit_overhead_robot", "kit_overhead_human"):
            v = getattr(self, name)
            if v is not None and (not math.isfinite(v) or v < 0):
                raise UsageError(f"{name} must be finite and >= 0, got {v!r}")

    @classmethod
    def deterministic(cls, **changes: Any) -> TimingModel:
        """No randomness at all: humans take the mean times, picks the instance's times."""
        return cls(**{"participant_cv": 0.0, "task_cv": 0.0, "robot_cv": 0.0, **changes})

    def cv_for(self, instance: Instance) -> float:
        """The participant factor's SD for this instance (resolves ``participant_cv=None``)."""
        if self.participant_cv is not None:
            return self.participant_cv
        total = sum(t.human_mean for t in instance.base_tasks)
        return sum(t.human_sd for t in instance.base_tasks) / total if total > 0 else 0.0


@dataclass(frozen=True)
class SampledTimes:
    """The times of one run: per task the human duration and the robot's pick durations.

    ``picks[task]`` holds ``(part type or None, seconds)`` in picking order; ``None`` marks the
    single block of a task with a robot-time override and no parts.
    """

    human: dict[str, float]
    picks: dict[str, tuple[tuple[str | None, float], ...]]
    speed: tuple[float, ...] = field(default=())  # participant factor per unit

    def robot(self, task: str) -> float:
        return sum(d for _, d in self.picks[task])

    def robot_times(self) -> dict[str, float]:
        return {t: self.robot(t) for t in self.picks}


def _mean_one(rng: np.random.Generator, cv: float, size: int, dist: str) -> np.ndarray:
    """``size`` positive factors with mean 1 and SD ``cv``."""
    if cv == 0 or size == 0:
        return np.ones(size)
    if dist == "lognormal":
        sigma2 = math.log1p(cv * cv)
        return rng.lognormal(-sigma2 / 2, math.sqrt(sigma2), size)
    out = rng.normal(1.0, cv, size)
    bad = out <= 0
    while bad.any():  # truncation by resampling; P(s <= 0) is ~1e-9 at the paper's cv
        out[bad] = rng.normal(1.0, cv, int(bad.sum()))
        bad = out <= 0
    return out


def sample_participants(
    instance: Instance, model: TimingModel, rng: np.random.Generator, n: int
) -> np.ndarray:
    """``n`` participant speed factors (mean 1, SD ``model.cv_for(instance)``)."""
    return _mean_one(rng, model.cv_for(instance), n, model.participant_dist)


def sample_times(
    instance: Instance,
    model: TimingModel,
    human_rng: np.random.Generator,
    robot_rng: np.random.Generator,
) -> SampledTimes:
    """Human and robot times of every task of ``instance`` (already the effective instance:
    scales and overheads applied, units expanded)."""
    speed = sample_participants(instance, model, human_rng, instance.units)
    tasks = instance.tasks
    noise = _mean_one(human_rng, model.task_cv, len(tasks), "lognormal")
    f = model.session_factor
    human = {
        t.id: t.human_mean * float(speed[t.unit - 1]) * float(e) * f
        for t, e in zip(tasks, noise, strict=True)
    }
    picks: dict[str, tuple[tuple[str | None, float], ...]] = {}
    n_picks = sum(max(1, sum(n for _, n in t.parts)) for t in tasks)
    rnoise = iter(_mean_one(robot_rng, model.robot_cv, n_picks, "lognormal").tolist())
    for t in tasks:
        n_parts = sum(n for _, n in t.parts)
        if t.robot_time is not None and n_parts == 0:
            picks[t.id] = ((None, t.robot_time * next(rnoise)),)
            continue
        if n_parts == 0:
            next(rnoise)
            picks[t.id] = ()
            continue
        each = t.robot_time / n_parts if t.robot_time is not None else None
        seq = []
        for p, n in t.parts:
            base = each if each is not None else instance.part_types[p].pick_time
            seq += [(p, base * next(rnoise)) for _ in range(n)]
        picks[t.id] = tuple(seq)
    return SampledTimes(human, picks, tuple(float(s) for s in speed))


def counterbalanced_orders(n_conditions: int) -> list[tuple[int, ...]]:
    """Every order of ``n_conditions`` conditions (3 -> the 6 orders a within-subject study
    counterbalances over; participant ``i`` gets order ``i % 6``)."""
    from itertools import permutations

    return list(permutations(range(n_conditions)))


@dataclass(frozen=True)
class WithinSubjectModel:
    """A participant's speed in each session of a within-subject study (paper Section V-A:
    18 participants, 3 conditions, counterbalanced orders).

    A session's human times are the means times ``f = exp(a_p + b_pc + c) * L[position]``:

    * ``a_p ~ N(0, speed_sd^2)``: the participant's own speed, the same in every session;
    * ``b_pc ~ N(0, within_cv^2)``: participant x condition (how this participant did in this
      session: attention, the condition's rhythm); this is what a repeated-measures ANOVA
      tests the conditions against;
    * ``L = (1 + learning, 1, 1 - learning)`` by the session's position in the participant's
      counterbalanced order (later sessions are faster; mean 1 over positions);
    * ``c = -(speed_sd^2 + within_cv^2) / 2``, so ``E[f] = 1``.

    Sources: ``total_cv`` is the paper's SD / mean of the human's active time per table over all
    sessions, 61.14 / 374.78 (Section VI), and ``speed_sd`` is what is left of its log-variance
    after the two within-participant components, so a session's active time keeps (about) the
    paper's mean and SD; ``within_cv`` is fitted by the reproduction
    (docs/reproduction.md); ``learning`` is assumed (the paper counterbalanced and let the
    participants practise "to minimize learning effects", and reports no size).
    """

    total_cv: float = PAPER_CV
    within_cv: float = 0.0
    learning: float = 0.05

    def __post_init__(self) -> None:
        for name in ("total_cv", "within_cv"):
            v = getattr(self, name)
            if not math.isfinite(v) or v < 0:
                raise UsageError(f"{name} must be finite and >= 0, got {v!r}")
        if not 0 <= self.learning < 1:
            raise UsageError(f"learning must be in [0, 1), got {self.learning!r}")
        if self.speed_var < 0:
            raise UsageError(
                f"within_cv={self.within_cv:g} and learning={self.learning:g} leave no "
                f"between-participant variance of total_cv={self.total_cv:g}"
            )

    @property
    def learning_factors(self) -> tuple[float, float, float]:
        return (1.0 + self.learning, 1.0, 1.0 - self.learning)

    @property
    def speed_var(self) -> float:
        """Log-variance of the participant's own speed ``a_p``."""
        logs = np.log(self.learning_factors)
        return math.log1p(self.total_cv**2) - self.within_cv**2 - float(np.var(logs))

    @property
    def speed_sd(self) -> float:
        return math.sqrt(max(self.speed_var, 0.0))

    def session_factors(self, z_speed: np.ndarray, z_within: np.ndarray) -> np.ndarray:
        """Factors ``f[p, c]`` from standard normals ``z_speed[p]`` and ``z_within[p, c]``
        (common random numbers: the same z at every parameter value), with participant ``p``
        in counterbalanced order ``p % n_orders`` (condition ``c`` at position
        ``order.index(c)``)."""
        n, k = z_within.shape
        if k > 3:
            raise UsageError("the learning effect is defined for at most 3 sessions")
        orders = counterbalanced_orders(k)
        pos = np.array([[orders[p % len(orders)].index(c) for c in range(k)] for p in range(n)])
        lf = np.asarray(self.learning_factors)[pos]
        c0 = -(self.speed_var + self.within_cv**2) / 2
        return np.exp(self.speed_sd * z_speed[:, None] + self.within_cv * z_within + c0) * lf
