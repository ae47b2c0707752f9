r"""Branch, bound and remember over the ideals of the precedence graph (docs/formulations.md,
"Branch, bound and remember"; Sewell & Jacobson 2012, Morrison, Sewell & Jacobson 2014).

A node is an ideal ``J`` (the tasks of the kits so far, a bit mask) with the timeline's state
after them (:mod:`.space`; with several stations :mod:`.stations`, a kit of one station's
tasks). The search is best-first on the node's lower bound ``f``
(:meth:`.space.Space.lower_bound`), deeper nodes first among equal bounds:

* **branch**: a node's children are its kits (:meth:`.space.Space.children`), each the node's
  ideal plus a down-set extension whose parts fit the tray; with ``batch``, a node pushes at
  most that many children per expansion and then goes back on the heap with its own ``f``,
  the rest of its kits generated when it is popped again (partial expansion: a node with a
  million kits below the incumbent does not hold the search until all are generated, and its
  ``f`` still bounds every plan through the kits not yet generated);
* **bound**: a child whose ``f`` is not below the incumbent's makespan is dropped; on the
  makespan's grid ``g`` (:func:`~bilevel_kit.bounds.makespan_grid`: every makespan a multiple
  of it) a plan better than the incumbent is at least ``g`` better, so a child whose ``f`` is
  above the incumbent's makespan minus ``g / 2`` is dropped too (the margin ``g / 2`` also
  covers the float sums' error; without a grid it is ``1e-9`` of the makespan);
* **remember**: the nodes kept per ideal are those no other dominates (same ideal, state
  componentwise at most); a dominated child is dropped, a dominating one retires the nodes it
  dominates.

The tray's geometry enters lazily: a kit is enumerated by its area alone, and the packing
oracle (memoised by part multiset) is asked only when a node is expanded (or completes a
plan). A kit it rules out for every layout is dropped. A kit it finds no layout for without
such a proof (a 0/90-degree proof only, or no decision within its limit) is **relaxed**
(``relax=True``, the default): kept for the bound, since parts at other angles may fit it,
but a plan through it is no plan the search can lay out, so it never becomes the incumbent;
its makespan is a lower bound candidate (``relaxed_best``). A relaxed node never retires one
that is not. With ``relax=False`` such a kit is dropped instead and narrows what the search
proves to the plans it covers (``scope``, docs/formulations.md#what-optimal-means).

**Claims.** When the heap's least ``f`` reaches the incumbent's makespan and no relaxed plan
is below it, no plan is better: the incumbent is optimal (within ``scope``: every plan with
``relax``). At any stop the least of the open nodes' ``f``, the relaxed plans' makespans and
the incumbent's makespan is a lower bound on every plan's makespan (within ``scope``). Work
is counted in expanded nodes, so a run to a node limit is deterministic; the wall clock and
the number of nodes kept (memory) are checked within an expansion too, as one node may have
millions of kits: a search stopped there keeps the node open with the kits it has not pushed.
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Protocol

from ...bounds import makespan_grid
from ...instance import Instance
from ..common import Packer
from ..packing import ANY_ANGLE, AXIS_ALIGNED

#: Answer of the fit test for a part multiset: True, or the scope of a "no" (None: undecided).
FitTest = Callable[[dict[str, int]], "tuple[bool, str | None]"]
#: What the search does with a kit (:meth:`_Search.fit`).
FITS, NO, RELAXED = "fits", "no", "relaxed"
#: Nodes kept before the search stops (``stop`` ``memory``): about 1.1 kB each, so with the
#: process's own 0.25 GB about 1.3 GB at the cap (``bbr`` on ``sparse_n50_s1_tu_loose_d0``:
#: 1.32 GB peak at 1,000,000 nodes, 2.40 GB at 2,000,000; docs/formulations.md).
MAX_NODES = 1_000_000


class Space(Protocol):
    """What the search asks of its space: one station's (:class:`.space.Space`) or several
    stations' (:class:`.stations.StationSpace`)."""

    instance: Instance
    full: int

    def root(self) -> tuple[float, ...]: ...

    def step(
        self, state: tuple[float, ...], r: float, h: float, station: int = 0
    ) -> tuple[float, ...]: ...

    def lower_bound(self, done: int, state: tuple[float, ...]) -> float: ...

    def children(
        self, done: int, state: tuple[float, ...], below: float
    ) -> Iterator[tuple[int, float, float, int]]: ...

    def order(self, mask: int) -> list[str]: ...


@dataclass
class Node:
    """A node of the search: ideal, state, parent and the kit that led here."""

    done: int
    state: tuple[float, ...]
    parent: Node | None
    kit: int
    alive: bool = True
    #: the oracle said its last kit fits (asked when the node is expanded, module docstring)
    verified: bool = False
    #: a kit on its path is relaxed (module docstring)
    relaxed: bool = False
    #: the kits not yet generated of a node partly expanded (module docstring)
    pending: Iterator[tuple[int, float, float, int]] | None = None


