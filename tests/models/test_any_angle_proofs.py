"""Any-angle proofs that a kit does not fit: one rectangle in a box at any angle (Carver's
condition) against a dense scan of angles and its own witness angle; the band rule never
rejects a kit with a layout the checker accepts (band parts axis-aligned, the others shelf
packed or along the diagonal of what is left), and rejects the stool-seat kits of KitBench
at any angle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bilevel_kit.geometry import TOL, layout_violations
from bilevel_kit.instance import PartType, Tray
from bilevel_kit.models import packing_oracle
from bilevel_kit.models.packing import ANY_ANGLE, AXIS_ALIGNED, _true_size_scope
from bilevel_kit.models.packing_bounds import band_blocks, fits_at_some_angle
from bilevel_kit.plan import Placement

ANGLES = np.linspace(0.0, math.pi / 2, 20_001)


def _scan(p: float, q: float, A: float, B: float, slack: float) -> bool:
    """Some scanned angle t has extents p|cos t| + q|sin t| <= A + slack and
    p|sin t| + q|cos t| <= B + slack ([0, 90] degrees covers every angle by symmetry)."""
    c, s = np.cos(ANGLES), np.sin(ANGLES)
    return bool(((p * c + q * s <= A + slack) & (p * s + q * c <= B + slack)).any())


def _carver_y(p: float, q: float, A: float) -> float:
    """The y extent of a p x q part (p > A) turned until its x extent is A."""
    return (2 * p * q * A + (p * p - q * q) * math.sqrt(p * p + q * q - A * A)) / (p * p + q * q)


def _witness(p: float, q: float, A: float) -> float:
    """That turn t1 (radians): p cos t1 + q sin t1 = A, p sin t1 - q cos t1 = sqrt(...)."""
    k = math.sqrt(p * p + q * q - A * A)
    return math.atan2(q * A + p * k, p * A - q * k)


def _cases(n: int, seed: int) -> list[tuple[float, float, float, float]]:
    """Random parts and boxes: a third on Carver's boundary (B within 1e-4 of the extent at
    the witness turn, either side), some that fit along the diagonal only, some exactly as
    long as the box."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        A, B = sorted(rng.uniform(10.0, 200.0, 2), reverse=True)
        q = float(rng.uniform(0.02, 1.0) * B)
        p = float(rng.uniform(max(q, 0.8 * A), 1.1 * math.hypot(A, B)))
        if i % 3 == 0 and p > A:
            B = max(q, _carver_y(p, q, A) * (1 + rng.choice([-1e-4, 1e-4])))
        elif i % 3 == 2 and p > A and max(q, _carver_y(p, q, A)) < A:
            B = float(rng.uniform(max(q, _carver_y(p, q, A)), A))  # along the diagonal only
        elif i % 7 == 1:
            p = max(p, q) if p <= A else float(A)
        out.append((max(p, q), min(p, q), float(A), float(B)))
    return out


@pytest.mark.parametrize("seed", range(3))
def test_carver_agrees_with_a_dense_scan(seed: int) -> None:
    """A scanned angle that fits (exactly) is never a "no"; a "fits" has a scanned angle
    within the scan's step (the extents move by at most hypot(p, q) per radian)."""
    step = ANGLES[1] - ANGLES[0]
    n_no = n_yes = 0
    for p, q, A, B in _cases(200, seed):
        says = fits_at_some_angle(p, q, A, B)
        assert says == fits_at_some_angle(q, p, B, A)  # argument order does not matter
        if _scan(p, q, A, B, 0.0):
            assert says, (p, q, A, B)
        if says:
            n_yes += 1
            assert _scan(p, q, A, B, math.hypot(p, q) * step), (p, q, A, B)
        else:
            n_no += 1
    assert n_yes > 40 and n_no > 40


