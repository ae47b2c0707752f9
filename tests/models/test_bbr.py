"""Branch, bound and remember (``bbr``, docs/formulations.md): its state transition against the
independent reference timeline, its lower bound against every plan of small instances, its
optimum against the brute force with 1, 2 and unlimited trays, and the method's claims."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
from brute import best_makespan, fits, segmentations
from reference_timeline import reference
from strategies import random_doc
from timing import PROOF_LIMIT

from bilevel_kit.errors import UsageError
from bilevel_kit.instance import from_dict, load
from bilevel_kit.methods import solve
from bilevel_kit.models.bbr.search import search
from bilevel_kit.models.bbr.space import Space
from bilevel_kit.models.packing import ANY_ANGLE, AXIS_ALIGNED

pytest.importorskip("ortools")

INSTANCES = Path(__file__).resolve().parents[2] / "instances"

#: 12 seeds x {unlimited, 1, 2 trays} = 36 brute-force cases of 4-7 tasks; every third seed
#: makes its first task part-less (docs/timeline.md#part-less-tasks), odd seeds have a fast
#: robot (robot times of 0.5-2 s on every task), so that two trays bind
SEEDS = range(12)
TRAYS = (None, 1, 2)


def case(seed: int, trays: int | None, tray: tuple[float, float] | None = None):
    fast = seed % 2 == 1
    doc = random_doc(
        seed,
        4 + seed % 4,
        robot_share=1.0 if fast else 0.4,
        robot_halves=(1, 4) if fast else (1, 30),
    )
    if trays is not None:
        doc["trays"] = trays
    if tray is not None:  # a larger tray: more plans fit
        doc["tray"] = {"width": tray[0], "height": tray[1]}
    if seed % 3 == 0:
        doc["tasks"][0]["parts"] = []
        doc["tasks"][0].pop("robot_time", None)
    return from_dict(doc)


def brute_fits(inst):
    """The brute force's fit test (exact 0/90-degree packing on the 1 mm grid) on the part
    multiset the search asks about; a "no" stands for every layout here, as the brute force
    is the optimum over 0/90-degree plans."""

    def test(counts):
        ok = _pack(inst, counts)
        return ok, None if ok else ANY_ANGLE

    return test


def _pack(inst, counts) -> bool:
    from bilevel_kit.models import packing as pk

    if sum(inst.part_types[p].area * c for p, c in counts.items()) > inst.tray.area:
        return False
    items = [(f"{p}{j}", inst.part_types[p]) for p, c in counts.items() for j in range(c)]
    return pk.pack(inst.tray, items, time_limit=10.0).status == "feasible"


@pytest.mark.parametrize("trays", TRAYS)
@pytest.mark.parametrize("seed", SEEDS)
def test_search_equals_the_brute_force(seed, trays):
    inst = case(seed, trays)
    opt, _ = best_makespan(inst)
    out = search(Space(inst), brute_fits(inst))
    assert out.exhausted and out.stop == "exhausted"
    assert out.value == pytest.approx(opt, abs=1e-9)
    assert out.bound == pytest.approx(opt, abs=1e-9)
    assert out.kits is not None
    ref = reference(inst, out.kits)
    assert ref.makespan == pytest.approx(opt, abs=1e-9)
    assert all(fits(inst, k) for k in out.kits)


@pytest.mark.parametrize("trays", TRAYS)
@pytest.mark.parametrize("seed", SEEDS[:6])
def test_early_stop_bound_is_below_the_optimum(seed, trays):
    inst = case(seed, trays)
    opt, _ = best_makespan(inst)
    bounds = []
    for k in (1, 2, 3, 5):
        out = search(Space(inst), brute_fits(inst), max_expansions=k)
        assert out.bound <= opt + 1e-9
        bounds.append(out.bound)
    assert bounds == sorted(bounds)  # best-first: the bound only rises with the work


@pytest.mark.parametrize("trays", (None, 1, 2, 3))
@pytest.mark.parametrize("seed", range(6))
def test_transition_and_bound_on_every_plan(seed, trays):
    """For every plan whose kits fit (tests/brute.py) and each of its prefixes: the state the
    transition gives after the prefix ends the human's work where the reference timeline
    does, and the lower bound there is at most the plan's makespan (the bound holds for every
    completion)."""
    inst = case(seed, trays, tray=(200.0, 120.0))
    sp = Space(inst)
    pos = {t: i for i, t in enumerate(sp.ids)}
    seen = 0
    for kits in segmentations(inst):
        if not all(fits(inst, k) for k in kits):  # the bound speaks of plans that fit
            continue
        ref = reference(inst, kits)
        state, done = sp.root(), 0
        for k, kit in enumerate(kits):
            mask = sum(1 << pos[t] for t in kit)
            r = sum(sp.r[pos[t]] for t in kit)
            h = sum(sp.h[pos[t]] for t in kit)
            assert sp.lower_bound(done, state) <= ref.makespan + 1e-9
            state, done = sp.step(state, r, h), done | mask
            assert state[0] == pytest.approx(ref.kits[k].human_end, abs=1e-9)
        assert sp.lower_bound(done, state) == pytest.approx(ref.makespan, abs=1e-9)
        seen += 1
    assert seen >= 4  # every case has a few plans that fit the larger tray


def test_kits_are_every_down_set_extension_once():
    inst = case(7, None)  # 7 tasks with precedence
    sp = Space(inst)
    got = [m for m, *_ in sp.kits(0)]
    assert len(got) == len(set(got))
    for mask in got:
        ids = sp.order(mask)
        for a, b in inst.precedence:  # a kit of the first ideal holds its ancestors
            assert not (b in ids and a not in ids)
    # brute: every subset that is a down-set, fits the area and holds a task with parts
    area_cap = inst.tray.area
    want = set()
    for mask in range(1, 1 << sp.n):
        ids = set(sp.order(mask))
        if any(b in ids and a not in ids for a, b in inst.precedence):
            continue
        if sum(sp.area[i] for i in range(sp.n) if mask >> i & 1) > area_cap * (1 + 1e-12):
            continue
        if any(sp.needs[i] for i in range(sp.n) if mask >> i & 1):
            want.add(mask)
    assert set(got) == want


def test_method_on_the_table_is_optimal_and_checked():
    inst = load(INSTANCES / "hrc_table.json")
    res = solve(inst, "bbr", time_limit=PROOF_LIMIT, check=True, start="quick")
    assert res.status == "optimal"
    assert res.objective == pytest.approx(435.085, abs=1e-6)
    assert res.bound == pytest.approx(435.085, abs=1e-6)
    assert res.extra["violations"] == []
    assert res.extra["bound_source"] == "bbr"
    assert res.extra["stop"] == "exhausted"
    assert res.extra["proof_scope"] == ANY_ANGLE
    assert res.extra["expanded"] > 0


@pytest.mark.parametrize("seed", (1, 4, 5))
def test_method_claims_are_checked(seed):
    inst = case(seed, 1)
    opt, _ = best_makespan(inst)
    res = solve(inst, "bbr", time_limit=PROOF_LIMIT, check=True, start="quick")
    assert res.extra["violations"] == []
    assert res.makespan == pytest.approx(opt, abs=1e-9)
    assert res.status in ("optimal", "feasible")
    if res.status == "optimal":
        assert res.bound == pytest.approx(opt, abs=1e-9)
    assert res.bound <= opt + 1e-9


def test_expansion_limit_is_deterministic_and_honest():
    inst = load(INSTANCES / "kitbench" / "table_u5_t1_tight_d10.json")
    runs = [
        solve(inst, "bbr", time_limit=PROOF_LIMIT, start="quick", expansions=20) for _ in range(2)
    ]
    a, b = runs
    assert a.extra["stop"] == b.extra["stop"] == "expansions"
    assert a.extra["expanded"] == b.extra["expanded"] == 20
    assert a.bound == b.bound and a.makespan == b.makespan
    assert a.status == "feasible" and a.bound < a.makespan


def test_refusals():
    """Another objective is refused (several stations: tests/models/test_bbr_stations.py)."""
    inst = load(INSTANCES / "hrc_table.json")
    with pytest.raises(UsageError, match="objective"):
        solve(inst, "bbr", time_limit=5, objective="sum_completion")


# ---------------------------------------------------------------------------------------------
# the search before the model (option ``search`` of cpsat and milp)
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_search_first_proves_the_stool_record(method):
    """``stool_u17_t1_loose_d0`` (51 tasks, one tray) was 1.8 % open in KitBench: the search
    from the incumbent proves 1,008 s optimal, no model built."""
    inst = load(INSTANCES / "kitbench" / "stool_u17_t1_loose_d0.json")
    res = solve(inst, method, time_limit=PROOF_LIMIT, check=True, search=0.3)
    assert res.extra["violations"] == []
    assert res.status == "optimal"
    assert res.objective == pytest.approx(1008.0, abs=1e-6)
    assert res.bound == pytest.approx(1008.0, abs=1e-6)
    assert res.extra["bound_source"] == "bbr"
    info = res.extra["search_first"]
    assert info["stop"] == "exhausted" and info["proven"] and info["relaxed_kits"] == 0
    assert res.extra["solver_status"] == "proven_bound"


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_search_first_is_off_by_default_and_skipped_for_other_objectives(method):
    """Off unless asked; with stations another objective than the makespan skips it as with one
    station (no proof asked: a short limit; tests/models/test_search_first_stations.py)."""
    inst = case(2, 1)
    res = solve(inst, method, time_limit=PROOF_LIMIT)
    assert res.extra["search_first"] == {"skipped": "option search is 0"}
    stations = load(INSTANCES / "stations" / "table_u1_s2.json")
    res = solve(stations, method, time_limit=5, search=0.3, objective="sum_completion")
    assert res.extra["search_first"] == {"skipped": "the search minimises the makespan"}


@pytest.mark.parametrize("trays", TRAYS)
@pytest.mark.parametrize("seed", (2, 3, 7))
def test_search_first_equals_the_brute_force(seed, trays):
    inst = case(seed, trays)
    opt, _ = best_makespan(inst)
    res = solve(inst, "cpsat", time_limit=PROOF_LIMIT, check=True, search=0.5, workers=1)
    assert res.extra["violations"] == []
    assert res.makespan == pytest.approx(opt, abs=1e-6)
    assert res.bound <= opt + 1e-9
    info = res.extra.get("search_first")  # absent when a quick plan met a bound first
    if info is not None:
        assert "skipped" not in info
        assert info["bound"] <= opt + 1e-9
        if info["proven"]:
            assert res.status == "optimal" and res.extra["bound_source"] == "bbr"


def test_raised_bound_reaches_every_kit_count():
    from bilevel_kit.models.relax import closed_at, proven_bound, raised

    inst = load(INSTANCES / "hrc_table.json")
    before = proven_bound(inst, time_limit=1.0, lp=False)
    after = raised(before, before.value + 5.0, "bbr", inst)
    assert after.value == before.value + 5.0 and after.source == "bbr"
    assert after.sources["bbr"] == before.value + 5.0
    closed = closed_at(inst)
    for m in range(1, inst.n_tasks + 1):
        assert after.at(m, closed) >= before.value + 5.0
        assert after.at(m, closed) >= before.at(m, closed)
    lower = raised(before, before.value - 1.0, "bbr", inst)
    assert lower.value == before.value and lower.source == before.source


@pytest.mark.parametrize("trays", TRAYS)
@pytest.mark.parametrize("seed", SEEDS[:6])
def test_kits_without_a_proof_for_every_layout_are_relaxed(seed, trays):
    """Every "no" of the fit test here holds for 0/90-degree layouts only (as the CP-SAT
    packer's proofs): with ``relax`` (the default) such kits count for the bound, which is
    then the optimum over the plans whose kits fit by area (a valid bound, at most the true
    optimum), and no plan through one becomes the incumbent; without it they are dropped,
    the optimum is the brute force's and the proof's scope is 0/90 degrees."""
    inst = case(seed, trays)
    opt, _ = best_makespan(inst)
    exact = brute_fits(inst)

    def axis_only(counts):
        ok, _ = exact(counts)
        return (True, None) if ok else (False, AXIS_ALIGNED)

    by_area = search(Space(inst), lambda counts: (True, None))
    relaxed = search(Space(inst), axis_only)
    assert relaxed.bound == pytest.approx(by_area.value, abs=1e-9)
    assert relaxed.bound <= opt + 1e-9
    if relaxed.kits is not None:  # an incumbent is a plan whose kits all fit
        assert all(fits(inst, k) for k in relaxed.kits)
        assert relaxed.value >= opt - 1e-9
    if relaxed.exhausted:
        assert relaxed.value == pytest.approx(opt, abs=1e-9)
    given = search(Space(inst), axis_only, upper=opt)  # the optimum as the incumbent
    assert given.exhausted == (by_area.value >= opt - 1e-9)
    assert given.bound == pytest.approx(min(opt, by_area.value), abs=1e-9)
    strict = search(Space(inst), axis_only, relax=False)
    assert strict.value == pytest.approx(opt, abs=1e-9) and strict.exhausted
    no_at_all = relaxed.counters["relaxed_kits"] == 0
    assert strict.scope == (ANY_ANGLE if no_at_all else AXIS_ALIGNED)


def test_time_limit_and_honesty_at_250_tasks():
    """At 250 tasks one expansion enumerates far more kits than the limit allows: the clock
    is read inside it (every 64 kits), the plan is valid and the claims are checked."""
    from timing import allowed

    inst = load(INSTANCES / "kitbench" / "intree_n250_s1_tu_tight_d30.json")
    res = solve(inst, "bbr", time_limit=6.0, check=True)
    assert res.wall_time_s <= allowed(6.0)
    assert res.extra["violations"] == []
    assert res.status == "feasible" and res.extra["stop"] == "time_limit"
    assert res.bound <= res.makespan


# ---------------------------------------------------------------------------------------------
# option ``upper``: a makespan to prove (a known plan elsewhere)
# ---------------------------------------------------------------------------------------------


def test_given_upper_proves_what_it_can_and_claims_no_more():
    """Below the quick start's makespan Q, a given upper U is searched below as if a plan of U
    were held. With O the optimum the run without U proves (every layout): U at O, or under
    it, comes back as the bound with the start's plan, not ``optimal``; U between O and Q
    finds and proves O; U at Q is not used (the same result as without it). The cases are
    those the run without U proves optimal for every layout and starts above O."""
    checked = 0
    for seed in SEEDS:
        for trays in TRAYS:
            inst = case(seed, trays)
            plain = solve(inst, "bbr", time_limit=PROOF_LIMIT, start="quick")
            opt, start = plain.makespan, plain.extra["start_makespan"]
            if plain.status != "optimal" or start <= opt + 1e-6:
                continue  # a relaxed kit left open (a 0/90 proof only), or a start at O
            checked += 1
            for upper in (opt, opt - 1.0):
                res = solve(inst, "bbr", time_limit=PROOF_LIMIT, start="quick", upper=upper)
                assert res.status == "feasible" and res.extra["stop"] == "exhausted"
                assert res.bound == pytest.approx(upper, abs=1e-9)
                assert res.makespan == pytest.approx(start, abs=1e-9)
                assert res.extra["upper_given"] == upper
            res = solve(inst, "bbr", time_limit=PROOF_LIMIT, start="quick", upper=(opt + start) / 2)
            assert res.status == "optimal" and res.makespan == pytest.approx(opt, abs=1e-9)
            assert res.bound == pytest.approx(opt, abs=1e-9)
            res = solve(inst, "bbr", time_limit=PROOF_LIMIT, start="quick", upper=start)
            assert "upper_given" not in res.extra
            assert (res.status, res.makespan, res.bound) == (
                plain.status,
                plain.makespan,
                plain.bound,
            )
    assert checked == 14  # the cases where the quick start is not optimal (of 36)


def _prefix_states(inst, sp):
    """Every (ideal, state) after a prefix of a plan whose kits fit (the states the search
    may meet), each once."""
    pos = {t: i for i, t in enumerate(sp.ids)}
    seen = {}
    for kits in segmentations(inst):
        if not all(fits(inst, k) for k in kits):
            continue
        state, done = sp.root(), 0
        for kit in kits[:-1]:
            mask = sum(1 << pos[t] for t in kit)
            r = sum(sp.r[pos[t]] for t in kit)
            h = sum(sp.h[pos[t]] for t in kit)
            state, done = sp.step(state, r, h), done | mask
            seen[(done, state)] = None
    return list(seen)


@pytest.mark.parametrize("trays", (None, 1, 2))
@pytest.mark.parametrize("seed", range(8))
def test_kit_cut_drops_only_kits_the_bound_drops(seed, trays):
    """The kits a node generates under :meth:`Space.kit_cut` are every kit whose child's
    bound is below ``below`` (and no kit that is not one): the cut on robot time and area
    only saves the generation of children the bound test would drop."""
    inst = case(seed, trays, tray=(200.0, 120.0))
    sp = Space(inst)
    for done, state in _prefix_states(inst, sp):
        every = {m: (r, h) for m, r, h, _ in sp.kits(done)}
        for slack in (0.0, 0.5, 1.0, 3.0, 10.0):
            below = sp.lower_bound(done, state) + slack
            got = {m for m, *_ in sp.children(done, state, below)}
            assert got <= set(every)
            need = {
                m
                for m, (r, h) in every.items()
                if sp.lower_bound(done | m, sp.step(state, r, h)) < below
            }
            assert need <= got


def test_kit_cut_on_area_cuts_what_the_robot_cap_keeps():
    """A kit that leaves as many kits to the rest as its node had must fit one more o_H: on
    the node after the first kit {t45} of a KitBench record below its best-known 1350 s,
    where bbr generated over 200,000 children (all dropped by the bound), the robot cap alone
    keeps kits the cut on area leaves out, and every kit left out would fail the bound."""
    inst = load(INSTANCES / "kitbench" / "sparse_n50_s1_tu_loose_d0.json")
    sp = Space(inst)
    first = sp.ids.index("t45")
    done = 1 << first
    state = sp.step(sp.root(), sp.r[first], sp.h[first])
    below = 1350.0 * (1 - 1e-9)
    cut = sp.kit_cut(done, state, below)
    assert cut.same_r < cut.max_r and cut.min_area > 0
    plain = list(itertools.islice(sp.kits(done, cut.max_r), 2000))
    kept = {m for m, *_ in sp.children(done, state, below)}
    dropped = [(m, r, h) for m, r, h, _ in plain if m not in kept]
    assert len(dropped) >= 1000
    for m, r, h in dropped:
        assert sp.lower_bound(done | m, sp.step(state, r, h)) >= below


@pytest.mark.parametrize("trays", (None, 1, 2))
def test_bound_with_exactly_k0_kits_left_rises(trays):
    """The bound's term for the kits left: with exactly k0 of them the next holds the area the
    others cannot (its robot time), with more the human has one more overhead. On small
    cases it rises above the bound without it somewhere (and stays below every plan:
    test_transition_and_bound_on_every_plan)."""
    raised = 0
    for seed in range(12):
        inst = case(seed, trays, tray=(200.0, 120.0))
        sp = Space(inst)
        for done, state in [(0, sp.root()), *_prefix_states(inst, sp)]:
            c = sp.constants(done)
            b, a = state[0], state[1]
            old = max(b + c.human, a + c.flow, max(b, a + c.first) + c.human, a + c.robot_one)
            new = sp.lower_bound(done, state)
            assert new >= old - 1e-9
            raised += new > old + 1e-9
    assert raised >= 3


@pytest.mark.parametrize("trays", TRAYS)
@pytest.mark.parametrize("seed", SEEDS)
def test_partial_expansion_equals_the_brute_force(seed, trays):
    """With one child pushed per expansion (``batch=1``), every node goes back on the heap
    until its kits are all generated: the search still finds and proves the optimum, and a
    bound at an early stop (a parent partly expanded among the open nodes) is below it."""
    inst = case(seed, trays)
    opt, _ = best_makespan(inst)
    out = search(Space(inst), brute_fits(inst), batch=1)
    assert out.exhausted and out.stop == "exhausted"
    assert out.value == pytest.approx(opt, abs=1e-9)
    assert out.bound == pytest.approx(opt, abs=1e-9)
    assert out.counters["resumed"] > 0
    for k in (1, 2, 4):
        early = search(Space(inst), brute_fits(inst), max_expansions=k, batch=1)
        assert early.bound <= opt + 1e-9


def test_batch_option_reaches_the_search():
    """``-p batch=N`` of the method: the search resumes nodes (``extra["resumed"]``); without
    it none is."""
    inst = load(INSTANCES / "hrc_table.json")
    whole = solve(inst, "bbr", start="quick", expansions=30)
    part = solve(inst, "bbr", start="quick", expansions=30, batch=2)
    assert whole.extra["resumed"] == 0 and part.extra["resumed"] > 0


@pytest.mark.parametrize("trays", TRAYS)
@pytest.mark.parametrize("seed", SEEDS[:6])
def test_node_cap_holds_within_an_expansion(seed, trays):
    """``max_nodes`` caps the nodes kept inside one expansion too (one node of a sparse graph
    with a loose tray has millions of kits): the search stops with ``memory`` at the cap, its
    bound below the optimum, and it reaches the cap from every cap below the root's kits."""
    inst = case(seed, trays, tray=(400.0, 400.0))
    opt, _ = best_makespan(inst)
    whole = search(Space(inst), brute_fits(inst), max_expansions=1)
    root_kits = whole.counters["kept"] - 1
    assert root_kits >= 3
    for cap in (2, root_kits // 2 + 1, root_kits):
        out = search(Space(inst), brute_fits(inst), max_nodes=cap)
        assert out.stop == "memory"
        assert out.counters["kept"] == cap
        assert out.counters["expanded"] == 1
        assert out.bound <= opt + 1e-9
