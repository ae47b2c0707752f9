"""The paper's upper level: greedy rolling-horizon task segmentation (Section IV-A, Eqs. 3-7).

At each decision epoch (the robot is free to start the next kit) the policy enumerates the
precedence-feasible partial sequences ``K`` of the remaining tasks of length
``L = min(N, remaining)`` and every split ``i in 1..L``, scores each pair with

.. math::

    F(K, i) = W_1 \\sum_j (1 - \\text{allowed}(K_j))                      \\quad (3)
            - W_2\\, i                                                       \\quad (4)
            + W_3\\, |d + R(K_{1:i}) - H_{rem}|                              \\quad (5)
            + W_4\\, |d + R(K_{i+1:L}) - H(K_{1:i})|                         \\quad (6)
            - W_5\\, \\text{kit\\_fitness}(P(K_{1:i}))                       \\quad (7)
            + W_7 \\sum_{p \\in P(K_{1:i})} U(p)                              \\quad (V\\text{-B})

and commits the minimiser's prefix ``T_{t+1} = K_{1:i}`` as the next kit. The terms are
computed by :mod:`bilevel_kit.heuristics.upper_level` (the one implementation of F).

Decisions taken where the paper is silent (docs/errata.md):

* Terms (5) and (6) use absolute differences (``signed=True`` restores the printed form).
* Precedence is a hard constraint: only feasible ``K`` are enumerated, so term (3) is 0
  (``precedence="penalty"`` enumerates every sequence and adds ``W1`` per violation).
* ``R(.)`` and ``H(.)`` of a kit include the per-kit overheads ``o_R``/``o_H`` of the
  instance, matching the timeline evaluator.
* ``H_rem``, the paper's ``duration^H(T_t)``, is the human's remaining time on the current
  kit when the robot starts the next one (0 for the first kit), computed with the one
  timeline evaluator; online, the simulator passes it in the :class:`PolicyState`.
* A prefix whose parts cannot be laid out (CE and the packer fallback both fail) is not a
  candidate. ``kit_fitness`` is memoised by the multiset of parts, so each distinct kit is
  arranged once per plan; each multiset gets its own seed derived from (seed, multiset), so a
  kit's layout does not depend on the order in which kits are considered.
* Ties are broken deterministically: the first minimum in enumeration order (sequences in
  depth-first order of the tasks' file positions, then increasing ``i``), with a tolerance of
  1e-9 on the score.

Options (:class:`GreedyCEOptions`, validated centrally): ``horizon`` (N), ``signed``,
``precedence``, ``polish`` (convex polish of every CE layout, :mod:`bilevel_kit.heuristics.convex`),
the weights ``W1``..``W7``, every :class:`~bilevel_kit.heuristics.cross_entropy.CEParams` field
and ``finger_room`` (every kit is laid out with its parts' grasp footprints, which hold the
station gripper's open fingers, then given back their true sizes: docs/execution.md#finger-room).
Past ``time_limit``: single-task kits. Several stations: :mod:`.greedy_stations`.

``extra`` of the registered method ``greedy-ce``:

* ``epochs``: decision epochs (= kits); ``sequences``: partial sequences enumerated, summed
  over epochs; ``candidates``: (K, i) pairs with a layout, summed over epochs;
* ``ce_calls``: CE runs (distinct part multisets); ``fitness_cache_hits``: look-ups served
  from the memo; ``kits_not_fitting``: multisets without a valid layout;
* ``epoch_F_sum``: the sum over epochs of the chosen pair's F. Not a whole-plan objective:
  term (6) looks at the hypothetical window rest, not the kit that really came next
  (bilevel-milp's J, :mod:`bilevel_kit.models.bilevel_milp`, is the plan's objective);
* ``kit_terms``: per kit, ``score`` (its F), ``i``, ``fitness``, ``d_same``, ``d_diff``,
  ``z`` (mm^2), ``n_parts``, ``ce_iterations``, ``ce_converged``, ``layout_source`` and
  ``trace`` (best CE fitness per iteration) of its layout.
"""

from __future__ import annotations

