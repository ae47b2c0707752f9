"""Kit arrangement by the cross-entropy method (paper Section IV-B, Algorithm 1).

The decision vector holds, for the n parts of a kit, the centres x (n), y (n) and the angles
theta (degrees) of the r rotatable parts; fixed parts keep theta = 0 and are not sampled.
Each iteration draws ``samples`` vectors from N(mu, Sigma) (Cholesky factor times standard
normals), scores them all in one numpy pass (:class:`bilevel_kit.fitness.PairScorer`),
and refits mu and the full Sigma to the ``elite`` best ones. The score to minimise is Eq. 11
with the erratum's sign (docs/errata.md), ``D_same - D_diff + W6 * Z_box``, plus a
penalty on tray overhang (below); ``trace`` and fitness values are its negation.

Choices the paper leaves open (details in :class:`CEParams`):

- Initialisation: mu uniform over the tray (angles uniform in [0, 180)), Sigma diagonal with
  standard deviations ``init_sd_frac`` times the tray side and ``init_sd_theta`` degrees.
- Tray containment by *projection*: every sampled centre is clipped so that its rotated
  bounding box lies inside the tray, and the clipped vector is what is scored and refitted
  (so the mean stays inside). Only when a rotated box is wider than the tray does clipping
  fail; that overhang is penalised with ``out_weight`` per mm.
- Sigma gets ``min_sd**2`` added on its diagonal after each refit: 30 elites cannot span the
  3n-dimensional space, so the sample covariance is singular; the floor keeps the Cholesky
  factor defined and keeps some exploration in every coordinate.
- Smoothing: Sigma <- 0.3 Sigma_elite + 0.7 Sigma by default (de Boer et al.'s tutorial,
  which the paper cites, recommends smoothed updates). With the literal refit
  (``cov_smoothing=1``) the 84-dimensional search of the 28-part table kit collapses early
  while parts still overlap: over 16 seeds the median fitness fell from 35.7k to 30.8k and 4
  runs needed the packer fallback (none with smoothing).
- Sampling is mirrored (mu + L z and mu - L z), which halves the random numbers drawn.
- Elitism: the best sample ever drawn is kept; at the end it and the final mean (and the best
  sample whose boxes did not overlap) compete on exact fitness.
- Precision: samples are scored in float32 by default (ranking only, about 4x faster than
  float64 here); every returned number is recomputed in float64 on the exact rectangles.

Exactness of the answer: a candidate is accepted only if :mod:`bilevel_kit.geometry` finds
every part inside the tray and no pair penetrating by more than ``geometry.TOL``. A candidate
with small overlaps is first *repaired* by pushing overlapping bounding boxes apart; if no CE
candidate is valid, CE is re-run from the shelf packer's layout, and the packer's layout
itself competes too. Overlapping layouts are never reported as ``fits=True``.

Performance: with numba installed the iterations run compiled
(:mod:`bilevel_kit.heuristics._kernels`: sampling, extents, projection, the fused pair loop of
the scores, elite refit and Cholesky factor in one call per pool of standard normals, which
are still drawn here, so the random stream is the numpy loop's). Scores then differ from the
numpy loop only by float32 rounding (summation order, ``cos``/``sin`` in the last bit), which
can reorder near-tied samples; ``BILEVEL_KIT_NO_NUMBA=1`` forces the numpy loop. Runs with a
reach map or with parts that can stick out of the tray use the numpy loop (with the compiled
scorer). In the numpy loop all (n, S)- and (P, S)-sized arrays are allocated once per run;
matrix products inside the loop are cut into blocks that OpenBLAS runs single-threaded
(threaded products of this size were 10-100x slower on a busy 2-core machine).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import geometry
from ..errors import UsageError
from ..fitness import PairScorer, PairTable, box_overlap_1d, layout_terms
from ..instance import Instance, PartType, Tray
from ..plan import Placement
from ..reachability import ReachGrid, reach_grid
from . import _kernels


@dataclass(frozen=True)
class CEParams:
    """Parameters of Algorithm 1 (paper values: 200 samples, 30 elites, 100 iterations).

    Convergence test (de Boer et al.'s rule): the run stops when the elite threshold gamma
    (the score of the ``elite``-th best sample of an iteration) has moved by at most
    ``tol * max(1, |gamma|)`` over the last ``patience`` iterations; ``converged`` says
    whether that happened before ``max_iter``. The paper's literal Algorithm 1 is
    ``CEParams(cov_smoothing=1, mirrored=False, precision="float64")``.
    """

    #: Samples drawn per iteration.
    samples: int = 200
    #: Top samples (c in the paper) that mean and covariance are refitted to.
    elite: int = 30
    #: Iteration cap (the paper's 100).
    max_iter: int = 100
    #: Relative change of gamma that still counts as progress.
    tol: float = 1e-4
    #: Iterations over which gamma must stay within ``tol`` to count as converged.
    patience: int = 10
    #: Initial standard deviation of x and y as a fraction of the tray width and height.
    init_sd_frac: float = 0.25
    #: Initial standard deviation of the angles, degrees.
    init_sd_theta: float = 30.0
    #: Diagonal floor of Sigma (added as min_sd**2): mm for positions, degrees for angles.
    #: 0.5 beat 0.05, 0.2 and 1.0 on the 28-part table kit (median fitness over seeds).
    min_sd: float = 0.5
    #: Penalty per mm of tray overhang left after projection; None: max(W6, 1) * max tray side
    #: (the overlap penalty of a 1 mm strip across the tray).
    out_weight: float | None = None
    #: "float32" (default) or "float64" for scoring the samples.
    precision: str = "float32"
    #: Push overlapping candidates apart before giving up on them.
    repair: bool = True
    #: Initial standard deviations of a run started from a given layout, relative to the
    #: random-start ones (a small value searches near the start).
    restart_sd_scale: float = 0.1
    #: Mirrored (antithetic) sampling: half the samples are mu + L z, the other half mu - L z.
    #: Each sample is still N(mu, Sigma); it halves the normals and the Cholesky product.
    mirrored: bool = True
    #: Smoothing of the mean update, mu <- a * mu_elite + (1 - a) * mu (1: the paper's rule).
    smoothing: float = 1.0
    #: Smoothing of the covariance update, Sigma <- b * Sigma_elite + (1 - b) * Sigma
    #: (1: the paper's rule; 0.3 beat 0.2, 0.5, 0.7 and 1 on the 28-part table kit).
    cov_smoothing: float = 0.3

    def __post_init__(self) -> None:
        if self.samples < 2 or not 2 <= self.elite <= self.samples:
            raise UsageError(
                f"need samples >= elite >= 2, got samples={self.samples}, elite={self.elite}"
            )
        if self.max_iter < 1 or self.patience < 1:
            raise UsageError("max_iter and patience must be >= 1")
        if self.min_sd <= 0 or self.init_sd_frac <= 0 or self.init_sd_theta < 0:
            raise UsageError("min_sd and init_sd_frac must be > 0, init_sd_theta >= 0")
        if not (0 < self.smoothing <= 1 and 0 < self.cov_smoothing <= 1):
            raise UsageError("smoothing and cov_smoothing must lie in (0, 1]")
        if self.precision not in ("float32", "float64"):
            raise UsageError(f"precision must be 'float32' or 'float64', got {self.precision!r}")


@dataclass(frozen=True)
class Arrangement:
    """A kit layout and how it was found.

    ``z`` is the exact overlap area (mm^2) of the rotated rectangles, ``z_bbox`` the paper's
    bounding-box Z; ``fitness = -(d_same - d_diff + W6 * z)`` (bigger is better; ``-inf``
    when there is no layout). ``iterations``, ``converged`` and ``trace`` (best fitness after
    each iteration) describe the last CE run performed. ``source`` names where the layout came
    from: ``ce``, ``ce+start`` (CE from the caller's start), ``ce+packer-start``, any of these
    with ``+repair``, ``packer``, or, without a layout, ``area-bound``/``too-large``.
    """

    layout: tuple[Placement, ...]
    fits: bool
    d_same: float
    d_diff: float
    z: float
    z_bbox: float
    fitness: float
    iterations: int
    converged: bool
    trace: tuple[float, ...]
    source: str


# ---------------------------------------------------------------------------------------------
# The kit as arrays
# ---------------------------------------------------------------------------------------------


@dataclass
class _Kit:
    """Per-call constants: part ids, footprints, the pair table and the vector layout."""

    tray: Tray
    ids: list[str]
    types: list[PartType]
    w: np.ndarray
    h: np.ndarray
    rot_idx: np.ndarray
    fixed_idx: np.ndarray
    pairs: PairTable
    #: Reach grid when the instance enforces Sawyer reachability (else None).
    reach: ReachGrid | None = None
    n: int = field(init=False)
    dim: int = field(init=False)

    def __post_init__(self) -> None:
        self.n = len(self.ids)
        self.dim = 2 * self.n + self.rot_idx.size

    def decode(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, y, theta) in float64 of a decision vector, projected into the tray and with
        angles wrapped to (-90, 90] (a rectangle is symmetric under 180 degrees)."""
        v = np.asarray(v, dtype=np.float64)
        n = self.n
        theta = np.zeros(n)
        theta[self.rot_idx] = 90.0 - np.mod(90.0 - v[2 * n :], 180.0)
        ex, ey = _extents64(self, theta)
        x = _clip_centre(v[:n], ex, self.tray.width)
        y = _clip_centre(v[n : 2 * n], ey, self.tray.height)
        return x, y, theta

    def encode(self, x: np.ndarray, y: np.ndarray, theta: np.ndarray) -> np.ndarray:
        return np.concatenate([x, y, np.asarray(theta)[self.rot_idx]]).astype(np.float64)

    def layout(self, x: np.ndarray, y: np.ndarray, theta: np.ndarray) -> tuple[Placement, ...]:
        return tuple(
            Placement(
                self.ids[k], t.id, float(x[k]), float(y[k]), float(theta[k]), t.width, t.height
            )
            for k, t in enumerate(self.types)
        )


def _extents64(kit: _Kit, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rad = np.radians(theta)
    c, s = np.abs(np.cos(rad)), np.abs(np.sin(rad))
    return 0.5 * (kit.w * c + kit.h * s), 0.5 * (kit.w * s + kit.h * c)


def _clip_centre(c: np.ndarray, e: np.ndarray, side: float) -> np.ndarray:
    """Centres moved so that [c - e, c + e] lies in [0, side]; centred if it cannot."""
    out = np.minimum(np.maximum(c, e), side - e)
    too_big = 2.0 * e > side
    out[too_big] = side / 2.0
    return out


def _build_kit(instance: Instance, parts: Mapping[str, int], dtype: type) -> _Kit:
    ids: list[str] = []
    types: list[PartType] = []
    for t in sorted(parts):
        count = parts[t]
        if t not in instance.part_types:
            raise UsageError(f"unknown part type {t!r}")
        if count < 0:
            raise UsageError(f"negative count {count} of part type {t!r}")
        for k in range(1, count + 1):
            ids.append(f"{t}-{k}")
            types.append(instance.part_types[t])
    rot = np.array([t.rotatable for t in types], dtype=bool)
    return _Kit(
        tray=instance.tray,
        ids=ids,
        types=types,
        w=np.array([t.width for t in types], dtype=np.float64),
        h=np.array([t.height for t in types], dtype=np.float64),
        rot_idx=np.flatnonzero(rot),
        fixed_idx=np.flatnonzero(~rot),
        pairs=PairTable.build([t.id for t in types], dtype),
        reach=reach_grid(instance),
    )


# ---------------------------------------------------------------------------------------------
# Sampling and the CE loop
# ---------------------------------------------------------------------------------------------


def _standard_normal(
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
class _Run:
    best: np.ndarray
    best_feasible: np.ndarray | None
    mean: np.ndarray
    trace: list[float]
    iterations: int
    converged: bool


#: OpenBLAS runs a GEMM single-threaded when m*n*k is at most 65536 * 4. Threaded GEMMs of
#: this size were measured 10-100x slower on a busy 2-core machine (worker threads spin and
#: compete with the caller), so the loop's products are cut into blocks of that size.
_GEMM_SINGLE_THREAD = 1 << 18
#: Iterations' worth of standard normals drawn per call (amortises the call overhead).
_POOL = 8


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


def _ce_run(
    kit: _Kit,
    gen: np.random.Generator,
    p: CEParams,
    w6: float,
    w_out: float,
    mu0: np.ndarray,
    sd0: np.ndarray,
) -> _Run:
    """One run of Algorithm 1 from N(mu0, diag(sd0^2)); see the module docstring.

    Everything of size (dim, S) or (n, S) is allocated once before the loop; the loop body
    is a fixed sequence of numpy calls (sample, project, score, select, refit)."""
    dt = np.float32 if p.precision == "float32" else np.float64
    n, dim, S, c = kit.n, kit.dim, p.samples, p.elite
    W, H = kit.tray.width, kit.tray.height
    rot = kit.rot_idx
    r = rot.size
    scorer = PairScorer(kit.pairs, S, dt)
    half_w = (kit.w[rot] / 2.0).astype(dt)[:, None]
    half_h = (kit.h[rot] / 2.0).astype(dt)[:, None]
    # Half-extents of the rotated boxes; fixed parts' rows are constant and filled once.
    exT = np.empty((n, S), dtype=dt)
    eyT = np.empty((n, S), dtype=dt)
    exT[kit.fixed_idx] = (kit.w[kit.fixed_idx] / 2.0).astype(dt)[:, None]
    eyT[kit.fixed_idx] = (kit.h[kit.fixed_idx] / 2.0).astype(dt)[:, None]
    hi = np.empty((n, S), dtype=dt)
    cs = np.empty((r, S), dtype=dt)
    sn = np.empty((r, S), dtype=dt)
    tmp = np.empty((r, S), dtype=dt)
    # All parts rotatable (the common case): write the extents straight into exT/eyT.
    exr, eyr = (exT, eyT) if r == n else (np.empty((r, S), dtype=dt), np.empty((r, S), dtype=dt))
    # Can a rotated box be wider or taller than the tray (so that projection cannot work)?
    reach = np.where(np.isin(np.arange(n), rot), np.hypot(kit.w, kit.h), np.maximum(kit.w, kit.h))
    may_stick_out = bool((reach > min(W, H)).any())
    floor = p.min_sd**2
    w6f: Any = dt(w6)
    w_outf: Any = dt(w_out)
    deg = dt(math.pi / 180.0)
    kernel = _kernels.score_kernel()
    if kernel is not None:
        consts = np.array([math.pi / 180.0, W, H, w6, 0.0, 2.0], dtype=dt)
        k_half_w, k_half_h = half_w[:, 0].copy(), half_h[:, 0].copy()
        k_i, k_j = kit.pairs.i.astype(np.int64), kit.pairs.j.astype(np.int64)
        k_sign = kit.pairs.sign.astype(dt)
        k_rot = rot.astype(np.int64)
        cost: np.ndarray = np.empty(S, dtype=dt)
        z: np.ndarray = np.empty(S, dtype=dt)
    # Mirrored sampling: m normal columns give samples mu + LZ and mu - LZ.
    m = S - S // 2 if p.mirrored else S
    LZ = np.empty((dim, m), dtype=dt)
    step = max(1, _GEMM_SINGLE_THREAD // (dim * dim))

    block = _kernels.ce_block_kernel()
    if block is not None and not may_stick_out and kit.reach is None:
        return _ce_run_compiled(kit, gen, p, block, (half_w, half_h, exT, eyT, consts), m, mu0, sd0)

    pool = np.empty((0, m), dtype=dt)
    mu = np.asarray(mu0, dtype=np.float64).copy()
    cov = np.diag(np.asarray(sd0, dtype=np.float64) ** 2)
    L = np.diag(np.asarray(sd0, dtype=np.float64)).astype(dt)
    X = np.empty((dim, S), dtype=dt)
    x, y, th = X[:n], X[n : 2 * n], X[2 * n :]
    best_cost = math.inf
    best = mu.copy()
    feas_cost = math.inf
    best_feasible: np.ndarray | None = None
    trace: list[float] = []
    gammas: list[float] = []
    converged = False
    it = 0
    for it in range(1, p.max_iter + 1):
        # Sample: X = mu + L Z (and mu - L Z when mirrored).
        k_pool = (it - 1) % _POOL
        if k_pool == 0:
            pool = _standard_normal(gen, (_POOL * dim, m), dt)
        Z = pool[k_pool * dim : (k_pool + 1) * dim]
        for a in range(0, m, step):
            np.matmul(L, Z[:, a : a + step], out=LZ[:, a : a + step])
        mu_col = mu.astype(dt)[:, None]
        np.add(LZ, mu_col, out=X[:, :m])
        if m < S:
            np.subtract(mu_col, LZ[:, : S - m], out=X[:, m:])
        if kernel is not None:  # extents, projection and score in one compiled pass
            kernel(X, n, k_rot, k_half_w, k_half_h, exT, eyT, consts, k_i, k_j, k_sign, cost, z)
        else:
            if r:
                np.multiply(th, deg, out=tmp)
                np.cos(tmp, out=cs)
                np.abs(cs, out=cs)
                np.sin(tmp, out=sn)
                np.abs(sn, out=sn)
                np.multiply(cs, half_w, out=exr)
                exr += np.multiply(sn, half_h, out=tmp)
                np.multiply(sn, half_w, out=eyr)
                eyr += np.multiply(cs, half_h, out=tmp)
                if r < n:
                    exT[rot] = exr
                    eyT[rot] = eyr
            # Project into the tray, in place: the refit sees the projected samples.
            np.maximum(x, exT, out=x)
            np.minimum(x, np.subtract(dt(W), exT, out=hi), out=x)
            np.maximum(y, eyT, out=y)
            np.minimum(y, np.subtract(dt(H), eyT, out=hi), out=y)
            # Score all samples in one pass: D_same - D_diff + W6 * Z_box (+ overhang penalty).
            cost, z = scorer.signed(x, y, exT, eyT)
            cost += w6f * z
        feasible: np.ndarray = z == 0
        if may_stick_out:
            over = np.maximum(2 * exT - dt(W), dt(0)).sum(axis=0)
            over += np.maximum(2 * eyT - dt(H), dt(0)).sum(axis=0)
            cost += w_outf * over
            feasible &= over == 0
        if kit.reach is not None:  # unreachable centroids cost like sticking out of the tray
            lost = (~kit.reach.lookup(x, y)).sum(axis=0)
            cost += w_outf * dt(kit.tray.width) * lost
            feasible &= lost == 0
        k = int(np.argmin(cost))
        if cost[k] < best_cost:
            best_cost = float(cost[k])
            best = X[:, k].astype(np.float64)
        if feasible.any():
            kf = int(np.argmin(np.where(feasible, cost, np.inf)))
            if cost[kf] < feas_cost:
                feas_cost = float(cost[kf])
                best_feasible = X[:, kf].astype(np.float64)
        trace.append(-best_cost)
        # Refit to the elite: mean and full covariance (ML), smoothed, plus the diagonal floor.
        order = np.argpartition(cost, c - 1)[:c]
        gammas.append(float(cost[order].max()))
        elite = X[:, order].astype(np.float64)
        mu_e = np.add.reduce(elite, axis=1)
        mu_e *= 1.0 / c
        elite -= mu_e[:, None]
        cov_e = _gram(elite)
        b = p.cov_smoothing
        if b >= 1.0:
            cov = cov_e
        else:
            cov *= 1.0 - b
            cov_e *= b
            cov += cov_e
        mu *= 1.0 - p.smoothing
        mu += p.smoothing * mu_e
        L = _cholesky(cov, floor).astype(dt)
        if it > p.patience:
            gain = gammas[-1 - p.patience] - gammas[-1]
            if abs(gain) <= p.tol * max(1.0, abs(gammas[-1])):
                converged = True
                break
    return _Run(best, best_feasible, mu, trace, it, converged)


def _ce_run_compiled(
    kit: _Kit,
    gen: np.random.Generator,
    p: CEParams,
    block: Callable[..., int],
    arrays: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    m: int,
    mu0: np.ndarray,
    sd0: np.ndarray,
) -> _Run:
    """:func:`_ce_run` with the iterations compiled (:func:`bilevel_kit.heuristics._kernels.
    _ce_block`), one call per pool of standard normals drawn exactly as the numpy loop draws
    them (the same random stream). Used without overhang penalty and reach map."""
    half_w, half_h, exT, eyT, consts = arrays
    dt = exT.dtype.type
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
        np.ascontiguousarray(half_w[:, 0]),
        np.ascontiguousarray(half_h[:, 0]),
        consts,
        kit.pairs.i.astype(np.int64),
        kit.pairs.j.astype(np.int64),
        kit.pairs.sign.astype(dt),
    )
    cost = np.empty(S, dtype=dt)
    z = np.empty(S, dtype=dt)
    it = 0
    while it < p.max_iter and state[2] == 0.0:
        pool = _standard_normal(gen, (_POOL * dim, m), dt)
        n_it = min(_POOL, p.max_iter - it)
        args = (mu, cov, L, X, exT, eyT, cost, z, *statics, p.elite, fparams, p.patience)
        it += block(pool, it + 1, n_it, *args, best, best_feasible, state, trace, gammas)
        if state[2] < 0:
            raise np.linalg.LinAlgError("covariance is not positive definite")
    feasible = best_feasible.copy() if math.isfinite(state[1]) else None
    return _Run(best, feasible, mu, trace[:it].tolist(), it, bool(state[2] > 0))


# ---------------------------------------------------------------------------------------------
# Exact acceptance and repair
# ---------------------------------------------------------------------------------------------


def _exactly_valid(layout: Sequence[Placement], tray: Tray, reach: ReachGrid | None = None) -> bool:
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
class _Candidate:
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    fitness: float
    valid: bool
    source: str


def _assess(
    kit: _Kit, x: np.ndarray, y: np.ndarray, theta: np.ndarray, w6: float, source: str
) -> _Candidate:
    """Validity and fitness of a decoded layout, cheaply: box overlaps for all pairs at once,
    exact separating-axis tests and clipped areas only for pairs whose boxes overlap (the
    others are disjoint). Valid: exact fitness; invalid: fitness with the box Z (only used to
    rank layouts that will not be presented as valid)."""
    ex, ey = _extents64(kit, theta)
    W, H = kit.tray.width, kit.tray.height
    tol = geometry.TOL
    inside = bool(
        (x - ex >= -tol).all()
        and (x + ex <= W + tol).all()
        and (y - ey >= -tol).all()
        and (y + ey <= H + tol).all()
    )
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
    if kit.reach is not None and not kit.reach.lookup(x, y).all():
        inside = False  # an unreachable centroid is as invalid as a part off the tray
    if not inside:
        return _Candidate(x, y, theta, -(dsd + w6 * z_box), False, source)
    z = 0.0
    for p in hit:
        a, b = int(i[p]), int(j[p])
        ca = geometry.corners(x[a], y[a], kit.w[a], kit.h[a], theta[a])
        cb = geometry.corners(x[b], y[b], kit.w[b], kit.h[b], theta[b])
        if geometry.rects_overlap(ca, cb):
            return _Candidate(x, y, theta, -(dsd + w6 * z_box), False, source)
        z += geometry.intersection_area(ca, cb)
    return _Candidate(x, y, theta, -(dsd + w6 * z), True, source)


def _push_apart(
    kit: _Kit,
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
    ex, ey = _extents64(kit, theta)
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
        x = _clip_centre(x, ex, kit.tray.width)
        y = _clip_centre(y, ey, kit.tray.height)
    return None


def _candidate(kit: _Kit, v: np.ndarray, w6: float, source: str, repair: bool) -> _Candidate:
    """Decode a vector and assess it; if it is invalid, assess its push-apart repair."""
    x, y, theta = kit.decode(v)
    cand = _assess(kit, x, y, theta, w6, source)
    if cand.valid or not repair:
        return cand
    moved = _push_apart(kit, x, y, theta)
    if moved is not None:
        fixed = _assess(kit, moved[0], moved[1], theta, w6, source + "+repair")
        if fixed.valid:
            return fixed
    return cand


def _choose(kit: _Kit, cands: Sequence[_Candidate]) -> _Candidate:
    """The fittest candidate that passes the exact geometry check, else the fittest invalid
    one (marked invalid). Ties go to the earlier candidate."""
    order = sorted(range(len(cands)), key=lambda k: (not cands[k].valid, -cands[k].fitness, k))
    for k in order:
        cd = cands[k]
        if not cd.valid:
            break
        if _exactly_valid(kit.layout(cd.x, cd.y, cd.theta), kit.tray, kit.reach):
            return cd
        cd.valid = False
    return cands[order[0]]


# ---------------------------------------------------------------------------------------------
# Public entry point
# ---------------------------------------------------------------------------------------------


def _too_large(pt: PartType, tray: Tray) -> bool:
    """True when no placement can hold the part (sound, not complete, for rotatable parts:
    a rectangle's width in every direction is at least its shorter side)."""
    tol = geometry.TOL
    if not pt.rotatable:
        return pt.width > tray.width + tol or pt.height > tray.height + tol
    return min(pt.width, pt.height) > min(tray.width, tray.height) + tol


def _no_layout(source: str) -> Arrangement:
    return Arrangement((), False, 0.0, 0.0, 0.0, 0.0, -math.inf, 0, False, (), source)


def _start_vector(kit: _Kit, start: Sequence[Placement]) -> np.ndarray:
    """Decision vector of a given layout: parts matched by id, else by type in order."""
    by_id = {p.part: p for p in start}
    if len(by_id) == len(start) and set(by_id) == set(kit.ids):
        ordered = [by_id[pid] for pid in kit.ids]
    else:
        queues: dict[str, list[Placement]] = {}
        for p in start:
            queues.setdefault(p.type, []).append(p)
        try:
            ordered = [queues[t.id].pop(0) for t in kit.types]
        except (KeyError, IndexError):
            raise UsageError("start layout does not hold the kit's parts") from None
        if any(queues.values()):
            raise UsageError("start layout holds parts the kit does not need")
    theta = np.array(
        [p.theta if t.rotatable else 0.0 for p, t in zip(ordered, kit.types, strict=True)]
    )
    return kit.encode(np.array([p.x for p in ordered]), np.array([p.y for p in ordered]), theta)


def arrange(
    instance: Instance,
    parts: Mapping[str, int],
    *,
    rng: np.random.Generator | int | None = 0,
    params: CEParams = CEParams(),
    w6: float | None = None,
    start: Sequence[Placement] | None = None,
) -> Arrangement:
    """Arrange the multiset ``parts`` (type -> count) on the instance's tray (Algorithm 1).

    Part ids are ``f"{type}-{k}"``, types in sorted order, k = 1..count. ``w6`` defaults to
    the instance's W6. ``start`` replaces the random initial mean by a given layout (searched
    with ``restart_sd_scale`` times the initial spread). Every random draw comes from
    ``np.random.default_rng(rng)``, so equal seeds give equal layouts.
    """
    gen = np.random.default_rng(rng)
    w6 = float(instance.weights["W6"] if w6 is None else w6)
    dtype = np.float32 if params.precision == "float32" else np.float64
    kit = _build_kit(instance, parts, dtype)
    tray = kit.tray
    if kit.n == 0:
        return Arrangement((), True, 0.0, 0.0, 0.0, 0.0, 0.0, 0, True, (), "ce")
    if sum(t.area for t in kit.types) > tray.area * (1 + 1e-12):
        return _no_layout("area-bound")
    if any(_too_large(t, tray) for t in kit.types):
        return _no_layout("too-large")

    w_out = params.out_weight
    if w_out is None:
        w_out = max(w6, 1.0) * max(tray.width, tray.height)
    r = kit.rot_idx.size
    sd0 = np.concatenate(
        [
            np.full(kit.n, params.init_sd_frac * tray.width),
            np.full(kit.n, params.init_sd_frac * tray.height),
            np.full(r, params.init_sd_theta),
        ]
    )
    sd0 = np.maximum(sd0, params.min_sd)
    # a run from a given start (a layout, the shelf packer's) begins with a narrower spread
    restart_sd = np.maximum(sd0 * params.restart_sd_scale, params.min_sd)

    if start is None:
        mu0 = np.concatenate(
            [
                gen.uniform(0.0, tray.width, kit.n),
                gen.uniform(0.0, tray.height, kit.n),
                gen.uniform(0.0, 180.0, r),
            ]
        )
        tag = "ce"
        run = _ce_run(kit, gen, params, w6, w_out, mu0, sd0)
    else:
        mu0 = _start_vector(kit, start)
        tag = "ce+start"
        run = _ce_run(kit, gen, params, w6, w_out, mu0, restart_sd)
    cands = _run_candidates(kit, run, w6, tag, params.repair)
    if start is not None:
        cands.append(_candidate(kit, mu0, w6, tag, params.repair))
    choice = _choose(kit, cands)

    if not choice.valid:
        from .shelf import shelf_pack

        packed = shelf_pack(tray, list(zip(kit.ids, kit.types, strict=True)))
        if packed is not None:
            p0 = _start_vector(kit, packed)
            run = _ce_run(kit, gen, params, w6, w_out, p0, restart_sd)
            more = _run_candidates(kit, run, w6, "ce+packer-start", params.repair)
            more.append(_candidate(kit, p0, w6, "packer", repair=False))
            choice = _choose(kit, [*more, choice])
    return _arrangement(kit, choice, run, w6)


def _run_candidates(kit: _Kit, run: _Run, w6: float, tag: str, repair: bool) -> list[_Candidate]:
    vecs = [run.best, run.mean]
    if run.best_feasible is not None:
        vecs.append(run.best_feasible)
    return [_candidate(kit, v, w6, tag, repair) for v in vecs]


def _arrangement(kit: _Kit, choice: _Candidate, run: _Run, w6: float) -> Arrangement:
    layout = kit.layout(choice.x, choice.y, choice.theta)
    d_same, d_diff, z_bbox, z_exact = layout_terms(layout)
    return Arrangement(
        layout=layout,
        fits=choice.valid,
        d_same=d_same,
        d_diff=d_diff,
        z=z_exact,
        z_bbox=z_bbox,
        fitness=-(d_same - d_diff + w6 * z_exact),
        iterations=run.iterations,
        converged=run.converged,
        trace=tuple(run.trace),
        source=choice.source,
    )
