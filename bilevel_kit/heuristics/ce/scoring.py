"""Scoring one batch of cross-entropy samples (:mod:`bilevel_kit.heuristics.cross_entropy`):
the rotated boxes' half-extents, the projection of the centres into the tray (written back
into the samples, so the refit sees them), the score of Eq. 11 with the box Z
(``D_same - D_diff + W6 * Z_box``, docs/errata.md for the sign) and the penalties for tray
overhang and unreachable centres. With numba the first three are one compiled pass
(:func:`bilevel_kit.heuristics._kernels.score_kernel`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...fitness import PairScorer
from .. import _kernels
from .kit import Kit
from .params import CEParams


class BatchScorer:
    """Scores of batches of ``p.samples`` decision vectors of one kit, columns of a (dim, S)
    array. Every (n, S)- and (r, S)-sized array is allocated once, here; the rows of the
    half-extents ``exT``/``eyT`` that belong to fixed parts are constant and filled once."""

    def __init__(self, kit: Kit, p: CEParams, w6: float, w_out: float) -> None:
        dt = np.float32 if p.precision == "float32" else np.float64
        n, S = kit.n, p.samples
        W, H = kit.tray.width, kit.tray.height
        rot = kit.rot_idx
        r = rot.size
        self.kit = kit
        self.dt = dt
        self.half_w = (kit.w[rot] / 2.0).astype(dt)[:, None]
        self.half_h = (kit.h[rot] / 2.0).astype(dt)[:, None]
        self.exT = np.empty((n, S), dtype=dt)
        self.eyT = np.empty((n, S), dtype=dt)
        self.exT[kit.fixed_idx] = (kit.w[kit.fixed_idx] / 2.0).astype(dt)[:, None]
        self.eyT[kit.fixed_idx] = (kit.h[kit.fixed_idx] / 2.0).astype(dt)[:, None]
        # Can a rotated box be wider or taller than the tray (so that projection cannot work)?
        span = np.where(
            np.isin(np.arange(n), rot), np.hypot(kit.w, kit.h), np.maximum(kit.w, kit.h)
        )
        self.may_stick_out = bool((span > min(W, H)).any())
        self.w6: Any = dt(w6)
        self.w_out: Any = dt(w_out)
        #: (pi / 180, tray width, tray height, W6, 0, 2) as the compiled kernels take them.
        self.consts = np.array([math.pi / 180.0, W, H, w6, 0.0, 2.0], dtype=dt)
        self.kernel = _kernels.score_kernel()
        self.cost: np.ndarray = np.empty(S, dtype=dt)
        self.z: np.ndarray = np.empty(S, dtype=dt)
        if self.kernel is not None:
            self._kernel_args = (
                rot.astype(np.int64),
                self.half_w[:, 0].copy(),
                self.half_h[:, 0].copy(),
                self.exT,
                self.eyT,
                self.consts,
                kit.pairs.i.astype(np.int64),
                kit.pairs.j.astype(np.int64),
                kit.pairs.sign.astype(dt),
            )
        else:
            self._pairs = PairScorer(kit.pairs, S, dt)
            self._hi = np.empty((n, S), dtype=dt)
            self._cs = np.empty((r, S), dtype=dt)
            self._sn = np.empty((r, S), dtype=dt)
            self._tmp = np.empty((r, S), dtype=dt)
            # All parts rotatable (the common case): the extents go straight into exT/eyT.
            same = r == n
            self._exr = self.exT if same else np.empty((r, S), dtype=dt)
            self._eyr = self.eyT if same else np.empty((r, S), dtype=dt)

    def score(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(cost, overlap-free-and-inside mask) of the samples ``X``, whose centres are
        projected into the tray in place. ``cost`` may be a buffer reused by the next call."""
        n = self.kit.n
        if self.kernel is not None:  # extents, projection and score in one compiled pass
            self.kernel(X, n, *self._kernel_args, self.cost, self.z)
            cost, z = self.cost, self.z
        else:
            cost, z = self._score_numpy(X)
        feasible: np.ndarray = z == 0
        if self.may_stick_out:
            over = np.maximum(2 * self.exT - self.dt(self.kit.tray.width), self.dt(0)).sum(axis=0)
            over += np.maximum(2 * self.eyT - self.dt(self.kit.tray.height), self.dt(0)).sum(axis=0)
            cost += self.w_out * over
            feasible &= over == 0
        reach = self.kit.reach
        if reach is not None:  # unreachable centroids cost like sticking out of the tray
            lost = (~reach.lookup(X[:n], X[n : 2 * n])).sum(axis=0)
            cost += self.w_out * self.dt(self.kit.tray.width) * lost
            feasible &= lost == 0
        return cost, feasible

    def _score_numpy(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Extents, projection and (cost, box Z) with numpy: the compiled kernel's steps."""
        n, dt = self.kit.n, self.dt
        x, y = X[:n], X[n : 2 * n]
        self._extents(X[2 * n :])
        exT, eyT, hi = self.exT, self.eyT, self._hi
        # Project into the tray, in place: the refit sees the projected samples.
        np.maximum(x, exT, out=x)
        np.minimum(x, np.subtract(dt(self.kit.tray.width), exT, out=hi), out=x)
        np.maximum(y, eyT, out=y)
        np.minimum(y, np.subtract(dt(self.kit.tray.height), eyT, out=hi), out=y)
        # Score all samples in one pass: D_same - D_diff + W6 * Z_box.
        cost, z = self._pairs.signed(x, y, exT, eyT)
        cost += self.w6 * z
        return cost, z

    def _extents(self, th: np.ndarray) -> None:
        """Half-extents of the rotatable parts' boxes at angles ``th`` (degrees) into the
        rows of ``exT``/``eyT``."""
        rot = self.kit.rot_idx
        if not rot.size:
            return
        cs, sn, tmp, exr, eyr = self._cs, self._sn, self._tmp, self._exr, self._eyr
        np.multiply(th, self.dt(math.pi / 180.0), out=tmp)
        np.cos(tmp, out=cs)
        np.abs(cs, out=cs)
        np.sin(tmp, out=sn)
        np.abs(sn, out=sn)
        np.multiply(cs, self.half_w, out=exr)
        exr += np.multiply(sn, self.half_h, out=tmp)
        np.multiply(sn, self.half_w, out=eyr)
        eyr += np.multiply(cs, self.half_h, out=tmp)
        if rot.size < self.kit.n:
            self.exT[rot] = exr
            self.eyT[rot] = eyr