@dataclass
class Outcome:
    """What a search proved: the best plan's kits (task-id lists, None: none better than the
    given incumbent), its makespan, the lower bound, ``exhausted`` (the incumbent is proven
    optimal: the search ran out of nodes below it and no relaxed plan is below it), the
    proof's ``scope``, why it stopped and its counters."""

    kits: list[list[str]] | None
    value: float
    bound: float
    exhausted: bool
    scope: str | None
    stop: str
    counters: dict[str, int] = field(default_factory=dict)


def packer_fits(packer: Packer) -> FitTest:
    """The fit test of a run's packer (:class:`..common.Packer`): "fits", or the scope of its
    "no" (a proof for 0/90-degree layouts at least), or undecided (None)."""

    def fits(counts: dict[str, int]) -> tuple[bool, str | None]:
        verdict = packer.verdict(counts)
        if verdict.fits:
            return True, None
        return False, (verdict.scope or AXIS_ALIGNED) if verdict.fits is False else None

    return fits


def _narrow(scope: str | None, by: str | None) -> str | None:
    """The scope a proof keeps after a "no" of scope ``by`` (None: undecided)."""
    if scope is None or by is None:
        return None
    return AXIS_ALIGNED if AXIS_ALIGNED in (scope, by) else ANY_ANGLE


def search(
    space: Space,
    fits: FitTest,
    *,
    upper: float = math.inf,
    deadline: float | None = None,
    max_expansions: int | None = None,
    max_nodes: int = MAX_NODES,
    relax: bool = True,
    batch: int | None = None,
) -> Outcome:
    """Best-first branch, bound and remember (module docstring) below ``upper`` (a known
    plan's makespan; inf: none), until exhausted, ``deadline`` (a ``perf_counter`` time),
    ``max_expansions`` nodes expanded or ``max_nodes`` nodes kept; ``relax``: kits without a
    layout nor a proof for every layout are relaxed (module docstring); ``batch``: children
    pushed per expansion (partial expansion, module docstring; None: every child at once)."""
    run = _Search(space, fits, upper, deadline, relax)
    run.batch, run.max_nodes = batch, max_nodes
    while run.heap and run.stop == "exhausted":
        f, _, _, node = run.heap[0]
        if f >= min(run.upper, run.relaxed_best) - run.tol:
            break
        if deadline is not None and time.perf_counter() >= deadline:
            run.stop = "time_limit"
        elif max_expansions is not None and run.counts["expanded"] >= max_expansions:
            run.stop = "expansions"
        elif run.counts["kept"] >= max_nodes:
            run.stop = "memory"
        else:
            heapq.heappop(run.heap)
            if node.alive and run.verify(node):
                run.expand(node, f)
            else:
                node.pending = None
    return run.outcome()


