"""One cross-entropy run (:mod:`bilevel_kit.heuristics.cross_entropy`, Algorithm 1): the
sampling distribution N(mu, Sigma), its standard normals, and its refit to the elite samples
until the elite threshold stops moving. The iterations run compiled
(:func:`bilevel_kit.heuristics._kernels.ce_block_kernel`) when they can, else in the numpy
loop here; both take their normals from the same random stream."""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass, field

import numpy as np

from .. import _kernels
from .kit import Kit
from .params import CEParams
from .scoring import BatchScorer


def standard_normal(
    gen: np.random.Generator, shape: tuple[int, int], dtype: type, compiled: bool = True
) -> np.ndarray:
    """Standard normals from ``gen``.

    float64: ``Generator.standard_normal``. float32: Box-Muller on two 24-bit uniforms per
    64-bit word of ``gen``'s bit generator (``random_raw``; 24-bit uniforms cut the tails at
    ~5.8 sd, harmless for ranking samples), about 2x faster here than numpy's float32 uniforms
    and ufuncs: ``1 - u0`` is exact, its ``log`` is numpy's vectorised float32 ``log``, and
    the rest runs in one compiled loop (:func:`bilevel_kit.heuristics._kernels._box_muller`,
    polynomial sine and cosine) when numba is available. The numpy path uses numpy's ``cos``
    and ``sin``: the same uniforms, normals equal to float32 rounding."""
    if dtype is np.float64:
        return gen.standard_normal(shape)
    size = shape[0] * shape[1]
    m = (size + 1) // 2
    raw = gen.bit_generator.random_raw(m)
    x = np.empty(m, dtype=np.float32)
    t = np.empty(m, dtype=np.float32)
    z = np.empty((2, m), dtype=np.float32)
    kernels = _kernels.normal_kernels() if compiled else None
    if kernels is not None:
        uniform_pairs, box_muller = kernels
        uniform_pairs(raw, x, t)
        np.log(x, out=x)  # in (0, 1]: finite
        box_muller(x, t, z)
    else:
        scale = np.float32(2.0**-24)
        np.subtract(np.float32(1.0), (raw >> np.uint64(40)).astype(np.float32) * scale, out=x)
        t[:] = ((raw >> np.uint64(16)) & np.uint64(0xFFFFFF)).astype(np.float32) * scale
        np.log(x, out=x)
        x *= np.float32(-2.0)
        np.sqrt(x, out=x)
        t *= np.float32(2.0 * math.pi)
        np.cos(t, out=z[0])
        np.sin(t, out=z[1])
        z *= x
    return z.reshape(-1)[:size].reshape(shape)


@dataclass
class Run:
    """What one CE run found: the best sample, the best overlap-free one, the final mean."""

    best: np.ndarray
    best_feasible: np.ndarray | None
    mean: np.ndarray
    trace: list[float]
    iterations: int
    converged: bool


#: ``time.perf_counter()`` past which a run stops early (None: no deadline); set by
#: :func:`deadline` around a method's lower-level calls.
_DEADLINE: ContextVar[float | None] = ContextVar("ce_deadline", default=None)
#: Iterations a run always does before a deadline may stop it: a start for the best sample
#: (a run of a 30-part kit takes seconds, and ``max_iter=100000 tol=0`` minutes, which
#: carried greedy-ce's 5 s limit to 14-43 s: docs/cli.md#time-limits).
MIN_ITER_BEFORE_DEADLINE = 10


@contextlib.contextmanager
def deadline(at: float | None) -> Iterator[None]:
    """Inside, every CE run stops (not converged, its best so far) once ``at``
    (``time.perf_counter()``) has passed and it did :data:`MIN_ITER_BEFORE_DEADLINE`
    iterations."""
    token = _DEADLINE.set(at)
    try:
        yield
    finally:
        _DEADLINE.reset(token)


def _out_of_time(it: int) -> bool:
    at = _DEADLINE.get()
    return at is not None and it >= MIN_ITER_BEFORE_DEADLINE and time.perf_counter() > at


#: OpenBLAS runs a GEMM single-threaded when m*n*k is at most 65536 * 4. Threaded GEMMs of
#: this size were measured 10-100x slower on a busy 2-core machine (worker threads spin and
#: compete with the caller), so the loop's products are cut into blocks of that size.
_GEMM_SINGLE_THREAD = 1 << 18
#: Iterations' worth of standard normals drawn per call (amortises the call overhead).
_POOL = 8


