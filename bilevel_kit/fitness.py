"""Kit-fitness terms of the lower level (paper Section IV-B, Eqs. 8-11), vectorised.

For the parts P of one kit, with centres (P_x, P_y) and types Q::

    D_diff(P) = sum_{k<j, Q(P_k) != Q(P_j)} |P_k - P_j|          (Eq. 8)
    D_same(P) = sum_{k<j, Q(P_k) == Q(P_j)} |P_k - P_j|          (Eq. 9)
    Z(P)      = sum_{k<j} area(BB(P_k) cap BB(P_j))               (Eq. 10)
    min_P  D_same - D_diff + W6 * Z                               (Eq. 11, corrected)

Erratum (docs/errata.md): Eq. 11 is printed as ``D_same - D_diff - W6*Z``, which would
*reward* overlap although the text says overlap is penalised; this module uses ``+ W6*Z``.
The fitness is reported as ``-(D_same - D_diff + W6*Z)``, so bigger is better.

Geometry of Z. The batch evaluation (:func:`kit_fitness_terms` and its hot path
:class:`PairScorer`, which the cross-entropy method calls once per iteration) uses the
paper's BB literally: the *axis-aligned bounding box* of each rotated footprint, half-extents
``ex = (w|cos t| + h|sin t|)/2``, ``ey = (w|sin t| + h|cos t|)/2``. The pairwise box overlap
is the product of the overlap lengths along x and y (:func:`box_overlap_1d`). It
over-estimates the exact overlap of rotated parts (it is exact for parts at 0/90 degrees) and
is zero only if the exact overlap is zero, so a zero box-Z certifies a layout.
:func:`layout_terms` also returns the exact Z of the rotated rectangles (convex clipping via
:func:`bilevel_kit.geometry.intersection_area`); that is what final answers report.

Batches are evaluated with numpy broadcasting over all pairs ``np.triu_indices(n, 1)`` in
part-major layout ``(n, S)`` (gathering rows is several times faster than gathering columns),
with no Python loop over samples or pairs. Arrays keep the caller's float dtype, so a caller
that only ranks samples (the CE method) may score in float32.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from . import geometry
from .instance import Tray
from .plan import Placement


@dataclass(frozen=True)
class PairTable:
    """What the pair sums of one kit need and that does not change between samples.

    ``i < j`` index every unordered pair once (``np.triu_indices``); ``same[p]`` says whether
    pair p has equal types; ``sign`` is +1 for same-type and -1 for different-type pairs, so
    ``sign @ dist`` is ``D_same - D_diff`` in one contraction.
    """

    n: int
    i: np.ndarray
    j: np.ndarray
    same: np.ndarray
    sign: np.ndarray

    @classmethod
    def build(cls, types: Sequence[Hashable], dtype: np.dtype | type = np.float64) -> PairTable:
        labels = list(types)
        codes = np.array([labels.index(t) for t in labels], dtype=np.intp)
        i, j = np.triu_indices(len(labels), 1)
        same = codes[i] == codes[j]
        sign = np.where(same, 1.0, -1.0).astype(dtype)
        return cls(len(labels), i, j, same, sign)

    @property
    def n_pairs(self) -> int:
        return int(self.i.size)


class KitTerms(NamedTuple):
    """Per-sample terms, each of shape (S,): Eqs. 9, 8, 10 (box geometry) and the tray
    violation (total length by which rotated bounding boxes stick out of the tray)."""

    d_same: np.ndarray
    d_diff: np.ndarray
    z: np.ndarray
    out: np.ndarray


def half_extents(
    w: np.ndarray | float, h: np.ndarray | float, theta_deg: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Half-extents (ex, ey) of the axis-aligned bounding boxes of rotated w x h rectangles.

    Broadcasts; computed in the dtype of ``theta_deg`` (float32 stays float32)."""
    t = np.asarray(theta_deg)
    if not np.issubdtype(t.dtype, np.floating):
        t = t.astype(np.float64)
    rad = np.radians(t)
    c = np.abs(np.cos(rad))
    s = np.abs(np.sin(rad))
    w = np.asarray(w, dtype=t.dtype)
    h = np.asarray(h, dtype=t.dtype)
    ex = 0.5 * (w * c + h * s)
    ey = 0.5 * (w * s + h * c)
    return ex, ey


