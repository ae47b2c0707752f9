"""Time limits end to end: every registered method (and ``bilevel-kit pack``) returns within
``T + max(2 s, 5 %)`` on an instance that needs the whole budget, with an honest status (a
valid bound never above the objective) and a plan the independent checker accepts."""

from __future__ import annotations

import json
import time

import pytest
from packs import perfect_packing
from timing import allowed

from bilevel_kit import check, solve
from bilevel_kit.generate import generate
from bilevel_kit.instance import from_dict
from bilevel_kit.methods import REGISTRY, Status

pytest.importorskip("ortools")
T = 4.0


@pytest.fixture(scope="module", autouse=True)
def compiled_kernels(table):
    """numba compiles the CE kernels on their first call after an install (about 15 s, which
    the CLI announces and docs/scaling.md states), and the prefix search's kernels on the
    first instance wide enough to use them (the in-tree below, not the table); compile them
    once here, so that the limits below measure the solves, not the compiler."""
    solve(table, "greedy-ce")
    solve(from_dict(generate("intree", 60, seed=1)), "greedy-ce")


#: The instance per method: an in-tree of 60 tasks, except the MILP (20: it builds its model
#: within the budget and then needs all of it) and bilevel-milp (the paper's table: its column
#: MILP needs minutes there; it refuses more than 16 tasks).
DOCS = {"milp": ("intree", 20), "bilevel-milp": ("table", 1)}


@pytest.mark.slow
@pytest.mark.parametrize("method", list(REGISTRY))
def test_method_honours_its_time_limit(method):
    family, size = DOCS.get(method, ("intree", 60))
    inst = from_dict(generate(family, size, seed=1))
    t0 = time.perf_counter()
    res = solve(inst, method, time_limit=T, seed=0)
    wall = time.perf_counter() - t0
    assert wall <= allowed(T), f"{method}: {wall:.2f} s for a {T} s limit"
    assert res.status in (Status.OPTIMAL, Status.FEASIBLE, Status.UNKNOWN)
    assert res.makespan_bound is not None  # every method's, whatever it minimised
    if res.plan is None:  # bilevel-milp on the table: no incumbent within 4 s
        assert res.status == Status.UNKNOWN
        return
    assert check(inst, res.plan) == []
    assert res.makespan_bound <= res.makespan + 1e-6


@pytest.mark.slow
def test_cpsat_warm_start_gets_a_share_of_the_budget():
    """The greedy-ce warm start alone used to run ~30 s on this instance (issue 13)."""
    inst = from_dict(generate("intree", 30, seed=1))
    res = solve(inst, "cpsat", time_limit=T)
    assert res.wall_time_s <= allowed(T)
    # greedy-ce gets 30 % of T as its own limit, which it may overrun by about a second
    assert res.extra["hint_time_s"] < T
    assert check(inst, res.plan) == []


def test_a_model_over_the_memory_limit_returns_its_incumbent_unbuilt(monkeypatch):
    """Over the memory limit the model is not built; the incumbent (here the quick plan: no
    warm start) is returned as feasible with the proven bound and the reason."""
    from bilevel_kit.models import budget

    monkeypatch.setattr(budget, "MEMORY_LIMIT", budget.BASE_MEMORY + 1000)
    inst = from_dict(generate("intree", 12, seed=1))
    for method in ("cpsat", "milp"):
        opts = {"hint": "none"}
        res = solve(inst, method, time_limit=5.0, **opts)
        assert res.plan is not None and check(inst, res.plan) == []
        assert res.bound is not None and res.bound <= res.objective + 1e-6
        if res.status != Status.OPTIMAL:  # unless the quick plan meets the proven bound
            assert res.status == Status.FEASIBLE
            assert "task x kit variables" in res.extra["reason"]
            assert "memory limit" in res.extra["reason"]


def test_the_cli_returns_the_incumbent_naming_the_size(tmp_path, monkeypatch, capsys):
    """1,000 tasks without overheads or delivery time, so no kit cap: the CP-SAT model
    (~10^6 task x kit variables) is over the memory limit and never built; the quick plan is
    returned as feasible (exit 0) with the reason. (The closed-form shortcut is switched off:
    on this human-bound in-tree the quick plan is already optimal.)"""
    from bilevel_kit.cli import main
    from bilevel_kit.models.cpsat import method

    monkeypatch.setattr(method, "johnson_plan", lambda *a, **k: method.Johnson(None, False))
    doc = generate("intree", 1000, seed=0)
    doc.update(delivery_time=0.0, kit_overhead={"robot": 0.0, "human": 0.0})
    path = tmp_path / "big.json"
    path.write_text(json.dumps(doc))
    out_path = tmp_path / "res.json"
    args = ["solve", str(path), "-m", "cpsat", "--time-limit", "20", "-p", "hint=none"]
    code = main([*args, "--out", str(out_path)])
    err = capsys.readouterr().err
    assert code == 0, err
    res = json.loads(out_path.read_text())
    text = json.dumps(res)
    assert "memory limit" in text and "task x kit variables" in text


@pytest.mark.slow
def test_pack_honours_its_time_limit(tmp_path, capsys):
    from bilevel_kit.cli import main

    path = tmp_path / "perfect.json"
    path.write_text(json.dumps(perfect_packing(1)))
    t0 = time.perf_counter()
    code = main(["pack", str(path), "--time-limit", "3", "--out", str(tmp_path / "lay.json")])
    wall = time.perf_counter() - t0
    assert wall <= allowed(3.0), f"pack: {wall:.2f} s for a 3 s limit"
    doc = json.loads((tmp_path / "lay.json").read_text())
    assert (code, doc["status"]) in ((0, "feasible"), (3, "unknown"))  # never "infeasible"
