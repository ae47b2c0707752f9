"""``bbr`` with several assembly stations (docs/formulations.md, "Branch, bound and remember";
issue 37 item 3): its transition against the evaluator and its lower bound against every
completion of every node of small instances, its optimum and claims against the brute force
(tests/brute.py's ``station_optima``) on two and three stations with 1, 2 and unlimited
trays, its bound at a stop by ``expansions``, determinism, its time limit and the refusal of
the objectives it does not minimise."""

from __future__ import annotations

import math
import time

import pytest
from brute import fits, station_optima
from test_bbr import brute_fits
from test_objectives_brute import instance_doc
from timing import PROOF_LIMIT, allowed

from bilevel_kit.instance import from_dict, load
from bilevel_kit.methods import solve
from bilevel_kit.models.bbr.search import search
from bilevel_kit.models.bbr.stations import StationSpace
from bilevel_kit.plan import Kit, Plan, evaluate

pytest.importorskip("ortools")


def case(seed: int, n_stations: int, trays: int | None):
    """6-8 tasks on ``n_stations`` stations; odd seeds have a fast robot and long human
    overheads (a one-tray station's kit waits for its tray), seeds 2 and 3 mod 4 a tray that
    holds two tasks at most (more kits, so the robot's order across stations matters)."""
    tray = "two" if seed % 4 in (2, 3) else "binding"
    doc = instance_doc(seed, n_stations, trays, n=6 + seed % 3, tray=tray, long_overhead=seed % 2)
    return from_dict(doc)


#: 4 seeds x {2, 3} stations x {1, 2, unlimited} trays: 24 brute-force cases
CASES = [(seed, s, trays) for seed in range(4) for s in (2, 3) for trays in (1, 2, None)]


@pytest.mark.parametrize(("seed", "n_stations", "trays"), CASES)
def test_bbr_equals_the_brute_force_on_stations(seed, n_stations, trays):
    inst = case(seed, n_stations, trays)
    opt = station_optima(inst)["makespan"]
    res = solve(inst, "bbr", time_limit=PROOF_LIMIT, check=True, start="quick")
    assert res.extra["violations"] == []
    assert res.extra["stop"] == "exhausted" and res.extra["bound_source"] == "bbr"
    assert res.makespan == pytest.approx(opt, abs=1e-6)
    # the brute force is the optimum over 0/90-degree plans (tests/brute.py): proven for
    # those always; for every plan unless a kit had a 0/90-degree proof only (relaxed)
    assert res.extra["optimal_axis_aligned"]
    assert res.extra["bound_axis_aligned"] == pytest.approx(opt, abs=1e-6)
    assert res.bound <= opt + 1e-6
    if res.status == "optimal":
        assert res.bound == pytest.approx(opt, abs=1e-6)
    else:
        assert res.status == "feasible" and res.extra["relaxed_kits"] > 0
    out = search(StationSpace(inst), brute_fits(inst))  # the brute force's own fit test
    assert out.exhausted and out.value == pytest.approx(opt, abs=1e-9)
    assert out.kits is not None and all(fits(inst, k) for k in out.kits)
    got = evaluate(inst, Plan(tuple(Kit(tuple(k)) for k in out.kits))).makespan
    assert got == pytest.approx(opt, abs=1e-9)


def _every_completion(sp: StationSpace, inst, done: int, state, kits: list) -> float:
    """The least makespan of a plan that completes the node (every kit that fits, no pruning),
    holding the bound below it at every node and the transition to the evaluator at every
    leaf."""
    if done == sp.full:
        plan = Plan(tuple(Kit(tuple(sp.order(m))) for m in kits))
        value = sp.lower_bound(done, state)
        assert value == pytest.approx(evaluate(inst, plan).makespan, abs=1e-9)
        return value
    best = math.inf
    for mask, r, h, s in sp.children(done, state, math.inf):
        if fits(inst, sp.order(mask)):
            child = sp.step(state, r, h, s)
            best = min(best, _every_completion(sp, inst, done | mask, child, [*kits, mask]))
    assert sp.lower_bound(done, state) <= best + 1e-9
    return best


