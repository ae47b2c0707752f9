"""Quarter-turn snapping of cross-entropy layouts (option ``snap`` of greedy-ce,
bilevel_kit/heuristics/ce/snap.py): a turn is kept only when the layout stays valid and its
fitness does not drop."""

from __future__ import annotations

import numpy as np
import pytest
from test_cross_entropy import TABLE, TABLE_PARTS, make

from bilevel_kit import check, geometry, solve
from bilevel_kit.heuristics.ce.accept import assess, exactly_valid
from bilevel_kit.heuristics.ce.kit import build_kit
from bilevel_kit.heuristics.ce.snap import off_quarter, quarter_turn, snap, unsnapped
from bilevel_kit.heuristics.cross_entropy import CEParams, arrange
from bilevel_kit.heuristics.greedy_ce import GreedyCEOptions


@pytest.mark.parametrize(
    ("theta", "turn", "off"),
    [(-88.36, 90.0, 1.64), (2.18, 0.0, 2.18), (-7.32, 0.0, 7.32), (89.9, 90.0, 0.1), (0, 0, 0)],
)
def test_quarter_turn(theta, turn, off):
    assert quarter_turn(theta) == turn
    assert off_quarter(theta) == pytest.approx(off)


@pytest.mark.parametrize("seed", range(4))
def test_snap_keeps_fitness_and_validity_on_the_table_kit(seed):
    plain = arrange(TABLE, TABLE_PARTS, rng=seed)
    snapped = arrange(TABLE, TABLE_PARTS, rng=seed, params=CEParams(snap=True))
    assert plain.fits and snapped.fits
    assert snapped.fitness >= plain.fitness - 1e-9 * abs(plain.fitness)
    assert geometry.exactly_valid(snapped.layout, TABLE.tray.width, TABLE.tray.height)
    off_plain = sum(off_quarter(p.theta) > 1e-9 for p in plain.layout)
    off_snapped = sum(off_quarter(p.theta) > 1e-9 for p in snapped.layout)
    assert off_snapped < off_plain and off_snapped <= 2  # 0 or 1 left over seeds 0..7
    assert snapped.source.endswith("+snap")
    # only angles change (and a centre only to stay inside the tray)
    for a, b in zip(plain.layout, snapped.layout, strict=True):
        assert a.part == b.part
        assert b.theta in (0.0, 90.0) or b.theta == a.theta


def test_a_turn_that_would_overlap_is_not_taken():
    inst = make(200, 100, [("bar", 150, 10, True), ("nut", 10, 10, True)])
    kit = build_kit(inst, {"bar": 1, "nut": 1}, np.float64)
    # the bar lies at 30 degrees; the nut sits where the straight bar would be
    x, y, theta = np.array([100.0, 150.0]), np.array([50.0, 50.0]), np.array([30.0, 2.0])
    cand = assess(kit, x, y, theta, 1.0, "ce")
    assert cand.valid
    out = snap(kit, cand, 1.0)
    assert out.theta[0] == 30.0  # turning the bar straight would hit the nut
    assert out.theta[1] == 0.0  # the nut turns freely
    assert out.fitness >= cand.fitness and out.source == "ce+snap"
    assert exactly_valid(kit.layout(out.x, out.y, out.theta), inst.tray)
    assert unsnapped(out.theta, kit.rot_idx) == 1


def test_invalid_candidates_are_left_alone():
    inst = make(200, 100, [("bar", 150, 10, True)])
    kit = build_kit(inst, {"bar": 2}, np.float64)
    x, y, theta = np.array([100.0, 100.0]), np.array([50.0, 50.0]), np.array([3.0, 3.0])
    cand = assess(kit, x, y, theta, 1.0, "ce")
    assert not cand.valid and snap(kit, cand, 1.0) is cand


def test_greedy_ce_snap_option_gives_checked_plans_with_straight_parts(table, stool):
    assert GreedyCEOptions().snap is False and CEParams().snap is False
    assert GreedyCEOptions(snap=True).ce_params().snap is True
    for inst in (table, stool):
        plain = solve(inst, "greedy-ce")
        snapped = solve(inst, "greedy-ce", snap=True)
        assert check(inst, snapped.plan) == []
        assert all(off_quarter(p.theta) == 0 for k in snapped.plan.kits for p in k.layout)
        assert any(off_quarter(p.theta) > 0 for k in plain.plan.kits for p in k.layout)
        fit_plain = {
            k.tasks: t["fitness"]
            for k, t in zip(plain.plan.kits, plain.extra["kit_terms"], strict=True)
        }
        for k, t in zip(snapped.plan.kits, snapped.extra["kit_terms"], strict=True):
            if k.tasks in fit_plain:
                assert t["fitness"] >= fit_plain[k.tasks] - 1e-9 * abs(fit_plain[k.tasks])