@pytest.mark.parametrize("seed", range(3))
def test_carver_fits_at_its_witness_turn(seed: int) -> None:
    """Every diagonal "fits" is constructive: the part at the witness turn lies in the box;
    a "no" near the boundary has no fitting angle on a fine scan around that turn."""
    n = 0
    for p, q, A0, B0 in _cases(200, seed):
        A, B = max(A0, B0), min(A0, B0)
        if p <= A or q > B:
            continue
        t = _witness(p, q, A)
        x_ext = p * math.cos(t) + q * math.sin(t)
        y_ext = p * math.sin(t) + q * math.cos(t)
        if fits_at_some_angle(p, q, A, B):
            n += 1
            assert x_ext <= A * (1 + 1e-9) and y_ext <= B * (1 + 1e-9), (p, q, A, B)
        else:
            local = np.linspace(max(0.0, t - 1e-2), min(math.pi / 2, t + 1e-2), 20_001)
            c, s = np.cos(local), np.sin(local)
            assert not ((p * c + q * s <= A) & (p * s + q * c <= B)).any(), (p, q, A, B)
    assert n > 30


def test_carver_exact_fits_and_textbook_cases() -> None:
    assert fits_at_some_angle(120.0, 120.0, 160.0, 120.0)  # exactly as wide as the box
    assert fits_at_some_angle(40.0, 120.0, 40.0, 120.0)
    assert not fits_at_some_angle(10.0, 10.0, 8.0, 8.0)  # q > B, though the fraction is 8
    assert not fits_at_some_angle(41.0, 41.0, 40.0, 120.0)
    assert not fits_at_some_angle(152.4, 12.7, 40.0, 120.0)
    assert fits_at_some_angle(152.4, 12.7, 140.0, 120.0)  # along the diagonal only
    p, q, A = 152.4, 12.7, 140.0
    assert fits_at_some_angle(p, q, A, _carver_y(p, q, A))  # on the boundary: fits


# ---------------------------------------------------------------------------------------------
# the band rule
# ---------------------------------------------------------------------------------------------


def _diagonal(w: float, S: float, rng: np.random.Generator) -> tuple[float, float, float]:
    """A part (p, q, turn in degrees) that lies in a w x S strip only just: p is the longest
    that fits with q (bisection on Carver's condition), less 1e-7 relative."""
    q = float(rng.uniform(0.05, 0.5) * min(w, S))
    lo, hi = max(w, S), math.hypot(w, S)
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if fits_at_some_angle(mid, q, w, S) else (lo, mid)
    p = lo * (1 - 1e-7)
    A = max(w, S)
    turn = 0.0 if p <= A else math.degrees(_witness(p, q, A))
    return p, q, turn if w >= S else 90.0 - turn


def _shelves(x0: float, w: float, S: float, rng: np.random.Generator) -> list[Placement]:
    """Rows of axis-aligned parts filling a w x S strip from x0; the last part of each row
    ends exactly at the strip's edge, the last row exactly at the top."""
    out: list[Placement] = []
    y = 0.0
    while y < S:
        h = S - y if rng.random() < 0.3 else float(min(S - y, rng.uniform(0.1, 0.6) * S))
        x = 0.0
        while x < w:
            pw = w - x if rng.random() < 0.4 else float(min(w - x, rng.uniform(0.1, 0.7) * w))
            out.append(Placement("", "", x0 + x + pw / 2, y + h / 2, 0.0, pw, h))
            x += pw
        y += h
    return out


