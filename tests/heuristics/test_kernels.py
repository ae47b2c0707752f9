"""The compiled CE scorer against the numpy path: same scores (float32 rounding), same CE result."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_cross_entropy import TABLE, TABLE_PARTS

from bilevel_kit.fitness import PairScorer, PairTable, half_extents
from bilevel_kit.heuristics import _kernels
from bilevel_kit.heuristics.cross_entropy import arrange

needs_numba = pytest.mark.skipif(not _kernels.available(), reason="numba unavailable or disabled")


def numpy_scores(
    X: np.ndarray,
    n: int,
    w: np.ndarray,
    h: np.ndarray,
    types: list[str],
    W: float,
    H: float,
    w6: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The numpy path of the CE loop: extents, projection, score (all parts rotatable)."""
    dt = X.dtype.type
    X = X.copy()
    ex, ey = half_extents(w[:, None].astype(dt), h[:, None].astype(dt), X[2 * n :])
    X[:n] = np.minimum(np.maximum(X[:n], ex), dt(W) - ex)
    X[n : 2 * n] = np.minimum(np.maximum(X[n : 2 * n], ey), dt(H) - ey)
    scorer = PairScorer(PairTable.build(types, dt), X.shape[1], dt)
    dsd, z = scorer.signed(X[:n], X[n : 2 * n], ex, ey)
    return dsd + dt(w6) * z, z, X


@needs_numba
@pytest.mark.parametrize("precision", [np.float32, np.float64])
def test_kernel_scores_equal_numpy_scores(precision: type) -> None:
    types = [t for t in sorted(TABLE_PARTS) for _ in range(TABLE_PARTS[t])]
    n, S = len(types), 200
    w = np.array([TABLE.part_types[t].width for t in types])
    h = np.array([TABLE.part_types[t].height for t in types])
    W, H, w6 = TABLE.tray.width, TABLE.tray.height, float(TABLE.weights["W6"])
    rng = np.random.default_rng(3)
    X = np.concatenate(
        [
            rng.uniform(-20, W + 20, (n, S)),
            rng.uniform(-20, H + 20, (n, S)),
            rng.uniform(-90, 270, (n, S)),
        ]
    ).astype(precision)
    want_cost, want_z, want_X = numpy_scores(X, n, w, h, types, W, H, w6)
    pairs = PairTable.build(types, precision)
    exT = np.empty((n, S), dtype=precision)
    eyT = np.empty((n, S), dtype=precision)
    cost = np.empty(S, dtype=precision)
    z = np.empty(S, dtype=precision)
    consts = np.array([math.pi / 180.0, W, H, w6, 0.0, 2.0], dtype=precision)
    kernel = _kernels.score_kernel()
    assert kernel is not None
    kernel(
        X,
        n,
        np.arange(n, dtype=np.int64),
        (w / 2).astype(precision),
        (h / 2).astype(precision),
        exT,
        eyT,
        consts,
        pairs.i.astype(np.int64),
        pairs.j.astype(np.int64),
        pairs.sign.astype(precision),
        cost,
        z,
    )
    rtol = 1e-4 if precision is np.float32 else 1e-10
    np.testing.assert_allclose(X, want_X, rtol=rtol, atol=rtol * 300)
    np.testing.assert_allclose(z, want_z, rtol=rtol, atol=rtol * 1e3)
    np.testing.assert_allclose(cost, want_cost, rtol=rtol, atol=rtol * abs(want_cost).max())
    # the ranking that CE uses: the same elite set
    assert set(np.argsort(cost)[:30]) == set(np.argsort(want_cost)[:30])


@needs_numba
def test_kernel_and_numpy_give_the_same_ce_result(monkeypatch: pytest.MonkeyPatch) -> None:
    fast = arrange(TABLE, TABLE_PARTS, rng=0)
    monkeypatch.setenv(_kernels.ENV_DISABLE, "1")
    slow = arrange(TABLE, TABLE_PARTS, rng=0)
    assert (fast.fits, fast.source, fast.iterations) == (slow.fits, slow.source, slow.iterations)
    assert fast.fitness == pytest.approx(slow.fitness, rel=1e-4)
    for p, q in zip(fast.layout, slow.layout, strict=True):
        assert (p.part, p.type) == (q.part, q.type)
        assert (p.x, p.y) == pytest.approx((q.x, q.y), abs=0.05)


