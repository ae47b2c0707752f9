"""Kit-fitness terms (paper Eqs. 8-11) on hand-computed layouts, batch vs single, box vs exact."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bilevel_kit import geometry
from bilevel_kit.fitness import (
    PairScorer,
    PairTable,
    exact_overlap_area,
    half_extents,
    kit_fitness,
    kit_fitness_terms,
    layout_fitness,
    layout_terms,
    overlapping_box_pairs,
    pair_distance_sums,
)
from bilevel_kit.instance import Tray
from bilevel_kit.plan import Placement


def pl(part: str, typ: str, x: float, y: float, w: float, h: float, th: float = 0.0) -> Placement:
    return Placement(part, typ, x, y, th, w, h)


# A (type a) at the origin, B (type a) at (3, 4), C (type b) at (6, 8):
#   D_same = |AB| = 5;  D_diff = |AC| + |BC| = 10 + 5 = 15
#   A = [-5, 5]^2, B = [-2, 8] x [-1, 9], C = [4, 8] x [7, 9]
#   A n B = 7 x 6 = 42;  A n C = 0 (A ends at y = 5);  B n C = C = 4 x 2 = 8;  Z = 50
THREE = (
    pl("A", "a", 0.0, 0.0, 10.0, 10.0),
    pl("B", "a", 3.0, 4.0, 10.0, 10.0),
    pl("C", "b", 6.0, 8.0, 4.0, 2.0),
)


def test_three_parts_by_hand() -> None:
    d_same, d_diff, z_bbox, z_exact = layout_terms(THREE)
    assert d_same == pytest.approx(5.0, abs=1e-12)
    assert d_diff == pytest.approx(15.0, abs=1e-12)
    assert z_bbox == pytest.approx(50.0, abs=1e-12)
    assert z_exact == pytest.approx(50.0, abs=1e-9)  # axis-aligned: box = exact


def test_fitness_sign_penalises_overlap() -> None:
    # Eq. 11 with the erratum: -(D_same - D_diff + W6 Z) = -(5 - 15 + 10 * 50)
    assert layout_fitness(THREE, 10.0) == pytest.approx(-490.0)
    # moving C out of B removes 8 mm^2 of overlap and must raise the fitness
    moved = (*THREE[:2], pl("C", "b", 6.0, 30.0, 4.0, 2.0))
    assert layout_terms(moved)[3] == pytest.approx(42.0)
    assert layout_fitness(moved, 10.0) > layout_fitness(THREE, 10.0)


def test_rotated_square_box_vs_exact() -> None:
    # A 10 x 10 square turned 45 degrees at the origin, an upright one centred at (10, 0).
    # Box of the diamond: half-extent 5 sqrt(2); it overlaps the upright square's box by
    # (5 sqrt(2) - 5) x 10. Exactly, only the diamond's tip past x = 5 overlaps: a triangle
    # of height t = 5 sqrt(2) - 5 and base 2t, area t^2.
    t = 5 * math.sqrt(2) - 5
    lay = (pl("d", "a", 0.0, 0.0, 10.0, 10.0, 45.0), pl("s", "a", 10.0, 0.0, 10.0, 10.0))
    _, _, z_bbox, z_exact = layout_terms(lay)
    assert z_bbox == pytest.approx(10 * t, rel=1e-12)
    assert z_exact == pytest.approx(t * t, rel=1e-9)
    assert overlapping_box_pairs(lay) == [(0, 1)]


def test_rotated_parts_whose_boxes_overlap_but_not_themselves() -> None:
    # Two thin 100 x 2 bars at +-45 degrees, side by side: the boxes overlap a lot, the
    # bars do not touch at all.
    lay = (pl("a", "a", 0.0, 0.0, 100.0, 2.0, 45.0), pl("b", "a", 20.0, 0.0, 100.0, 2.0, 45.0))
    _, _, z_bbox, z_exact = layout_terms(lay)
    assert z_bbox > 1000.0
    assert z_exact == 0.0


def test_half_extents_values() -> None:
    ex, ey = half_extents(20.0, 10.0, 30.0)
    assert float(ex) == pytest.approx((20 * math.cos(math.pi / 6) + 10 * 0.5) / 2)
    assert float(ey) == pytest.approx((20 * 0.5 + 10 * math.cos(math.pi / 6)) / 2)
    ex, ey = half_extents(np.array([20.0]), np.array([10.0]), np.array([90.0, -90.0, 180.0]))
    np.testing.assert_allclose(ex, [5.0, 5.0, 10.0], atol=1e-12)
    np.testing.assert_allclose(ey, [10.0, 10.0, 5.0], atol=1e-12)


def _batch(layouts: list[tuple[Placement, ...]]) -> tuple[np.ndarray, ...]:
    x = np.array([[p.x for p in lay] for lay in layouts])
    y = np.array([[p.y for p in lay] for lay in layouts])
    th = np.array([[p.theta for p in lay] for lay in layouts])
    return x, y, th


def test_batch_rows_equal_single_layouts() -> None:
    rot = (THREE[0], THREE[1], pl("C", "b", 6.0, 8.0, 4.0, 2.0, 30.0))
    far = tuple(pl(p.part, p.type, p.x * 10, p.y * 10, p.w, p.h, 90.0) for p in THREE)
    layouts = [THREE, rot, far]
    x, y, th = _batch(layouts)
    terms = kit_fitness_terms(x, y, th, ["a", "a", "b"], [10, 10, 4], [10, 10, 2])
    for k, lay in enumerate(layouts):
        d_same, d_diff, z_bbox, _ = layout_terms(lay)
        assert terms.d_same[k] == pytest.approx(d_same)
        assert terms.d_diff[k] == pytest.approx(d_diff)
        assert terms.z[k] == pytest.approx(z_bbox)
    assert terms.z[2] == 0.0
    np.testing.assert_allclose(
        kit_fitness(terms, 10.0), -(terms.d_same - terms.d_diff + 10.0 * terms.z)
    )


def test_float32_batch_agrees_with_float64() -> None:
    rng = np.random.default_rng(3)
    S, n = 50, 12
    x, y, th = rng.random((S, n)) * 300, rng.random((S, n)) * 200, rng.random((S, n)) * 180
    types = [f"t{k % 4}" for k in range(n)]
    w, h = rng.uniform(5, 60, n), rng.uniform(5, 60, n)
    t64 = kit_fitness_terms(x, y, th, types, w, h)
    t32 = kit_fitness_terms(
        x.astype(np.float32), y.astype(np.float32), th.astype(np.float32), types, w, h
    )
    assert t32.d_same.dtype == np.float32
    for a, b in zip(t64, t32, strict=True):
        np.testing.assert_allclose(b, a, rtol=1e-4, atol=1e-2)


def test_tray_violation_sums_overhangs() -> None:
    # 10 x 10 at x = 2 sticks out 3 mm on the left; a 20 x 10 part turned 90 degrees at
    # y = 96 has half-height 10 and sticks out 6 mm at the top.
    x, y, th = np.array([[2.0, 50.0]]), np.array([[50.0, 96.0]]), np.array([[0.0, 90.0]])
    terms = kit_fitness_terms(x, y, th, ["a", "b"], [10, 20], [10, 10], tray=Tray(100, 100))
    assert terms.out[0] == pytest.approx(9.0)
    inside = kit_fitness_terms(
        x + 10, y - 10, th, ["a", "b"], [10, 20], [10, 10], tray=(100.0, 100.0)
    )
    assert inside.out[0] == 0.0


def test_pair_table_and_scorer_reuse() -> None:
    pairs = PairTable.build(["a", "b", "a", "c"])
    assert pairs.n_pairs == 6
    np.testing.assert_array_equal(pairs.same, [False, True, False, False, False, False])
    scorer = PairScorer(pairs, 2, np.float64)
    rng = np.random.default_rng(0)
    xT, yT = rng.random((4, 2)) * 100, rng.random((4, 2)) * 100
    e = np.full((4, 2), 5.0)
    first = scorer.terms(xT, yT, e, e)
    scorer.signed(yT, xT, e, e)  # dirty the buffers
    again = scorer.terms(xT, yT, e, e)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a, b)
    dsd, _ = scorer.signed(xT, yT, e, e)
    np.testing.assert_allclose(dsd, first[0] - first[1])
    with pytest.raises(ValueError, match="shape"):
        scorer.signed(xT[:, :1], yT[:, :1], e[:, :1], e[:, :1])


def test_degenerate_inputs() -> None:
    assert layout_terms(()) == (0.0, 0.0, 0.0, 0.0)
    assert layout_terms(THREE[:1]) == (0.0, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError):
        kit_fitness_terms(
            np.zeros((2, 3)), np.zeros((2, 2)), np.zeros((2, 3)), "abc", [1, 1, 1], [1, 1, 1]
        )


rect = st.tuples(
    st.floats(0, 100),
    st.floats(0, 100),
    st.floats(1, 40),
    st.floats(1, 40),
    st.sampled_from([0.0, 90.0, 180.0, -90.0]),
)


@settings(max_examples=40, deadline=None)
@given(st.lists(rect, min_size=2, max_size=5))
def test_axis_aligned_box_z_is_exact(rects: list[tuple[float, ...]]) -> None:
    lay = tuple(pl(f"p{k}", "t", x, y, w, h, th) for k, (x, y, w, h, th) in enumerate(rects))
    _, _, z_bbox, z_exact = layout_terms(lay)
    assert z_exact == pytest.approx(z_bbox, rel=1e-7, abs=1e-6)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.floats(0, 100),
            st.floats(0, 100),
            st.floats(1, 40),
            st.floats(1, 40),
            st.floats(-180, 180),
        ),
        min_size=2,
        max_size=5,
    )
)
def test_box_z_bounds_exact_z(rects: list[tuple[float, ...]]) -> None:
    lay = tuple(pl(f"p{k}", "t", x, y, w, h, th) for k, (x, y, w, h, th) in enumerate(rects))
    _, _, z_bbox, z_exact = layout_terms(lay)
    assert z_exact <= z_bbox + 1e-6
    # and Z_exact is the plain pairwise sum of geometry's clipped areas
    corners = [geometry.corners(p.x, p.y, p.w, p.h, p.theta) for p in lay]
    brute = sum(
        geometry.intersection_area(corners[a], corners[b])
        for a in range(len(lay))
        for b in range(a + 1, len(lay))
    )
    assert exact_overlap_area(lay) == pytest.approx(brute, abs=1e-6)


def _random_layout(n: int, seed: int) -> tuple[Placement, ...]:
    """Overlapping and separate parts of three types, some rotated."""
    rng = np.random.default_rng(seed)
    return tuple(
        pl(
            f"p{k}",
            "abc"[k % 3],
            float(rng.uniform(0, 400)),
            float(rng.uniform(0, 300)),
            float(rng.uniform(5, 30)),
            float(rng.uniform(5, 30)),
            float(rng.choice([0.0, 90.0, 33.0])),
        )
        for k in range(n)
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_large_layout_path_gives_the_same_terms(monkeypatch, seed: int) -> None:
    """Above LARGE_LAYOUT parts a layout is scored in blocks of rows and over the grid hash's
    near pairs: the same four terms as the all-pairs path, to summation rounding."""
    import bilevel_kit.fitness as fit

    layout = _random_layout(120, seed)
    small = fit.layout_terms(layout)
    pairs = fit.overlapping_box_pairs(layout)
    monkeypatch.setattr(fit, "LARGE_LAYOUT", 10)
    monkeypatch.setattr(fit, "DISTANCE_BLOCK", 500)  # several row blocks
    large = fit.layout_terms(layout)
    assert fit.overlapping_box_pairs(layout) == pairs
    assert len(pairs) > 5  # the layout does overlap, so Z is tested
    for a, b in zip(large, small, strict=True):
        assert math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-6)


def test_pair_distance_sums_by_hand() -> None:
    x, y = np.array([0.0, 3.0, 0.0]), np.array([0.0, 4.0, 1.0])
    # pairs: (0,1) 5 different, (0,2) 1 same, (1,2) sqrt(9 + 9) different
    d_same, d_diff = pair_distance_sums(x, y, ["a", "b", "a"])
    assert d_same == pytest.approx(1.0)
    assert d_diff == pytest.approx(5.0 + math.sqrt(18.0))
