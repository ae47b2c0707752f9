"""Exact geometry of rotated rectangles (part footprints on the tray).

The checker and every solver's final answer use these functions: a separating-axis test for
overlap, corner containment for the tray, and exact intersection areas by convex clipping.
:func:`layout_violations` is the one layout-validity test built on them: the checker
(:mod:`bilevel_kit.validate`) reports its findings, the layout searches
(:mod:`bilevel_kit.heuristics.cross_entropy`, :mod:`bilevel_kit.heuristics.convex`) accept a layout
only when :func:`exactly_valid` says so, so no solver can call valid what the checker rejects.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

#: Length tolerance (mm) of every geometric test: touching parts and parts flush with the tray
#: edge are fine; penetrations deeper than this are violations. The one rule of every packer
#: and of the checker (docs/timeline.md#packing-tolerance): :func:`length_fits`,
#: :func:`area_fits`, :func:`cells_needed` and :func:`cells_available` say it for them.
TOL = 1e-6


def length_fits(length: float, room: float) -> bool:
    """Does ``length`` (mm, e.g. parts side by side) fit in ``room``? Up to :data:`TOL`, as
    the checker measures: three 30.1 mm parts, 90.30000000000001 mm in floats, fit 90.3 mm."""
    return length <= room + TOL


def area_fits(area: float, width: float, height: float) -> bool:
    """Can parts of total ``area`` (mm^2) fit a ``width`` x ``height`` tray? The necessary
    condition, with the room each side gains from :data:`TOL`."""
    return area <= (width + TOL) * (height + TOL)


def cells_needed(length: float, resolution: float) -> int:
    """Grid cells a part of ``length`` takes at ``resolution`` (rounded up, at least 1): a
    part never shrinks by more than :data:`TOL`."""
    return max(1, math.ceil((length - TOL) / resolution))


def cells_available(length: float, resolution: float) -> int:
    """Grid cells a tray of ``length`` holds at ``resolution`` (rounded down): a tray never
    grows by more than :data:`TOL`."""
    return math.floor((length + TOL) / resolution)


def corners(x: float, y: float, w: float, h: float, theta_deg: float) -> np.ndarray:
    """The 4 corners (counter-clockwise, shape (4, 2)) of a w x h rectangle centred at (x, y)
    and rotated by ``theta_deg`` degrees."""
    t = math.radians(theta_deg)
    c, s = math.cos(t), math.sin(t)
    hw, hh = w / 2.0, h / 2.0
    local = np.array([[-hw, -hh], [hw, -hh], [hw, hh], [-hw, hh]])
    rot = np.array([[c, -s], [s, c]])
    return local @ rot.T + np.array([x, y])


def _axis_overlaps(a: np.ndarray, b: np.ndarray) -> Iterator[float]:
    """The overlap of the two shapes' projections on each of their 8 edge normals, in order."""
    for poly in (a, b):
        for i in range(4):
            edge = poly[(i + 1) % 4] - poly[i]
            n = np.array([-edge[1], edge[0]])
            n /= np.linalg.norm(n)
            pa = a @ n
            pb = b @ n
            yield min(pa.max(), pb.max()) - max(pa.min(), pb.min())


def penetration(a: np.ndarray, b: np.ndarray) -> float:
    """Separating-axis penetration depth of two convex quadrilaterals (corner arrays).

    Returns the smallest overlap of the projections over the 4 edge normals; a value <= 0
    means a separating axis exists (the shapes are disjoint or touch).
    """
    return min(_axis_overlaps(a, b))


def _penetration_over(a: np.ndarray, b: np.ndarray, tol: float) -> float | None:
    """:func:`penetration` when it exceeds ``tol``, else None. The depth only decreases from
    axis to axis, so the first axis with an overlap <= ``tol`` settles "no": the remaining
    axes (most of the work for the many pairs that merely come near) are skipped."""
    depth = math.inf
    for overlap in _axis_overlaps(a, b):
        depth = min(depth, overlap)
        if depth <= tol:
            return None
    return depth


def rects_overlap(a: np.ndarray, b: np.ndarray, tol: float = TOL) -> bool:
    """True when the interiors of two rectangles intersect by more than ``tol`` mm."""
    return _penetration_over(a, b, tol) is not None


def inside_tray(c: np.ndarray, width: float, height: float, tol: float = TOL) -> bool:
    """True when every corner lies in [0, width] x [0, height] (within ``tol``)."""
    return bool(
        (c[:, 0] >= -tol).all()
        and (c[:, 0] <= width + tol).all()
        and (c[:, 1] >= -tol).all()
        and (c[:, 1] <= height + tol).all()
    )