class PairScorer:
    """The hot path: Eqs. 8-10 (box Z) for batches of ``samples`` samples of one kit.

    Inputs are part-major, shape (n, S): row gathers are contiguous, column gathers are not.
    All (P, S) temporaries live in buffers allocated once: fresh arrays of this size cost
    page faults on every call, which tripled the time per batch in measurements. The pair
    sums are ``np.einsum`` reductions, which do not go through a multithreaded BLAS.

    Box overlap per axis: two intervals of half-lengths e_i, e_j whose centres are d apart
    overlap by ``max(0, min(e_i + e_j - |d|, 2 min(e_i, e_j)))`` (the second term when one
    interval contains the other). ``np.maximum`` is given a zero array, not the scalar 0:
    the scalar form is about 4x slower here.
    """

    def __init__(self, pairs: PairTable, samples: int, dtype: np.dtype | type = np.float64) -> None:
        self.pairs = pairs
        self.samples = samples
        self.dtype = np.dtype(dtype)
        shape = (pairs.n_pairs, samples)
        # dx, dy, dist, a, b, m, zero
        self._buf = [np.empty(shape, dtype=self.dtype) for _ in range(6)]
        self._zero = np.zeros(shape, dtype=self.dtype)
        self._sign = pairs.sign.astype(self.dtype)
        self._masks = np.stack([pairs.same, ~pairs.same]).astype(self.dtype)

    def _fill(self, xT: np.ndarray, yT: np.ndarray) -> np.ndarray:
        """Centre differences into dx, dy; returns the pair distances."""
        i, j = self.pairs.i, self.pairs.j
        dx, dy, dist, a, _, _ = self._buf
        xT.take(i, axis=0, out=dx)
        xT.take(j, axis=0, out=a)
        dx -= a
        yT.take(i, axis=0, out=dy)
        yT.take(j, axis=0, out=a)
        dy -= a
        np.multiply(dx, dx, out=dist)
        np.multiply(dy, dy, out=a)
        dist += a
        np.sqrt(dist, out=dist)
        return dist

    def _axis(
        self, eT: np.ndarray, d: np.ndarray, out: np.ndarray, other: np.ndarray, m: np.ndarray
    ) -> np.ndarray:
        """Overlap lengths along one axis into ``out``; overwrites ``d``, ``other``, ``m``."""
        i, j = self.pairs.i, self.pairs.j
        eT.take(i, axis=0, out=out)
        eT.take(j, axis=0, out=other)
        np.minimum(out, other, out=m)
        m += m  # 2 min(e_i, e_j)
        out += other  # e_i + e_j
        np.abs(d, out=d)
        out -= d
        np.minimum(out, m, out=out)
        np.maximum(out, self._zero, out=out)
        return out

    def _overlap(self, exT: np.ndarray, eyT: np.ndarray) -> np.ndarray:
        dx, dy, _, a, b, m = self._buf
        ox = self._axis(exT, dx, a, b, m)
        oy = self._axis(eyT, dy, b, dx, m)
        return np.einsum("ps,ps->s", ox, oy)

    def _check(self, xT: np.ndarray) -> None:
        if xT.shape != (self.pairs.n, self.samples):
            raise ValueError(f"expected shape {(self.pairs.n, self.samples)}, got {xT.shape}")

    def signed(
        self, xT: np.ndarray, yT: np.ndarray, exT: np.ndarray, eyT: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(D_same - D_diff, Z_box), each of shape (S,)."""
        self._check(xT)
        dsd = np.einsum("p,ps->s", self._sign, self._fill(xT, yT))
        return dsd, self._overlap(exT, eyT)

    def terms(
        self, xT: np.ndarray, yT: np.ndarray, exT: np.ndarray, eyT: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(D_same, D_diff, Z_box), each of shape (S,)."""
        self._check(xT)
        d_same, d_diff = np.einsum("qp,ps->qs", self._masks, self._fill(xT, yT))
        return d_same, d_diff, self._overlap(exT, eyT)


def box_overlap_1d(d: np.ndarray, e_i: np.ndarray, e_j: np.ndarray) -> np.ndarray:
    """Overlap length of intervals with half-lengths e_i, e_j and centres d apart."""
    return np.maximum(0.0, np.minimum(e_i + e_j - np.abs(d), 2.0 * np.minimum(e_i, e_j)))


def tray_violation(
    xT: np.ndarray, yT: np.ndarray, exT: np.ndarray, eyT: np.ndarray, width: float, height: float
) -> np.ndarray:
    """Per sample, the summed lengths (mm) by which rotated bounding boxes leave the tray
    (left, right, bottom and top overhangs of every part); inputs in shape (n, S)."""
    dt = xT.dtype.type
    out = np.maximum(exT - xT, dt(0)).sum(axis=0)
    out += np.maximum(xT + exT - dt(width), dt(0)).sum(axis=0)
    out += np.maximum(eyT - yT, dt(0)).sum(axis=0)
    out += np.maximum(yT + eyT - dt(height), dt(0)).sum(axis=0)
    return out


def kit_fitness_terms(
    x: np.ndarray,
    y: np.ndarray,
    theta: np.ndarray,
    types: Sequence[Hashable],
    widths: Sequence[float] | np.ndarray,
    heights: Sequence[float] | np.ndarray,
    *,
    tray: Tray | tuple[float, float] | None = None,
    pairs: PairTable | None = None,
) -> KitTerms:
    """Eqs. 8-10 and the tray violation for a batch: x, y, theta (degrees) of shape (S, n).

    ``types``, ``widths`` and ``heights`` describe the n parts (unrotated footprints).
    ``Z`` uses the axis-aligned bounding boxes of the rotated footprints (module docstring).
    ``out`` is zero when ``tray`` is None. Computed in the float dtype of ``x``.
    """
    x = np.atleast_2d(np.asarray(x))
    if not np.issubdtype(x.dtype, np.floating):
        x = x.astype(np.float64)
    dt = x.dtype
    y = np.atleast_2d(np.asarray(y, dtype=dt))
    theta = np.atleast_2d(np.asarray(theta, dtype=dt))
    n = x.shape[1]
    if y.shape != x.shape or theta.shape != x.shape:
        raise ValueError(
            f"x, y, theta must share shape (S, n); got {x.shape}, {y.shape}, {theta.shape}"
        )
    if len(types) != n or len(widths) != n or len(heights) != n:
        raise ValueError(f"types, widths, heights must have n = {n} entries")
    if pairs is None:
        pairs = PairTable.build(types, dt)
    w = np.asarray(widths, dtype=dt)[:, None]
    h = np.asarray(heights, dtype=dt)[:, None]
    xT, yT = x.T, y.T
    exT, eyT = half_extents(w, h, theta.T)
    d_same, d_diff, z = PairScorer(pairs, x.shape[0], dt).terms(xT, yT, exT, eyT)
    if tray is None:
        out = np.zeros(x.shape[0], dtype=dt)
    else:
        width, height = (tray.width, tray.height) if isinstance(tray, Tray) else tray
        out = tray_violation(xT, yT, exT, eyT, width, height)
    return KitTerms(d_same, d_diff, z, out)


def kit_fitness(terms: KitTerms, w6: float) -> np.ndarray:
    """Fitness ``-(D_same - D_diff + W6 * Z)`` per sample (Eq. 11 with the erratum's sign;
    bigger is better). The tray violation is not part of it: callers constrain or penalise."""
    return -(terms.d_same - terms.d_diff + w6 * terms.z)


def layout_terms(layout: Sequence[Placement]) -> tuple[float, float, float, float]:
    """(D_same, D_diff, Z_box, Z_exact) of one layout, in float64.

    ``Z_exact`` sums the exact intersection areas of the rotated rectangles; only pairs whose
    bounding boxes overlap are clipped (the others intersect in zero area). Above
    :data:`LARGE_LAYOUT` parts the distance sums run over blocks of rows and the overlaps over
    the grid hash's near pairs, so memory stays linear in the number of parts."""
    if len(layout) < 2:
        return 0.0, 0.0, 0.0, 0.0
    if len(layout) > LARGE_LAYOUT:
        return _large_layout_terms(layout)
    x = np.array([[p.x for p in layout]])
    y = np.array([[p.y for p in layout]])
    th = np.array([[p.theta for p in layout]])
    w = [p.w for p in layout]
    h = [p.h for p in layout]
    terms = kit_fitness_terms(x, y, th, [p.type for p in layout], w, h)
    return (
        float(terms.d_same[0]),
        float(terms.d_diff[0]),
        float(terms.z[0]),
        exact_overlap_area(layout),
    )


#: Above this many parts a single layout is scored without the all-pairs table (the kits too
#: large for the cross-entropy search, laid out by the shelf packer).
LARGE_LAYOUT = 500
#: Pair distances computed at once by :func:`pair_distance_sums` (bounds its memory).
DISTANCE_BLOCK = 1 << 20


def pair_distance_sums(
    x: np.ndarray, y: np.ndarray, labels: Sequence[Hashable]
) -> tuple[float, float]:
    """(D_same, D_diff) of Eqs. 8-9 for one layout: ``D_same`` as the sum over each type's
    own pairs, ``D_diff`` as all pairs' sum minus it. Quadratic time in scipy's C loops,
    memory of :data:`DISTANCE_BLOCK` distances."""
    points = np.column_stack([x, y]).astype(np.float64)
    codes = np.unique(np.asarray(labels, dtype=object).astype(str), return_inverse=True)[1]
    d_all = _pairwise_sum(points)
    kinds = np.unique(codes).tolist()
    if len(kinds) == 1:
        return d_all, 0.0
    d_same = sum(_pairwise_sum(points[codes == c]) for c in kinds)
    return float(d_same), float(d_all - d_same)


def _pairwise_sum(points: np.ndarray) -> float:
    """The sum of the distances of every unordered pair of ``points``, in blocks of rows."""
    from scipy.spatial.distance import cdist, pdist

    n = len(points)
    rows = max(1, DISTANCE_BLOCK // max(n, 1))
    total = 0.0
    for a in range(0, n, rows):
        b = min(n, a + rows)
        total += float(pdist(points[a:b]).sum()) + float(cdist(points[a:b], points[b:]).sum())
    return total


def _box_arrays(layout: Sequence[Placement]) -> tuple[np.ndarray, ...]:
    x = np.array([p.x for p in layout], dtype=np.float64)
    y = np.array([p.y for p in layout], dtype=np.float64)
    ex, ey = half_extents(
        np.array([p.w for p in layout], dtype=np.float64),
        np.array([p.h for p in layout], dtype=np.float64),
        np.array([p.theta for p in layout], dtype=np.float64),
    )
    return x, y, ex, ey


def _large_layout_terms(layout: Sequence[Placement]) -> tuple[float, float, float, float]:
    """:func:`layout_terms` for a large layout (same terms, summed in another order)."""
    x, y, ex, ey = _box_arrays(layout)
    d_same, d_diff = pair_distance_sums(x, y, [p.type for p in layout])
    i, j = box_pairs(x, y, ex, ey)
    z_box = float(
        box_overlap_1d(x[i] - x[j], ex[i], ex[j]) @ box_overlap_1d(y[i] - y[j], ey[i], ey[j])
    )
    order = np.lexsort((j, i))
    pairs = zip(i[order].tolist(), j[order].tolist(), strict=True)
    return d_same, d_diff, z_box, exact_overlap_area(layout, pairs)


def box_pairs(
    x: np.ndarray, y: np.ndarray, ex: np.ndarray, ey: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i < j) whose boxes overlap with positive area: every pair below
    :data:`LARGE_LAYOUT` parts, the grid hash's near pairs above."""
    n = len(x)
    if n <= LARGE_LAYOUT:
        i, j = np.triu_indices(n, 1)
    else:
        lo = np.stack([x - ex, y - ey], axis=1)
        hi = np.stack([x + ex, y + ey], axis=1)
        found = list(geometry.near_pairs(lo, hi, 0.0))
        i = np.concatenate([a for a, _ in found]) if found else np.zeros(0, dtype=np.int64)
        j = np.concatenate([b for _, b in found]) if found else np.zeros(0, dtype=np.int64)
    ox = ex[i] + ex[j] - np.abs(x[i] - x[j])
    oy = ey[i] + ey[j] - np.abs(y[i] - y[j])
    hit = (ox > 0) & (oy > 0)
    return i[hit], j[hit]


def overlapping_box_pairs(layout: Sequence[Placement]) -> list[tuple[int, int]]:
    """Index pairs whose bounding boxes overlap with positive area: the only candidates for an
    exact overlap (a disjoint or touching box pair cannot intersect in its interior)."""
    if len(layout) < 2:
        return []
    i, j = box_pairs(*_box_arrays(layout))
    order = np.lexsort((j, i))
    return [(int(a), int(b)) for a, b in zip(i[order], j[order], strict=True)]


def exact_overlap_area(
    layout: Sequence[Placement], pairs: Iterable[tuple[int, int]] | None = None
) -> float:
    """Exact Eq.-10 Z on the rotated rectangles themselves (not their bounding boxes), mm^2;
    ``pairs``: the :func:`overlapping_box_pairs` of the layout when the caller has them."""
    corners = {}
    total = 0.0
    for a, b in overlapping_box_pairs(layout) if pairs is None else pairs:
        for k in (a, b):
            if k not in corners:
                p = layout[k]
                corners[k] = geometry.corners(p.x, p.y, p.w, p.h, p.theta)
        total += geometry.intersection_area(corners[a], corners[b])
    return total


def layout_fitness(layout: Sequence[Placement], w6: float) -> float:
    """Exact fitness ``-(D_same - D_diff + W6 * Z_exact)`` of one layout (bigger is better)."""
    d_same, d_diff, _, z_exact = layout_terms(layout)
    return -(d_same - d_diff + w6 * z_exact)
