"""Infeasibility pre-checks for packing: every dual-feasible function is dual feasible (by
enumeration), no test ever rejects a set that fits (random guillotine cuts of a tray, which
fit by construction, with and without rotation, and brute force on tiny trays), and each test
catches its textbook case."""

from __future__ import annotations

import random

import numpy as np
import pytest
from brute import fits_on_grid

from bilevel_kit.models import packing_bounds as pb


def _multisets_up_to(C: int) -> list[list[int]]:
    """Every multiset of positive integers with sum <= C (partitions of 0..C)."""
    out: list[list[int]] = []

    def rec(rest: int, largest: int, acc: list[int]) -> None:
        out.append(acc[:])
        for v in range(min(rest, largest), 0, -1):
            acc.append(v)
            rec(rest - v, v, acc)
            acc.pop()

    rec(C, C, [])
    return out


@pytest.mark.parametrize("C", [1, 2, 5, 7, 10, 12, 13])
def test_every_function_is_dual_feasible(C: int) -> None:
    table, caps = pb.dff_table(C, np.arange(C + 1))
    assert (table[:, C] == caps).all()
    assert (table >= 0).all()
    for ms in _multisets_up_to(C):
        if ms:
            assert (table[:, ms].sum(axis=1) <= caps).all(), ms


def _guillotine(W: int, H: int, n: int, rng: random.Random) -> list[tuple[int, int]]:
    pieces = [(W, H)]
    while len(pieces) < n:
        pieces.sort(key=lambda p: p[0] * p[1])
        w, h = pieces.pop()
        if w >= 2 and (w >= h or h < 2):
            c = rng.randint(1, w - 1)
            pieces += [(c, h), (w - c, h)]
        elif h >= 2:
            c = rng.randint(1, h - 1)
            pieces += [(w, c), (w, h - c)]
        else:
            pieces.append((w, h))
            break
    return pieces


@pytest.mark.parametrize("seed", range(60))
def test_never_rejects_a_perfect_packing(seed: int) -> None:
    rng = random.Random(seed)
    W, H = rng.randint(2, 40), rng.randint(2, 40)
    pieces = _guillotine(W, H, rng.randint(2, 25), rng)
    rot = seed % 2 == 1
    sizes = [((h, w) if rot and rng.random() < 0.5 else (w, h)) for w, h in pieces]
    assert pb.infeasibility_reason([(w, h, rot) for w, h in sizes], W, H) is None


def test_never_rejects_a_fitting_set_brute_force() -> None:
    rng = random.Random(7)
    checked = 0
    for _ in range(400):
        W, H = rng.randint(2, 6), rng.randint(2, 6)
        n = rng.randint(2, 5)
        sizes = [(rng.randint(1, W), rng.randint(1, H), rng.random() < 0.5) for _ in range(n)]
        if pb.infeasibility_reason(sizes, W, H) is not None:
            assert not fits_on_grid(sizes, W, H), (sizes, W, H)
            checked += 1
    assert checked > 20


def test_textbook_cases() -> None:
    assert pb.infeasibility_reason([(11, 2, False)], 10, 10) == "part larger than tray"
    assert pb.infeasibility_reason([(11, 2, True)], 10, 12) is None
    assert pb.infeasibility_reason([(5, 5, False)] * 5, 10, 10) == "area"
    # two 6 x 6 squares on 10 x 10: neither side by side nor stacked
    assert pb.infeasibility_reason([(6, 6, False)] * 2, 10, 10) == "tall or wide parts"
    # 7 x 4 and 4 x 7 on 10 x 10: neither side by side (11) nor stacked (11); 6 x 4 and 4 x 6 fit
    assert pb.infeasibility_reason([(7, 4, False), (4, 7, False)], 10, 10) == "incompatible pair"
    assert pb.infeasibility_reason([(6, 4, False), (4, 6, False)], 10, 10) is None
    assert pb.infeasibility_reason([(6, 4, False), (4, 6, False), (6, 6, False)], 9, 9) is not None
    # three 4 x 4 squares in 7 x 7 (area 48 <= 49): no two share a row or column of width 7
    assert pb.infeasibility_reason([(4, 4, False)] * 3, 7, 7) is not None
    # ... nor 8 x 7 (one row of two), but they fit 8 x 8
    assert pb.infeasibility_reason([(4, 4, False)] * 3, 8, 7) is not None
    assert pb.infeasibility_reason([(4, 4, False)] * 3, 8, 8) is None


def test_rotation_is_taken_into_account() -> None:
    # two 8 x 3 bars in 8 x 8 (fit stacked); turnable or not, never rejected
    for r in (False, True):
        assert pb.infeasibility_reason([(8, 3, r)] * 2, 8, 8) is None
    # 3 x 8 bars that cannot turn in a 10 x 6 tray do not fit at all; turnable ones do
    assert pb.infeasibility_reason([(3, 8, False)], 10, 6) == "part larger than tray"
    assert pb.infeasibility_reason([(3, 8, True)] * 2, 10, 6) is None


def test_dff_catches_what_area_misses() -> None:
    """Five 4 x 4 squares on 10 x 10 (area 80 <= 100, no pair in conflict): Fekete-Schepers
    u^(2) counts each 4 as half the side, so each square as a quarter of the tray: 5/4 > 1."""
    sizes = [(4, 4, False)] * 5
    assert not pb.tall_parts_too_wide(sizes, 10, 10)
    assert not pb.incompatible_pair(sizes, 10, 10)
    assert pb.infeasibility_reason(sizes, 10, 10) == "dual-feasible function bound"
    assert pb.infeasibility_reason(sizes[:4], 10, 10) is None


def test_the_dff_cut_is_the_proof_as_an_inequality_over_part_counts() -> None:
    """``dff_cut`` (the LNS windows' learned inequality): a row exactly when a pair of
    dual-feasible functions proves the multiset misfit; the multiset breaks it, and no
    multiset that fits on the grid (brute force) does."""
    rng = random.Random(11)
    rows = found = 0
    for _ in range(300):
        W, H = rng.randint(3, 6), rng.randint(3, 6)
        types = {
            f"t{k}": (rng.randint(1, W), rng.randint(1, H), rng.random() < 0.5) for k in range(3)
        }
        counts = {t: rng.randint(0, 3) for t in types}
        sizes = [types[t] for t, n in counts.items() for _ in range(n)]
        row = pb.dff_cut(types, counts, W, H)
        assert (row is not None) == pb.dff_violated(sizes, W, H)
        if row is None:
            continue
        coef, cap = row
        found += 1
        assert sum(coef[t] * n for t, n in counts.items()) > cap
        for _ in range(10):  # sub-multisets that fit satisfy it
            sub = {t: rng.randint(0, n) for t, n in counts.items()}
            subsizes = [types[t] for t, n in sub.items() for _ in range(n)]
            if len(subsizes) <= 5 and fits_on_grid(subsizes, W, H):
                assert sum(coef[t] * n for t, n in sub.items()) <= cap
                rows += 1
    assert found > 30 and rows > 30