def _clip(subject: list[np.ndarray], a: np.ndarray, b: np.ndarray) -> list[np.ndarray]:
    """Sutherland-Hodgman: keep the part of ``subject`` left of the directed line a -> b."""

    def side(p: np.ndarray) -> float:
        return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])

    out: list[np.ndarray] = []
    n = len(subject)
    for i in range(n):
        cur, nxt = subject[i], subject[(i + 1) % n]
        sc, sn = side(cur), side(nxt)
        if sc >= 0:
            out.append(cur)
        if (sc >= 0) != (sn >= 0):
            t = sc / (sc - sn)
            out.append(cur + t * (nxt - cur))
    return out


def polygon_area(poly: list[np.ndarray] | np.ndarray) -> float:
    """Shoelace area of a simple polygon."""
    if len(poly) < 3:
        return 0.0
    p = np.asarray(poly)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def intersection_area(a: np.ndarray, b: np.ndarray) -> float:
    """Exact area of the intersection of two convex polygons given counter-clockwise."""
    poly = list(a)
    for i in range(len(b)):
        poly = _clip(poly, b[i], b[(i + 1) % len(b)])
        if not poly:
            return 0.0
    return polygon_area(poly)


class Footprint(Protocol):
    """A w x h rectangle centred at (x, y), rotated by ``theta`` degrees (mm);
    :class:`bilevel_kit.plan.Placement` is one."""

    @property
    def x(self) -> float: ...
    @property
    def y(self) -> float: ...
    @property
    def w(self) -> float: ...
    @property
    def h(self) -> float: ...
    @property
    def theta(self) -> float: ...


@dataclass(frozen=True)
class LayoutViolation:
    """One geometric fault of a layout; indices refer to the footprints given.

    ``outside_tray``: footprint ``index`` has a corner more than ``tol`` outside the tray.
    ``overlap``: footprints ``index`` < ``other`` penetrate by ``depth`` > ``tol`` mm
    (separating-axis depth) and intersect in ``area`` mm^2.
    """

    kind: Literal["outside_tray", "overlap"]
    index: int
    other: int | None = None
    depth: float = 0.0
    area: float = 0.0


def layout_violations(
    parts: Sequence[Footprint],
    width: float,
    height: float,
    tol: float = TOL,
    *,
    first: bool = False,
    limit: int | None = None,
) -> list[LayoutViolation]:
    """Every footprint outside the ``width`` x ``height`` tray (in input order), then every
    overlapping pair (in lexicographic index order); ``first=True`` stops at the first fault,
    ``limit`` after that many overlapping pairs (then the pairs listed are those of the first
    blocks of parts :func:`near_pairs` visits, still sorted).

    Only pairs whose axis-aligned bounding boxes come within ``tol`` of each other get the
    separating-axis test: for boxes farther apart, one of the two rectangles' edge normals
    separates them (separating-axis theorem), so their depth is negative. Up to
    :data:`SMALL_LAYOUT` parts every pair of boxes is compared; above, a grid hash finds the
    near pairs and a vectorised separating-axis test keeps only the pairs that may penetrate
    for the exact test, in time and memory near-linear in the number of parts for a layout
    without overlaps (docs/formats.md).
    """
    out: list[LayoutViolation] = []
    n = len(parts)
    if n <= SMALL_LAYOUT:
        corner_sets = [corners(p.x, p.y, p.w, p.h, p.theta) for p in parts]
        outside = [not inside_tray(c, width, height, tol) for c in corner_sets]
    else:
        allc = _all_corners(parts)
        lo_c, hi_c = allc.min(axis=1), allc.max(axis=1)
        outside = (
            (lo_c < -tol).any(axis=1) | (hi_c[:, 0] > width + tol) | (hi_c[:, 1] > height + tol)
        ).tolist()
    for k in np.flatnonzero(outside).tolist():
        out.append(LayoutViolation("outside_tray", k))
        if first:
            return out
    if n < 2:
        return out
    stop = 1 if first else limit
    found: list[LayoutViolation] = []
    if n <= SMALL_LAYOUT:
        lo = np.array([c.min(axis=0) for c in corner_sets])
        hi = np.array([c.max(axis=0) for c in corner_sets])
        i, j = np.triu_indices(n, 1)
        near = ((np.minimum(hi[i], hi[j]) - np.maximum(lo[i], lo[j])) > -tol).all(axis=1)
        _exact_pairs(parts, corner_sets, i[near], j[near], tol, found, stop)
    else:
        for i, j in near_pairs(lo_c, hi_c, tol):
            keep = _sat_depth(allc[i], allc[j]) > tol / 2  # the exact test decides (> tol)
            _exact_pairs(parts, None, i[keep], j[keep], tol, found, stop)
            if stop is not None and len(found) >= stop:
                break
    found.sort(key=lambda f: (f.index, f.other))
    return out + found[:stop]


