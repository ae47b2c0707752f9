"""Compiled kernels of the lower level (numba), with numpy as the fallback.

The cross-entropy loop (:mod:`bilevel_kit.layout.cross_entropy`) spends most of its time
scoring its samples (Eqs. 8-10 with the box Z, docs/errata.md for the sign of Eq. 11). Numpy
needs a dozen passes over (pairs x samples) temporaries for that; the kernel here makes one
pass: for each pair, a loop over the samples (contiguous, vectorised by the compiler) that
adds the signed distance and ``W6`` times the box overlap to the sample's score. The same
kernel first computes the rotated boxes' half-extents and projects the centres into the tray
(the CE projection), in place.

The arithmetic is the numpy path's, operation by operation (no fast-math, so no reassociation
and no fused multiply-add); only the order in which the pair terms are summed differs (pair
by pair here, ``np.einsum``'s blocking there) and the float32 ``cos``/``sin`` may differ in
the last bit, so scores agree to float32 rounding and a ranking can differ only between
samples whose scores are within that rounding (tests/layout/test_kernels.py compares both).

numba is imported on first use, not at import time (it takes about a second). Set the
environment variable ``BILEVEL_KIT_NO_NUMBA=1`` to force the numpy path (also used when numba
is not installed); :func:`available` says which path runs.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from functools import cache

import numpy as np

#: Environment variable that forces the numpy path when set to anything but "" or "0".
ENV_DISABLE = "BILEVEL_KIT_NO_NUMBA"


def _disabled() -> bool:
    return os.environ.get(ENV_DISABLE, "") not in ("", "0")


#: Signature of the compiled scorer (see :func:`score_kernel`).
ScoreKernel = Callable[..., None]


def _score_samples(
    X: np.ndarray,
    n: int,
    rot_idx: np.ndarray,
    half_w: np.ndarray,
    half_h: np.ndarray,
    exT: np.ndarray,
    eyT: np.ndarray,
    consts: np.ndarray,
    pair_i: np.ndarray,
    pair_j: np.ndarray,
    sign: np.ndarray,
    cost: np.ndarray,
    z: np.ndarray,
) -> None:  # pragma: no cover - compiled by numba (the numpy path is tested against it)
    """Half-extents, projection and score of every sample, in place.

    ``X``: (dim, S) decision vectors (x rows, y rows, then the angles in degrees of the
    rotatable parts ``rot_idx``); ``exT``/``eyT``: (n, S) half-extents, the rows of fixed
    parts pre-filled; ``half_w``/``half_h``: half sides of the rotatable parts; ``consts``:
    (pi / 180, tray width, tray height, W6, 0, 2) in the samples' dtype. Writes the
    projected centres into ``X``, ``z`` (box Z) and ``cost`` (D_same - D_diff + W6 Z)."""
    S = X.shape[1]
    deg = consts[0]
    wd = consts[1]
    ht = consts[2]
    w6f = consts[3]
    zero = consts[4]
    two = consts[5]
    for k in range(rot_idx.size):
        row = rot_idx[k]
        hw = half_w[k]
        hh = half_h[k]
        for s in range(S):
            t = X[2 * n + k, s] * deg
            c = abs(np.cos(t))
            sn = abs(np.sin(t))
            exT[row, s] = c * hw + sn * hh
            eyT[row, s] = sn * hw + c * hh
    for a in range(n):
        for s in range(S):
            ex = exT[a, s]
            v = max(X[a, s], ex)
            X[a, s] = min(v, wd - ex)
            ey = eyT[a, s]
            v = max(X[n + a, s], ey)
            X[n + a, s] = min(v, ht - ey)
    for s in range(S):
        cost[s] = zero
        z[s] = zero
    for p in range(pair_i.size):
        i = pair_i[p]
        j = pair_j[p]
        sg = sign[p]
        for s in range(S):
            dx = X[i, s] - X[j, s]
            dy = X[n + i, s] - X[n + j, s]
            dist = np.sqrt(dx * dx + dy * dy)
            exi = exT[i, s]
            exj = exT[j, s]
            ox = min(exi + exj - abs(dx), two * min(exi, exj))
            eyi = eyT[i, s]
            eyj = eyT[j, s]
            oy = min(eyi + eyj - abs(dy), two * min(eyi, eyj))
            cost[s] += sg * dist
            z[s] += max(ox, zero) * max(oy, zero)
    for s in range(S):
        cost[s] += w6f * z[s]


@cache
def score_kernel() -> ScoreKernel | None:
    """The compiled scorer, or None when numba is disabled or missing (numpy path)."""
    if _disabled():
        return None
    try:
        import numba
    except ImportError:
        return None
    return numba.njit(cache=True, nogil=True)(_score_samples)


def available() -> bool:
    """True when the compiled kernels run (numba importable and not disabled)."""
    return score_kernel() is not None