class _Search:
    """One search's heap, memory, incumbent, fit memo and counters (:func:`search`)."""

    def __init__(
        self, space: Space, fits: FitTest, upper: float, deadline: float | None, relax: bool
    ) -> None:
        self.space, self.fits, self.deadline, self.relax = space, fits, deadline, relax
        self.relaxed_best = math.inf
        self.step = makespan_grid(space.instance)
        self.upper = upper
        self.tol = self.margin(upper)
        root = Node(0, space.root(), None, 0, verified=True)
        self.tick = itertools.count(1)
        self.heap: list[tuple[float, int, int, Node]] = [
            (space.lower_bound(0, root.state), 0, 0, root)
        ]
        self.memory: dict[int, list[Node]] = {0: [root]}
        self.fit_memo: dict[frozenset[tuple[str, int]], tuple[bool, str | None]] = {}
        self.scope: str | None = ANY_ANGLE
        self.best: Node | None = None
        self.counts = {
            "expanded": 0,
            "generated": 0,
            "kept": 1,
            "dominated": 0,
            "oracle": 0,
            "relaxed_kits": 0,
            "resumed": 0,
        }
        self.stop = "exhausted"
        self.batch: int | None = None
        self.max_nodes = MAX_NODES

    def fit(self, mask: int) -> str:
        """:data:`FITS`, :data:`NO` or :data:`RELAXED` for the kit (the oracle, memoised by
        part multiset; module docstring); without ``relax`` a "no" narrows the proof's scope
        by its own."""
        multiset = dict(self.space.instance.kit_parts(self.space.order(mask)))
        key = frozenset(multiset.items())
        verdict = self.fit_memo.get(key)
        if verdict is None:
            self.counts["oracle"] += 1
            verdict = self.fits(multiset) if multiset else (True, None)
            self.fit_memo[key] = verdict
            if not verdict[0] and verdict[1] != ANY_ANGLE and self.relax:
                self.counts["relaxed_kits"] += 1
        if verdict[0]:
            return FITS
        if verdict[1] != ANY_ANGLE and self.relax:
            return RELAXED
        self.scope = _narrow(self.scope, verdict[1])
        return NO

    def verify(self, node: Node) -> bool:
        """The lazy fit test of a node about to be expanded; a node that passes retires the
        nodes of its ideal it dominates (a relaxed one only relaxed ones)."""
        if node.verified:
            return True
        answer = self.fit(node.kit)
        if answer == NO:
            node.alive = False
            return False
        node.verified = True
        node.relaxed = node.relaxed or answer == RELAXED
        mine = self.memory[node.done]
        for o in mine:
            if o is not node and o.alive and _dominates(node, o):
                o.alive = False
                self.counts["dominated"] += 1
        mine[:] = [o for o in mine if o.alive]
        return True

    def expand(self, node: Node, f: float) -> None:
        """Push the node's children that survive the bound and the dominance test, at most
        ``batch`` of them: with more kits left the node goes back on the heap with its ``f``
        (deeper children first among equal bounds) and the next pop resumes it (``resumed``;
        module docstring)."""
        space, counts = self.space, self.counts
        kits = node.pending
        if kits is None:
            counts["expanded"] += 1
            kits = space.children(node.done, node.state, self.upper - self.tol)
        else:
            counts["resumed"] += 1
        node.pending = None
        pushed, batch = 0, self.batch
        for mask, r, h, station in kits:
            counts["generated"] += 1
            stop = self._stop_within(counts)
            if stop is not None:  # the node's other kits are not pushed: keep it open
                self.stop = stop
                node.pending = kits
                heapq.heappush(self.heap, (f, 0, next(self.tick), node))
                return
            done = node.done | mask
            state = space.step(node.state, r, h, station)
            bound = space.lower_bound(done, state)
            if bound >= self.upper - self.tol:
                continue
            child = Node(done, state, node, mask, relaxed=node.relaxed)
            kept = self.memory.get(done)
            if kept is not None and any(o.verified and _dominates(o, child) for o in kept):
                counts["dominated"] += 1
                continue
            if done == space.full:  # a plan better than the incumbent (if its last kit fits)
                self._complete(child, bound)  # the bound of a complete plan is its makespan
                continue
            self.memory.setdefault(done, []).append(child)
            counts["kept"] += 1
            depth = -bin(done).count("1")
            heapq.heappush(self.heap, (bound, depth, next(self.tick), child))
            pushed += 1
            if (
                batch is not None and pushed >= batch
            ):  # the rest later: the node stays open with its f
                node.pending = kits
                depth = -bin(node.done).count("1")
                heapq.heappush(self.heap, (f, depth, next(self.tick), node))
                return

    def _complete(self, child: Node, makespan: float) -> None:
        """A complete plan below the incumbent: the new incumbent, or a relaxed plan's
        makespan as a bound candidate (module docstring)."""
        answer = self.fit(child.kit)
        if answer == NO:
            return
        if child.relaxed or answer == RELAXED:
            self.relaxed_best = min(self.relaxed_best, makespan)
            return
        self.upper, self.best = makespan, child
        self.tol = self.margin(makespan)

    def margin(self, upper: float) -> float:
        """How far below ``upper`` a bound must be for a plan that is better (module
        docstring, "bound"): half the makespan's grid, else ``1e-9`` of ``upper``."""
        if self.step is not None:
            return self.step / 2
        return 1e-9 * max(1.0, abs(upper)) if upper < math.inf else 0.0

    def _late(self) -> bool:
        return self.deadline is not None and time.perf_counter() >= self.deadline

    def _stop_within(self, counts: dict[str, int]) -> str | None:
        """Why an expansion stops before its next kit (None: it goes on): the deadline, or
        ``max_nodes`` kept. One node of a sparse precedence graph with a loose tray has
        millions of kits (``sparse_n50_s1_tu_loose_d0``: 9.6 million nodes kept in 3
        expansions, 10.7 GB), so the cap between expansions alone does not bound memory."""
        if counts["kept"] >= self.max_nodes:
            return "memory"
        if not counts["generated"] & 63 and self._late():
            return "time_limit"
        return None

    def outcome(self) -> Outcome:
        """The incumbent found, the bound, the scope and the counters (module docstring)."""
        open_f = min((f for f, _, _, n in self.heap if n.alive), default=math.inf)
        exhausted = self.stop == "exhausted"
        low = min(self.upper, self.relaxed_best)
        bound = low if exhausted else min(low, open_f)
        exhausted = exhausted and self.relaxed_best >= self.upper - self.tol
        kits = None if self.best is None else _kits_of(self.space, self.best)
        self.counts["ideals"] = len(self.memory)
        return Outcome(kits, self.upper, bound, exhausted, self.scope, self.stop, self.counts)


def _dominates(a: Node, b: Node) -> bool:
    """``a`` dominates ``b`` (same ideal): a state at most ``b``'s in every component, and not
    relaxed unless ``b`` is (module docstring)."""
    return (b.relaxed or not a.relaxed) and _leq(a.state, b.state)


def _leq(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    """Componentwise ``a <= b`` (``a``'s node dominates ``b``'s, same ideal)."""
    return all(x <= y for x, y in zip(a, b, strict=True))


def _kits_of(space: Space, node: Node) -> list[list[str]]:
    """The kits on the path to ``node``, first kit first."""
    out: list[list[str]] = []
    cur: Node | None = node
    while cur is not None and cur.parent is not None:
        out.append(space.order(cur.kit))
        cur = cur.parent
    return out[::-1]
