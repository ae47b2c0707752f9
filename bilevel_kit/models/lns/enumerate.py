"""The exact windows of ``lns`` with several stations (:mod:`.stations`): every rearrangement
of a window's tasks into kits, by enumeration (docs/stations.md#lns-with-several-stations).

A window frees the tasks of a run of consecutive kits. Its tasks of station ``s`` stay between
``s``'s kits before and after it, so a rearrangement is valid when, per station, it is an order
of that station's freed tasks that keeps their precedence, cut into kits that fit the tray
(docs/timeline.md#several-stations: a kit holds one station's tasks), and the stations' kit
sequences are interleaved in any way. Each distinct rearrangement (kits as task sets) is
yielded once.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence

#: A kit sequence: kits of task indices, in delivery order.
Kits = list[list[int]]


def station_sequences(
    tasks: Sequence[int],
    preds: Mapping[int, frozenset[int]],
    fits: Callable[[Sequence[int]], bool],
) -> Iterator[Kits]:
    """Every precedence-keeping order of ``tasks`` (one station's) cut into fitting kits,
    each distinct kit sequence once; ``preds[i]`` are ``i``'s predecessors (those outside
    ``tasks`` are placed already)."""
    free = set(tasks)
    need = {i: preds.get(i, frozenset()) & free for i in tasks}
    seen: set[tuple[frozenset[int], ...]] = set()

    def grow(done: set[int], kits: Kits) -> Iterator[Kits]:
        if len(done) == len(free):
            key = tuple(frozenset(k) for k in kits)
            if key not in seen:
                seen.add(key)
                yield [list(k) for k in kits]
            return
        for i in tasks:
            if i in done or not need[i] <= done:
                continue
            done.add(i)
            if kits and fits([*kits[-1], i]):  # i joins the current kit
                kits[-1].append(i)
                yield from grow(done, kits)
                kits[-1].pop()
            if fits([i]):  # i opens a new kit
                kits.append([i])
                yield from grow(done, kits)
                kits.pop()
            done.remove(i)

    yield from grow(set(), [])


def interleavings(sequences: Sequence[Kits]) -> Iterator[Kits]:
    """Every merge of the kit ``sequences`` that keeps each one's order."""
    total = sum(len(s) for s in sequences)
    at = [0] * len(sequences)
    out: Kits = []

    def step() -> Iterator[Kits]:
        if len(out) == total:
            yield list(out)
            return
        for j, seq in enumerate(sequences):
            if at[j] < len(seq):
                out.append(seq[at[j]])
                at[j] += 1
                yield from step()
                at[j] -= 1
                out.pop()

    yield from step()


def rearrangements(
    by_station: Sequence[Sequence[int]],
    preds: Mapping[int, frozenset[int]],
    fits: Callable[[Sequence[int]], bool],
) -> Iterator[Kits]:
    """Every rearrangement of a window (module docstring): ``by_station`` its tasks grouped
    by station (each group in its current order)."""
    per = [list(station_sequences(tasks, preds, fits)) for tasks in by_station if tasks]
    if any(not p for p in per):
        return

    def choose(j: int, picked: list[Kits]) -> Iterator[Kits]:
        if j == len(per):
            yield from interleavings(picked)
            return
        for seq in per[j]:
            picked.append(seq)
            yield from choose(j + 1, picked)
            picked.pop()

    yield from choose(0, [])
