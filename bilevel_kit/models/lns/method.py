r"""The registered method ``lns``: a large-neighbourhood search with exact CP-SAT windows.

A matheuristic (docs/formulations.md, "Large-neighbourhood search"):

1. **Start** from the best quick plan: the baselines (single-task, whole-assembly), the cuts of
   the topological order (fixed sizes and the exact one-tray cut of :mod:`..segment`), the
   Johnson-priority order's, and (``start="auto"``) greedy-ce's plan within ``start_share`` of
   the time limit (when that is at least 2 s).
2. **Bound**: the best proven lower bound of :mod:`..relax` (closed forms, heads and tails, the
   kit-count LP; at most ``bound_share`` of the time limit). It is the result's ``bound``,
   never the search's own incumbent; a plan that meets it is optimal and ends the run.
3. **Windows**: free the tasks of a run of consecutive kits (about ``window`` tasks) and
   re-optimise them exactly with CP-SAT (:mod:`.window`: the whole plan's makespan, the rest
   fixed), keeping a strictly better plan. Windows start at the kits in a random order (a
   *sweep*); with one tray the task order of a sweep's plan is cut again exactly
   (:func:`.start.exact_cut`) when the sweep improved it; a sweep without improvement makes
   the windows half as large again, up to
   ``max_window``; a sweep without improvement at that size is a local optimum and ends the run.
   With option ``stall``, ``stall`` windows in a row without improvement end it earlier
   (counted in windows, so deterministic; the exact models' LNS first, :mod:`..exact.lns_first`).

**Several stations, and the human idle** (``objective`` ``sum_completion`` or ``human_idle``):
the search of :mod:`.stations` (moves and enumerated windows timed by the timeline itself, no
CP-SAT windows; docs/stations.md#lns-with-several-stations), with the options of
:data:`STATION_OPTIONS`. With one station ``sum_completion`` is the makespan.

**From a given plan** (``lns(..., start_plan=, known_bound=)``, what ``cpsat`` and ``milp``
hand over when their model is not built, :mod:`.fallback`): the given plan is the first start
(``start_method`` ``incumbent``; a quick start replaces it only when strictly better, so the
result is never worse), its layouts are kept, and a given proven bound replaces step 2.

**Determinism.** Every random choice draws from ``numpy.random.default_rng(seed)``, and every
window solve is limited by CP-SAT's deterministic time (``window_time``), with one worker or
with interleaved workers (deterministic too), so a run to a fixed number of windows
(``iterations``), or to its local optimum, gives the same plan for a seed and a worker count
(greedy-ce's start included when it finishes within its share; packing calls that time out
count as "does not fit"). Under a wall-clock limit the run ends after the last window that
finished: its plan is that of a prefix of the same sequence of windows, and a window cut off
by the clock is discarded.

**Result.** ``status`` ``optimal`` only when the plan meets the proven bound, else ``feasible``;
``bound`` the proven bound; ``extra``: ``start_method``, ``start_makespan``, ``iterations``
(windows solved), ``improvements``, ``windows_optimal`` (windows CP-SAT proved), ``sweeps``,
``window`` (the last window size), ``stop`` (``optimal``, ``local_optimum``, ``stall``,
``iterations``, ``time_limit``), ``bound_source`` and ``bound_sources`` (every bound computed, s),
``bound_time_s``, ``start_time_s``, ``makespan``, ``n_kits``, ``gap``, ``wall_time_s``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from ...instance import Instance
from ...methods import MethodOutput, Status, gap
from ...objectives import get as get_objective
from ...objectives import scenario_objectives
from ...options import option
from ...plan import Kit, Placement, Plan, evaluate
from ..budget import Budget
from ..common import Packer, pack_time_limit, unfit_outcome
from ..cpsat.scaling import scale_times, scaled_makespan
from ..exact.station_options import HONOURED, Refused, check_station_options, declare
from .fit import FastFit
from .start import CUT_SHARE
from .window import Context, solve_window

#: Seconds kept back for the final layouts, plus this share of the time limit.
MARGIN_S, MARGIN_SHARE = 0.3, 0.02
#: The most kits a window frees.
WINDOW_KITS = 8
#: The share of the time left the exact one-tray cut after a sweep may use.
RECUT_SHARE = 0.1
#: The options only the scenario objectives read: set with another, a usage error
#: (docs/robust.md#options-of-the-scenario-objectives).
SCENARIO_ONLY = {"objective": scenario_objectives}


@dataclass(frozen=True)
class LnsOptions:
    """Options of the registered method ``lns``."""

    iterations: int | None = option(
        None, "windows to solve (none: until the time limit or a local optimum)"
    )
    stall: int | None = option(
        None,
        "windows in a row without improvement that end the run (none: sweeps to a local optimum)",
        min=1,
    )
    window: int = option(24, "tasks freed per window at first", min=2)
    max_window: int = option(60, "largest window (tasks) after sweeps without gain", min=2)
    window_time: float = option(
        1.0, "CP-SAT deterministic time per window (about seconds)", min=0.01
    )
    workers: int = option(1, "CP-SAT workers per window (several: interleaved)", min=1)
    start: Literal["auto", "quick"] = option(
        "auto", "start plans: auto (quick plans and greedy-ce) or quick (no greedy-ce)"
    )
    start_share: float = option(0.1, "share of the time limit for greedy-ce's start", min=0.0)
    cut_share: float = option(
        CUT_SHARE,
        "share of the time limit for the start plans cut from task orders (the exact "
        "one-tray cut and the fixed-size cuts)",
        min=0.0,
        max=1.0,
    )
    bound_share: float = option(0.1, "share of the time limit for the kit-count LP bound", min=0.0)
    objective: Literal[
        "makespan", "expected_makespan", "cvar_makespan", "sum_completion", "human_idle"
    ] = option(
        "makespan",
        "makespan (mean times), expected_makespan (sample average over "
        "scenarios of the human times), cvar_makespan (their CVaR at level alpha), "
        "docs/formulations.md; sum_completion or human_idle (docs/stations.md)",
    )
    alpha: float = option(
        0.9,
        "CVaR level of cvar_makespan: the mean of the worst (1 - alpha) share "
        "of the scenarios (0: their average)",
        min=0.0,
        below=1.0,
        needs={"objective": ("cvar_makespan",)},
    )
    scenarios: int = option(20, "scenarios of the human times", min=1, needs=SCENARIO_ONLY)
    scenario_seed: int = option(0, "seed of the scenarios", min=0, needs=SCENARIO_ONLY)
    cv: float | None = option(
        None,
        "coefficient of variation of every human time in the scenarios (none: "
        "each task's sd / mean)",
        min=0.0,
        needs=SCENARIO_ONLY,
    )


#: The options with several stations (docs/stations.md#lns-with-several-stations): the search
#: of :mod:`.stations` has no CP-SAT windows and no kit-count LP, and the scenario objectives
#: are the one-station SAA's.
_NO_WINDOWS = "the station search's windows are enumerated, at most 5 tasks"
_SCENARIOS = "the scenario objectives are modelled for one station"
STATION_OPTIONS = declare(
    LnsOptions,
    {
        "iterations": HONOURED,
        "stall": HONOURED,
        "window": Refused(_NO_WINDOWS),
        "max_window": Refused(_NO_WINDOWS),
        "window_time": Refused(_NO_WINDOWS),
        "workers": Refused(_NO_WINDOWS),
        "start": HONOURED,
        "start_share": HONOURED,
        "cut_share": HONOURED,
        "bound_share": Refused("the bound is the objective's closed form"),
        "objective": Refused(_SCENARIOS, also=("sum_completion", "human_idle")),
        "alpha": Refused(_SCENARIOS),
        "scenarios": Refused(_SCENARIOS),
        "scenario_seed": Refused(_SCENARIOS),
        "cv": Refused(_SCENARIOS),
    },
)


def lns(
    instance: Instance,
    options: LnsOptions,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    start_plan: Plan | None = None,
    known_bound: float | None = None,
) -> MethodOutput:
    """Registered method ``lns`` (module docstring); ``start_plan`` a valid plan to start from,
    ``known_bound`` a proven makespan bound (then none is computed). ``objective=
    "expected_makespan"`` or ``"cvar_makespan"``: :func:`.saa.lns_saa`; several stations or
    the human idle: :func:`.stations.station_search` (its options: :data:`STATION_OPTIONS`)."""
    check_station_options(instance, "lns", options, STATION_OPTIONS)
    if not instance.stations and get_objective(options.objective).makespan_with_one_station:
        options = replace(options, objective="makespan")  # sum_completion: the makespan
    if get_objective(options.objective).scenarios:  # the sample average (docs/formulations.md)
        from .saa import lns_saa

        return lns_saa(
            instance,
            options,
            seed=seed,
            time_limit=time_limit,
            start_plan=start_plan,
            mean_time=lns,
        )
    budget = Budget(time_limit)
    stop_at = budget.cut(MARGIN_S + MARGIN_SHARE * budget.time_limit)
    sc = scale_times(instance, 0.1, True)
    packer = Packer(instance, pack_time_limit(budget), stop_at)
    extra: dict[str, Any] = {}
    unfit = None if start_plan is not None else packer.task_not_fitting()  # a plan: all fit
    if unfit is not None:
        return MethodOutput(None, unfit_outcome(unfit, extra), None, extra)
    if instance.stations or not get_objective(options.objective).is_makespan:
        from .stations import station_search

        return station_search(
            instance,
            options,
            budget,
            stop_at,
            FastFit(instance, packer),
            seed=seed,
            start_plan=start_plan,
            known_bound=known_bound,
            greedy_at=budget.cut(MARGIN_S),
        )
    run = _Run(instance, options, budget, stop_at, sc, packer, seed, extra)
    run.start(start_plan)
    if run.kits is None:
        extra["reason"] = "no start plan within the time limit"
        return MethodOutput(None, Status.UNKNOWN, run.bound_value(), extra)
    if known_bound is None:
        run.prove()
    else:
        run.bound = known_bound
    if not run.optimal():
        run.search()
    return run.finish()


@dataclass
class _Run:
    """One run's state: the incumbent (kits of task indices, scaled and real makespan), the
    layouts known for its kits, the proven bound and the counters of the module docstring."""

    instance: Instance
    options: LnsOptions
    budget: Budget
    stop_at: Budget
    sc: Any
    packer: Packer
    seed: int
    extra: dict[str, Any]
    kits: list[list[int]] | None = None
    scaled: int = 0
    real: float = math.inf
    layouts: dict[tuple[int, ...], tuple[Placement, ...]] = field(default_factory=dict)
    bound: float | None = None
    fit: Any = None  # the run's FastFit (start)
    stalled: int = 0  # windows since the last improvement (option ``stall``)

    # -- 1. start --------------------------------------------------------------------------
    def start(self, given: Plan | None = None) -> None:
        """The best of ``given`` and the start plans (module docstring)."""
        from .start import start_plans

        t0 = self.budget.elapsed()
        self.fit = FastFit(self.instance, self.packer)
        if given is not None:  # its layouts are valid: its kits and their parts fit
            for kit in given.kits:
                if kit.layout:
                    self.packer.learn(self.instance.kit_parts(kit.tasks), kit.layout)
            self._consider(given, "incumbent")
        plans = start_plans(
            self.instance,
            self.fit,
            self.stop_at,
            greedy=self.options.start == "auto",
            share=self.options.start_share,
            cut_share=self.options.cut_share,
            seed=self.seed,
        )
        for name, plan in plans:
            self._consider(plan, name)
        self.extra["start_makespan"] = None if self.kits is None else self.real
        self.extra["start_time_s"] = self.budget.elapsed() - t0

    def _consider(self, plan: Plan, name: str) -> bool:
        """Take ``plan`` if it is better than the incumbent (its layouts kept)."""
        idx = self.instance.index
        kits = [[idx[t] for t in k.tasks] for k in plan.kits if k.tasks]
        real = evaluate(self.instance, plan).makespan
        if real >= self.real - 1e-9:
            return False
        self.kits, self.real, self.scaled = kits, real, scaled_makespan(self.sc, kits)
        self.extra["start_method"] = name
        for k in plan.kits:
            if k.layout:
                self.layouts[tuple(idx[t] for t in k.tasks)] = k.layout
        return True

    # -- 2. bound ----------------------------------------------------------------------------
    def prove(self) -> None:
        """The proven bound of :mod:`..relax` within ``bound_share`` of the time limit."""
        from ..relax import proven_bound

        t0 = self.budget.elapsed()
        share = self.options.bound_share * self.budget.time_limit
        left = max(0.0, min(share, self.stop_at.remaining()))
        found = proven_bound(self.instance, time_limit=left, upper=self.real, lp=left > 0.05)
        self.bound = found.value
        self.extra.update(
            bound_source=found.source,
            bound_sources=found.sources,
            bound_time_s=self.budget.elapsed() - t0,
        )

    def bound_value(self) -> float | None:
        from ...bounds import best_bound

        return self.bound if self.bound is not None else best_bound(self.instance)

    def optimal(self) -> bool:
        return self.bound is not None and self.real <= self.bound + 1e-6

    # -- 3. windows --------------------------------------------------------------------------
    def search(self) -> None:
        """Sweeps of windows (module docstring) until optimal, a local optimum, the iteration
        budget or the time limit."""
        opts = self.options
        ctx = Context.of(self.instance, self.sc, self.fit, opts.workers, opts.window_time)
        rng = np.random.default_rng(self.seed)
        size = opts.window
        counts = {"iterations": 0, "improvements": 0, "windows_optimal": 0, "sweeps": 0}
        stop = "local_optimum"
        while stop == "local_optimum":
            counts["sweeps"] += 1
            gained, stop = self._sweep(ctx, rng, size, counts)
            if stop != "local_optimum":
                break
            if not gained:
                if size >= opts.max_window:
                    break
                size = min(opts.max_window, math.ceil(1.5 * size))
        self.extra.update(counts, window=size, stop=stop)

    def _sweep(
        self, ctx: Context, rng: np.random.Generator, size: int, counts: dict[str, int]
    ) -> tuple[bool, str]:
        """One sweep: a window from every kit in a random order; (any gain, why it ended:
        ``local_optimum`` when the sweep is complete)."""
        assert self.kits is not None
        gained = False
        for k0 in rng.permutation(len(self.kits)).tolist():
            if self.optimal():
                return gained, "optimal"
            if self.options.iterations is not None and counts["iterations"] >= (
                self.options.iterations
            ):
                return gained, "iterations"
            if self.stop_at.remaining() <= 0.05:
                return gained, "time_limit"
            if self.options.stall is not None and self.stalled >= self.options.stall:
                return gained, "stall"
            if k0 >= len(self.kits) - 1 and len(self.kits) > 1:
                continue  # a window of one last kit: covered by the windows before it
            k1 = _window_end(self.kits, k0, size)
            out = solve_window(
                ctx, self.kits, k0, k1, self.scaled, self.seed, self.stop_at.remaining()
            )
            if out.stopped:
                return gained, "time_limit"
            counts["iterations"] += 1
            counts["windows_optimal"] += out.optimal
            self.stalled += 1
            if out.kits is not None and self._improve(self.kits[:k0] + out.kits + self.kits[k1:]):
                counts["improvements"] += 1
                gained, self.stalled = True, 0
        if gained and self._recut():
            counts["improvements"] += 1
        return gained, "local_optimum"

    def _improve(self, kits: list[list[int]]) -> bool:
        """Take ``kits`` if strictly better."""
        scaled = scaled_makespan(self.sc, kits)
        if scaled >= self.scaled:
            return False
        plan = Plan(tuple(Kit(tuple(self.instance.tasks[i].id for i in k)) for k in kits))
        real = evaluate(self.instance, plan).makespan
        if real >= self.real - 1e-9:
            return False
        self.kits, self.scaled, self.real = kits, scaled, real
        return True

    def _recut(self) -> bool:
        """With one tray, the exact cut of the plan's task order (:func:`..common.best_cut`),
        its packing calls within :data:`RECUT_SHARE` of the time left, if it is better."""
        from .start import exact_cut

        assert self.kits is not None
        if self.instance.params_of().tray_limit != 1:  # (lns: one station)
            return False
        ids = [self.instance.tasks[i].id for k in self.kits for i in k]
        cut = exact_cut(self.instance, ids, self.fit, self.stop_at.next(RECUT_SHARE))
        if cut is None:
            return False
        idx = self.instance.index
        return self._improve([[idx[t] for t in k] for k in cut])

    # -- the result ----------------------------------------------------------------------------
    def finish(self) -> MethodOutput:
        """The plan with a layout for every kit (known ones kept, the oracle's otherwise)."""
        assert self.kits is not None
        inst = self.instance
        out = []
        for kit in self.kits:
            tasks = tuple(inst.tasks[i].id for i in kit)
            layout = self.layouts.get(tuple(kit))
            if layout is None:
                layout = self.fit.layout(tasks)
            if layout is None and inst.kit_parts(tasks):
                self.extra["reason"] = "no layout for some kit within the time limit"
                return MethodOutput(None, Status.UNKNOWN, self.bound_value(), self.extra)
            out.append(Kit(tasks, layout or ()))
        plan = Plan(tuple(out))
        real = evaluate(inst, plan).makespan
        bound = self.bound_value()
        status = Status.OPTIMAL if bound is not None and real <= bound + 1e-6 else Status.FEASIBLE
        self.extra.update(
            makespan=real,
            n_kits=len(out),
            gap=gap(real, bound),
            wall_time_s=self.budget.elapsed(),
        )
        self.extra.setdefault("stop", "optimal" if status == Status.OPTIMAL else "time_limit")
        return MethodOutput(plan, status, bound, self.extra)


def _window_end(kits: Sequence[Sequence[int]], k0: int, size: int) -> int:
    """The end of the window from kit ``k0``: kits while at most ``size`` tasks and
    :data:`WINDOW_KITS` kits, two at least."""
    k1 = min(len(kits), k0 + 2)
    total = sum(len(k) for k in kits[k0:k1])
    while k1 < len(kits) and total + len(kits[k1]) <= size and k1 - k0 < WINDOW_KITS:
        total += len(kits[k1])
        k1 += 1
    return k1