def _band_layout(rng: np.random.Generator) -> tuple[float, float, list[Placement]]:
    """A tray and a valid layout with one or two band parts (smaller side = the tray's smaller
    side S) and the rest packed into the strips left and right of them; transposed half the
    time."""
    S = float(rng.choice([rng.uniform(20.0, 200.0), rng.integers(20, 200)]))
    k = int(rng.integers(1, 3))
    lengths = [S if rng.random() < 0.4 else float(S + rng.uniform(0.0, S)) for _ in range(k)]
    room = 0.0 if rng.random() < 0.15 else float(rng.uniform(0.5, 1.5) * S)
    w1 = room * float(rng.choice([0.0, rng.uniform(0.2, 0.8), 1.0]))
    w2 = room - w1
    L = w1 + sum(lengths) + w2
    layout: list[Placement] = []
    x = w1
    for a in lengths:
        layout.append(Placement("", "", x + a / 2, S / 2, float(rng.choice([0.0, 180.0])), a, S))
        x += a
    for x0, w in ((0.0, w1), (L - w2, w2)):
        if w <= 0:
            continue
        if rng.random() < 0.5:
            p, q, turn = _diagonal(w, S, rng)
            layout.append(Placement("", "", x0 + w / 2, S / 2, turn, p, q))
        else:
            layout += _shelves(x0, w, S, rng)
    if rng.random() < 0.5:  # the tray taller than wide
        layout = [Placement("", "", c.y, c.x, 90.0 - c.theta, c.w, c.h) for c in layout]
        return S, L, layout
    return L, S, layout


