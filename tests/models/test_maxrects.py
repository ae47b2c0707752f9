"""The maximal-rectangles packer, the packing oracle's fast "yes" before CP-SAT: every layout
it returns is valid on the grid, it finds layouts where the shelf packer and a short CP-SAT
limit do not, and the oracle uses it."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bilevel_kit import geometry
from bilevel_kit.instance import load
from bilevel_kit.models import maxrects as mr
from bilevel_kit.models import packing as pk

ROOT = Path(__file__).resolve().parents[2]
KITBENCH = ROOT / "instances" / "kitbench"
BENCH_DATA = ROOT / "bench" / "data"
sys.path.insert(0, str(ROOT / "bench"))
from bench_packing import load as load_packing  # noqa: E402
from bench_packing import valid  # noqa: E402


def _kit_items(inst, counts):
    """A kit's parts as (part id, part type) pairs, as :func:`bilevel_kit.models.packing.pack`
    takes them."""
    return [(f"{k}{j}", inst.part_types[k]) for k, n in counts.items() for j in range(n)]


sizes_st = st.lists(
    st.tuples(st.integers(1, 12), st.integers(1, 12), st.booleans()), min_size=0, max_size=9
)


@settings(max_examples=300, deadline=None)
@given(sizes=sizes_st, width=st.integers(1, 30), height=st.integers(1, 30))
def test_every_layout_is_valid(sizes, width, height):
    out = mr.maxrects_pack(sizes, width, height)
    if out is not None:
        assert len(out) == len(sizes)
        assert valid(width, height, sizes, out)
    if sum(w * h for w, h, _ in sizes) > width * height:
        assert out is None


def test_the_transposed_tray_turns_back():
    """Only the attempts on the transposed tray lay these out; the layout comes back in the
    tray's own axes, the part that may not rotate unturned."""
    sizes = [(9, 8, True), (9, 4, True), (8, 5, True), (8, 9, True), (9, 6, True), (7, 8, False)]
    direct = [
        mr._pack(sizes, 19, 18, sorted(range(6), key=lambda j: key(sizes[j])), rule)
        for key in mr.ORDERS.values()
        for rule in mr.RULES.values()
    ]
    assert direct == [None] * len(direct)
    out = mr.maxrects_pack(sizes, 19, 18)
    assert out is not None and valid(19, 18, sizes, out)
    assert out[5][2] is False


def test_a_kit_cpsat_left_undecided_is_laid_out_before_the_model():
    """A kit of 45 parts (86 % of the tray) of `sparse_n50_s1_tu_loose_d0` that a 60 s `cpsat`
    run left undecided at a 0.2 s packing limit, and that the shelf packer does not lay out:
    `pack` answers with the maximal-rectangles layout, valid at the true sizes, without a
    model."""
    inst = load(KITBENCH / "sparse_n50_s1_tu_loose_d0.json")
    counts = {"p0": 13, "p1": 11, "p2": 7, "p3": 3, "p4": 9, "p5": 2}
    items = _kit_items(inst, counts)
    grid = pk._grid(inst.tray, items, 1.0, None)
    assert pk._shelf(grid.sizes, grid.W, grid.H) is None
    res = pk.pack(inst.tray, items, time_limit=0.2)
    assert res.status == "feasible"
    assert res.extra["reason"] == "maxrects heuristic"
    assert "cpsat_status" not in res.extra
    assert sorted(p.part for p in res.layout) == sorted(pid for pid, _ in items)
    polys = [geometry.corners(p.x, p.y, p.w, p.h, p.theta) for p in res.layout]
    assert all(geometry.inside_tray(c, inst.tray.width, inst.tray.height) for c in polys)
    assert not any(geometry.rects_overlap(a, b) for i, a in enumerate(polys) for b in polys[:i])


def test_no_layout_is_no_answer():
    """Two 6 x 6 squares in 10 x 10: area allows them, no layout exists; the packer says None
    (not a proof: `pack` proves it with its pre-search tests or CP-SAT)."""
    assert mr.maxrects_pack([(6, 6, True)] * 2, 10, 10) is None
    assert mr.maxrects_pack([], 3, 3) == []


