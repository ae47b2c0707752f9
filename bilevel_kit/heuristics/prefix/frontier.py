"""The order in which the decision visits prefixes (:mod:`..greedy_search`): the best-first
queue of :meth:`PrefixSearch.decide <..greedy_search.PrefixSearch.decide>` and the beam's
choice of the best rows of a level, both with the ties of a stable sort."""

from __future__ import annotations

import heapq

import numpy as np

#: An entry of the queue: (bound, stage, level, row).
Entry = tuple[float, int, int, int]


def smallest(values: np.ndarray, k: int) -> np.ndarray:
    """The indices (increasing) of the ``k`` smallest values, ties to the smaller index: the
    first ``k`` of a stable sort, without sorting everything."""
    n = len(values)
    if n <= k:
        return np.arange(n)
    kth = values[np.argpartition(values, k - 1)[k - 1]]
    if np.isnan(kth):  # NaNs sort last; keep the plain rule
        return np.sort(np.lexsort((np.arange(n), values))[:k])
    below = np.flatnonzero(values < kth)
    ties = np.flatnonzero(values == kth)[: k - len(below)]
    return np.sort(np.concatenate([below, ties]))


class Frontier:
    """The best-first queue of the decision: entries (bound, stage, level, row) popped in
    increasing order, the initial ones sorted at once (numpy) and merged with a heap of the
    later pushes; the same order as one heap of all (entries are distinct)."""

    def __init__(self, bound: np.ndarray, stage: np.ndarray, level: np.ndarray, row: np.ndarray):
        order = np.lexsort((row, level, stage, bound))
        self._cols = [c[order] for c in (bound, stage, level, row)]
        self._pos = 0
        self._buf: list[Entry] = []
        self._next = 0
        self._heap: list[Entry] = []

    def _static(self) -> Entry | None:
        if self._next == len(self._buf):  # convert the next block of sorted entries
            a, b = self._pos, min(self._pos + 256, len(self._cols[0]))
            if a == b:
                return None
            cols = [c[a:b].tolist() for c in self._cols]
            self._buf, self._next, self._pos = list(zip(*cols, strict=True)), 0, b
        return self._buf[self._next]

    def __bool__(self) -> bool:
        return bool(self._heap) or self._static() is not None

    def peek(self) -> Entry:
        s = self._static()
        if s is None or (self._heap and self._heap[0] < s):
            return self._heap[0]
        return s

    def pop(self) -> Entry:
        s = self._static()
        if s is None or (self._heap and self._heap[0] < s):
            return heapq.heappop(self._heap)
        self._next += 1
        return s

    def push(self, item: Entry) -> None:
        heapq.heappush(self._heap, item)