def ce_run(
    kit: Kit,
    gen: np.random.Generator,
    p: CEParams,
    w6: float,
    w_out: float,
    mu0: np.ndarray,
    sd0: np.ndarray,
) -> Run:
    """One run of Algorithm 1 from N(mu0, diag(sd0^2)); see
    :mod:`bilevel_kit.heuristics.cross_entropy`. Compiled unless a rotated box can be wider
    than the tray (overhang penalty) or a reach map applies."""
    scorer = BatchScorer(kit, p, w6, w_out)
    # Mirrored sampling: m normal columns give samples mu + LZ and mu - LZ.
    m = p.samples - p.samples // 2 if p.mirrored else p.samples
    block = _kernels.ce_block_kernel()
    if block is not None and not scorer.may_stick_out and kit.reach is None:
        return _ce_run_compiled(kit, gen, p, block, scorer, m, mu0, sd0)
    return _ce_run_numpy(kit, gen, p, scorer, m, mu0, sd0)


# ---------------------------------------------------------------------------------------------
# The numpy loop
# ---------------------------------------------------------------------------------------------


@dataclass
class _Search:
    """The state of a run in the numpy loop: the distribution N(mu, L L^T) with L the
    Cholesky factor of ``cov`` in the samples' dtype, and the best samples so far."""

    mu: np.ndarray
    cov: np.ndarray
    L: np.ndarray
    best: np.ndarray
    best_cost: float = math.inf
    best_feasible: np.ndarray | None = None
    feas_cost: float = math.inf
    trace: list[float] = field(default_factory=list)
    gammas: list[float] = field(default_factory=list)


def _ce_run_numpy(
    kit: Kit,
    gen: np.random.Generator,
    p: CEParams,
    scorer: BatchScorer,
    m: int,
    mu0: np.ndarray,
    sd0: np.ndarray,
) -> Run:
    """:func:`ce_run` as a fixed sequence of numpy calls per iteration (sample, score, track,
    refit); (dim, S)-sized arrays are allocated once before the loop."""
    dt = scorer.dt
    dim, S = kit.dim, p.samples
    mu = np.asarray(mu0, dtype=np.float64).copy()
    cov = np.diag(np.asarray(sd0, dtype=np.float64) ** 2)
    L = np.diag(np.asarray(sd0, dtype=np.float64)).astype(dt)
    st = _Search(mu, cov, L, best=mu.copy())
    X = np.empty((dim, S), dtype=dt)
    LZ = np.empty((dim, m), dtype=dt)
    pool = np.empty((0, m), dtype=dt)
    converged = False
    it = 0
    for it in range(1, p.max_iter + 1):
        k_pool = (it - 1) % _POOL
        if k_pool == 0:
            pool = _standard_normal_pool(gen, dim, m, dt)
        _sample(st, pool[k_pool * dim : (k_pool + 1) * dim], LZ, X)
        cost, feasible = scorer.score(X)
        _track(st, X, cost, feasible)
        _refit(st, X, cost, p)
        if _converged(st.gammas, it, p):
            converged = True
            break
        if _out_of_time(it):
            break
    return Run(st.best, st.best_feasible, st.mu, st.trace, it, converged)


def _standard_normal_pool(gen: np.random.Generator, dim: int, m: int, dt: type) -> np.ndarray:
    """Standard normals for :data:`_POOL` iterations: ``_POOL * dim`` rows of ``m``."""
    return standard_normal(gen, (_POOL * dim, m), dt)