@pytest.mark.parametrize("rule", list(mr.RULES))
def test_each_rule_fills_a_tray_exactly(rule):
    """Four 5 x 5 squares fill 10 x 10 with every rule and order."""
    sizes = [(5, 5, False)] * 4
    for key in mr.ORDERS.values():
        order = sorted(range(4), key=lambda j: key(sizes[j]))
        out = mr._pack(sizes, 10, 10, order, mr.RULES[rule])
        assert out is not None and sorted(out) == [
            (0, 0, False),
            (0, 5, False),
            (5, 0, False),
            (5, 5, False),
        ]


def _kit_sizes(inst, counts):
    grid = pk._grid(inst.tray, _kit_items(inst, counts), 1.0, None)
    return grid.sizes, grid.W, grid.H


def test_the_kits_cpsat_left_undecided():
    """docs/formulations.md, "CP-SAT packing": of the kits a 60 s `cpsat` run left undecided
    (bench/data/oracle_undecided.json), the packer lays out 46 of 60 on
    `sparse_n50_s1_tu_loose_d0` and 10 of 34 on `sp_n50_s2_t1_tight_d30`, the shelf packer
    none; none of the 9 kits with a 0/90-degree proof of no fit (it must not)."""
    doc = json.loads((BENCH_DATA / "oracle_undecided.json").read_text())
    counts = {}
    for name, kinds in doc["records"].items():
        inst = load(KITBENCH / f"{name}.json")
        for kind, kits in kinds.items():
            laid = shelf = 0
            for kit in kits:
                sizes, width, height = _kit_sizes(inst, kit)
                out = mr.maxrects_pack(sizes, width, height)
                laid += out is not None and valid(width, height, sizes, out)
                shelf += pk._shelf(sizes, width, height) is not None
            counts[name, kind] = (len(kits), laid, shelf)
    assert counts == {
        ("sparse_n50_s1_tu_loose_d0", "unknown"): (60, 46, 0),
        ("sparse_n50_s1_tu_loose_d0", "nofit_axis_aligned"): (0, 0, 0),
        ("sp_n50_s2_t1_tight_d30", "unknown"): (34, 10, 0),
        ("sp_n50_s2_t1_tight_d30", "nofit_axis_aligned"): (9, 0, 0),
    }


def test_the_packing_benchmark_instances_it_lays_out():
    """docs/formulations.md, "CP-SAT packing": of the packing benchmark's 62 instances it lays
    out 10, all but `K_in1_2` ones the shelf packer does not."""
    laid, shelf = [], []
    paths = sorted((BENCH_DATA / "packing").glob("*/*.json"))
    for path in paths:
        width, height, sizes = load_packing(path)
        out = mr.maxrects_pack(sizes, width, height)
        if out is not None:
            assert valid(width, height, sizes, out)
            laid.append(path.stem)
            if pk._shelf(sizes, width, height) is not None:
                shelf.append(path.stem)
    assert len(paths) == 62
    assert laid == [
        "E02F22",
        "E04F17",
        "E05F20",
        "E07F15",
        "E20X15",
        "K_in1_2",
        "K_in2_0",
        "K_in4_0",
        "K_in4_2",
        "K_se3_2",
    ]
    assert shelf == ["K_in1_2"]


def test_large_kits_get_fewer_attempts(monkeypatch):
    """All 48 attempts up to 30 parts, then fewer (the work per attempt grows with the parts
    squared), at least 4: a kit of 100 parts that no attempt lays out costs 4 attempts."""
    assert [mr.attempts(n) for n in (1, 30, 31, 50, 100, 1000)] == [48, 48, 44, 17, 4, 4]
    calls = []
    real = mr._pack

    def counted(*args):
        calls.append(args[1:3])
        return real(*args)

    monkeypatch.setattr(mr, "_pack", counted)
    assert mr.maxrects_pack([(6, 6, True)] * 2, 10, 10) is None
    assert len(calls) == 48
    calls.clear()
    assert mr.maxrects_pack([(11, 9, True)] * 100, 100, 100) is None  # (99 in a grid)
    assert len(calls) == 4
    assert calls[1] == (100, 100)  # the transposed tray second