import functools
import heapq
import itertools
import math
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from ..errors import KitDoesNotFit, UsageError
from ..instance import Instance
from ..methods import MethodOutput, Status
from ..plan import Kit, Plan, TimelineBuilder, fold_kitless, next_robot_start
from . import upper_level
from .ce.sampling import deadline as ce_deadline
from .cross_entropy import Arrangement, arrange
from .greedy_options import DEFAULT_OPTIONS as DEFAULT_OPTIONS
from .greedy_options import GreedyCEOptions as GreedyCEOptions
from .greedy_options import GreedyParams as GreedyParams
from .greedy_search import (
    OutOfTime,
    PrefixSearch,
    SearchLimits,
    SearchStats,
    available_vector,
    timed,
)
from .greedy_stations import plan_greedy
from .prefix.levels import unique_rows

#: Refuse to enumerate more than this many partial sequences at one epoch (each is scored,
#: and its parts laid out: 2,000,000 took 30 s and 0.8 GB at a 2 s limit).
MAX_SEQUENCES = 200_000


@dataclass(frozen=True)
class PolicyState:
    """What the robot knows at a decision epoch.

    ``done``: tasks already kitted (delivered or committed); ``human_remaining``: seconds the
    human still needs for the kit in hand (0 if idle); ``available``: parts of each type the
    robot has right now (``None``: everything is available, W7 is then inactive).
    """

    done: frozenset[str] = frozenset()
    human_remaining: float = 0.0
    available: Mapping[str, int] | None = None


@dataclass
class GreedyStats(SearchStats):
    """The policy's counters; the prefix search's (:class:`SearchStats`: closed prefix sets
    scored, prefixes evaluated with their layout, beam epochs, capped window-rest searches)
    are copied from it after each exact decision."""

    epochs: int = 0
    sequences: int = 0
    candidates: int = 0
    ce_calls: int = 0
    fitness_cache_hits: int = 0
    kits_not_fitting: int = 0
    #: True once ``time_limit`` ran out (the remaining kits are single tasks)
    time_limit_hit: bool = False
    objective_terms: list[dict[str, Any]] = field(default_factory=list)


