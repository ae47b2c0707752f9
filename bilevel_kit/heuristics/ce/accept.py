"""Exact acceptance of cross-entropy layouts (:mod:`bilevel_kit.heuristics.cross_entropy`):
validity and fitness of a candidate, the push-apart repair of small overlaps, and the choice
among candidates. Nothing overlapping leaves here marked valid."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ... import geometry
from ...fitness import box_overlap_1d, box_pairs, pair_distance_sums
from ...instance import Tray
from ...plan import Placement
from ...reachability import ReachGrid
from .. import _kernels
from .kit import MAX_CE_PARTS, Kit, clip_centre, extents64


def exactly_valid(layout: Sequence[Placement], tray: Tray, reach: ReachGrid | None = None) -> bool:
    """The checker's own geometry test (:func:`bilevel_kit.geometry.exactly_valid`: every part
    inside the tray, no pair penetrating deeper than ``geometry.TOL``) and, with a reach map,
    every centre reachable: the final gate of every answer."""
    if not geometry.exactly_valid(layout, tray.width, tray.height):
        return False
    return bool(
        reach is None
        or reach.lookup(np.array([p.x for p in layout]), np.array([p.y for p in layout])).all()
    )


@dataclass
class Candidate:
    """A decoded layout, its fitness and whether it passed the cheap exact test."""

    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    fitness: float
    valid: bool
    source: str


def assess(
    kit: Kit, x: np.ndarray, y: np.ndarray, theta: np.ndarray, w6: float, source: str
) -> Candidate:
    """Validity and fitness of a decoded layout, cheaply: box overlaps for all pairs at once,
    exact separating-axis tests and clipped areas only for pairs whose boxes overlap (the
    others are disjoint). Valid: exact fitness; invalid: fitness with the box Z (only used to
    rank layouts that will not be presented as valid)."""
    ex, ey = extents64(kit, theta)
    W, H = kit.tray.width, kit.tray.height
    tol = geometry.TOL
    inside = bool(
        (x - ex >= -tol).all()
        and (x + ex <= W + tol).all()
        and (y - ey >= -tol).all()
        and (y + ey <= H + tol).all()
    )
    dsd, i, j, z_box = _pair_terms(kit, x, y, ex, ey)
    if kit.reach is not None and not kit.reach.lookup(x, y).all():
        inside = False  # an unreachable centroid is as invalid as a part off the tray
    if not inside:
        return Candidate(x, y, theta, -(dsd + w6 * z_box), False, source)
    z = 0.0
    for a, b in zip(i.tolist(), j.tolist(), strict=True):
        ca = geometry.corners(x[a], y[a], kit.w[a], kit.h[a], theta[a])
        cb = geometry.corners(x[b], y[b], kit.w[b], kit.h[b], theta[b])
        if geometry.rects_overlap(ca, cb):
            return Candidate(x, y, theta, -(dsd + w6 * z_box), False, source)
        z += geometry.intersection_area(ca, cb)
    return Candidate(x, y, theta, -(dsd + w6 * z), True, source)


def _pair_terms(
    kit: Kit, x: np.ndarray, y: np.ndarray, ex: np.ndarray, ey: np.ndarray
) -> tuple[float, np.ndarray, np.ndarray, float]:
    """(D_same - D_diff, the pairs (i, j) whose boxes overlap, their box Z) of one layout:
    over the kit's pair table, or for a kit too large for CE without it
    (:func:`bilevel_kit.fitness.pair_distance_sums` and the grid hash)."""
    if kit.n > MAX_CE_PARTS:
        d_same, d_diff = pair_distance_sums(x, y, [t.id for t in kit.types])
        i, j = box_pairs(x, y, ex, ey)
        dx, dy = x[i] - x[j], y[i] - y[j]
        z_box = float(box_overlap_1d(dx, ex[i], ex[j]) @ box_overlap_1d(dy, ey[i], ey[j]))
        return d_same - d_diff, i, j, z_box
    i, j = kit.pairs.i, kit.pairs.j
    dx = x[i] - x[j]
    dy = y[i] - y[j]
    dsd = float(kit.pairs.sign.astype(np.float64) @ np.hypot(dx, dy))
    ox = ex[i] + ex[j] - np.abs(dx)
    oy = ey[i] + ey[j] - np.abs(dy)
    hit = np.flatnonzero((ox > 0) & (oy > 0))
    z_box = float(
        box_overlap_1d(dx[hit], ex[i[hit]], ex[j[hit]])
        @ box_overlap_1d(dy[hit], ey[i[hit]], ey[j[hit]])
    )
    return dsd, i[hit], j[hit], z_box


def push_apart(
    kit: Kit,
    x: np.ndarray,
    y: np.ndarray,
    theta: np.ndarray,
    rounds: int = 200,
    compiled: bool = True,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Separate overlapping bounding boxes by moving both parts of each overlapping pair half
    the overlap (plus 1e-5 mm) apart along the axis of smaller overlap, then clipping to the
    tray; repeated until no boxes overlap. Disjoint boxes imply disjoint parts. None if the
    rounds run out."""
    ex, ey = extents64(kit, theta)
    x, y = x.copy(), y.copy()
    i, j = kit.pairs.i, kit.pairs.j
    kernel = _kernels.push_apart_kernel() if compiled else None
    if kernel is not None:  # the same floats, compiled (tests/heuristics/test_kernels.py)
        W, H = float(kit.tray.width), float(kit.tray.height)
        ok = kernel(x, y, ex, ey, i.astype(np.int64), j.astype(np.int64), W, H, rounds)
        return (x, y) if ok else None
    margin = 1e-5
    for _ in range(rounds):
        dx = x[i] - x[j]
        dy = y[i] - y[j]
        ox = ex[i] + ex[j] - np.abs(dx)
        oy = ey[i] + ey[j] - np.abs(dy)
        bad = (ox > 0) & (oy > 0)
        if not bad.any():
            return x, y
        along_x = bad & (ox <= oy)
        along_y = bad & ~along_x
        sx = np.where(dx >= 0, 1.0, -1.0) * np.where(along_x, (ox + margin) / 2, 0.0)
        sy = np.where(dy >= 0, 1.0, -1.0) * np.where(along_y, (oy + margin) / 2, 0.0)
        x += np.bincount(i, sx, kit.n) - np.bincount(j, sx, kit.n)
        y += np.bincount(i, sy, kit.n) - np.bincount(j, sy, kit.n)
        x = clip_centre(x, ex, kit.tray.width)
        y = clip_centre(y, ey, kit.tray.height)
    return None


def candidate(kit: Kit, v: np.ndarray, w6: float, source: str, repair: bool) -> Candidate:
    """Decode a vector and assess it; if it is invalid, assess its push-apart repair."""
    x, y, theta = kit.decode(v)
    cand = assess(kit, x, y, theta, w6, source)
    if cand.valid or not repair:
        return cand
    moved = push_apart(kit, x, y, theta)
    if moved is not None:
        fixed = assess(kit, moved[0], moved[1], theta, w6, source + "+repair")
        if fixed.valid:
            return fixed
    return cand


def choose(kit: Kit, cands: Sequence[Candidate]) -> Candidate:
    """The fittest candidate that passes the exact geometry check, else the fittest invalid
    one (marked invalid). Ties go to the earlier candidate."""
    order = sorted(range(len(cands)), key=lambda k: (not cands[k].valid, -cands[k].fitness, k))
    for k in order:
        cd = cands[k]
        if not cd.valid:
            break
        if exactly_valid(kit.layout(cd.x, cd.y, cd.theta), kit.tray, kit.reach):
            return cd
        cd.valid = False
    return cands[order[0]]