def test_env_var_forces_the_numpy_path(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(_kernels.ENV_DISABLE, "1")
    assert not _kernels.available()
    assert _kernels.score_kernel() is None and _kernels.ce_block_kernel() is None


def textbook_cholesky(a: np.ndarray, floor: float) -> np.ndarray | None:
    """Left-looking Cholesky of ``a + floor * I`` in Python floats (one rounding per
    operation, the subtraction order the compiled kernel must keep)."""
    d = a.shape[0]
    f = np.zeros((d, d))
    for j in range(d):
        s = float(a[j, j]) + floor
        for k in range(j):
            s -= f[j, k] * f[j, k]
        if not s > 0.0:
            return None
        f[j, j] = math.sqrt(s)
        for i in range(j + 1, d):
            t = float(a[i, j])
            for k in range(j):
                t -= f[i, k] * f[j, k]
            f[i, j] = t / f[j, j]
    return f


@needs_numba
@pytest.mark.parametrize(
    ("d", "floor", "factors"),
    [(1, 0.25, True), (7, 0.25, True), (30, 0.25, True), (30, 0.0, False)],
)
def test_compiled_cholesky_is_the_textbook_loop_bit_for_bit(
    d: int, floor: float, factors: bool
) -> None:
    _kernels.available()  # compiles the kernels
    rng = np.random.default_rng(d)
    e = rng.standard_normal((d, 9)) * 40.0
    a = e @ e.T / 9 + rng.standard_normal((d, d)) * 1e-9  # not exactly symmetric
    want = textbook_cholesky(a, floor)
    out = np.full((d, d), 7.0)
    ok = _kernels._cholesky_into(a, floor, out)
    assert ok == (want is not None)
    assert ok == factors  # rank 9 without a floor is not positive definite
    if want is not None:
        assert np.array_equal(out, want)
        np.testing.assert_allclose(out @ out.T, a + floor * np.eye(d), rtol=1e-9, atol=1e-6)


SMALL_KIT = {"leg": 1, "foot": 2, "connector": 2, "screw_long": 2, "screw_short": 2}


@needs_numba
def test_compiled_push_apart_is_the_numpy_loop_float_for_float() -> None:
    """The repair of overlapping layouts (random centres and angles): the same moves, the
    same floats, the same give-up. A 9-part kit is mostly separated within 200 rounds, the
    28-part table kit never (random layouts); 3 rounds separate neither."""
    from bilevel_kit.heuristics.ce.accept import push_apart
    from bilevel_kit.heuristics.ce.kit import build_kit

    separated = {9: 0, 28: 0}
    for parts in (SMALL_KIT, TABLE_PARTS):
        kit = build_kit(TABLE, parts, np.float64)
        for seed in range(12):
            rng = np.random.default_rng(seed)
            x = rng.uniform(0, TABLE.tray.width, kit.n)
            y = rng.uniform(0, TABLE.tray.height, kit.n)
            theta = rng.uniform(-90, 90, kit.n)
            theta[kit.fixed_idx] = 0.0
            for rounds in (3, 200):
                fast = push_apart(kit, x, y, theta, rounds=rounds)
                slow = push_apart(kit, x, y, theta, rounds=rounds, compiled=False)
                assert (fast is None) == (slow is None)
                if fast is not None and slow is not None:
                    assert np.array_equal(fast[0], slow[0]) and np.array_equal(fast[1], slow[1])
                    assert rounds == 200
                    separated[kit.n] += 1
    assert separated[9] >= 8 and separated[28] == 0


@needs_numba
def test_float32_extents_polynomial_is_accurate() -> None:
    """The vectorised float32 |cos|/|sin| of the compiled scorer against float64 numpy over
    angles from -720 to 720 degrees (every quadrant, both parities of the reduction)."""
    _kernels.available()
    S = 100_001
    angles = np.linspace(-720.0, 720.0, S).astype(np.float32)
    X = np.zeros((3, S), dtype=np.float32)
    X[2] = angles
    ex = np.empty((1, S), dtype=np.float32)
    ey = np.empty((1, S), dtype=np.float32)
    hw, hh = np.float32(76.2), np.float32(6.35)  # half a table leg
    deg = np.float32(math.pi / 180.0)
    _kernels._rotated_extents(X[2:], np.array([0]), np.array([hw]), np.array([hh]), ex, ey, deg)
    rad = np.radians(angles.astype(np.float64))
    c, s = np.abs(np.cos(rad)), np.abs(np.sin(rad))
    # float32 rounding of the angle itself (|angle| <= 720: 3e-5 degrees) bounds the error
    assert np.abs(ex[0] - (c * 76.2 + s * 6.35)).max() < 2.5e-5
    assert np.abs(ey[0] - (s * 76.2 + c * 6.35)).max() < 2.5e-5


@needs_numba
def test_compiled_normals_equal_the_numpy_path() -> None:
    """The float32 normals of a CE pool: the same 24-bit uniforms from the generator's raw
    words, Box-Muller with polynomial (compiled) or numpy's sine and cosine; both standard
    normal (Kolmogorov-Smirnov, moments) and equal to float32 rounding."""
    from scipy import stats

    from bilevel_kit.heuristics.ce.sampling import standard_normal

    raw = np.random.default_rng(11).bit_generator.random_raw(1000)
    x, t = np.empty(1000, dtype=np.float32), np.empty(1000, dtype=np.float32)
    uniform_pairs, _ = _kernels.normal_kernels()  # type: ignore[misc]
    uniform_pairs(raw, x, t)
    assert np.array_equal(x, 1 - (raw >> np.uint64(40)).astype(np.float32) / 2**24)
    assert np.array_equal(t, ((raw >> np.uint64(16)) % 2**24).astype(np.float32) / 2**24)

    fast = standard_normal(np.random.default_rng(5), (336, 501), np.float32)
    slow = standard_normal(np.random.default_rng(5), (336, 501), np.float32, compiled=False)
    assert fast.shape == slow.shape == (336, 501) and fast.dtype == np.float32
    assert np.abs(fast - slow).max() < 1e-5
    assert abs(float(fast.mean())) < 0.005 and abs(float(fast.std()) - 1.0) < 0.005
    assert stats.kstest(fast.ravel(), "norm").pvalue > 0.01
    assert 4.5 < float(np.abs(fast).max()) < 5.8  # 24-bit uniforms cap the tails at ~5.8
    # a second draw continues the generator's stream (no reuse of words)
    gen = np.random.default_rng(5)
    standard_normal(gen, (336, 501), np.float32)
    assert not np.array_equal(standard_normal(gen, (336, 501), np.float32), fast)
