r"""``lns`` with several assembly stations, and with the human idle as objective
(docs/stations.md#lns-with-several-stations, docs/timeline.md#several-stations).

The CP-SAT windows of :mod:`.window` model one station's timeline and its makespan; here the
search is over the plan itself, every candidate timed by the one timeline rule on the integer
grid of :mod:`..cpsat.scaling` (:func:`~..cpsat.scaling.scaled_objective`, held to
:func:`bilevel_kit.plan.evaluate` by property tests) and taken only when
:func:`~bilevel_kit.plan.evaluate`'s value of the objective is strictly better:

1. **Start** from the best of the given plan (``start_plan``), single-task's and
   whole-assembly's plans (which interleave the stations by earliest need), the fixed-size
   cuts of each station's topological order, interleaved the same way
   (:func:`.start.station_cuts`, :func:`_best_cut`), and (``start="auto"``) greedy-ce's:
   within ``start_share`` of the time limit up to :data:`.start.GREEDY_TASKS` tasks, within
   all the time left beyond (:func:`_greedy_start`); stopped by its limit, also its plan with
   each station's trailing single-task kits cut again (:func:`.start.recut_tail`). A greedy-ce
   that finished is the search's start even where a cut is better (from its kits the search
   ended better); the best cut is then held back and taken after the search if better.
2. **Bound**: the objective's closed form (:func:`bilevel_kit.bounds.objective_bound`, as
   ``cpsat`` and ``milp`` report with stations), or the given ``known_bound`` (makespan).
3. **Sweeps**: the kits in a random order; from each kit (one *iteration*) the moves of
   :func:`moves` (a task across the boundary to its station's next kit, the merge with that
   kit, a split, the kit to another place in the robot's sequence between its station's
   neighbours, a task into a nearby kit of its station), then the **exact window**: the
   consecutive kits from it holding at most :data:`EXACT_TASKS` tasks, every rearrangement
   of their tasks enumerated (:mod:`.enumerate`), only those whose end state (:mod:`.clock`)
   is not dominated timed in full. On an exact grid a candidate (a move's or a window's) is
   timed in full only when its state stays undominated by the incumbent's along the kits
   after its change (:mod:`.trail`): the others cannot be better. A sweep without
   improvement is a local optimum: then a *kick* (:data:`KICK_MOVES` random valid moves,
   better or not) and sweeps again from there, back to the best plan when they find none
   better; :data:`KICKS` kicks in a row without a better plan end the run (``stop``
   ``local_optimum``), as do ``iterations`` (kits visited), ``stall`` (visits in a row
   without improvement), optimal (the plan meets the bound) and the time limit. Every
   random choice draws from ``numpy.random.default_rng(seed)``.

**Result.** ``status`` ``optimal`` only when the plan meets the closed-form bound, else
``feasible``; ``bound`` the makespan's (closed form or given); with another objective
``status_objective`` is it, and ``extra`` states its ``objective_value``, ``objective_bound``
and ``objective_gap`` (:func:`bilevel_kit.bounds.objective_extra`). ``extra``: ``search``
(``stations``), ``start_method``, ``start_objective``, ``start_time_s``, ``start_cut_size``
(the best fixed-size cut's kit size),
``start_greedy_cut`` (greedy-ce's start stopped by its time, when it ran),
``cut_after_search`` (the best fixed-size cut, held back behind a finished greedy-ce, was
better than the search's plan and taken), ``iterations``,
``improvements``, ``sweeps``, ``kicks``, ``tried`` (moves tried), ``hopeless`` (candidates
rejected from their states, :mod:`.trail`), ``window_plans`` (rearrangements enumerated),
``stop``, ``bound_source``, ``makespan``, ``n_kits``, ``gap``, ``wall_time_s``.

A kit holds one station's tasks, fits the tray (:class:`.fit.FastFit`) and is not made of
part-less tasks only (docs/timeline.md#part-less-tasks); the tasks' order keeps every
precedence: every candidate is held to these rules, so the plan passes
:func:`bilevel_kit.validate.check`. With a plan of at most :data:`EXACT_TASKS` tasks the first
window is the whole plan, so the search is exact there (the brute-force tests).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...bounds import objective_bound, objective_extra
from ...instance import Instance
from ...methods import MethodOutput, Status, gap
from ...objectives import ModelTerms
from ...objectives import get as get_objective
from ...plan import Kit, Placement, Plan, evaluate
from ..budget import Budget
from ..cpsat.scaling import Clock, Scaled, clock_after, scale_times, scaled_objective
from .clock import dominated, end_key
from .enumerate import Kits, rearrangements
from .fit import FastFit
from .start import GREEDY_TASKS, recut_tail, station_cuts
from .trail import Trail

#: The most tasks an exact window frees (a window of 5 tasks of one station has at most 541
#: rearrangements, the ordered set partitions).
EXACT_TASKS = 5
#: Kits of its station a task may move to, before and after its own.
REACH = 2
#: Kicks in a row without a better plan that end the run (a local optimum of the kicks).
KICKS = 30
#: Random moves per kick.
KICK_MOVES = 2
#: The start plans :meth:`_Search.consider` takes as valid (a method's plan, or the plan
#: given); the others' kits and order are checked first.
TRUSTED = ("incumbent", "single-task", "whole-assembly", "greedy-ce")
#: Seconds a packing call of a candidate kit may take (undecided: does not fit), as CP-SAT's
#: deterministic time (:func:`..packing_oracle.deterministic_limits`): a wall-clock probe gave
#: another verdict, and so another search, on a loaded machine.
PROBE_S = 0.05


def station_search(
    instance: Instance,
    options: Any,
    budget: Budget,
    stop_at: Budget,
    fit: FastFit,
    *,
    seed: int,
    start_plan: Plan | None,
    known_bound: float | None,
    greedy_at: Budget,
) -> MethodOutput:
    """The module docstring's search for ``options.objective`` (a modelled objective);
    ``greedy_at`` the deadline of greedy-ce's start at scale (:func:`_greedy_start`)."""
    from ..exact.warm import best_heuristic_plan

    extra: dict[str, Any] = {"search": "stations"}
    run = _Search(instance, options.objective, scale_times(instance, 0.1, True), fit, extra)
    t0 = budget.elapsed()
    if start_plan is not None:
        run.consider(start_plan, "incumbent")
    for name in ("single-task", "whole-assembly"):
        plan, _ = best_heuristic_plan(instance, (name,), seed=seed, objective=run.name)
        if plan is not None:
            run.consider(plan, name)
    cut = _best_cut(run, stop_at, options.cut_share)
    finished = False
    if options.start == "auto":
        finished = _greedy_start(
            run, options.start_share, budget, stop_at, greedy_at, seed, cut[:3] if cut else None
        )
    if cut is not None and not finished:  # (a finished greedy-ce's plan: the search's start)
        run.consider(cut[3], f"fixed cut {cut[0]}")
    extra.update(start_objective=run.real, start_time_s=budget.elapsed() - t0)
    if run.kits is None:
        extra["reason"] = "no start plan within the time limit"
        return MethodOutput(None, Status.UNKNOWN, None, extra, status_objective=run.name)
    run.bound = objective_bound(instance, run.name)
    if known_bound is not None and run.objective.is_makespan:
        run.bound = max(run.bound, known_bound)
    extra["bound_source"] = "given" if known_bound is not None else "closed_form"
    if not run.optimal():
        run.search(np.random.default_rng(seed), stop_at, options.iterations, options.stall)
    if cut is not None and finished and cut[2] < run.real - 1e-9:  # (its value, assessed)
        started = extra["start_method"]
        run.consider(cut[3], f"fixed cut {cut[0]}")  # held back, and better than the search's
        extra.update(start_method=started, cut_after_search=True)
    return run.finish(budget)


