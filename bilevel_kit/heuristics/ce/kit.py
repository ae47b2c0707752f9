"""The kit as arrays for the cross-entropy arrangement
(:mod:`bilevel_kit.heuristics.cross_entropy`): part ids, footprints, the pair table, and the
decision vector (centres x, y of the n parts, then the angles of the r rotatable ones) with
its projection into the tray."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ...errors import UsageError
from ...fitness import PairTable
from ...instance import Instance, PartType, Tray
from ...plan import Placement
from ...reachability import ReachGrid, reach_grid


@dataclass
class Kit:
    """Per-call constants: part ids, footprints, the pair table and the vector layout."""

    tray: Tray
    ids: list[str]
    types: list[PartType]
    w: np.ndarray
    h: np.ndarray
    rot_idx: np.ndarray
    fixed_idx: np.ndarray
    #: Float dtype of the pair table (the CE's scoring precision).
    dtype: type
    #: Reach grid when the instance enforces Sawyer reachability (else None).
    reach: ReachGrid | None = None
    n: int = field(init=False)
    dim: int = field(init=False)

    def __post_init__(self) -> None:
        self.n = len(self.ids)
        self.dim = 2 * self.n + self.rot_idx.size

    @cached_property
    def pairs(self) -> PairTable:
        """Every unordered pair of parts, built on first use: it is quadratic in ``n``, and a
        kit too large for CE (:data:`MAX_CE_PARTS`) is scored without it."""
        return PairTable.build([t.id for t in self.types], self.dtype)

    def decode(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, y, theta) in float64 of a decision vector, projected into the tray and with
        angles wrapped to (-90, 90] (a rectangle is symmetric under 180 degrees)."""
        v = np.asarray(v, dtype=np.float64)
        n = self.n
        theta = np.zeros(n)
        theta[self.rot_idx] = 90.0 - np.mod(90.0 - v[2 * n :], 180.0)
        ex, ey = extents64(self, theta)
        x = clip_centre(v[:n], ex, self.tray.width)
        y = clip_centre(v[n : 2 * n], ey, self.tray.height)
        return x, y, theta

    def encode(self, x: np.ndarray, y: np.ndarray, theta: np.ndarray) -> np.ndarray:
        return np.concatenate([x, y, np.asarray(theta)[self.rot_idx]]).astype(np.float64)

    def layout(self, x: np.ndarray, y: np.ndarray, theta: np.ndarray) -> tuple[Placement, ...]:
        return tuple(
            Placement(
                self.ids[k], t.id, float(x[k]), float(y[k]), float(theta[k]), t.width, t.height
            )
            for k, t in enumerate(self.types)
        )


#: The most parts CE lays out: its search space has 3 numbers per part and it keeps a
#: covariance of that size squared (a 4,000-part kit asked for 6 GiB and ran for minutes per
#: iteration). A larger kit gets the shelf packer's layout, or none, scored without the pair
#: table (:func:`bilevel_kit.fitness.large_layout_terms`).
MAX_CE_PARTS = 500


def extents64(kit: Kit, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Half-extents (x, y) in float64 of the parts' boxes rotated by ``theta`` degrees."""
    rad = np.radians(theta)
    c, s = np.abs(np.cos(rad)), np.abs(np.sin(rad))
    return 0.5 * (kit.w * c + kit.h * s), 0.5 * (kit.w * s + kit.h * c)


def clip_centre(c: np.ndarray, e: np.ndarray, side: float) -> np.ndarray:
    """Centres moved so that [c - e, c + e] lies in [0, side]; centred if it cannot."""
    out = np.minimum(np.maximum(c, e), side - e)
    too_big = 2.0 * e > side
    out[too_big] = side / 2.0
    return out


def build_kit(instance: Instance, parts: Mapping[str, int], dtype: type) -> Kit:
    """The kit of the multiset ``parts`` (type -> count): ids ``f"{type}-{k}"``, types in
    sorted order, the pair table in ``dtype``."""
    ids: list[str] = []
    types: list[PartType] = []
    for t in sorted(parts):
        count = parts[t]
        if t not in instance.part_types:
            raise UsageError(f"unknown part type {t!r}")
        if count < 0:
            raise UsageError(f"negative count {count} of part type {t!r}")
        for k in range(1, count + 1):
            ids.append(f"{t}-{k}")
            types.append(instance.part_types[t])
    rot = np.array([t.rotatable for t in types], dtype=bool)
    return Kit(
        tray=instance.tray,
        ids=ids,
        types=types,
        w=np.array([t.width for t in types], dtype=np.float64),
        h=np.array([t.height for t in types], dtype=np.float64),
        rot_idx=np.flatnonzero(rot),
        fixed_idx=np.flatnonzero(~rot),
        dtype=dtype,
        reach=reach_grid(instance),
    )


def start_vector(kit: Kit, start: Sequence[Placement]) -> np.ndarray:
    """Decision vector of a given layout: parts matched by id, else by type in order."""
    by_id = {p.part: p for p in start}
    if len(by_id) == len(start) and set(by_id) == set(kit.ids):
        ordered = [by_id[pid] for pid in kit.ids]
    else:
        queues: dict[str, list[Placement]] = {}
        for p in start:
            queues.setdefault(p.type, []).append(p)
        try:
            ordered = [queues[t.id].pop(0) for t in kit.types]
        except (KeyError, IndexError):
            raise UsageError("start layout does not hold the kit's parts") from None
        if any(queues.values()):
            raise UsageError("start layout holds parts the kit does not need")
    theta = np.array(
        [p.theta if t.rotatable else 0.0 for p, t in zip(ordered, kit.types, strict=True)]
    )
    return kit.encode(np.array([p.x for p in ordered]), np.array([p.y for p in ordered]), theta)
