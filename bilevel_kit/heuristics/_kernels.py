"""Compiled kernels of the lower level (numba), with numpy as the fallback.

The cross-entropy loop (:mod:`bilevel_kit.heuristics.ce.sampling`) spends most of its time
scoring its samples (Eqs. 8-10 with the box Z, docs/errata.md for the sign of Eq. 11). Numpy
needs a dozen passes over (pairs x samples) temporaries for that; the kernel here makes one
pass: for each pair, a loop over the samples (contiguous, vectorised by the compiler) that
adds the signed distance and ``W6`` times the box overlap to the sample's score. The same
kernel first computes the rotated boxes' half-extents and projects the centres into the tray
(the CE projection), in place.

The arithmetic is the numpy path's, operation by operation (no fast-math, so no reassociation
and no fused multiply-add); only the order in which the pair terms are summed differs (pair
by pair here, ``np.einsum``'s blocking there) and, in float32, ``cos``/``sin`` come from a
polynomial the compiler vectorises (:func:`_sin_cos_small`, about 1 ulp from numpy's), so
scores agree to float32 rounding and a ranking can differ only between samples whose scores
are within that rounding (tests/heuristics/test_kernels.py compares both). The CE's float32
normals are transformed here too (:func:`_uniform_pairs`, :func:`_box_muller`) from the
generator's raw words, which numpy draws, so both paths use the same random stream.

numba is imported on first use, not at import time (it takes about a second). Set the
environment variable ``BILEVEL_KIT_NO_NUMBA=1`` to force the numpy path (also used when numba
is not installed); :func:`available` says which path runs.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

#: Environment variable that forces the numpy path when set to anything but "" or "0".
ENV_DISABLE = "BILEVEL_KIT_NO_NUMBA"


def disabled() -> bool:
    """Whether the environment forces the numpy path (read at every call)."""
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
    _rotated_extents(X[2 * n :], rot_idx, half_w, half_h, exT, eyT, consts[0])
    _project(X, n, exT, eyT, consts[1], consts[2])
    _pair_scores(X, n, exT, eyT, pair_i, pair_j, sign, consts[3], consts[4], consts[5], cost, z)


def _project(
    X: np.ndarray, n: int, exT: np.ndarray, eyT: np.ndarray, wd: float, ht: float
) -> None:  # pragma: no cover - compiled by numba
    """The CE projection, in place: each centre clipped so that its box lies in the
    ``wd`` x ``ht`` tray (``min(max(c, e), side - e)``, as the numpy loop computes it)."""
    for a in range(n):
        for s in range(X.shape[1]):
            ex = exT[a, s]
            v = max(X[a, s], ex)
            X[a, s] = min(v, wd - ex)
            ey = eyT[a, s]
            v = max(X[n + a, s], ey)
            X[n + a, s] = min(v, ht - ey)


def _pair_scores(
    X: np.ndarray,
    n: int,
    exT: np.ndarray,
    eyT: np.ndarray,
    pair_i: np.ndarray,
    pair_j: np.ndarray,
    sign: np.ndarray,
    w6f: float,
    zero: float,
    two: float,
    cost: np.ndarray,
    z: np.ndarray,
) -> None:  # pragma: no cover - compiled by numba
    """Box Z into ``z`` and ``D_same - D_diff + W6 Z`` into ``cost``: for each pair, one
    contiguous (vectorised) loop over the samples adding the signed distance and the box
    overlap ``max(0, min(e_i + e_j - |d|, 2 min(e_i, e_j)))`` per axis."""
    S = X.shape[1]
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


#: Cephes' float32 minimax polynomials of sine and cosine on [-pi/4, pi/4] (about 1 ulp).
_SIN = (np.float32(-1.9515295891e-4), np.float32(8.3321608736e-3), np.float32(-1.6666654611e-1))
_COS = (
    np.float32(2.443315711809948e-5),
    np.float32(-1.388731625493765e-3),
    np.float32(4.166664568298827e-2),
)


def _sin_cos_small(a: np.float32) -> tuple[np.float32, np.float32]:  # pragma: no cover
    """(sin a, cos a) in float32 for ``|a| <= pi/4`` by :data:`_SIN`/:data:`_COS`: plain
    arithmetic, so loops calling it vectorise (the C library's ``sinf``/``cosf`` do not)."""
    w = a * a
    sn = ((_SIN[0] * w + _SIN[1]) * w + _SIN[2]) * w * a + a
    c = (((_COS[0] * w + _COS[1]) * w + _COS[2]) * w * w - np.float32(0.5) * w) + np.float32(1.0)
    return sn, c


def _rotated_extents(
    angles: np.ndarray,
    rot_idx: np.ndarray,
    half_w: np.ndarray,
    half_h: np.ndarray,
    exT: np.ndarray,
    eyT: np.ndarray,
    deg: float,
) -> None:  # pragma: no cover - compiled by numba (tests compare it with numpy's cos/sin)
    """Half-extents ``|cos t| w/2 + |sin t| h/2`` and ``|sin t| w/2 + |cos t| h/2`` of the
    rotatable parts (row k of ``angles``: part k's angles in degrees, ``deg``: pi / 180), with
    numpy's ``cos``/``sin`` in float64 and in float32 with a polynomial ``sin``/``cos`` the
    compiler vectorises (the C library's ``cosf``/``sinf`` are scalar calls: they were 45 % of
    the scoring time).

    In float32 the angle (degrees) is reduced by the nearest multiple q of 90 degrees to
    ``r in [-pi/4, pi/4]``, where Cephes' float32 minimax polynomials give ``sin r`` and
    ``cos r`` to about 1 ulp; ``|cos t|`` and ``|sin t|`` are those of r, swapped when q is
    odd."""
    S = angles.shape[1]
    f32 = angles.itemsize == 4
    half = np.float32(0.5)
    two = np.float32(2.0)
    ninety = np.float32(90.0)
    inv90 = np.float32(1.0 / 90.0)
    for k in range(rot_idx.size):
        row = rot_idx[k]
        hw = half_w[k]
        hh = half_h[k]
        th = angles[k]
        ex = exT[row]
        ey = eyT[row]
        if not f32:
            for s in range(S):
                t = th[s] * deg
                c64 = abs(np.cos(t))
                sn64 = abs(np.sin(t))
                ex[s] = c64 * hw + sn64 * hh
                ey[s] = sn64 * hw + c64 * hh
        else:
            for s in range(S):
                a = th[s]
                q = np.floor(a * inv90 + half)
                sn, c = _sin_cos_small((a - q * ninety) * deg)
                sn, c = abs(sn), abs(c)
                odd = q - two * np.floor(q * half) != np.float32(0.0)
                ac = sn if odd else c
                asn = c if odd else sn
                ex[s] = ac * hw + asn * hh
                ey[s] = asn * hw + ac * hh


def _uniform_pairs(raw: np.ndarray, x: np.ndarray, t: np.ndarray) -> None:  # pragma: no cover
    """Two 24-bit float32 uniforms from each 64-bit word of ``raw``: ``x = 1 - u0`` (bits
    63-40; exact, in (0, 1]) and ``t = u1`` (bits 39-16), as
    :func:`bilevel_kit.heuristics.ce.sampling.standard_normal` computes them with numpy."""
    scale = np.float32(2.0**-24)
    one = np.float32(1.0)
    for k in range(raw.size):
        b = raw[k]
        x[k] = one - np.float32(b >> np.uint64(40)) * scale
        t[k] = np.float32((b >> np.uint64(16)) & np.uint64(0xFFFFFF)) * scale


def _box_muller(log_x: np.ndarray, t: np.ndarray, z: np.ndarray) -> None:  # pragma: no cover
    """Box-Muller's normals ``z[0] = r cos(2 pi t)``, ``z[1] = r sin(2 pi t)`` with
    ``r = sqrt(-2 log x)``, the sine and cosine from the polynomials of
    :func:`_sin_cos_small` (reduced by quarter turns, signs by quadrant), so that the loop
    vectorises."""
    half = np.float32(0.5)
    four = np.float32(4.0)
    quarter = np.float32(0.25)
    two_pi = np.float32(2.0 * np.pi)
    minus_two = np.float32(-2.0)
    for k in range(t.size):
        r = np.sqrt(minus_two * log_x[k])
        q = np.floor(t[k] * four + half)  # 0..4; 4 is a full turn
        sn, c = _sin_cos_small((t[k] - q * quarter) * two_pi)  # exact difference first
        q1 = q == np.float32(1.0)
        q2 = q == np.float32(2.0)
        q3 = q == np.float32(3.0)
        cos_t = -sn if q1 else (-c if q2 else (sn if q3 else c))
        sin_t = c if q1 else (-sn if q2 else (-c if q3 else sn))
        z[0, k] = r * cos_t
        z[1, k] = r * sin_t


def _cholesky_into(a: np.ndarray, floor: float, out: np.ndarray) -> bool:  # pragma: no cover
    """Lower Cholesky factor of ``a + floor * I`` into ``out`` (any float dtype); False if
    ``a + floor * I`` is not positive definite.

    Column q of the factor is row q of ``w`` (contiguous), and it is updated by the finished
    columns k < q four at a time. Entry (i, q) still starts at ``a[i, q]`` (plus the floor on
    the diagonal) and loses ``f[i, k] * f[q, k]`` for k = 0, 1, ... in turn, one rounding
    per operation as in the textbook loop, so every entry is the same float as there; the
    contiguous inner loops vectorise, about 2x faster at the 84 dimensions of the 28-part
    kit."""
    d = a.shape[0]
    w = np.empty((d, d))  # w[q, i]: entry (i, q) of the lower triangle, i >= q
    for q in range(d):
        # Slices and indices from 0: the loop form numba vectorises (not range(q, d)).
        dst = w[q, q:]
        m = d - q
        for t in range(m):
            dst[t] = a[q + t, q]
        dst[0] += floor
        k = 0
        while k + 4 <= q:
            c0, c1, c2, c3 = w[k, q], w[k + 1, q], w[k + 2, q], w[k + 3, q]
            s0, s1, s2, s3 = w[k, q:], w[k + 1, q:], w[k + 2, q:], w[k + 3, q:]
            for t in range(m):
                dst[t] = (((dst[t] - s0[t] * c0) - s1[t] * c1) - s2[t] * c2) - s3[t] * c3
            k += 4
        while k < q:
            c0 = w[k, q]
            s0 = w[k, q:]
            for t in range(m):
                dst[t] -= s0[t] * c0
            k += 1
        if not dst[0] > 0.0:
            return False
        djj = np.sqrt(dst[0])
        dst[0] = djj
        for t in range(1, m):
            dst[t] = dst[t] / djj
    out[:, :] = 0.0
    for q in range(d):
        for i in range(q, d):
            out[i, q] = w[q, i]
    return True


def _ce_block(
    pool: np.ndarray,
    it0: int,
    n_it: int,
    mu: np.ndarray,
    cov: np.ndarray,
    L: np.ndarray,
    X: np.ndarray,
    exT: np.ndarray,
    eyT: np.ndarray,
    cost: np.ndarray,
    z: np.ndarray,
    n: int,
    rot_idx: np.ndarray,
    half_w: np.ndarray,
    half_h: np.ndarray,
    consts: np.ndarray,
    pair_i: np.ndarray,
    pair_j: np.ndarray,
    sign: np.ndarray,
    elite: int,
    fparams: np.ndarray,
    patience: int,
    best: np.ndarray,
    best_feasible: np.ndarray,
    state: np.ndarray,
    trace: np.ndarray,
    gammas: np.ndarray,
) -> int:  # pragma: no cover - compiled by numba
    """Up to ``n_it`` CE iterations (numbers ``it0``, ``it0 + 1``, ...) with the standard normals
    of ``pool`` (``n_it * dim`` rows): sample (:func:`_sample_into`), score
    (:func:`_score_samples`), track the best (and best overlap-free) sample
    (:func:`_track_best`), refit mean and covariance to the elite (:func:`_refit`), factor
    (:func:`_factor`), test convergence. The numpy loop of
    :mod:`bilevel_kit.heuristics.ce.sampling` does the same steps; mirrored sampling when
    ``pool`` has fewer columns than samples.

    ``fparams``: (mean smoothing, covariance smoothing, Sigma floor, tol); ``state``:
    (best cost, best overlap-free cost, converged flag, last iteration) in and out. Returns the
    iterations performed."""
    dim = X.shape[0]
    m = pool.shape[1]
    mu_dt = np.empty(dim, dtype=X.dtype)
    LZ = np.empty((dim, m), dtype=X.dtype)
    el = np.empty((dim, elite))
    mu_e = np.empty(dim)
    for q in range(n_it):
        it = it0 + q
        _sample_into(pool[q * dim : (q + 1) * dim], L, mu, mu_dt, LZ, X)
        _score_samples(
            X, n, rot_idx, half_w, half_h, exT, eyT, consts, pair_i, pair_j, sign, cost, z
        )
        _track_best(X, cost, z, best, best_feasible, state)
        trace[it - 1] = -state[0]
        gammas[it - 1] = _refit(X, cost, el, mu_e, mu, cov, fparams[0], fparams[1])
        state[3] = it
        if not _factor(cov, fparams[2], L):
            state[2] = -1.0  # the caller raises LinAlgError
            return q + 1
        if it > patience and _flat(gammas, it, patience, fparams[3]):
            state[2] = 1.0
            return q + 1
    return n_it


def _sample_into(
    Z: np.ndarray, L: np.ndarray, mu: np.ndarray, mu_dt: np.ndarray, LZ: np.ndarray, X: np.ndarray
) -> None:  # pragma: no cover - compiled by numba
    """Samples ``mu + L Z`` into the first ``m`` columns of ``X`` (m: Z's columns) and
    ``mu - L Z`` into the rest (mirrored); ``mu`` is rounded to the samples' dtype first
    (``mu_dt``), as the numpy loop adds it."""
    dim = X.shape[0]
    S = X.shape[1]
    m = Z.shape[1]
    np.dot(L, Z, LZ)
    for d in range(dim):
        mu_dt[d] = mu[d]
    for d in range(dim):
        md = mu_dt[d]
        for s in range(m):
            X[d, s] = LZ[d, s] + md
        for s in range(S - m):
            X[d, m + s] = md - LZ[d, s]


def _track_best(
    X: np.ndarray,
    cost: np.ndarray,
    z: np.ndarray,
    best: np.ndarray,
    best_feasible: np.ndarray,
    state: np.ndarray,
) -> None:  # pragma: no cover - compiled by numba
    """Copy the batch's best sample into ``best`` and its best overlap-free one (box Z = 0)
    into ``best_feasible`` when they beat ``state[0]`` and ``state[1]`` (updated too); ties
    go to the earlier sample, as ``np.argmin``'s."""
    dim = X.shape[0]
    k = 0
    kf = -1
    for s in range(X.shape[1]):
        if cost[s] < cost[k]:
            k = s
        if z[s] == 0 and (kf < 0 or cost[s] < cost[kf]):
            kf = s
    if cost[k] < state[0]:
        state[0] = cost[k]
        for d in range(dim):
            best[d] = X[d, k]
    if kf >= 0 and cost[kf] < state[1]:
        state[1] = cost[kf]
        for d in range(dim):
            best_feasible[d] = X[d, kf]


def _refit(
    X: np.ndarray,
    cost: np.ndarray,
    el: np.ndarray,
    mu_e: np.ndarray,
    mu: np.ndarray,
    cov: np.ndarray,
    a_mu: float,
    b_cov: float,
) -> float:  # pragma: no cover - compiled by numba
    """Refit ``mu`` and ``cov`` in place to the ``el.shape[1]`` best samples (maximum
    likelihood, smoothed by ``a_mu`` and ``b_cov``; ``el``, ``mu_e``: float64 scratch);
    returns the elite threshold gamma (the worst elite score)."""
    dim = X.shape[0]
    elite = el.shape[1]
    order = np.argsort(cost)[:elite]
    gamma = cost[order[0]]
    for e in range(elite):
        if cost[order[e]] > gamma:
            gamma = cost[order[e]]
    for d in range(dim):
        acc = 0.0
        for e in range(elite):
            v = np.float64(X[d, order[e]])
            el[d, e] = v
            acc += v
        mu_e[d] = acc * (1.0 / elite)
    for d in range(dim):
        for e in range(elite):
            el[d, e] -= mu_e[d]
    cov_e = np.dot(el, el.T)
    cov_e *= 1.0 / elite
    if b_cov >= 1.0:
        cov[:, :] = cov_e
    else:
        for i in range(dim):
            for j in range(dim):
                cov[i, j] = cov[i, j] * (1.0 - b_cov) + cov_e[i, j] * b_cov
    for d in range(dim):
        mu[d] = mu[d] * (1.0 - a_mu) + a_mu * mu_e[d]
    return gamma


def _factor(cov: np.ndarray, floor: float, L: np.ndarray) -> bool:  # pragma: no cover
    """Cholesky factor of ``cov + floor * I`` into ``L`` (:func:`_cholesky_into`), the floor
    growing tenfold on failure, eight tries; False if none succeeded."""
    fl = floor
    for _ in range(8):
        if _cholesky_into(cov, fl, L):
            return True
        fl *= 10.0
    return False


def _flat(gammas: np.ndarray, it: int, patience: int, tol: float) -> bool:  # pragma: no cover
    """de Boer et al.'s convergence test after iteration ``it > patience``: gamma moved by at
    most ``tol * max(1, |gamma|)`` over the last ``patience`` iterations."""
    gain = gammas[it - 1 - patience] - gammas[it - 1]
    return abs(gain) <= tol * max(1.0, abs(gammas[it - 1]))


def _push_apart_loop(
    x: np.ndarray,
    y: np.ndarray,
    ex: np.ndarray,
    ey: np.ndarray,
    pair_i: np.ndarray,
    pair_j: np.ndarray,
    width: float,
    height: float,
    rounds: int,
) -> bool:  # pragma: no cover - compiled by numba (tests compare it with the numpy loop)
    """The rounds of :func:`bilevel_kit.heuristics.ce.accept.push_apart` on ``x``, ``y`` in
    place; True once no boxes overlap. The numpy loop's arithmetic operation by operation:
    the pair moves are summed per part in pair order, as ``np.bincount`` sums them, so the
    result is the same float for float."""
    n = x.size
    margin = 1e-5
    add_xi = np.empty(n)
    add_xj = np.empty(n)
    add_yi = np.empty(n)
    add_yj = np.empty(n)
    for _ in range(rounds):
        add_xi[:] = 0.0
        add_xj[:] = 0.0
        add_yi[:] = 0.0
        add_yj[:] = 0.0
        any_bad = False
        for p in range(pair_i.size):
            a = pair_i[p]
            b = pair_j[p]
            dx = x[a] - x[b]
            dy = y[a] - y[b]
            ox = ex[a] + ex[b] - abs(dx)
            oy = ey[a] + ey[b] - abs(dy)
            bad = ox > 0 and oy > 0
            any_bad = any_bad or bad
            along_x = bad and ox <= oy
            along_y = bad and not along_x
            sx = (1.0 if dx >= 0 else -1.0) * ((ox + margin) / 2 if along_x else 0.0)
            sy = (1.0 if dy >= 0 else -1.0) * ((oy + margin) / 2 if along_y else 0.0)
            add_xi[a] += sx
            add_xj[b] += sx
            add_yi[a] += sy
            add_yj[b] += sy
        if not any_bad:
            return True
        for k in range(n):
            x[k] += add_xi[k] - add_xj[k]
            y[k] += add_yi[k] - add_yj[k]
            e = ex[k]
            x[k] = width / 2.0 if 2.0 * e > width else min(max(x[k], e), width - e)
            e = ey[k]
            y[k] = height / 2.0 if 2.0 * e > height else min(max(y[k], e), height - e)
    return False


#: The compiled (scorer, CE block) once built.
_JITTED: tuple[ScoreKernel, Callable[..., int]] | None = None


def njit() -> Callable[[Callable[..., Any]], Any] | None:
    """``numba.njit(cache=True, nogil=True)``, the one way the package compiles a kernel, or
    None when numba is disabled or not installed."""
    if disabled():
        return None
    try:
        import numba
    except ImportError:
        from ..interrupt import checkpoint

        checkpoint()  # a signal during the import turns into an ImportError (docs/cli.md)
        return None
    return numba.njit(cache=True, nogil=True)


def compiled_once(namespace: dict[str, Any], helpers: Sequence[str], entry: str) -> Any | None:
    """A kernel module's compiled ``entry``, kept in its ``_JITTED`` once built: its
    ``helpers`` are compiled in place first (so that the compiled entry calls compiled code);
    None when numba is disabled (read at every call) or missing."""
    if disabled():
        return None
    if namespace["_JITTED"] is None:
        jit = njit()
        if jit is None:
            return None
        for name in helpers:
            namespace[name] = jit(namespace[name])
        namespace["_JITTED"] = jit(namespace[entry])
    return namespace["_JITTED"]


def cache_missing() -> bool:
    """True when numba will compile kernels on their first call (no on-disk cache yet of one
    of :func:`cache_indexes`: the first run after an install compiles for 10-70 s), so that a
    command can say so instead of staying silent. numba caches beside the sources, or only
    under ``NUMBA_CACHE_DIR`` when that is set (docs/scaling.md#first-run)."""
    if njit() is None:
        return False
    import os

    # numba uses NUMBA_CACHE_DIR alone when it is set, else the folder beside the sources
    user = os.environ.get("NUMBA_CACHE_DIR")
    places = [Path(user)] if user else [Path(__file__).parent / "__pycache__"]
    return not all(
        any(any(p.rglob(index)) for p in places if p.is_dir()) for index in cache_indexes()
    )


def cache_indexes() -> list[str]:
    """The names (glob patterns) of numba's index files of the entry kernels: the CE block
    and greedy-ce's compiled decision (rest searches, beam; docs/scaling.md). numba names an
    index by the module, the function and its first source line; the decision's modules are
    read, not imported (they import this one)."""
    func = getattr(_ce_block, "py_func", _ce_block)
    out = [f"_kernels._ce_block-{func.__code__.co_firstlineno}.py*.nbi"]
    for module, name in DECISION_KERNELS:
        lines = (_SOURCES / f"{module}.py").read_text().splitlines()
        line = next(k for k, text in enumerate(lines, 1) if text.startswith(f"def {name}("))
        out.append(f"{module}.{name}-{line}.py*.nbi")
    return out


#: Where the kernels' sources are (their cache is beside them unless ``NUMBA_CACHE_DIR``).
_SOURCES = Path(__file__).resolve().parent

#: greedy-ce's compiled decision: (module, entry kernel) (:func:`cache_indexes`).
DECISION_KERNELS = (
    ("_dfs_kernel", "depth_first"),
    ("_beam_kernel", "beam_scores"),
    ("_rest_kernel", "best_rest"),
)


def _compiled() -> tuple[ScoreKernel, Callable[..., int]] | None:
    """numba-compiled (scorer, CE block), or None when numba is disabled or missing.

    Built on first use: the module's functions are replaced by their compiled versions, so
    that the CE block calls the compiled scorer and Cholesky factorisation. The environment
    variable is read at every call."""
    global _JITTED, _score_samples, _sin_cos_small, _rotated_extents, _cholesky_into, _ce_block
    global _sample_into, _track_best, _refit, _factor, _flat
    global _project, _pair_scores
    global _push_apart_loop, _uniform_pairs, _box_muller
    if disabled():
        return None
    if _JITTED is None:
        jit = njit()
        if jit is None:
            return None
        _sin_cos_small = jit(_sin_cos_small)
        _rotated_extents = jit(_rotated_extents)
        _project = jit(_project)
        _pair_scores = jit(_pair_scores)
        _score_samples = jit(_score_samples)
        _cholesky_into = jit(_cholesky_into)
        _sample_into = jit(_sample_into)
        _track_best = jit(_track_best)
        _refit = jit(_refit)
        _factor = jit(_factor)
        _flat = jit(_flat)
        _ce_block = jit(_ce_block)
        _push_apart_loop = jit(_push_apart_loop)
        _uniform_pairs = jit(_uniform_pairs)
        _box_muller = jit(_box_muller)
        _JITTED = (_score_samples, _ce_block)
    return _JITTED


def score_kernel() -> ScoreKernel | None:
    """The compiled scorer (:func:`_score_samples`), or None (numpy path)."""
    got = _compiled()
    return None if got is None else got[0]


def ce_block_kernel() -> Callable[..., int] | None:
    """The compiled CE iterations (:func:`_ce_block`), or None (numpy path)."""
    got = _compiled()
    return None if got is None else got[1]


def normal_kernels() -> tuple[Callable[..., None], Callable[..., None]] | None:
    """The compiled (:func:`_uniform_pairs`, :func:`_box_muller`), or None (numpy path)."""
    return None if _compiled() is None else (_uniform_pairs, _box_muller)


def push_apart_kernel() -> Callable[..., bool] | None:
    """The compiled push-apart repair (:func:`_push_apart_loop`), or None (numpy path)."""
    return None if _compiled() is None else _push_apart_loop


def available() -> bool:
    """True when the compiled kernels run (numba importable and not disabled)."""
    return _compiled() is not None