def _best_cut(run: _Search, stop_at: Budget, share: float) -> tuple[int, float, float, Plan] | None:
    """The best of the fixed-size cuts of :func:`.start.station_cuts`, made within ``share``
    of the time limit (option ``cut_share``): (its kit size, the seconds it took, its value,
    the plan); None when none was made."""
    best: tuple[int, float, float, Plan] | None = None
    for size, took, plan in station_cuts(run.instance, run.fit, stop_at.head(share)):
        value = run.assess(plan)
        if best is None or value < best[2]:
            best = (size, took, value, plan)
    if best is not None:
        run.extra["start_cut_size"] = best[0]
    return best


def _greedy_start(
    run: _Search,
    start_share: float,
    budget: Budget,
    stop_at: Budget,
    greedy_at: Budget,
    seed: int,
    cut: tuple[int, float, float] | None = None,
) -> bool:
    """greedy-ce's plan as a start (docs/stations.md#lns-with-several-stations), within
    ``start_share`` of the time limit; ``cut`` the best fixed-size cut's (kit size, seconds
    it took, value) (:func:`_best_cut`). Whether a greedy-ce plan finished (its limit did not
    stop it): that plan is the search's start, the cut held back (the search from greedy-ce's
    kits ended better than from the best cut's, bench/results/lns_scale.md).

    A greedy-ce its limit stopped leaves its remaining tasks in single-task kits: with
    ``cut`` they are cut again into kits of that size after the kits it decided
    (:func:`.start.recut_tail`), another start. Beyond :data:`.start.GREEDY_TASKS` tasks
    greedy-ce runs within all the time left less the cut's time (kept for cutting its tail
    again), up to ``greedy_at`` (:data:`.method.MARGIN_S` before the limit, not ``stop_at``,
    which also keeps a share of the limit for the oracle's final layouts: every start plan
    carries its own), so that it gets about the time greedy-ce alone gets. No time is kept
    back per task for its overrun (the warm start's rule): at scale that margin exceeds the
    whole share, and greedy-ce checks its clock at every decision."""
    if run.instance.n_tasks <= GREEDY_TASKS:
        limit = min(start_share * budget.time_limit, stop_at.remaining())
    else:
        limit = greedy_at.remaining() - (cut[1] if cut is not None else 0.0)
    return _greedy_run(run, limit, seed, cut, greedy_at)