class GreedyCEPolicy:
    """The paper's bilevel heuristic as an online policy: ``decide(state) -> next Kit``."""

    def __init__(
        self, instance: Instance, params: GreedyParams | None = None, seed: int = 0
    ) -> None:
        self.params = params or GreedyParams()
        self.instance = instance.with_overrides(
            horizon=self.params.horizon, weights=self.params.weights
        )
        if self.params.precedence not in ("hard", "penalty"):
            raise UsageError(
                f"precedence must be 'hard' or 'penalty', got {self.params.precedence!r}"
            )
        if self.params.decision not in ("exact", "enumerate"):
            raise UsageError(
                f"decision must be 'exact' or 'enumerate', got {self.params.decision!r}"
            )
        self.seed = int(seed)
        self.stats = GreedyStats()
        self._arrangements: dict[tuple[tuple[str, int], ...], Arrangement] = {}
        #: (fitness, fits) by the bytes of a count row over ``_types`` (the same memo, keyed
        #: for the decision's hot path)
        self._fit_memo: dict[bytes, tuple[float, bool]] = {}
        inst = self.instance
        #: its one station's d, o_H and trays: a policy plans one station's kits, several
        #: stations have one policy each (:mod:`.greedy_stations`), so several are refused here
        self.station = inst.params_of()
        self._ids = [t.id for t in inst.tasks]
        self._r = np.array([inst.robot_time(t) for t in self._ids])
        self._h_mean = np.array([inst.human_time(t) for t in self._ids])
        self._h = self._h_mean
        self._pred = [frozenset(inst.index[p] for p in inst.predecessors[t]) for t in self._ids]
        self._types = sorted(inst.part_types)
        col = {t: k for k, t in enumerate(self._types)}
        #: parts of each task as a count vector over the sorted part types
        self._part_matrix = np.zeros((len(self._ids), len(self._types)), dtype=np.int64)
        for j, tid in enumerate(self._ids):
            for t, n in inst.task_by_id[tid].parts:
                self._part_matrix[j, col[t]] += n
        limits = SearchLimits(
            self.params.max_prefix_sets, self.params.beam_width, self.params.max_rest_nodes
        )
        self._search = PrefixSearch(
            inst, self._r, self._h, self._pred, self._part_matrix, self._types, limits
        )
        #: ``time.perf_counter()`` after which decisions are single tasks (None: no limit)
        self.deadline: float | None = None

    def set_human_scale(self, scale: float | np.ndarray) -> None:
        """Plan the next decisions with every task's human time ``H`` (terms (5)-(6)) the
        instance's mean times ``scale`` (one factor, or one per task in instance order); 1
        restores the means exactly. The adaptive policies' estimate of the participant's pace
        (docs/simulation.md); the per-kit ``o_H`` is not scaled, layouts do not depend on it."""
        self._h = self._h_mean * scale
        self._search.h = self._h

    # -- lower level, memoised ---------------------------------------------------------------
    def arrangement(self, counts: Mapping[str, int]) -> Arrangement:
        """The CE arrangement of a part multiset (computed once per multiset)."""
        key = tuple(sorted((t, int(n)) for t, n in counts.items() if n))
        hit = self._arrangements.get(key)
        if hit is not None:
            self.stats.fitness_cache_hits += 1
            return hit
        code = [self._types.index(t) * 1000 + n for t, n in key]
        self.stats.ce_calls += 1

        def run() -> Arrangement:
            rng = np.random.default_rng(np.random.SeedSequence([self.seed, *code]))
            w6 = self.instance.weights["W6"]
            return arrange(self.instance, dict(key), rng=rng, params=self.params.ce, w6=w6)

        with ce_deadline(self.deadline):  # past the time limit, CE runs stop early
            arr = run()
        if not arr.fits and self.past_deadline():
            arr = run()  # a run cut short proves nothing: "does not fit" takes a whole one
        if not arr.fits:
            self.stats.kits_not_fitting += 1
        elif self.params.polish:
            from .convex import polish_arrangement

            arr = polish_arrangement(self.instance, arr, self.instance.weights["W6"])
        self._arrangements[key] = arr
        return arr

    # -- upper level ---------------------------------------------------------------------------
    def _sequences(self, done: set[int], length: int) -> Iterator[tuple[int, ...]]:
        """Depth-first, in file order: feasible sequences (or all, in the penalty form)."""
        n = len(self._ids)
        hard = self.params.precedence == "hard"
        seq: list[int] = []
        used = set(done)

        def rec() -> Iterator[tuple[int, ...]]:
            if len(seq) == length:
                yield tuple(seq)
                return
            for j in range(n):
                if j in used or (hard and not self._pred[j] <= used):
                    continue
                seq.append(j)
                used.add(j)
                yield from rec()
                used.discard(j)
                seq.pop()

        return rec()

    def _fitness(self, row: np.ndarray) -> tuple[float, bool]:
        """(fitness, fits) of a count row over the sorted part types (CE run if new)."""
        hit = self._cached_fitness(row)
        if hit is not None:
            return hit
        arr = self.arrangement(dict(zip(self._types, row.tolist(), strict=True)))
        self._fit_memo[np.asarray(row, dtype=np.int64).tobytes()] = (arr.fitness, arr.fits)
        return arr.fitness, arr.fits

    def _cached_fitness(self, row: np.ndarray) -> tuple[float, bool] | None:
        """(fitness, fits) of a count row if its multiset was arranged already (a memo hit,
        counted as in :meth:`arrangement`), else None."""
        hit = self._fit_memo.get(np.asarray(row, dtype=np.int64).tobytes())
        if hit is not None:
            self.stats.fitness_cache_hits += 1
        return hit

    def _listed(self, done: set[int], length: int) -> list[tuple[int, ...]] | None:
        """Up to ``MAX_SEQUENCES + 1`` sequences, or None when the time limit has passed by
        the end of the listing. The listing itself is not cut by the clock (it is bounded by
        the cap): whether an epoch has more than ``MAX_SEQUENCES`` sequences, and so whether
        the run is refused, must not depend on the machine's load."""
        listed = list(itertools.islice(self._sequences(done, length), MAX_SEQUENCES + 1))
        if len(listed) <= MAX_SEQUENCES and self.past_deadline():
            return None
        return listed

    def _enumerate(
        self, state: PolicyState, done: set[int], length: int
    ) -> tuple[list[int], float] | None:
        """Every (K, i) scored at once (the penalty form, and ``decision="enumerate"``); None
        when the time limit passes before every new part multiset has its layout (the epoch
        then takes the single-task kit of :meth:`_cheap`, as every later one does)."""
        inst = self.instance
        remaining = len(self._ids) - len(done)
        if math.perm(remaining, length) > MAX_SEQUENCES and self.params.precedence != "hard":
            raise UsageError(
                f"{math.perm(remaining, length)} sequences to enumerate in the "
                "penalty form; lower the horizon"
            )
        listed = self._listed(done, length)
        if listed is None:
            return None
        if len(listed) > MAX_SEQUENCES:
            raise UsageError(
                f"more than {MAX_SEQUENCES:,} partial sequences at one epoch to enumerate; "
                "lower the horizon or use decision=exact"
            )
        seqs = np.array(listed, dtype=np.int64)
        self.stats.sequences += len(seqs)
        # Terms (3)-(6) of every (K, i), then the lower level: one arrangement per distinct
        # prefix part multiset (term 7 and the W7 term).
        violations = None
        if self.params.precedence == "penalty":
            violations = upper_level.precedence_violations(seqs, done, self._pred)[:, None]
        diff5, diff6 = upper_level.window_balance(
            self._r[seqs],
            self._h[seqs],
            delivery=self.station.delivery_time,
            human_remaining=state.human_remaining,
            overhead_robot=inst.kit_overhead_robot,
            overhead_human=self.station.kit_overhead_human,
            signed=self.params.signed,
        )
        counts = np.cumsum(self._part_matrix[seqs], axis=1).reshape(-1, len(self._types))
        keys, inverse = unique_rows(counts)
        inverse = inverse.reshape(len(seqs), length)
        fit = np.empty(len(keys))
        fits = np.empty(len(keys), dtype=bool)
        for k, row in enumerate(keys):
            if self.past_deadline() and self._cached_fitness(row) is None:
                return None
            fit[k], fits[k] = self._fitness(row)
        unavailable = None
        avail = available_vector(state.available, self._types)
        if avail is not None:
            unavailable = upper_level.unavailable_parts(keys, avail)[inverse]
        score = upper_level.objective(
            inst.weights,
            n_tasks=np.arange(1, length + 1)[None, :],
            diff5=diff5,
            diff6=diff6,
            fitness=fit[inverse],
            violations=violations,
            unavailable=unavailable,
        ).reshape(-1)
        score[~fits[inverse.reshape(-1)]] = np.inf
        self.stats.candidates += int(np.isfinite(score).sum())
        if not np.isfinite(score).any():
            return [], math.inf
        # first minimum in enumeration order (row-major: sequence, then split), tolerance 1e-9
        flat = int(np.flatnonzero(score <= score.min() + 1e-9)[0])
        s, col = divmod(flat, length)
        return seqs[s, : col + 1].tolist(), float(score[flat])

    def _exact(
        self, state: PolicyState, done: set[int], length: int
    ) -> tuple[list[int], float | None] | None:
        """The search over closed prefix sets (:mod:`.greedy_search`): same minimum, same kit;
        None when the time limit passes before every new part multiset has its layout (as
        :meth:`_enumerate`)."""
        mask = np.zeros(len(self._ids), dtype=bool)
        mask[list(done)] = True
        search = self._search
        before = (search.stats.evaluated, search.stats.prefix_sets)
        fitness = timed(self._fitness, self._cached_fitness, self.past_deadline)
        timed_out = False
        try:
            choice = search.decide(
                mask,
                length,
                state.human_remaining,
                available_vector(state.available, self._types),
                fitness,
                self.params.signed,
                self._cached_fitness,
            )
        except OutOfTime:
            choice, timed_out = None, True
        st = search.stats
        self.stats.candidates += st.evaluated - before[0]
        for f in fields(SearchStats):
            setattr(self.stats, f.name, getattr(st, f.name))
        if choice is None:
            return None if timed_out else ([], math.inf)
        return list(choice.prefix), choice.score

    def _cheap(self, done: set[int]) -> tuple[list[int], float | None]:
        """After the time limit: the first available task (file order) alone, if it fits."""
        for j in range(len(self._ids)):
            if j not in done and self._pred[j] <= done:
                if self._fitness(self._part_matrix[j])[1]:
                    return [j], None
                break
        return [], math.inf

    def decide(self, state: PolicyState) -> Kit | None:
        """The next kit (tasks in the human's order, with its CE layout); None when all done."""
        inst = self.instance
        done = {inst.index[t] for t in state.done}
        remaining = len(self._ids) - len(done)
        if remaining == 0:
            return None
        length = min(inst.horizon, remaining)
        self.stats.epochs += 1
        best_score: float | None
        if self.deadline is not None and time.perf_counter() > self.deadline:
            self.stats.time_limit_hit = True
            prefix, best_score = self._cheap(done)
        else:
            enumerate_ = self.params.precedence == "penalty" or self.params.decision == "enumerate"
            decision = self._enumerate if enumerate_ else self._exact
            found: tuple[list[int], float | None] | None = decision(state, done, length)
            if found is None:
                self.stats.time_limit_hit = True
                found = self._cheap(done)
            prefix, best_score = found
        if not prefix:
            raise KitDoesNotFit(
                f"{inst.source}: no next kit fits the tray: every candidate "
                f"prefix of the remaining {remaining} tasks failed to lay out"
            )
        return self._kit(prefix, best_score, state.human_remaining)

    def past_deadline(self) -> bool:
        return self.deadline is not None and time.perf_counter() > self.deadline

    def finish(self, done: set[str]) -> Iterator[Kit]:
        """After the time limit: every remaining task alone, the first available one (file
        order) first, as :meth:`_cheap` picks them: the smallest topological order, by a heap,
        and one layout per distinct part multiset, so 60,000 tasks take about a second."""
        inst = self.instance
        done_idx = {inst.index[t] for t in done}
        self.stats.time_limit_hit = True
        waiting = [len(p - done_idx) for p in self._pred]
        succ: list[list[int]] = [[] for _ in self._ids]
        for j, preds in enumerate(self._pred):
            for p in preds:
                succ[p].append(j)
        ready = [j for j in range(len(self._ids)) if j not in done_idx and waiting[j] == 0]
        heapq.heapify(ready)
        left = len(self._ids) - len(done_idx)
        made: dict[bytes, tuple[Kit, dict[str, Any]]] = {}
        terms = self.stats.objective_terms
        while ready:
            j = heapq.heappop(ready)
            key = self._part_matrix[j].tobytes()
            if key in made:
                terms.append(dict(made[key][1]))
            else:
                if not self._fitness(self._part_matrix[j])[1]:
                    raise KitDoesNotFit(
                        f"{inst.source}: no next kit fits the tray: the first available of "
                        f"the remaining {left} tasks does not lay out alone"
                    )
                made[key] = (self._kit([j], None, None), terms[-1])
            left -= 1
            self.stats.epochs += 1
            for s in succ[j]:
                waiting[s] -= 1
                if waiting[s] == 0:
                    heapq.heappush(ready, s)
            yield Kit((self._ids[j],), made[key][0].layout)

    def _kit(self, prefix: list[int], best_score: float | None, h_rem: float | None) -> Kit:
        """The kit of the tasks ``prefix`` with its CE layout, its terms kept in the stats."""
        row = self._part_matrix[prefix].sum(axis=0)
        arr = self.arrangement(dict(zip(self._types, row.tolist(), strict=True)))
        self.stats.objective_terms.append(
            {
                "score": best_score,
                "i": len(prefix),
                "h_rem": h_rem,
                "fitness": arr.fitness,
                "d_same": arr.d_same,
                "d_diff": arr.d_diff,
                "z": arr.z,
                "n_parts": len(arr.layout),
                "ce_iterations": arr.iterations,
                "ce_converged": arr.converged,
                "layout_source": arr.source,
                "trace": list(arr.trace),
            }
        )
        return Kit(tuple(self._ids[j] for j in prefix), arr.layout)