@pytest.mark.parametrize("seed", range(4))
def test_band_rule_never_rejects_a_valid_layout(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    for _ in range(100):
        W, H, layout = _band_layout(rng)
        assert layout_violations(layout, W, H) == []  # the construction is valid
        sizes = [(c.w, c.h) for c in layout]
        assert not band_blocks(sizes, W, H, TOL), (W, H, layout)
        items = [
            (str(i), PartType(id=f"t{i}", width=w, height=h, pick_time=1.0, rotatable=True))
            for i, (w, h) in enumerate(sizes)
        ]
        assert _true_size_scope(Tray(W, H), items) != ANY_ANGLE, (W, H, layout)


def _stool(**counts: int) -> packing_oracle.Fit:
    """A kit of mixed_u2_tu_tight_d0's parts on its 160 x 120 tray."""
    types = {
        pid: PartType(id=pid, width=w, height=h, pick_time=1.0, rotatable=True)
        for pid, w, h in (
            ("seat", 120.0, 120.0),
            ("connector", 41.0, 41.0),
            ("leg", 152.4, 12.7),
            ("foot", 43.0, 43.0),
            ("screw_long", 14.0, 6.0),
            ("screw_short", 8.0, 6.0),
            ("block", 40.0, 40.0),
            ("slat", 120.0, 40.0),
        )
    }
    return packing_oracle.fit_verdict(Tray(160.0, 120.0), types, counts, time_limit=5.0)


@pytest.mark.parametrize("other", ["connector", "leg", "foot"])
def test_stool_seat_kits_do_not_fit_at_any_angle(other: str) -> None:
    """The seat spans the tray's 120 mm: the others have 40 mm x 120 mm left, where a 41 mm
    or 43 mm square or a 152.4 mm leg lies at no angle."""
    fit = _stool(seat=1, screw_long=2, screw_short=2, **{other: 1})
    assert (fit.fits, fit.scope) == (False, ANY_ANGLE), fit
    sizes = [(120.0, 120.0), (41.0, 41.0) if other == "connector" else (43.0, 43.0)]
    if other == "leg":
        sizes[1] = (152.4, 12.7)
    assert band_blocks([*sizes, (14.0, 6.0), (8.0, 6.0)], 160.0, 120.0, TOL)
    assert band_blocks([(w, h) for h, w in sizes], 120.0, 160.0, TOL)  # transposed


def test_stool_seat_with_what_fits_beside_it() -> None:
    """A 40 mm square and a 40 x 120 slat fill the strip exactly: they fit."""
    assert _stool(seat=1, block=1).fits
    assert _stool(seat=1, slat=1).fits
    assert not band_blocks([(120.0, 120.0), (120.0, 40.0)], 160.0, 120.0, TOL)


def test_one_part_fits_at_no_angle_or_only_along_the_diagonal() -> None:
    """A 152.4 x 12.7 leg fits neither a 150 x 20 tray at any angle nor a 150 x 60 tray at 0/90
    degrees, but that one along its diagonal."""
    leg = {"leg": PartType(id="leg", width=152.4, height=12.7, pick_time=1.0, rotatable=True)}
    no = packing_oracle.fit_verdict(Tray(150.0, 20.0), leg, {"leg": 1}, time_limit=5.0)
    assert (no.fits, no.scope) == (False, ANY_ANGLE)
    tilted = packing_oracle.fit_verdict(Tray(150.0, 60.0), leg, {"leg": 1}, time_limit=5.0)
    assert (tilted.fits, tilted.scope) == (False, AXIS_ALIGNED)


def test_what_the_checker_tolerance_allows_is_not_ruled_out() -> None:
    """The checker lets parts cross each other and the tray edge by up to TOL: a seat and a
    part 2.5e-6 mm wider than the 40 mm left, or one part 1.5e-6 mm longer than the tray, are
    valid layouts, so no any-angle proof may rule them out (the parts leave area to spare)."""
    d = 0.9 * TOL
    seat = Placement("a", "seat", 60.0 - d, 60.0, 0.0, 120.0, 120.0)
    w, h = 40.0 + 2.5 * TOL, 100.0
    strip = Placement("b", "strip", 120.0 - 2 * d + w / 2, 60.0, 0.0, w, h)
    long_ = Placement("c", "long", 80.0, 60.0, 0.0, 160.0 + 1.5 * TOL, 100.0)
    for layout in ([seat, strip], [long_]):
        assert layout_violations(layout, 160.0, 120.0) == []
        items = [
            (c.part, PartType(id=c.type, width=c.w, height=c.h, pick_time=1.0, rotatable=True))
            for c in layout
        ]
        assert _true_size_scope(Tray(160.0, 120.0), items) != ANY_ANGLE, layout


def test_a_layout_using_every_tolerance_of_the_checker_is_not_ruled_out() -> None:
    """Two parts TOL larger than the strip they share, overlapping by 0.9 TOL and crossing
    both tray edges: ``check`` accepts the plan, though their area exceeds
    (W + TOL)(H + TOL), so no any-angle proof may rule the kit out (``exact_world``)."""
    from bilevel_kit import InstanceBuilder, Kit, Plan, check

    b = InstanceBuilder("tol", tray=(160.0, 120.0), delivery_time=1.0, kit_overhead=(1.0, 1.0))
    b.part_type("seat", 120.0 + TOL, 120.0 + TOL, pick_time=1.0)
    b.part_type("strip", 40.0 + TOL, 120.0 + TOL, pick_time=1.0)
    instance = b.task("t", {"seat": 1, "strip": 1}, human_time=10.0).build()
    types = dict(instance.part_types)
    seat, strip = types["seat"], types["strip"]
    x0 = -0.55 * TOL  # the row spans 160 + 1.1 TOL: 0.55 TOL past each edge
    x1 = x0 + seat.width - 0.9 * TOL
    layout = (
        Placement("t/seat/0", "seat", x0 + seat.width / 2, 60.0, 0.0, seat.width, seat.height),
        Placement("t/strip/0", "strip", x1 + strip.width / 2, 60.0, 0.0, strip.width, strip.height),
    )
    assert [v.kind for v in check(instance, Plan((Kit(("t",), layout),)))] == []
    assert seat.area + strip.area > (160.0 + TOL) * (120.0 + TOL)  # the area filter says "no"
    items = [(p.part, types[p.type]) for p in layout]
    assert _true_size_scope(Tray(160.0, 120.0), items) is None
    fit = packing_oracle.fit_verdict(
        Tray(160.0, 120.0), types, {"seat": 1, "strip": 1}, time_limit=5.0
    )
    assert fit.scope != ANY_ANGLE, fit