@pytest.mark.parametrize(("seed", "n_stations", "trays"), [c for c in CASES if c[0] < 2])
def test_transition_and_bound_on_every_completion(seed, n_stations, trays):
    inst = case(seed, n_stations, trays)
    sp = StationSpace(inst)
    best = _every_completion(sp, inst, 0, sp.root(), [])
    assert best == pytest.approx(station_optima(inst, check=False)["makespan"], abs=1e-9)


@pytest.mark.parametrize(("seed", "n_stations", "trays"), [c for c in CASES if c[0] >= 2])
def test_bound_at_an_expansion_stop_is_below_the_optimum(seed, n_stations, trays):
    inst = case(seed, n_stations, trays)
    opt = station_optima(inst, check=False)["makespan"]
    bounds = []
    for k in (1, 2, 3, 5, 8):
        out = search(StationSpace(inst), brute_fits(inst), max_expansions=k)
        assert out.bound <= opt + 1e-9
        if out.stop == "expansions":
            assert not out.exhausted
        bounds.append(out.bound)
    assert bounds == sorted(bounds)  # best-first: the bound only rises with the work
    first = search(StationSpace(inst), brute_fits(inst), max_expansions=1)
    assert first.stop == "expansions" and first.bound < opt  # a stop before the proof
    res = solve(inst, "bbr", start="quick", expansions=1, check=True)  # the method's claims
    assert res.extra["violations"] == [] and res.extra["stop"] == "expansions"
    assert res.bound <= opt + 1e-6 <= res.makespan + 2e-6
    assert res.status == "feasible" or res.makespan == pytest.approx(opt, abs=1e-6)


def test_expansion_limit_is_deterministic_and_honest():
    from bilevel_kit.generate import generate

    inst = from_dict(generate("intree", 20, seed=0, stations=2))
    runs = [solve(inst, "bbr", start="quick", expansions=30, check=True) for _ in "ab"]
    a, b = runs
    assert a.extra["violations"] == [] and a.extra["stop"] == b.extra["stop"] == "expansions"
    assert a.extra["expanded"] == b.extra["expanded"] == 30
    assert [k.tasks for k in a.plan.kits] == [k.tasks for k in b.plan.kits]
    assert a.bound == b.bound and a.makespan == b.makespan
    assert a.status == "feasible" and a.bound < a.makespan


def test_time_limit_on_a_larger_stations_instance():
    from bilevel_kit.generate import generate

    inst = from_dict(generate("sparse", 60, seed=0, stations=3))
    t0 = time.perf_counter()
    res = solve(inst, "bbr", time_limit=6.0, check=True)
    assert time.perf_counter() - t0 <= allowed(6.0)
    assert res.extra["violations"] == []
    assert res.status == "feasible" and res.extra["stop"] == "time_limit"
    assert res.bound <= res.makespan


@pytest.mark.parametrize("objective", ["sum_completion", "human_idle"])
def test_other_objectives_are_refused_in_one_line(root, capsys, objective):
    from bilevel_kit.cli import main

    path = root / "instances" / "stations" / "table_u1_s2.json"
    args = ["solve", str(path), "-m", "bbr", "-p", f"objective={objective}"]
    assert main([*args, "--time-limit", "5"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert "method 'bbr': unknown option 'objective'" in err


def test_committed_station_instance_is_accepted(root):
    inst = load(root / "instances" / "stations" / "stool_u1_s3.json")
    res = solve(inst, "bbr", time_limit=PROOF_LIMIT, check=True, start="quick")
    assert res.extra["violations"] == []
    assert res.makespan == pytest.approx(213.0, abs=1e-6)  # the optimum (docs/timeline.md)
    assert res.status == "optimal" and res.bound == pytest.approx(213.0, abs=1e-6)
