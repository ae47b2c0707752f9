"""The closed prefix sets of a decision, level by level (:mod:`..greedy_search`).

A prefix set is held as its smallest topological order, its *canonical sequence*; the sets of
size ``i + 1`` are those of size ``i`` each followed by one of its *children* (the tasks that
keep the sequence canonical). :class:`Precedence` is the precedence graph in the forms the
construction reads, :class:`Window` what ``done`` alone fixes for a decision, and
:func:`build_levels` the levels themselves (a beam beyond the cap on prefix sets).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .frontier import smallest


@dataclass
class Level:
    """The prefix sets of one size: canonical sequences and their sums."""

    seqs: list[tuple[int, ...]]
    tasks: np.ndarray
    robot: np.ndarray
    human: np.ndarray
    counts: np.ndarray


@dataclass(frozen=True)
class Window:
    """What ``done`` alone fixes for a decision: the available tasks, the window (the undone
    ancestors of each window task, :meth:`Precedence.window`), the window tasks of least and
    greatest robot times (``length`` of each, increasing and decreasing) and the range of
    their times, and the undone predecessors of each task (-1: done)."""

    avail: list[int]
    anc: dict[int, frozenset[int]]
    low: np.ndarray
    high: np.ndarray
    r_range: tuple[float, float]
    undone: list[int]


class Children:
    """Prefix rows (task indices) as parent rows plus one task each, built only where needed
    (a beam level scores many children and keeps few)."""

    def __init__(
        self, parents: np.ndarray, par: np.ndarray | None = None, child: np.ndarray | None = None
    ) -> None:
        self.parents = parents
        self.par = par
        self.child = child

    def __len__(self) -> int:
        return len(self.parents) if self.par is None else len(self.par)

    def take(self, rows: np.ndarray | None = None) -> np.ndarray:
        """The task matrix of ``rows`` (all if None)."""
        if self.par is None or self.child is None:
            return self.parents if rows is None else self.parents[rows]
        par, child = (self.par, self.child) if rows is None else (self.par[rows], self.child[rows])
        return np.concatenate([self.parents[par], child[:, None]], axis=1)

    def touches(self, marked: np.ndarray) -> np.ndarray:
        """Whether each row holds a task with ``marked`` set."""
        hit = marked[self.parents].any(axis=1)
        if self.par is None or self.child is None:
            return np.asarray(hit)
        return np.asarray(hit[self.par] | marked[self.child])


#: Scores of candidate rows of level ``i`` for the beam: (i, rows, robot, human, counts).
BeamScore = Callable[[int, Children, np.ndarray, np.ndarray, np.ndarray], np.ndarray]

#: A beam level at once, or None where it does not apply: (i, parents' tasks, their unlocked
#: children, robot sums, human sums, count rows) -> (parent row, child, score) of the
#: ``beam_width`` children the beam keeps, in the order of :func:`_children`.
FastBeam = Callable[
    [int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    tuple[np.ndarray, np.ndarray, np.ndarray] | None,
]


class Precedence:
    """The precedence graph (predecessors of each task) in the forms the prefix sets and the
    rest searches read: tuples per task, and arrays for many tasks at once. Static."""

    def __init__(self, pred: Sequence[frozenset[int]]) -> None:
        self.n = len(pred)
        self.pred = [tuple(sorted(p)) for p in pred]
        succ: list[list[int]] = [[] for _ in pred]
        for j, ps in enumerate(self.pred):
            for p in ps:
                succ[p].append(j)
        self.succ = [tuple(s) for s in succ]
        self.pred_set = [frozenset(p) for p in self.pred]
        #: the precedence arcs (predecessor, task), for the epoch's available tasks at once
        self.arc_pred = np.array([p for ps in self.pred for p in ps], dtype=np.int64)
        self.arc_task = np.array([j for j, ps in enumerate(self.pred) for _ in ps], dtype=np.int64)
        #: the arcs as sorted keys ``pred * n + task`` (membership of many arcs at once)
        self.arc_keys = np.sort(self.arc_pred * self.n + self.arc_task)
        #: the successors of every task, flat (CSR: task x's are ``succ_flat[start:start+deg]``)
        self.succ_deg = np.array([len(s) for s in self.succ], dtype=np.int64)
        self.succ_start = np.cumsum(self.succ_deg) - self.succ_deg
        self.succ_flat = np.array([z for s in self.succ for z in s], dtype=np.int64)

    def window(self, done: np.ndarray, length: int, robot: np.ndarray) -> Window:
        """The :class:`Window` of a decision with windows of ``length`` tasks."""
        undone = np.bincount(self.arc_task[~done[self.arc_pred]], minlength=self.n)
        avail: list[int] = np.flatnonzero((undone == 0) & ~done).tolist()
        anc = self._ancestors(done, avail, length)
        window = np.array(sorted(anc), dtype=np.int64)
        order = np.lexsort((window, robot[window]))
        low = window[order[:length]]
        high = window[order[::-1][:length]]
        r_range = (float(robot[low[0]]), float(robot[high[0]]))
        undone_list: list[int] = np.where(done, -1, undone).tolist()
        return Window(avail, anc, low, high, r_range, undone_list)

    def _ancestors(
        self, done: np.ndarray, avail: list[int], length: int
    ) -> dict[int, frozenset[int]]:
        """The undone ancestors of the tasks with at most ``length - 1`` of them: only those
        tasks can be in a window of ``length`` tasks, since a closed window holds every undone
        ancestor of its tasks."""
        anc: dict[int, frozenset[int]] = {y: frozenset() for y in avail}
        queue = list(avail)
        for x in queue:
            for y in self.succ[x]:
                if y in anc or done[y]:
                    continue
                ps = [p for p in self.pred[y] if not done[p]]
                if not all(p in anc for p in ps):
                    continue
                a = frozenset().union(*(anc[p] for p in ps)) | frozenset(ps)
                if len(a) <= length - 1:
                    anc[y] = a
                    queue.append(y)
        return anc

    def unlocked_after(
        self, unlocked: tuple[int, ...], seq: tuple[int, ...], y: int, undone: list[int]
    ) -> tuple[int, ...]:
        """The *unlocked children* of ``seq``, from those of its parent ``seq[:-1]``.

        The children of a canonical sequence ``s`` (the smallest topological order of its
        set) are the tasks ``z`` such that ``s + (z,)`` is canonical again: ``z`` available
        given done and ``s``, and above every task of ``s`` after the last predecessor of
        ``z`` in ``s``. Those available given done alone are the available tasks above
        ``max(s)``; the others, the unlocked ones (increasing), are built here. With
        ``seq = s + (y,)``: a child of ``s`` stays one iff it is above ``y``, and the
        successors of ``y`` whose undone predecessors (``undone``: their count, < 0 for a task
        done) all lie in ``seq`` are new children (``y`` comes last)."""
        kept = [u for u in unlocked if u > y] if unlocked else []
        new = [
            z
            for z in self.succ[y]
            if undone[z] == 1
            or (undone[z] > 1 and len(self.pred_set[z].intersection(seq)) == undone[z])
        ]
        if not new:
            return tuple(kept)
        return tuple(sorted([*kept, *new]))

    def unlocked_rows(
        self,
        p_unl: np.ndarray,
        par: np.ndarray,
        child: np.ndarray,
        tasks: np.ndarray,
        undone: np.ndarray,
    ) -> np.ndarray:
        """:meth:`unlocked_after` for every row of a level at once.

        ``p_unl``: the parents' unlocked children, one row per parent, increasing and padded
        with ``n`` (the number of tasks, above every task); row k of the level is parent
        ``par[k]`` followed by ``child[k]`` (its tasks: ``tasks[k]``). Returns the rows'
        unlocked children in the same padded form: the parent's above ``child[k]``, and the
        successors z of ``child[k]`` whose undone predecessors (``undone[z]``) all lie in
        ``tasks[k]``."""
        n = self.n
        k_rows = len(child)
        kept = p_unl[par]
        kr, kc = np.nonzero((kept < n) & (kept > child[:, None]))
        rows_out = [kr]
        vals_out = [kept[kr, kc]]
        deg = self.succ_deg[child]
        rows = np.repeat(np.arange(k_rows), deg)
        if rows.size:
            offset = ragged_positions(deg)
            z = self.succ_flat[np.repeat(self.succ_start[child], deg) + offset]
            need = undone[z]
            ok = need == 1
            multi = np.flatnonzero(need > 1)
            if multi.size:  # count the arcs (task of the row) -> z
                keys = tasks[rows[multi]] * n + z[multi, None]
                arcs = self.arc_keys
                pos = np.minimum(np.searchsorted(arcs, keys), len(arcs) - 1)
                ok[multi] = (arcs[pos] == keys).sum(axis=1) == need[multi]
            rows_out.append(rows[ok])
            vals_out.append(z[ok])
        all_rows = np.concatenate(rows_out)
        all_vals = np.concatenate(vals_out)
        if all_rows.size == 0:
            return np.full((k_rows, 0), n, dtype=np.int64)
        order = np.lexsort((all_vals, all_rows))
        all_rows, all_vals = all_rows[order], all_vals[order]
        count = np.bincount(all_rows, minlength=k_rows)
        col = ragged_positions(count)
        out = np.full((k_rows, int(count.max())), n, dtype=np.int64)
        out[all_rows, col] = all_vals
        return out


def build_levels(
    graph: Precedence,
    window: Window,
    length: int,
    *,
    robot: np.ndarray,
    human: np.ndarray,
    part_matrix: np.ndarray,
    max_sets: int,
    beam_width: int,
    beam_score: BeamScore,
    fast_beam: FastBeam | None = None,
) -> tuple[list[Level], bool]:
    """The closed prefix sets of sizes 1..``length``, and whether a level became a beam.

    ``robot``, ``human``, ``part_matrix``: each task's times and part counts (summed over a
    prefix). Once the sets would exceed ``max_sets``, this level and the deeper ones keep the
    ``beam_width`` rows of least ``beam_score`` (the optimistic score); ``fast_beam`` makes
    and scores a beam level's children at once (the same rows and scores)."""
    avail = np.array(window.avail, dtype=np.int64)
    undone = np.array(window.undone, dtype=np.int64)
    parents: list[tuple[int, ...]] = [()]
    p_tasks = np.zeros((1, 0), dtype=np.int64)
    p_robot = np.zeros(1)
    p_human = np.zeros(1)
    p_counts = np.zeros((1, part_matrix.shape[1]), dtype=np.int64)
    #: per parent, its children that ``done`` alone does not make available (increasing,
    #: padded with n: :meth:`Precedence.unlocked_rows`)
    p_unl = np.zeros((1, 0), dtype=np.int64)
    levels: list[Level] = []
    total = 0
    beam = False
    for i in range(1, length + 1):
        fast = None
        if fast_beam is not None and (
            beam or total + _n_children(avail, p_tasks, p_unl, graph.n) > max_sets
        ):
            fast = fast_beam(i, p_tasks, p_unl, p_robot, p_human, p_counts)
        if fast is not None:  # the beam's rows only
            par, child, _ = fast
            beam = True
        else:
            par, child = _children(avail, p_tasks, p_unl, graph.n)
        if len(child) == 0:
            break
        k_robot = p_robot[par] + robot[child]
        k_human = p_human[par] + human[child]
        k_counts = p_counts[par] + part_matrix[child]
        if fast is None and (beam or total + len(child) > max_sets):
            beam = True
            opt = beam_score(i, Children(p_tasks, par, child), k_robot, k_human, k_counts)
            keep = smallest(opt, beam_width)
            par, child = par[keep], child[keep]
            k_robot, k_human, k_counts = k_robot[keep], k_human[keep], k_counts[keep]
        seqs = [(*parents[a], y) for a, y in zip(par.tolist(), child.tolist(), strict=True)]
        tasks = np.concatenate([p_tasks[par], child[:, None]], axis=1)
        levels.append(Level(seqs, tasks, k_robot, k_human, k_counts))
        total += len(seqs)
        if i < length:
            p_unl = graph.unlocked_rows(p_unl, par, child, tasks, undone)
        parents, p_tasks, p_robot, p_human, p_counts = seqs, tasks, k_robot, k_human, k_counts
    return levels, beam