#: Up to this many footprints :func:`layout_violations` compares every pair of bounding boxes
#: (the layout searches' kits); above, it uses the grid hash of :func:`near_pairs`.
SMALL_LAYOUT = 64
#: Candidate pairs handled at once by the grid hash (bounds the memory of a dense layout).
PAIR_BLOCK = 100_000


def _exact_pairs(
    parts: Sequence[Footprint],
    corner_sets: Sequence[np.ndarray] | None,
    i: np.ndarray,
    j: np.ndarray,
    tol: float,
    found: list[LayoutViolation],
    stop: int | None,
) -> None:
    """The separating-axis depth of each pair (i, j) on the parts' own corners; the pairs
    deeper than ``tol`` go to ``found`` with their area, until ``stop`` of them."""
    for a, b in zip(i.tolist(), j.tolist(), strict=True):
        if corner_sets is not None:
            ca, cb = corner_sets[a], corner_sets[b]
        else:
            pa, pb = parts[a], parts[b]
            ca = corners(pa.x, pa.y, pa.w, pa.h, pa.theta)
            cb = corners(pb.x, pb.y, pb.w, pb.h, pb.theta)
        depth = _penetration_over(ca, cb, tol)
        if depth is not None:
            found.append(LayoutViolation("overlap", a, b, depth, intersection_area(ca, cb)))
            if stop is not None and len(found) >= stop:
                return


def _all_corners(parts: Sequence[Footprint]) -> np.ndarray:
    """The corners of every footprint at once, shape (n, 4, 2), as :func:`corners` gives them
    (to rounding)."""
    x, y, w, h, th = (
        np.array([getattr(p, k) for p in parts], dtype=float) for k in ("x", "y", "w", "h", "theta")
    )
    t = np.radians(th)
    c, s = np.cos(t), np.sin(t)
    lx = np.stack([-w, w, w, -w], axis=1) / 2.0
    ly = np.stack([-h, -h, h, h], axis=1) / 2.0
    px = lx * c[:, None] - ly * s[:, None] + x[:, None]
    py = lx * s[:, None] + ly * c[:, None] + y[:, None]
    return np.stack([px, py], axis=2)