def _greedy_run(
    run: _Search,
    limit: float,
    seed: int,
    cut: tuple[int, float, float] | None,
    greedy_at: Budget,
) -> bool:
    """greedy-ce within ``limit`` s as a start (:func:`_greedy_start`), and when its limit
    stopped it, its plan with its tail cut again at ``cut``'s size; whether it finished."""
    from ..exact.warm import KERNEL_LOAD_S, WarmRule, best_heuristic_plan

    if limit < 0.5:
        return False
    extra: dict[str, Any] = {}
    plan, _ = best_heuristic_plan(
        run.instance,
        ("greedy-ce",),
        seed=seed,
        time_limit=limit,
        objective=run.name,
        rule=WarmRule(kernel_load_s=KERNEL_LOAD_S),
        extra=extra,
    )
    run.extra["start_greedy_cut"] = bool(extra.get("warm_start_cut"))
    if plan is None:
        return False
    run.consider(plan, "greedy-ce")
    if not run.extra["start_greedy_cut"]:
        return True
    if cut is not None:
        tail = recut_tail(run.instance, plan, cut[0], run.fit, greedy_at)
        if tail is not None:
            run.consider(tail, f"greedy-ce, its tail cut {cut[0]}")
    return False


@dataclass
class _Search:
    """The incumbent (kits of task indices), its value on the grid (``scaled``) and in
    seconds (``real``, the evaluator's), its known layouts and the counters."""

    instance: Instance
    name: str
    sc: Scaled
    fit: FastFit
    extra: dict[str, Any]
    kits: Kits | None = None
    scaled: int = 0
    real: float = math.inf
    bound: float | None = None
    layouts: dict[tuple[int, ...], tuple[Placement, ...]] = field(default_factory=dict)
    stalled: int = 0
    trail: Trail | None = None  # the incumbent's states (:mod:`.trail`), built when needed
    counts: dict[str, int] = field(
        default_factory=lambda: dict.fromkeys(
            ("iterations", "improvements", "sweeps", "kicks", "tried", "hopeless", "window_plans"),
            0,
        )
    )

    def __post_init__(self) -> None:
        inst = self.instance
        self.objective = get_objective(self.name)
        self.ids = [t.id for t in inst.tasks]
        idx = inst.index
        self.station = [inst.station_of(t) for t in self.ids]
        self.preds = {idx[t]: frozenset(idx[p] for p in ps) for t, ps in inst.predecessors.items()}
        self.edges = [(idx[a], idx[b]) for a, b in inst.precedence]
        self.needs = [inst.needs_kit(t) for t in self.ids]
        self.valid: dict[frozenset[int], bool] = {}
        # the objective counts the human's kit overheads (the human idle): then fewer kits in
        # a window is never better either (.clock)
        self.idle = self.objective.expression(ModelTerms(0, lambda: 0, lambda: 1)) != 0
        # a station whose tasks need no kit keeps its part-less kits (the checker names them)
        self.partless_only = {
            s for s in set(self.station) if not any(self.needs[i] for i in self.of(s))
        }

    def of(self, station: str) -> list[int]:
        return [i for i, s in enumerate(self.station) if s == station]

    # -- candidates ---------------------------------------------------------------------------
    def fits(self, kit: Sequence[int]) -> bool:
        parts = self.instance.kit_parts([self.ids[i] for i in kit])
        return self.fit.counts(parts, PROBE_S, deterministic=True) is True

    def valid_kit(self, kit: Sequence[int]) -> bool:
        """One station's tasks, not part-less only (unless its station's all are), fits;
        memoised by task set (the order within a kit does not change these)."""
        key = frozenset(kit)
        known = self.valid.get(key)
        if known is None:
            known = self.valid[key] = self._valid_kit(kit)
        return known

    def _valid_kit(self, kit: Sequence[int]) -> bool:
        if not kit or any(self.station[i] != self.station[kit[0]] for i in kit):
            return False
        if not any(self.needs[i] for i in kit) and self.station[kit[0]] not in self.partless_only:
            return False
        return self.fits(kit)

    def ordered(self, kits: Kits) -> bool:
        """Every precedence holds in the plan's task order."""
        pos = {i: p for p, i in enumerate(i for k in kits for i in k)}
        return all(pos[a] < pos[b] for a, b in self.edges)

    def value(self, kits: Kits) -> float:
        """The objective of ``kits`` by the one evaluator (s)."""
        plan = Plan(tuple(Kit(tuple(self.ids[i] for i in k)) for k in kits))
        value = self.objective.value(evaluate(self.instance, plan))
        assert value is not None  # (a modelled objective: a function of the timeline)
        return value

    def hopeless(self, kits: Kits) -> bool:
        """``kits`` is no better on the grid than the incumbent, seen from its states
        (:mod:`.trail`); only on an exact grid, where a tie is no better either (off the grid
        the evaluator decides ties, :meth:`take`)."""
        if not self.sc.exact:
            return False
        assert self.kits is not None
        if self.trail is None or self.trail.kits is not self.kits:
            self.trail = Trail(self.sc, self.kits, self.idle, since=self.trail)
        if self.trail.hopeless(kits):
            self.counts["hopeless"] += 1
            return True
        return False

    def take(self, kits: Kits, changed: Sequence[Sequence[int]]) -> bool:
        """Take ``kits`` when valid (``changed``: its new kits) and strictly better."""
        self.counts["tried"] += 1
        if self.hopeless(kits):
            return False
        scaled = scaled_objective(self.sc, kits, self.name)
        if scaled > self.scaled or (scaled == self.scaled and self.sc.exact):
            return False
        if not all(self.valid_kit(k) for k in changed) or not self.ordered(kits):
            return False
        real = self.value(kits)
        if real >= self.real - 1e-9:
            return False
        self.kits, self.scaled, self.real = [list(k) for k in kits], scaled, real
        return True

    def assess(self, plan: Plan, trusted: bool = False) -> float:
        """The value of a plan whose kits are all valid and in order (``trusted``: a
        method's, not checked); inf when one is not."""
        idx = self.instance.index
        kits = [[idx[t] for t in k.tasks] for k in plan.kits if k.tasks]
        if not trusted and not (all(self.valid_kit(k) for k in kits) and self.ordered(kits)):
            return math.inf
        return self.value(kits)

    def consider(self, plan: Plan, name: str) -> float:
        """A start plan (valid: a method's, or every kit valid and in order), its layouts
        kept, if better; its value (inf: a kit not valid, or the order breaks a precedence)."""
        idx = self.instance.index
        kits = [[idx[t] for t in k.tasks] for k in plan.kits if k.tasks]
        real = self.assess(plan, trusted=name in TRUSTED)
        if real == math.inf:
            return real
        if real >= self.real - 1e-9:
            return real
        self.kits, self.real = kits, real
        self.scaled = scaled_objective(self.sc, kits, self.name)
        self.extra["start_method"] = name
        for k in plan.kits:
            if k.layout:
                self.layouts[tuple(idx[t] for t in k.tasks)] = k.layout
                self.fit.packer.learn(self.instance.kit_parts(k.tasks), k.layout)
        return real

    def optimal(self) -> bool:
        return self.bound is not None and self.real <= self.bound + 1e-6

    # -- sweeps -------------------------------------------------------------------------------
    def search(
        self, rng: np.random.Generator, stop_at: Budget, iterations: int | None, stall: int | None
    ) -> None:
        """Sweeps to a local optimum, then kicks (module docstring) until :data:`KICKS` in a
        row find no better plan, ``iterations``, ``stall``, optimal or the time limit."""
        assert self.kits is not None
        best = (self.kits, self.scaled, self.real)
        stop, fruitless = "local_optimum", 0
        while True:
            stop = self._descend(rng, stop_at, iterations, stall)
            if self.real < best[2] - 1e-9:
                best, fruitless = (self.kits, self.scaled, self.real), 0
            else:
                self.kits, self.scaled, self.real = best  # back to the best plan
                fruitless += 1
            if stop != "local_optimum" or fruitless > KICKS or not self._kick(rng):
                break
            self.counts["kicks"] += 1
        self.kits, self.scaled, self.real = best
        self.extra.update(self.counts, stop=stop)

    def _descend(
        self, rng: np.random.Generator, stop_at: Budget, iterations: int | None, stall: int | None
    ) -> str:
        """Sweeps until one finds nothing (``local_optimum``) or a stop (its reason)."""
        gained = True
        while gained:
            self.counts["sweeps"] += 1
            gained = False
            assert self.kits is not None
            for k0 in rng.permutation(len(self.kits)).tolist():
                stop = self._why_stop(stop_at, iterations, stall)
                if stop != "local_optimum":
                    return stop
                if k0 >= len(self.kits):
                    continue  # the plan has fewer kits than when the sweep began
                self.counts["iterations"] += 1
                self.stalled += 1
                if self._visit(k0, stop_at):
                    self.counts["improvements"] += 1
                    gained, self.stalled = True, 0
        return "local_optimum"

    def _kick(self, rng: np.random.Generator) -> bool:
        """:data:`KICK_MOVES` random valid moves, better or not; whether one was made."""
        assert self.kits is not None
        made = 0
        for _ in range(20 * KICK_MOVES):
            if made == KICK_MOVES:
                break
            options = list(moves(self.kits, int(rng.integers(len(self.kits))), self.station))
            if not options:  # a station's one kit of one task, nowhere else to go
                continue
            kits, changed = options[int(rng.integers(len(options)))]
            if all(self.valid_kit(k) for k in changed) and self.ordered(kits):
                self.kits, self.real = kits, self.value(kits)
                self.scaled = scaled_objective(self.sc, kits, self.name)
                made += 1
        return made > 0

    def _why_stop(self, stop_at: Budget, iterations: int | None, stall: int | None) -> str:
        if self.optimal():
            return "optimal"
        if iterations is not None and self.counts["iterations"] >= iterations:
            return "iterations"
        if stall is not None and self.stalled >= stall:
            return "stall"
        if stop_at.remaining() <= 0.05:
            return "time_limit"
        return "local_optimum"

    def _visit(self, k0: int, stop_at: Budget) -> bool:
        """The moves from kit ``k0``, then its exact window; whether any improved."""
        assert self.kits is not None
        better = False
        for kits, changed in moves(self.kits, k0, self.station):
            if stop_at.remaining() <= 0.05:
                return better
            if self.take(kits, changed):
                better = True
                break  # the incumbent changed: the window below starts from it
        if k0 < len(self.kits):
            better |= self._window(k0, stop_at)
        return better

    def _window(self, k0: int, stop_at: Budget) -> bool:
        """Every rearrangement of the kits from ``k0`` holding at most :data:`EXACT_TASKS`
        tasks (:mod:`.enumerate`); takes the best strictly better one."""
        assert self.kits is not None
        k1, total = k0, 0
        while k1 < len(self.kits) and total + len(self.kits[k1]) <= EXACT_TASKS:
            total += len(self.kits[k1])
            k1 += 1
        if k1 - k0 < 2 and not (k1 - k0 == 1 and len(self.kits[k0]) > 1):
            return False
        freed = [i for k in self.kits[k0:k1] for i in k]
        groups = [[i for i in freed if self.station[i] == s] for s in dict.fromkeys(self.station)]
        before, after = self.kits[:k0], self.kits[k1:]
        base = clock_after(self.sc, before)
        incumbent = self._end_key(base, self.kits[k0:k1])
        kept: dict[tuple[int, ...], Kits] = {}  # the rearrangements of no dominated end state
        enumerated = 0  # (none when a kit of the window no longer passes its probe)
        for middle in rearrangements(groups, self.preds, self.valid_kit):
            enumerated += 1
            if enumerated % 64 == 0 and stop_at.remaining() <= 0.05:
                return False
            key = self._end_key(base, middle)
            if dominated(key, incumbent) or any(dominated(key, k) for k in kept):
                continue
            kept = {k: m for k, m in kept.items() if not dominated(k, key)}
            kept[key] = middle
        self.counts["window_plans"] += enumerated
        ranked = sorted(  # (a hopeless plan would rank after the incumbent: never taken)
            (scaled_objective(self.sc, before + m + after, self.name), j, m)
            for j, m in enumerate(kept.values())
            if not self.hopeless(before + m + after)
        )
        for scaled, _, middle in ranked:  # the evaluator decides (off the grid: each in turn)
            if scaled > self.scaled or (scaled == self.scaled and self.sc.exact):
                break
            if self.take(before + middle + after, middle):
                return True
        return False

    def _end_key(self, base: Clock, middle: Kits) -> tuple[int, ...]:
        clock = base.copy()
        for kit in middle:
            clock.step(self.sc, kit)
        return end_key(self.sc, clock, self.idle)

    # -- the result -----------------------------------------------------------------------------
    def finish(self, budget: Budget) -> MethodOutput:
        """The plan with a layout for every kit, its status and claims (module docstring)."""
        assert self.kits is not None
        inst, out = self.instance, []
        for kit in self.kits:
            tasks = tuple(self.ids[i] for i in kit)
            layout = self.layouts.get(tuple(kit)) or self.fit.layout(tasks)
            if layout is None and inst.kit_parts(tasks):
                self.extra["reason"] = "no layout for some kit within the time limit"
                return MethodOutput(None, Status.UNKNOWN, None, self.extra, self.name)
            out.append(Kit(tasks, layout or ()))
        plan = Plan(tuple(out))
        timeline = evaluate(inst, plan)
        optimal = self.optimal()
        makespan_bound = objective_bound(inst, "makespan")
        self.extra.setdefault("stop", "optimal" if optimal else "time_limit")
        self.extra.update(
            makespan=timeline.makespan,
            n_kits=len(out),
            gap=gap(timeline.makespan, makespan_bound),
            wall_time_s=budget.elapsed(),
        )
        status = Status.OPTIMAL if optimal else Status.FEASIBLE
        if self.objective.is_makespan:
            return MethodOutput(plan, status, self.bound, self.extra)
        claims = objective_extra(inst, plan, self.name, (self.bound, None), (optimal, optimal))
        claims.pop("objective_bound_axis_aligned")
        self.extra.update(claims)
        return MethodOutput(plan, status, makespan_bound, self.extra, self.name)