def _n_children(avail: np.ndarray, p_tasks: np.ndarray, p_unl: np.ndarray, n: int) -> int:
    """How many rows :func:`_children` gives, without making them."""
    last = p_tasks.max(axis=1) if p_tasks.shape[1] else np.full(1, -1)
    starts = np.searchsorted(avail, last, side="right")
    return int((len(avail) - starts).sum() + (p_unl < n).sum())


def _children(
    avail: np.ndarray, p_tasks: np.ndarray, p_unl: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """The children of every parent row (``p_tasks``) as (parent row, child), parent-major
    and increasing within a parent (module docstring: canonical sequences): the available
    tasks (``avail``, sorted) above the parent's largest task, at once, plus the tasks the
    parent unlocks (``p_unl``, padded with ``n``)."""
    last = p_tasks.max(axis=1) if p_tasks.shape[1] else np.full(1, -1)
    # per parent the available tasks from its first above ``last``, parent-major
    starts = np.searchsorted(avail, last, side="right")
    n_per = len(avail) - starts
    par = np.repeat(np.arange(len(last)), n_per)
    offset = ragged_positions(n_per)
    child = avail[np.repeat(starts, n_per) + offset]
    extra_par, extra_col = np.nonzero(p_unl < n)
    if extra_par.size:
        par = np.concatenate([par, extra_par])
        child = np.concatenate([child, p_unl[extra_par, extra_col]])
        order = np.lexsort((child, par))
        par, child = par[order], child[order]
    return par, child


def ragged_positions(sizes: np.ndarray) -> np.ndarray:
    """For groups of ``sizes`` laid out one after another, each element's position in its
    group: ``[0, 1, .., sizes[0] - 1, 0, 1, .., sizes[1] - 1, ...]``."""
    return np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)


def unique_rows(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of a non-negative integer matrix and the index of each row's, as
    ``np.unique(axis=0)`` (rows packed into one integer each when they fit 52 bits)."""
    if len(counts) == 0 or counts.shape[1] == 0:
        keys, inverse = np.unique(counts, axis=0, return_inverse=True)
        return keys, inverse.reshape(-1)
    base = counts.max(axis=0).astype(np.float64) + 1.0
    if float(np.prod(base)) >= 2.0**52:  # the radix below exact in floating point
        keys, inverse = np.unique(counts, axis=0, return_inverse=True)
        return keys, inverse.reshape(-1)
    radix = np.cumprod(np.concatenate([[1.0], base[:0:-1]]))[::-1].astype(np.int64)
    _, first, inverse = np.unique(counts @ radix, return_index=True, return_inverse=True)
    return counts[first], inverse.reshape(-1)
