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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

#: Length tolerance (mm) of every geometric test: touching parts and parts flush with the tray
#: edge are fine; penetrations deeper than this are violations.
TOL = 1e-6


def corners(x: float, y: float, w: float, h: float, theta_deg: float) -> np.ndarray:
    """The 4 corners (counter-clockwise, shape (4, 2)) of a w x h rectangle centred at (x, y)
    and rotated by ``theta_deg`` degrees."""
    t = math.radians(theta_deg)
    c, s = math.cos(t), math.sin(t)
    hw, hh = w / 2.0, h / 2.0
    local = np.array([[-hw, -hh], [hw, -hh], [hw, hh], [-hw, hh]])
    rot = np.array([[c, -s], [s, c]])
    return local @ rot.T + np.array([x, y])


def rotated_extent(w: float, h: float, theta_deg: float) -> tuple[float, float]:
    """Half-extents (ex, ey) of the axis-aligned bounding box of a rotated w x h rectangle."""
    t = math.radians(theta_deg)
    c, s = abs(math.cos(t)), abs(math.sin(t))
    return (w * c + h * s) / 2.0, (w * s + h * c) / 2.0


def penetration(a: np.ndarray, b: np.ndarray) -> float:
    """Separating-axis penetration depth of two convex quadrilaterals (corner arrays).

    Returns the smallest overlap of the projections over the 4 edge normals; a value <= 0
    means a separating axis exists (the shapes are disjoint or touch).
    """
    depth = math.inf
    for poly in (a, b):
        for i in range(4):
            edge = poly[(i + 1) % 4] - poly[i]
            n = np.array([-edge[1], edge[0]])
            n /= np.linalg.norm(n)
            pa = a @ n
            pb = b @ n
            depth = min(depth, min(pa.max(), pb.max()) - max(pa.min(), pb.min()))
    return depth


def rects_overlap(a: np.ndarray, b: np.ndarray, tol: float = TOL) -> bool:
    """True when the interiors of two rectangles intersect by more than ``tol`` mm."""
    return penetration(a, b) > tol


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
) -> list[LayoutViolation]:
    """Every footprint outside the ``width`` x ``height`` tray (in input order), then every
    overlapping pair (in lexicographic index order); ``first=True`` stops at the first fault.

    Only pairs whose axis-aligned bounding boxes come within ``tol`` of each other get the
    separating-axis test: for boxes farther apart, one of the two rectangles' edge normals
    separates them (separating-axis theorem), so their depth is negative.
    """
    out: list[LayoutViolation] = []
    corner_sets = [corners(p.x, p.y, p.w, p.h, p.theta) for p in parts]
    for k, c in enumerate(corner_sets):
        if not inside_tray(c, width, height, tol):
            out.append(LayoutViolation("outside_tray", k))
            if first:
                return out
    if len(corner_sets) < 2:
        return out
    lo = np.array([c.min(axis=0) for c in corner_sets])
    hi = np.array([c.max(axis=0) for c in corner_sets])
    i, j = np.triu_indices(len(corner_sets), 1)
    near = ((np.minimum(hi[i], hi[j]) - np.maximum(lo[i], lo[j])) > -tol).all(axis=1)
    for a, b in zip(i[near].tolist(), j[near].tolist(), strict=True):
        depth = penetration(corner_sets[a], corner_sets[b])
        if depth > tol:
            area = intersection_area(corner_sets[a], corner_sets[b])
            out.append(LayoutViolation("overlap", a, b, depth, area))
            if first:
                return out
    return out


def exactly_valid(
    parts: Sequence[Footprint], width: float, height: float, tol: float = TOL
) -> bool:
    """True when :func:`layout_violations` finds nothing: every footprint inside the tray and no
    pair penetrating deeper than ``tol`` mm (the checker's own test)."""
    return not layout_violations(parts, width, height, tol, first=True)