def plan(
    instance: Instance,
    params: GreedyParams | None = None,
    seed: int = 0,
    policy: GreedyCEPolicy | None = None,
) -> Plan:
    """Offline plan with expected times: call the policy at each epoch until all tasks are kitted.

    An epoch is the moment the robot can start the next kit: the last kit has arrived and a
    tray is back (:func:`bilevel_kit.plan.next_robot_start`, the tray rule of
    docs/timeline.md). ``H_rem`` is the human's work left then, ``human_end - now >= 0``
    (with unlimited trays ``now`` is the last arrival), from the one timeline evaluator.
    """
    policy = policy or GreedyCEPolicy(instance, params, seed)
    kits: list[Kit] = []
    done: set[str] = set()
    timeline = TimelineBuilder(policy.instance)
    while len(done) < instance.n_tasks:
        if policy.past_deadline():
            for alone in policy.finish(done):
                kits.append(alone)
                done.update(alone.tasks)
            break
        remaining = 0.0
        if kits:
            now = next_robot_start(policy.instance, timeline.kits)
            remaining = max(0.0, timeline.human_free - now)
        kit = policy.decide(PolicyState(frozenset(done), remaining))
        assert kit is not None
        kits.append(kit)
        timeline.append(kit)
        done.update(kit.tasks)
    # a kit of part-less tasks alone rides in its neighbour (docs/timeline.md#part-less-tasks):
    # solve() folds every method's plan; this entry point is called directly too
    return fold_kitless(instance, Plan(tuple(kits)))