def moves(kits: Kits, k0: int, station: Sequence[str]) -> Iterator[tuple[Kits, Kits]]:
    """Plans one move from ``kits`` at kit ``k0`` (module docstring, step 3), each with its
    new kits (whose validity the caller checks, with the precedence of the whole order)."""
    s = station[kits[k0][0]]
    mine = [k for k, kit in enumerate(kits) if station[kit[0]] == s]
    at = mine.index(k0)
    nxt = mine[at + 1] if at + 1 < len(mine) else None
    prev = mine[at - 1] if at > 0 else -1
    kit = kits[k0]
    if nxt is not None:
        other = kits[nxt]
        if len(kit) > 1:  # its last task to the front of the next kit
            yield _with(kits, {k0: kit[:-1], nxt: [kit[-1], *other]})
        if len(other) > 1:  # the next kit's first task to its end
            yield _with(kits, {k0: [*kit, other[0]], nxt: other[1:]})
        merged = [*kit, *other]
        yield _with(kits, {k0: merged, nxt: None})
        yield _with(kits, {k0: None, nxt: merged})
    for j in range(1, len(kit)):  # split, the second part right after it
        yield [*kits[:k0], kit[:j], kit[j:], *kits[k0 + 1 :]], [kit[:j], kit[j:]]
    rest = kits[:k0] + kits[k0 + 1 :]
    last = nxt - 1 if nxt is not None else len(rest)
    for q in range(prev + 1, last + 1):  # the kit elsewhere between its station's neighbours
        if q != k0:
            yield [*rest[:q], kit, *rest[q:]], []
    near = mine[max(0, at - REACH) : at + REACH + 1]
    for t in kit:  # a task into a nearby kit of its station
        for k in near:
            if k == k0:
                continue
            for q in range(len(kits[k]) + 1):
                target = [*kits[k][:q], t, *kits[k][q:]]
                left = [i for i in kit if i != t] or None
                yield _with(kits, {k0: left, k: target})


def _with(kits: Kits, change: dict[int, list[int] | None]) -> tuple[Kits, Kits]:
    """``kits`` with the kits at ``change``'s positions replaced (None: removed)."""
    out = [change.get(k, kit) for k, kit in enumerate(kits)]
    return [k for k in out if k is not None], [k for k in change.values() if k is not None]
