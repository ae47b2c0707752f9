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
"""

from __future__ import annotations

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


def dff_violated(sizes: Sizes, W: int, H: int) -> bool:
    """True when some pair of dual-feasible functions proves that the parts do not fit."""
    orients = [_orientations(w, h, r, W, H) for w, h, r in sizes]
    if not sizes or any(not o for o in orients):
        return False
    a = np.array([o[0] for o in orients], dtype=np.int64)  # first orientation
    b = np.array([o[-1] for o in orients], dtype=np.int64)  # second (== first if one)
    fx, capx = dff_table(W, np.concatenate([a[:, 0], b[:, 0]]))
    gy, capy = dff_table(H, np.concatenate([a[:, 1], b[:, 1]]))
    n = len(sizes)
    fa, fb = fx[:, :n].astype(float), fx[:, n:].astype(float)
    ga, gb = gy[:, :n].astype(float), gy[:, n:].astype(float)
    # contribution of part i to the pair (f, g): the smaller of its two orientations
    lhs = np.minimum(fa[:, None, :] * ga[None, :, :], fb[:, None, :] * gb[None, :, :]).sum(axis=2)
    rhs = capx.astype(float)[:, None] * capy.astype(float)[None, :]
    return bool((lhs > rhs + 1e-9).any())


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
