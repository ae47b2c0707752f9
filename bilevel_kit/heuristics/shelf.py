"""A simple deterministic tray packer: shelf packing, first-fit decreasing height (FFDH).

Why: the baselines need *some* valid layout for every kit, and the cross-entropy solver needs a
valid start point when its own search ends with overlap. The packer either returns a layout the
checker accepts or ``None`` ("does not fit"); it never returns overlapping parts.

Algorithm: items are sorted by height (then width, then id) decreasing and placed left to right
on horizontal shelves; an item goes on the first shelf with room, else on a new shelf on top.
Four attempts are made in a fixed order, the first success wins: rotatable parts lying
landscape (long side along x) or portrait, with shelves as rows or as columns.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from ..geometry import area_fits, length_fits
from ..instance import PartType, Tray
from ..plan import Placement


def kit_items(
    part_types: Mapping[str, PartType], counts: Mapping[str, int]
) -> list[tuple[str, PartType]]:
    """The parts of a kit as (part id, type) pairs; ids are ``type-k`` in sorted type order."""
    return [(f"{t}-{k}", part_types[t]) for t in sorted(counts) for k in range(1, counts[t] + 1)]


def _ffdh(
    width: float, height: float, items: list[tuple[str, PartType, bool]]
) -> list[tuple[str, PartType, float, float, bool]] | None:
    """Shelf FFDH of (id, type, rotated) items in a width x height box; None if they don't fit."""

    def dims(pt: PartType, rot: bool) -> tuple[float, float]:
        return (pt.height, pt.width) if rot else (pt.width, pt.height)

    order = sorted(items, key=lambda it: (-dims(it[1], it[2])[1], -dims(it[1], it[2])[0], it[0]))
    shelves: list[list[float]] = []  # [y, shelf height, used width]
    top = 0.0
    placed = []
    for pid, pt, rot in order:
        w, h = dims(pt, rot)
        if not length_fits(w, width):
            return None
        for shelf in shelves:  # the one tolerance rule (docs/timeline.md#packing-tolerance)
            if length_fits(shelf[2] + w, width) and length_fits(h, shelf[1]):
                placed.append((pid, pt, shelf[2] + w / 2, shelf[0] + h / 2, rot))
                shelf[2] += w
                break
        else:
            if not length_fits(top + h, height):
                return None
            shelves.append([top, h, w])
            placed.append((pid, pt, w / 2, top + h / 2, rot))
            top += h
    return placed


def shelf_pack(tray: Tray, items: Sequence[tuple[str, PartType]]) -> tuple[Placement, ...] | None:
    """A valid axis-aligned layout of ``items`` on ``tray``, or ``None`` if the packer fails.

    ``None`` means this packer found no layout, not a proof that none exists (the CP-SAT
    packer of :mod:`bilevel_kit.models.packing` decides that exactly).
    """
    if not area_fits(sum(pt.area for _, pt in items), tray.width, tray.height):
        return None
    for landscape in (True, False):
        for columns in (False, True):
            oriented = []
            for pid, pt in items:
                rot = False
                if pt.rotatable:
                    long_on_x = pt.width >= pt.height
                    rot = long_on_x != landscape
                oriented.append((pid, pt, rot))
            if columns:  # pack in the transposed tray; a transposed footprint is a 90° turn
                # (a fixed part gets rot=True there, which maps back to theta = 0)
                flipped = [(pid, pt, not rot) for pid, pt, rot in oriented]
                res = _ffdh(tray.height, tray.width, flipped)
                if res is None:
                    continue
                return tuple(
                    Placement(pid, pt.id, y, x, 0.0 if rot else 90.0, pt.width, pt.height)
                    for pid, pt, x, y, rot in sorted(res, key=lambda r: r[0])
                )
            res = _ffdh(tray.width, tray.height, oriented)
            if res is not None:
                return tuple(
                    Placement(pid, pt.id, x, y, 90.0 if rot else 0.0, pt.width, pt.height)
                    for pid, pt, x, y, rot in sorted(res, key=lambda r: r[0])
                )
    return None
