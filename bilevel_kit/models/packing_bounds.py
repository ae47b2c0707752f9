r"""Cheap proofs that a set of rectangles does not fit a tray (before any search).

All sizes are integers (grid units, :mod:`bilevel_kit.models.packing`); a part that may
turn by 90 degrees counts with whichever orientation is the most favourable for the bound, so
every test below is valid with and without rotation.

* **Too large / area**: a part fits in neither orientation, or
  :math:`\sum_i w_i h_i > W H`.
* **Incompatible pair**: two parts that can be neither side by side (:math:`w_i + w_j > W`)
  nor stacked (:math:`h_i + h_j > H`) in any orientations.
* **Tall (wide) parts**: parts taller than :math:`H/2` all cross the line :math:`y = H/2`, so
  their widths add up to at most W (and symmetrically).
* **Dual-feasible functions** (Fekete and Schepers, "A general framework for bounds for
  higher-dimensional orthogonal packing problems", 2004; Carlier, Clautiaux and Moukrim, 2007).
  A function :math:`f: [0, C] \to [0, f(C)]` is *dual feasible* when
  :math:`\sum_{k} x_k \le C \Rightarrow \sum_k f(x_k) \le f(C)`. For two of them f (on widths,
  C = W) and g (on heights, C = H), any packing satisfies

  .. math:: \sum_i f(w_i)\, g(h_i) \le f(W)\, g(H)

  (the usual argument: the rectangles :math:`[x_i, x_i + w_i)` crossing any vertical line have
  total height at most H, so g-transformed heights too; integrating over the f-transformed
  x axis gives the bound). A violation for any pair (f, g) proves infeasibility. The families
  used, in integer form on :math:`x \in \{0..C\}`: the identity (the area bound);
  :math:`f_0^\lambda` (sizes below :math:`\lambda` count 0, above :math:`C - \lambda` count C);
  Fekete-Schepers :math:`u^{(k)}`; and Carlier-Clautiaux-Moukrim :math:`f_{CCM}^\lambda`.

The tests above assume 0/90-degree layouts. One test holds at **any angle** (true sizes in mm,
:func:`disks_collide`): a w x h part contains the disk of diameter min(w, h) around its centre
whatever its rotation, and that disk lies in the tray, so its centre lies in the tray shrunk by
the radius (and a part whose disk is wider than the tray fits at no angle). Two parts do not
overlap, so neither do their disks: the centres are at least
:math:`r_i + r_j` apart, while the shrunk trays allow at most
:math:`\sqrt{(W - r_i - r_j)^2 + (H - r_i - r_j)^2}`. This distance falls as
:math:`s = r_i + r_j` grows, so the two largest disks decide; two 60 mm squares on a 100 mm
tray fail it (56.6 < 60), at any angles.

Two more tests hold at any angle:

* **One part at any angle** (:func:`fits_at_some_angle`; Carver, "Solution to problem E 1225",
  Amer. Math. Monthly 63, 1956; also Wetzel, "Rectangles in rectangles", Math. Mag. 73, 2000).
  With :math:`p \ge q` and :math:`A \ge B`, a p x q rectangle fits an A x B box iff
  :math:`p \le A,\ q \le B`, or :math:`p > A,\ q \le B` and

  .. math:: B \ge \frac{2pqA + (p^2 - q^2)\sqrt{p^2 + q^2 - A^2}}{p^2 + q^2}.

  At angle t the extents are :math:`p\cos t + q\sin t` and :math:`p\sin t + q\cos t`
  (:math:`t \in [0, \pi/2]` by symmetry). When p > A the first one is at most A exactly on
  :math:`[t_1, \pi/2]`, with :math:`t_1` its second root; there :math:`p\sin t - q\cos t =
  \sqrt{p^2 + q^2 - A^2}`, which gives :math:`\cos t_1, \sin t_1` and the fraction above as
  the second extent at :math:`t_1`. That extent is :math:`R\sin(t + \psi)`, concave on the
  interval, so its minimum there is at :math:`t_1` or at :math:`\pi/2` (where it is p > B).
* **Band parts** (:func:`band_blocks`): on a tray L x S (S the smaller side), a part a x b with
  :math:`a \ge b = S` spans the tray across: at a tilt t its extent across is
  :math:`a|\sin t| + b|\cos t| > b` unless t is a multiple of 180 degrees (of 90 when a = b).
  So it lies axis-aligned, and every other part lies in the strips S wide left over, whose
  lengths add up to :math:`L - \sum a` over the band parts. No layout exists when (i) the
  band parts' lengths add up to more than L, (ii) another part fits at no angle in a
  :math:`(L - \sum a) \times S` box, or (iii) the other parts' area exceeds
  :math:`(L - \sum a) S`. In the exact world below a band part leaves
  :math:`\varepsilon = S - b` across, so it may tilt slightly: its tilt has
  :math:`\sin t \le \sigma = 2\varepsilon / b` (the extent across exceeds
  :math:`b` by :math:`\sin t\,(a - b\tan(t/2)) \ge \sin t\, b/2` for :math:`t \le 45°`), and
  it covers every vertical line of an x range of length at least
  :math:`a - a\sigma^2 - S\sigma` up to :math:`\varepsilon`. A part of smaller side
  :math:`q > \varepsilon` reaches into such a range by at most :math:`\varepsilon L / q` (its
  vertical chords are concave in x, reach q and are at most :math:`\varepsilon` there), which
  (ii) adds to the box on both sides; (iii) compares the areas.

**The checker's tolerance.** The any-angle tests argue on an exact world
(:func:`exact_world`): the checker lets a part (its type's footprint) cross the tray edge by up
to ``tol`` and another part by up to ``tol`` on one of the two rectangles' edge normals. Draw
every part ``tol / 2`` smaller on each side, about its centre: its projection on any unit
direction u, :math:`w|u_1| + h|u_2|`, loses :math:`\mathrm{tol}\,(|u_1| + |u_2|) \ge
\mathrm{tol}`, half at each end. Two parts that overlapped by at most ``tol`` on some axis are
then apart on it, so their interiors are disjoint, and every corner lies at least ``tol / 2``
further in, inside a tray ``tol`` larger. So a layout the checker accepts gives one with
disjoint interiors of parts ``tol`` smaller on a tray ``tol`` larger, and a proof there that no
layout exists holds for the checker. (The packers' area filter,
:func:`bilevel_kit.geometry.area_fits`, is not such a proof: it leaves out the overlaps the
checker allows, a micrometre-scale difference.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

#: Parts as (width, height, rotatable) in grid units.
Sizes = Sequence[tuple[int, int, bool]]

#: Upper limits on the number of functions per axis (the bound is checked for every pair).
MAX_LAMBDAS = 24
MAX_K = 12


def _orientations(w: int, h: int, r: bool, W: int, H: int) -> list[tuple[int, int]]:
    """The orientations (x extent, y extent) in which a part fits the tray on its own."""
    out = [(w, h)] if w <= W and h <= H else []
    if r and w != h and h <= W and w <= H:
        out.append((h, w))
    return out


def dff_table(C: int, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Dual-feasible functions for capacity C evaluated at ``values`` (ints in [0, C]):
    an array (n_functions, len(values)) and each function's value at C."""
    x = np.asarray(values, dtype=np.int64)
    rows: list[np.ndarray] = [x.copy()]
    caps: list[int] = [C]
    sizes = sorted({int(v) for v in x if 0 < v <= C})
    # f_0^lambda: lambda in 1..C/2, only where a size changes class (a size or C - size + 1)
    cand = sorted({v for v in sizes if v <= C // 2} | {C - v + 1 for v in sizes if v > C / 2})
    cand = [v for v in cand if 1 <= v <= C // 2]
    if len(cand) > MAX_LAMBDAS:
        cand = [cand[round(i * (len(cand) - 1) / (MAX_LAMBDAS - 1))] for i in range(MAX_LAMBDAS)]
    for lam in cand:
        rows.append(np.where(x > C - lam, C, np.where(x < lam, 0, x)))
        caps.append(C)
    # Fekete-Schepers u^(k), scaled by k*C: k x if (k+1) x / C is an integer, else
    # C * floor((k+1) x / C)
    for k in range(1, MAX_K + 1):
        rows.append(np.where(((k + 1) * x) % C == 0, k * x, C * (((k + 1) * x) // C)))
        caps.append(k * C)
    # Carlier-Clautiaux-Moukrim f_CCM^lambda, 1 <= lambda <= C/2
    lams = sorted({v for v in sizes if v <= C // 2})
    if len(lams) > MAX_LAMBDAS:
        lams = [lams[round(i * (len(lams) - 1) / (MAX_LAMBDAS - 1))] for i in range(MAX_LAMBDAS)]
    for lam in lams:
        q = C // lam
        rows.append(
            np.where(
                2 * x > C,
                2 * (q - (C - x) // lam),
                np.where(2 * x == C, q, 2 * (x // lam)),
            )
        )
        caps.append(2 * q)
    return np.stack(rows), np.asarray(caps, dtype=np.int64)


def _dff_pairs(
    orients: Sequence[list[tuple[int, int]]], W: int, H: int
) -> tuple[np.ndarray, np.ndarray]:
    """Every pair (f, g) of dual-feasible functions for the tray (f on x, g on y): each item's
    contribution, the smaller of its two orientations' f(x) g(y), shape (f, g, item), and each
    pair's capacity f(W) g(H), shape (f, g). ``orients``: each item's orientations that fit,
    none empty. Integers, so comparisons are exact."""
    n = len(orients)
    a = np.array([o[0] for o in orients], dtype=np.int64)  # first orientation
    b = np.array([o[-1] for o in orients], dtype=np.int64)  # second (== first if one)
    fx, capx = dff_table(W, np.concatenate([a[:, 0], b[:, 0]]))
    gy, capy = dff_table(H, np.concatenate([a[:, 1], b[:, 1]]))
    coef = np.minimum(fx[:, None, :n] * gy[None, :, :n], fx[:, None, n:] * gy[None, :, n:])
    return coef, capx[:, None] * capy[None, :]


def dff_violated(sizes: Sizes, W: int, H: int) -> bool:
    """True when some pair of dual-feasible functions proves that the parts do not fit."""
    orients = [_orientations(w, h, r, W, H) for w, h, r in sizes]
    if not sizes or any(not o for o in orients):
        return False
    coef, rhs = _dff_pairs(orients, W, H)
    return bool((coef.sum(axis=2) > rhs).any())


def dff_cut(
    types: dict[str, tuple[int, int, bool]], counts: dict[str, int], W: int, H: int
) -> tuple[dict[str, int], int] | None:
    """The most violated pair of dual-feasible functions for the part multiset ``counts``
    (``types``: each type's grid size and rotatability), as a linear inequality over part
    counts, ``sum_t coef[t] n_t <= cap``, valid for every 0/90-degree layout; None when no
    pair proves the misfit (the test of :func:`dff_violated`, by type)."""
    orients = {t: _orientations(*size, W, H) for t, size in types.items()}
    names = [t for t, o in orients.items() if o]
    if any(counts.get(t, 0) and not orients[t] for t in types):
        return None
    coef, rhs = _dff_pairs([orients[t] for t in names], W, H)
    lhs = coef @ np.array([counts.get(t, 0) for t in names], dtype=np.int64)
    i, j = np.unravel_index(int(np.argmax((lhs - rhs) / rhs)), rhs.shape)
    if lhs[i, j] <= rhs[i, j]:
        return None
    return {t: int(coef[i, j, k]) for k, t in enumerate(names)}, int(rhs[i, j])


def incompatible_pair(sizes: Sizes, W: int, H: int) -> bool:
    """True when two parts can be neither side by side nor stacked, whatever their rotation."""
    orients = [_orientations(w, h, r, W, H) for w, h, r in sizes]
    n = len(sizes)
    if n > 400:  # quadratic; larger kits skip this test
        return False
    for i in range(n):
        for j in range(i + 1, n):
            if all(wi + wj > W and hi + hj > H for wi, hi in orients[i] for wj, hj in orients[j]):
                return True
    return False


def tall_parts_too_wide(sizes: Sizes, W: int, H: int) -> bool:
    """Parts taller than H/2 in every orientation cross y = H/2, so their (smallest) widths add
    up to at most W; symmetrically for parts wider than W/2."""
    orients = [_orientations(w, h, r, W, H) for w, h, r in sizes]
    tall = sum(min(ow for ow, _ in o) for o in orients if o and all(2 * oh > H for _, oh in o))
    wide = sum(min(oh for _, oh in o) for o in orients if o and all(2 * ow > W for ow, _ in o))
    return tall > W or wide > H


def disks_collide(sizes: Sequence[tuple[float, float]], W: float, H: float) -> bool:
    """True when no layout exists at any angle by the inscribed disks (module docstring): a
    part's disk wider than the tray (its width in every direction is at least its smaller
    side), or the two largest disks with no room to lie apart. ``sizes``: true (w, h) in mm."""
    radii = sorted((min(w, h) / 2.0 for w, h in sizes), reverse=True)
    if not radii:
        return False
    if 2.0 * radii[0] > min(W, H) * (1 + 1e-12):
        return True
    if len(radii) < 2:
        return False
    s = radii[0] + radii[1]  # <= min(W, H): both disks fit on their own
    return (W - s) ** 2 + (H - s) ** 2 < s * s * (1 - 1e-9)


#: Relative room the any-angle tests add to a box, so that float rounding never turns a part
#: that fits (e.g. exactly, p == A) into a "no".
ANGLE_SLACK = 1e-9


def fits_at_some_angle(p: float, q: float, A: float, B: float) -> bool:
    """Does a p x q rectangle fit an A x B box at some angle? Carver's condition (module
    docstring); the box counts :data:`ANGLE_SLACK` larger, so a "no" is never a rounding
    margin."""
    p, q = max(p, q), min(p, q)
    A, B = max(A, B) * (1 + ANGLE_SLACK), min(A, B) * (1 + ANGLE_SLACK)
    if q > B:  # the part is at least q wide in every direction
        return False
    if p <= A:
        return True
    # p > A: the smallest turn that brings the x extent down to A, and the y extent there
    y = (2 * p * q * A + (p * p - q * q) * math.sqrt(p * p + q * q - A * A)) / (p * p + q * q)
    return y <= B


def exact_world(
    sizes: Sequence[tuple[float, float]], W: float, H: float, tol: float
) -> tuple[list[tuple[float, float]], float, float]:
    """The checker's tolerant world as an exact one (module docstring, "The checker's
    tolerance"): every part ``tol`` smaller in both sides, the tray ``tol`` larger. A proof
    that these parts do not fit this tray with disjoint interiors holds for the checker."""
    return [(max(w - tol, 0.0), max(h - tol, 0.0)) for w, h in sizes], W + tol, H + tol


def band_blocks(sizes: Sequence[tuple[float, float]], W: float, H: float, tol: float) -> bool:
    """True when no layout exists at any angle by the band rule (module docstring): parts
    whose smaller side is the tray's smaller side S split it into strips S wide in which every
    other part must fit. ``sizes``: true (w, h) in mm; ``tol``: the checker's length tolerance
    (the rule argues on :func:`exact_world`)."""
    S0 = min(W, H)
    exact, Wx, Hx = exact_world(sizes, W, H, tol)
    L, S = max(Wx, Hx), min(Wx, Hx)
    shrunk = [(max(w, h), min(w, h)) for w, h in exact]
    is_band = [min(w, h) >= S0 * (1 - 1e-12) for w, h in sizes]
    band = [ab for ab, b in zip(shrunk, is_band, strict=True) if b]
    others = [ab for ab, b in zip(shrunk, is_band, strict=True) if not b]
    if not band:
        return False
    eps = max(S - b for _, b in band)  # room across left by a band part
    if eps < 0:
        return True  # a band part wider than the tray in every direction
    if eps > 0.1 * min(b for _, b in band):
        return False  # the tilt bounds below assume a small eps
    slabs = 0.0  # a lower bound on the total length of the band parts' slabs
    for a, b in band:
        along = a if a > S else b  # a <= S: the part may also lie turned by 90 degrees
        sigma = 2 * eps / b  # sin of its largest tilt
        slabs += along - along * sigma * sigma - S * sigma
    if slabs > L * (1 + ANGLE_SLACK):  # (i)
        return True
    # the slack is added, not multiplied: a tray filled exactly leaves 0 room, give or take
    # rounding, for (iii) and for room
    if sum(a * b for a, b in others) > L * S * (1 + ANGLE_SLACK) - sum(a * b for a, b in band):
        return True  # (iii)
    room = L * (1 + ANGLE_SLACK) - slabs
    for a, b in others:  # (ii)
        if b > 2 * eps and not fits_at_some_angle(a, b, min(L, room + 2 * eps * L / b), S):
            return True
    return False


def infeasibility_reason(sizes: Sizes, W: int, H: int) -> str | None:
    """The first test that proves the parts cannot be packed on a W x H tray, or None."""
    if any(not _orientations(w, h, r, W, H) for w, h, r in sizes):
        return "part larger than tray"
    if sum(w * h for w, h, _ in sizes) > W * H:
        return "area"
    if tall_parts_too_wide(sizes, W, H):
        return "tall or wide parts"
    if incompatible_pair(sizes, W, H):
        return "incompatible pair"
    if dff_violated(sizes, W, H):
        return "dual-feasible function bound"
    return None