#: Seconds per task greedy-ce needs besides its decisions (measured 50-180 us at 60,000 tasks)
SETUP_PER_TASK = 2e-4


def greedy_ce(
    instance: Instance,
    options: GreedyCEOptions = DEFAULT_OPTIONS,
    *,
    seed: int = 0,
    time_limit: float | None = None,
) -> MethodOutput:
    """Registered method ``greedy-ce``: the paper's bilevel heuristic (options and ``extra``
    in the module docstring). Past ``time_limit`` seconds the remaining kits are single tasks
    (``extra["time_limit_hit"]``). Several stations: :mod:`.greedy_stations`."""
    params = options.to_params()
    # the clock starts before the policy's set-up, which is linear in the tasks (seconds at
    # 60,000 tasks): the limit bounds the whole method, and one too short for it is refused
    deadline = None if time_limit is None else time.perf_counter() + time_limit
    need = instance.n_tasks * SETUP_PER_TASK  # within the allowed overrun up to T + 1 s
    if time_limit is not None and need > time_limit + 1.0:
        raise UsageError(
            f"{instance.source}: --time-limit {time_limit:g} s is shorter than greedy-ce's "
            f"set-up for {instance.n_tasks:,} tasks (about {need:.0f} s, "
            f"{SETUP_PER_TASK * 1e6:.0f} us per task); give at least {math.ceil(need - 1)} s"
        )
    make = functools.partial(GreedyCEPolicy, params=params, seed=seed)
    packed = instance
    if options.finger_room:  # pack the grasp footprints, keep the centres and angles
        from ..sawyer.gripper import true_sizes, with_finger_room

        packed = with_finger_room(instance)
    result, st = plan_greedy(packed, make, PolicyState, plan, deadline)  # one or more stations
    if packed is not instance:
        result = true_sizes(result, instance)
    extra = {
        "epochs": st.epochs,
        "decision": "enumerate"
        if params.precedence == "penalty" or params.decision == "enumerate"
        else "exact",
        "sequences": st.sequences,
        "prefix_sets": st.prefix_sets,
        "evaluated": st.evaluated,
        "beam_epochs": st.beam_epochs,
        "rest_capped": st.rest_capped,
        "time_limit_hit": st.time_limit_hit,
        "candidates": st.candidates,
        "ce_calls": st.ce_calls,
        "fitness_cache_hits": st.fitness_cache_hits,
        "kits_not_fitting": st.kits_not_fitting,
        "epoch_F_sum": sum(float(t["score"]) for t in st.objective_terms if t["score"] is not None),
        "kit_terms": st.objective_terms,
    }
    return MethodOutput(result, Status.FEASIBLE, None, extra)