def _sat_depth(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`penetration` of many pairs of quadrilaterals at once (shapes (m, 4, 2))."""
    normals = []
    for poly in (a, b):
        edge = np.roll(poly, -1, axis=1) - poly
        nrm = np.stack([-edge[:, :, 1], edge[:, :, 0]], axis=2)
        normals.append(nrm / np.linalg.norm(nrm, axis=2, keepdims=True))
    axes = np.concatenate(normals, axis=1)  # (m, 8, 2)
    pa = np.einsum("mpd,mkd->mpk", a, axes)
    pb = np.einsum("mpd,mkd->mpk", b, axes)
    over = np.minimum(pa.max(axis=1), pb.max(axis=1)) - np.maximum(pa.min(axis=1), pb.min(axis=1))
    return np.asarray(over.min(axis=1))


def near_pairs(
    lo: np.ndarray, hi: np.ndarray, tol: float
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """The pairs (i < j) of boxes that come within ``tol`` of each other, in blocks of about
    :data:`PAIR_BLOCK` candidates: a multi-level grid hash. Each box (grown by ``tol``) gets
    the level whose cells are at least as large as it, so it covers at most 2 x 2 cells there;
    a box meets the boxes of its own level in its cells, and those of every coarser level in
    the (again at most 2 x 2) cells it covers at that level. Boxes that meet share a cell at
    the coarser of their levels, so no near pair is missed; a hash collision only adds a
    candidate, which the box test removes."""
    n = len(lo)
    glo, ghi = lo - tol, hi + tol
    ext = (ghi - glo).max(axis=1)
    span = float(max(ext.max(), (ghi.max(axis=0) - glo.min(axis=0)).max(), tol))
    base = max(float(ext.min()), span * 2.0**-40)
    level = np.ceil(np.log2(np.maximum(ext / base, 1.0))).astype(np.int64)
    reg_keys: list[np.ndarray] = []
    reg_parts: list[np.ndarray] = []
    for lv in np.unique(level).tolist():
        members = np.flatnonzero(level == lv)
        keys, owner = _cell_keys(glo[members], ghi[members], base * 2.0**lv, lv)
        reg_keys.append(keys)
        reg_parts.append(members[owner])
    keys_all, parts_all = np.concatenate(reg_keys), np.concatenate(reg_parts)
    order = np.argsort(keys_all, kind="stable")
    keys_all, parts_all = keys_all[order], parts_all[order]
    levels = np.unique(level).tolist()
    q_keys, q_parts = [], []
    for lv in levels:  # every box asks the levels at least as coarse as its own
        members = np.flatnonzero(level <= lv)
        keys, owner = _cell_keys(glo[members], ghi[members], base * 2.0**lv, lv)
        q_keys.append(keys)
        q_parts.append(members[owner])
    qk, qp = np.concatenate(q_keys), np.concatenate(q_parts)
    order = np.argsort(qp, kind="stable")  # blocks end at part boundaries
    qk, qp = qk[order], qp[order]
    left = np.searchsorted(keys_all, qk, "left")
    counts = np.searchsorted(keys_all, qk, "right") - left
    ends = np.cumsum(counts)
    start = 0
    while start < len(qk):
        stop = int(np.searchsorted(ends, ends[start] - counts[start] + PAIR_BLOCK, "right"))
        stop = max(stop, start + 1)
        if stop < len(qk):  # whole parts per block, so a pair is deduplicated in its block
            stop = int(np.searchsorted(qp, qp[stop - 1], "right"))
        c = counts[start:stop]
        a = np.repeat(qp[start:stop], c)
        first = np.repeat(left[start:stop] - (np.cumsum(c) - c), c)
        b = parts_all[first + np.arange(len(a))]
        same = level[a] == level[b]
        keep = (b > a) & same | (level[a] < level[b])
        a, b = a[keep], b[keep]
        a, b = np.minimum(a, b), np.maximum(a, b)
        pair = np.unique(a * n + b)
        a, b = pair // n, pair % n
        near = ((np.minimum(hi[a], hi[b]) - np.maximum(lo[a], lo[b])) > -tol).all(axis=1)
        yield a[near], b[near]
        start = stop


def _cell_keys(
    glo: np.ndarray, ghi: np.ndarray, cell: float, lv: int
) -> tuple[np.ndarray, np.ndarray]:
    """Hash keys of the cells (of size ``cell``, level ``lv``) each box covers, with the
    index of its box: 2 x 2 cells at most at its own level or a coarser one (3 x 3 when the
    rounding of ``cell`` makes it a hair smaller than the box)."""
    lim = 2.0**40
    i0 = np.clip(np.floor(glo / cell), -lim, lim).astype(np.int64)
    i1 = np.clip(np.floor(ghi / cell), -lim, lim).astype(np.int64)
    keys, owners = [], []
    for dx in (0, 1, 2):
        for dy in (0, 1, 2):
            ok = (i0[:, 0] + dx <= i1[:, 0]) & (i0[:, 1] + dy <= i1[:, 1])
            ix, iy = (i0[ok, 0] + dx).astype(np.uint64), (i0[ok, 1] + dy).astype(np.uint64)
            keys.append(
                np.uint64(lv * 0x9E3779B97F4A7C15 % 2**64)
                ^ ix * np.uint64(0xBF58476D1CE4E5B9)
                ^ iy * np.uint64(0x94D049BB133111EB)
            )
            owners.append(np.flatnonzero(ok))
    return np.concatenate(keys), np.concatenate(owners)


def exactly_valid(
    parts: Sequence[Footprint], width: float, height: float, tol: float = TOL
) -> bool:
    """True when :func:`layout_violations` finds nothing: every footprint inside the tray and no
    pair penetrating deeper than ``tol`` mm (the checker's own test)."""
    return not layout_violations(parts, width, height, tol, first=True)


def exact_step(values: Sequence[float], max_units: int | None = None) -> float | None:
    """The coarsest step of which every value is a multiple: the greatest common divisor of
    the values as fractions with denominators up to 10^6 (152.4, 12.7 and 300 give 0.1);
    None when a value is no such fraction (or not positive), or the largest value would span
    more than ``max_units`` steps (None: no cap)."""
    from fractions import Fraction

    fracs = []
    for v in values:
        f = Fraction(v).limit_denominator(10**6)
        if f <= 0 or abs(float(f) - v) > 1e-9 * max(1.0, abs(v)):
            return None
        fracs.append(f)
    if not fracs:
        return None
    den = 1
    for f in fracs:
        den = den * f.denominator // math.gcd(den, f.denominator)
    num = 0
    for f in fracs:
        num = math.gcd(num, f.numerator * (den // f.denominator))
    step = Fraction(num, den)
    if max_units is not None and max(fracs) / step > max_units:
        return None
    return float(step)