def _sample(st: _Search, Z: np.ndarray, LZ: np.ndarray, X: np.ndarray) -> None:
    """Samples into ``X``: mu + L Z, then mu - L Z in the columns Z does not fill (mirrored).
    The product runs in column blocks small enough for a single-threaded GEMM."""
    dim, m = LZ.shape
    S = X.shape[1]
    step = max(1, _GEMM_SINGLE_THREAD // (dim * dim))
    for a in range(0, m, step):
        np.matmul(st.L, Z[:, a : a + step], out=LZ[:, a : a + step])
    mu_col = st.mu.astype(X.dtype)[:, None]
    np.add(LZ, mu_col, out=X[:, :m])
    if m < S:
        np.subtract(mu_col, LZ[:, : S - m], out=X[:, m:])


def _track(st: _Search, X: np.ndarray, cost: np.ndarray, feasible: np.ndarray) -> None:
    """Keep the best sample ever drawn and the best feasible one; extend the trace."""
    k = int(np.argmin(cost))
    if cost[k] < st.best_cost:
        st.best_cost = float(cost[k])
        st.best = X[:, k].astype(np.float64)
    if feasible.any():
        kf = int(np.argmin(np.where(feasible, cost, np.inf)))
        if cost[kf] < st.feas_cost:
            st.feas_cost = float(cost[kf])
            st.best_feasible = X[:, kf].astype(np.float64)
    st.trace.append(-st.best_cost)


def _refit(st: _Search, X: np.ndarray, cost: np.ndarray, p: CEParams) -> None:
    """Refit to the elite: mean and full covariance (ML), smoothed, factored with the
    diagonal floor; records the elite threshold gamma."""
    c = p.elite
    order = np.argpartition(cost, c - 1)[:c]
    st.gammas.append(float(cost[order].max()))
    elite = X[:, order].astype(np.float64)
    mu_e = np.add.reduce(elite, axis=1)
    mu_e *= 1.0 / c
    elite -= mu_e[:, None]
    cov_e = _gram(elite)
    b = p.cov_smoothing
    if b >= 1.0:
        st.cov = cov_e
    else:
        st.cov *= 1.0 - b
        cov_e *= b
        st.cov += cov_e
    st.mu *= 1.0 - p.smoothing
    st.mu += p.smoothing * mu_e
    st.L = _cholesky(st.cov, p.min_sd**2).astype(X.dtype)


def _converged(gammas: list[float], it: int, p: CEParams) -> bool:
    """de Boer et al.'s test: gamma moved by at most ``tol`` (relative) in ``patience``
    iterations."""
    if it <= p.patience:
        return False
    gain = gammas[-1 - p.patience] - gammas[-1]
    return abs(gain) <= p.tol * max(1.0, abs(gammas[-1]))


def _gram(e: np.ndarray) -> np.ndarray:
    """``e @ e.T / e.shape[1]`` in row blocks small enough for a single-threaded GEMM."""
    d, c = e.shape
    out = np.empty((d, d))
    rows = max(1, _GEMM_SINGLE_THREAD // (d * c))
    for a in range(0, d, rows):
        np.matmul(e[a : a + rows], e.T, out=out[a : a + rows])
    out *= 1.0 / c
    return out


def _cholesky(cov: np.ndarray, floor: float) -> np.ndarray:
    """Lower Cholesky factor of ``cov + floor * I``; the floor grows tenfold on failure."""
    from scipy.linalg.lapack import dpotrf  # lazily: 0.5 s of import, not for --help

    d = cov.shape[0]
    for _ in range(8):
        a = cov.copy()
        a.flat[:: d + 1] += floor
        factor, info = dpotrf(a, lower=1, clean=1, overwrite_a=1)
        if info == 0:
            return factor
        floor *= 10.0
    raise np.linalg.LinAlgError("covariance is not positive definite")


# ---------------------------------------------------------------------------------------------
# The compiled loop
# ---------------------------------------------------------------------------------------------


def _ce_run_compiled(
    kit: Kit,
    gen: np.random.Generator,
    p: CEParams,
    block: Callable[..., int],
    scorer: BatchScorer,
    m: int,
    mu0: np.ndarray,
    sd0: np.ndarray,
) -> Run:
    """:func:`ce_run` with the iterations compiled (:func:`bilevel_kit.heuristics._kernels.
    _ce_block`), one call per pool of standard normals drawn exactly as the numpy loop draws
    them (the same random stream). Used without overhang penalty and reach map."""
    dt = scorer.dt
    n, dim, S = kit.n, kit.dim, p.samples
    mu = np.asarray(mu0, dtype=np.float64).copy()
    cov = np.diag(np.asarray(sd0, dtype=np.float64) ** 2)
    L = np.ascontiguousarray(np.diag(np.asarray(sd0, dtype=np.float64)).astype(dt))
    X = np.empty((dim, S), dtype=dt)
    best = mu.copy()
    best_feasible = np.zeros(dim)
    state = np.array([math.inf, math.inf, 0.0, 0.0])
    trace = np.zeros(p.max_iter)
    gammas = np.zeros(p.max_iter)
    fparams = np.array([p.smoothing, p.cov_smoothing, p.min_sd**2, p.tol])
    statics = (
        n,
        kit.rot_idx.astype(np.int64),
        np.ascontiguousarray(scorer.half_w[:, 0]),
        np.ascontiguousarray(scorer.half_h[:, 0]),
        scorer.consts,
        kit.pairs.i.astype(np.int64),
        kit.pairs.j.astype(np.int64),
        kit.pairs.sign.astype(dt),
    )
    arrays = (mu, cov, L, X, scorer.exT, scorer.eyT, scorer.cost, scorer.z)
    it = 0
    while it < p.max_iter and state[2] == 0.0 and not _out_of_time(it):
        pool = _standard_normal_pool(gen, dim, m, dt)
        n_it = min(_POOL, p.max_iter - it)
        args = (*arrays, *statics, p.elite, fparams, p.patience)
        it += block(pool, it + 1, n_it, *args, best, best_feasible, state, trace, gammas)
        if state[2] < 0:
            raise np.linalg.LinAlgError("covariance is not positive definite")
    feasible = best_feasible.copy() if math.isfinite(state[1]) else None
    return Run(best, feasible, mu, trace[:it].tolist(), it, bool(state[2] > 0))
