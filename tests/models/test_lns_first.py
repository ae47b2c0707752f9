"""The LNS inside the exact models' budget (docs/formulations.md, "The LNS first"): the
exact plan is never worse than the LNS first's; the LNS stops after a sweep's worth of windows
without improvement (``stall_windows``, counted in windows: the same count under any load),
solves windows on
small instances too, and keeps its cap and the time limit; a plan the
LNS found is ``optimal`` only with a proof (the model's, or the proven bound met); the paper's
table keeps its proven optimum."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import pytest

from bilevel_kit import load, solve
from bilevel_kit.generate import generate
from bilevel_kit.instance import from_dict
from bilevel_kit.methods import MethodOutput, Status
from bilevel_kit.models.budget import Budget
from bilevel_kit.models.common import claim_scope, scope_claims
from bilevel_kit.models.exact import keys, lns_first
from bilevel_kit.models.exact.nomodel import CPSAT, MILP, WHOLE, HandOff, NoModelSpec
from bilevel_kit.models.lns import method as lns_method
from bilevel_kit.models.packing import ANY_ANGLE, AXIS_ALIGNED
from bilevel_kit.validate import check

LIMIT = 6.0


def _slack(limit: float) -> float:
    """The time limit kept end to end (T + max(2 s, 5 %)), generously: the machine may be
    busy (the first solve of a process loads the compiled kernels); the LNS's own cap is
    asserted exactly, from the budget."""
    return limit + max(2.0, 0.05 * limit) + 5.0


def _honest(inst, out) -> None:
    """A checked plan, a bound below it, ``optimal`` only when the plan meets the bound (the
    model's proof lifts the bound to the plan)."""
    assert out.plan is not None and check(inst, out.plan) == []
    assert out.bound is not None and out.bound <= out.objective + 1e-6
    assert (out.status == "optimal") == (out.objective <= out.bound + 1e-6)


@pytest.fixture(scope="module")
def generated():
    # ``generate sparse --size 60`` (on main at 10 s: cpsat 1529 s, lns 1470 s optimal in
    # 1.7 s, docs/formulations.md, "The LNS first") and a 40-task wide instance
    return {
        "sparse60": from_dict(generate("sparse", 60)),
        "wide40": from_dict(generate("wide", 40, seed=1)),
    }


@pytest.mark.parametrize("method", ["cpsat", "milp"])
@pytest.mark.parametrize("name", ["sparse60", "wide40"])
def test_the_exact_plan_is_never_worse_than_the_lns_first(method, name, generated):
    inst = generated[name]
    out = solve(inst, method, seed=0, time_limit=LIMIT)
    _honest(inst, out)
    extra = out.extra
    if extra[keys.SOLVER_STATUS] in ("not_built", "too_large"):  # the LNS had the time left
        info = extra["fallback"]
    else:  # the model was built (or the LNS first met the bound): the LNS ran first
        info = extra[keys.LNS_FIRST]
        assert info["method"] == "lns" and info["share"] == lns_first.SHARE
        assert info[keys.LNS_STALL] >= lns_first.STALL_WINDOWS  # a sweep's windows, at least 4
        assert info[keys.LNS_MAX_WINDOWS] is None  # no window cap
        # it ran (or, on a machine too busy to leave it 1 s, said why not)
        assert info.get(keys.LNS_STOP) in keys.LNS_STOPS or "1 s left" in info["skipped"]
        # the cap: SHARE of the time left after the warm start, at most SHARE of the limit
        assert 0 < info["time_s"] <= lns_first.SHARE * LIMIT
        assert info[keys.LNS_USED_S] <= info["time_s"] + 1.0
        if info.get(keys.LNS_STOP) == "stall":  # the last stall windows found nothing
            assert info["windows"] >= info[keys.LNS_STALL]
    assert out.objective <= info["makespan_after"] + 1e-6 <= info["makespan_before"] + 2e-6
    assert extra["improved_by"] in ("lns", "model", None)
    after = extra.get(keys.LNS_AFTER, {})
    if "makespan_after" in after:  # the LNS resumed after the model's share, from its plan
        assert keys.MODEL_CAP_S in info and out.status != "optimal" and info["improvements"]
        assert info[keys.MODEL_CAP_S] <= lns_first.MODEL_SHARE * LIMIT
        assert out.objective <= after["makespan_after"] + 1e-6 <= after["makespan_before"] + 2e-6
        last = after if after["makespan_after"] < after["makespan_before"] - 1e-6 else info
    else:
        last = info
    if extra["improved_by"] == "lns":  # the plan is the LNS's (the last one that improved)
        assert out.objective == pytest.approx(last["makespan_after"], abs=1e-6)
    assert extra["wall_time_s"] <= _slack(LIMIT)


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_a_small_instance_gets_windows_and_the_model_its_proof(method, table):
    # 12 tasks: the LNS solves windows too (its quick start, 435.085 s, is a local optimum of
    # every window: it stops after its stall's windows), then the model proves the optimum
    # (in 1-5 s unloaded; the limit leaves room for a busy machine, the run ends at the proof)
    out = solve(table, method, seed=0, time_limit=60.0)
    info = out.extra[keys.LNS_FIRST]
    assert info[keys.LNS_MAX_WINDOWS] is None
    assert info[keys.LNS_STOP] in ("stall", "local_optimum", "optimal")
    if info[keys.LNS_STOP] == "stall":
        assert info["windows"] == info[keys.LNS_STALL] and info["improvements"] == 0
    why = ("solver_status", "backend_status", "build_time_s", "master_time_s", "wall_time_s")
    assert out.status == "optimal", str({k: out.extra.get(k) for k in why})
    assert out.objective == pytest.approx(435.085, abs=1e-6)
    assert check(table, out.plan) == []


# -- the stall rule of the LNS (option ``stall``), counted in windows -----------------------


def test_the_lns_stops_after_stall_windows_without_improvement(table):
    # the table's quick start (435.085 s) is a local optimum of every window: the LNS stops
    # after exactly ``stall`` windows, with the same plan in two runs (window solves are
    # limited by CP-SAT's deterministic time; a known bound of 0 keeps the LP out)
    opts = lns_method.LnsOptions(start="quick", window=8, stall=3)
    runs = [lns_method.lns(table, opts, seed=0, time_limit=120.0, known_bound=0.0) for _ in "ab"]
    for out in runs:
        assert out.extra["stop"] == "stall"
        assert out.extra["iterations"] == 3 and out.extra["improvements"] == 0
        assert out.extra["makespan"] == pytest.approx(435.085, abs=1e-6)
        assert check(table, out.plan) == []
    assert [k.tasks for k in runs[0].plan.kits] == [k.tasks for k in runs[1].plan.kits]


def test_an_improvement_restarts_the_stall_count(table, monkeypatch):
    # windows 2 and 5 improve (stubbed): the count restarts there, so with stall = 3 the run
    # ends after window 5 + 3 = 8, whatever the sweeps' boundaries
    solved: list[int] = []
    pending = {2, 5}

    def window(ctx, kits, k0, k1, scaled, seed, left):
        solved.append(k0)
        return SimpleNamespace(stopped=False, optimal=True, kits=kits[k0:k1])

    def improve(self, kits):
        if len(solved) in pending:
            pending.discard(len(solved))
            return True
        return False

    monkeypatch.setattr(lns_method, "solve_window", window)
    monkeypatch.setattr(lns_method._Run, "_improve", improve)
    opts = lns_method.LnsOptions(start="quick", window=8, stall=3)
    out = lns_method.lns(table, opts, seed=0, time_limit=120.0, known_bound=0.0)
    assert out.extra["stop"] == "stall"
    assert out.extra["iterations"] == len(solved) == 8
    assert out.extra["improvements"] == 2


def test_the_stall_option_is_checked(tiny):
    from bilevel_kit import UsageError

    with pytest.raises(UsageError, match="stall"):
        solve(tiny, "lns", stall=0)


def test_the_sparse_instance_is_proven_by_the_johnson_cut_and_the_bound(generated):
    # the Johnson-order one-tray cut meets the bound of models.relax (1470 s,
    # docs/formulations.md): optimal without a model, the proof being that bound, never a
    # plan's own makespan. The cut is the exact model's own candidate incumbent (its
    # closed-form check's plan), found within that check's 5 % of the time limit when the
    # packing cache is warm (e.g. after other tests), else the LNS first's start plan (0.6-0.8 s
    # unloaded, 3 s at a load of 9 on 2 cores; the run ends there, the limit is room for a busy
    # machine)
    inst = generated["sparse60"]
    out = solve(inst, "cpsat", seed=0, time_limit=30.0)
    _honest(inst, out)
    assert out.status == "optimal" and out.extra["solver_status"] == "proven_bound"
    assert out.bound == pytest.approx(max(out.extra["bound_sources"].values()), abs=1e-6)
    if out.extra.get("improved_by") is None:  # the incumbent met it: no LNS
        assert "lns_first" not in out.extra
        assert out.extra["upper_start"] == pytest.approx(out.makespan, abs=1e-9)
    else:
        assert out.extra["improved_by"] == "lns"
        assert out.extra["lns_first"]["start_method"] == "johnson one-tray cut"


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_fallback_none_runs_the_model_alone(method, table):
    out = solve(table, method, seed=0, time_limit=10.0, fallback="none")
    assert out.extra["lns_first"] == {"skipped": "option fallback=none"}
    assert out.objective == pytest.approx(435.085, abs=1e-6)


# -- the driver's step on a stub backend (no solver: the rules alone) -----------------------


@dataclass
class _Stub:
    """A backend whose LNS turns incumbent 0 into ``better`` of makespan ``after``."""

    after: float | None
    bound: float
    spec: NoModelSpec = CPSAT
    deterministic: bool = False
    stations: tuple[Any, ...] = ()
    extra: dict[str, Any] = field(default_factory=dict)
    given: float | None = None
    limit: HandOff | None = None
    margin: float = 0.1
    n_tasks: int = 40
    n_kits: int = 10
    is_makespan: bool = True

    def __post_init__(self) -> None:
        self.budget = Budget(10.0, stretch=2.0 if self.deterministic else 1.0)
        self.instance = SimpleNamespace(stations=self.stations, n_tasks=self.n_tasks)

    def known_bound(self) -> float:
        return self.bound

    def plan(self, inc: int) -> Any:
        return SimpleNamespace(kits=[()] * self.n_kits)

    def hand_off(self, inc: int, limit: HandOff = WHOLE) -> int:
        self.given, self.limit = limit.seconds, limit
        info = {"method": "lns", "time_s": limit.seconds, "makespan_before": 100.0}
        self.extra.update(improved_by=None, fallback=info)
        if self.after is None:
            info["makespan_after"] = 100.0
            return inc
        info["makespan_after"] = self.after
        self.extra["improved_by"] = "lns"
        return 1


def test_the_lns_gets_its_share_and_a_plan_above_the_bound_goes_to_the_model():
    stub = _Stub(after=90.0, bound=80.0)
    inc, met = lns_first.before_model(stub, 0, "lns")
    assert (inc, met) == (1, False)
    assert stub.given is not None and stub.given <= lns_first.SHARE * 10.0 + 1e-9
    assert stub.given >= lns_first.SHARE * 9.0  # of the time left less the margin
    assert "fallback" not in stub.extra  # reported as the LNS first, not as a fallback
    info = stub.extra[keys.LNS_FIRST]
    assert info["makespan_after"] == 90.0
    assert "solver_status" not in stub.extra  # no status claimed: the model decides
    # stopped by a sweep's windows without improvement (10 kits: 9), no window cap
    assert stub.limit == lns_first.limits(stub.given, 10.0, 10)
    assert (stub.limit.stall, stub.limit.windows) == (9, None)
    assert info[keys.LNS_STALL] == 9 and info[keys.LNS_MAX_WINDOWS] is None
    assert info[keys.LNS_USED_S] >= 0.0 and info["share"] == lns_first.SHARE == 0.8


@pytest.mark.parametrize("n", [1, 12, 24, 25, 500])
def test_every_instance_gets_windows(n):
    # small instances too (issue 37: 12 tasks, the start plans alone left cpsat 1.8 % above
    # lns at 10 s, bench/results/kitbench_cmp_10s.csv)
    stub = _Stub(after=None, bound=80.0, n_tasks=n, n_kits=min(n, 10))
    lns_first.before_model(stub, 0, "lns")
    assert stub.limit == lns_first.limits(stub.given, 10.0, min(n, 10))
    assert stub.limit.stall == max(4, min(n, 10) - 1) and stub.limit.windows is None
    assert stub.extra[keys.LNS_FIRST][keys.LNS_MAX_WINDOWS] is None
    assert stub.extra[keys.LNS_FIRST]["cut_share"] == stub.limit.cut_share


@pytest.mark.parametrize(("kits", "stall"), [(0, 4), (1, 4), (5, 4), (6, 5), (7, 6), (40, 39)])
def test_the_stall_is_a_sweeps_windows_at_least_four(kits, stall):
    # a sweep of lns solves a window from every kit but the last
    assert lns_first.stall_windows(kits) == stall
    assert lns_first.limits(5.0, 10.0, kits).stall == stall


def test_with_stations_the_stall_stays_four_sweeps():
    # the station search counts the stall in sweeps of its kit visits (stall x kits visits)
    stub = _Stub(after=None, bound=80.0, stations=("a", "b"), n_kits=30)
    lns_first.before_model(stub, 0, "lns")
    assert stub.limit is not None and stub.limit.stall == lns_first.STALL_WINDOWS == 4


def test_a_sweeps_stall_finds_what_four_windows_miss(root):
    # table_u5_tu_loose_d30 (60 tasks): from lns's quick start (the topological one-tray cut,
    # 2,018.9 s, 7 kits) 4 windows find nothing, a sweep's 6 find 2,006.035 s and the count,
    # restarted, 2,003.815 s (lns's plan at 10 s; cpsat's at 10 s before this stall: 2,018.9 s,
    # docs/formulations.md, "The LNS first"); windows are limited by deterministic time
    rec = load(root / "instances/kitbench/table_u5_tu_loose_d30.json")
    runs = {}
    for stall in (4, lns_first.stall_windows(7)):
        opts = lns_method.LnsOptions(start="quick", stall=stall)
        out = lns_method.lns(rec, opts, seed=0, time_limit=120.0, known_bound=1992.015)
        assert out.extra["start_makespan"] == pytest.approx(2018.9, abs=1e-6)
        assert out.extra["stop"] == "stall" and check(rec, out.plan) == []
        runs[stall] = out.extra
    assert runs[4]["makespan"] == pytest.approx(2018.9, abs=1e-6) and runs[4]["iterations"] == 4
    assert runs[6]["makespan"] == pytest.approx(2003.815, abs=1e-6)
    assert runs[6]["improvements"] == 2 and runs[6]["iterations"] == 13


@pytest.mark.parametrize(
    ("seconds", "time_limit", "share"),
    [
        (5.0, 10.0, 0.5),  # lns's 2.5 s at 10 s: half of a 5 s cap
        (40.0, 60.0, 0.375),  # 15 s of 40
        (8.0, 10.0, 0.3125),
        (100.0, 100.0, 0.25),  # never below lns's own share
        (1.0, 10.0, 0.5),  # nor above MAX_CUT_SHARE of the cap
        (0.0, 10.0, 0.25),
    ],
)
def test_the_lns_first_cuts_its_start_plans_in_lns_seconds(seconds, time_limit, share):
    limit = lns_first.limits(seconds, time_limit)
    assert limit.cut_share == pytest.approx(share, rel=1e-12) and limit.seconds == seconds


@pytest.mark.parametrize("spec", [CPSAT, MILP])
def test_a_plan_meeting_the_bound_ends_without_a_model(spec):
    stub = _Stub(after=80.0, bound=80.0, spec=spec)
    assert lns_first.before_model(stub, 0, "lns") == (1, True)
    assert stub.extra["solver_status"] == "proven_bound" and stub.extra["build_time_s"] == 0.0
    assert stub.extra["backend_status"] is None


def test_the_warm_start_meeting_nothing_is_not_claimed():
    stub = _Stub(after=None, bound=100.0)  # the LNS found nothing better: no claim from it
    assert lns_first.before_model(stub, 0, "lns") == (0, False)


@pytest.mark.parametrize(
    ("kw", "fallback", "why"),
    [
        ({}, "none", "fallback=none"),
        ({"stations": ("s1", "s2"), "is_makespan": False}, "lns", "several stations"),
        ({"deterministic": True}, "lns", "reproducible"),
    ],
)
def test_skipped_cleanly(kw, fallback, why):
    stub = _Stub(after=50.0, bound=10.0, **kw)
    assert lns_first.before_model(stub, 0, fallback) == (0, False)
    assert stub.given is None and why in stub.extra["lns_first"]["skipped"]


def test_stations_with_the_makespan_run_the_lns_first():
    """Several stations, the makespan: the LNS (its station search) runs first
    (docs/stations.md#lns-with-several-stations)."""
    stub = _Stub(after=90.0, bound=80.0, stations=("s1", "s2"))
    assert lns_first.before_model(stub, 0, "lns") == (1, False)
    assert stub.given is not None and "skipped" not in stub.extra[keys.LNS_FIRST]


def test_improved_by_names_the_model_when_it_beats_the_lns(tiny):
    stub = _Stub(after=90.0, bound=10.0)
    stub.instance = tiny
    lns_first.before_model(stub, 0, "lns")
    out = solve(tiny, "single-task")
    makespan = out.objective
    stub.extra["lns_first"]["makespan_after"] = makespan + 1.0  # the model's plan is better
    res = MethodOutput(out.plan, Status.FEASIBLE, None, dict(stub.extra))
    assert lns_first.after_model(stub, res, 0.0).extra["improved_by"] == "model"
    stub.extra["lns_first"]["makespan_after"] = makespan  # the model kept the LNS's plan
    res = MethodOutput(out.plan, Status.FEASIBLE, None, dict(stub.extra))
    assert lns_first.after_model(stub, res, 0.0).extra["improved_by"] == "lns"
    assert stub.extra["lns_first"]["model_s"] >= 0.0


# -- the LNS after the model's share (docs/formulations.md, "The LNS after the model") ------


def _ran_first(stub: _Stub, improvements: int = 1) -> _Stub:
    info = {"method": "lns", "makespan_after": 100.0, "improvements": improvements}
    stub.extra[keys.LNS_FIRST] = info
    return stub


@pytest.mark.parametrize("resume", [True, False])
def test_the_model_gets_its_share_of_the_time_left(resume):
    stub = _ran_first(_Stub(after=None, bound=10.0))
    left = stub.budget.remaining(stub.margin)
    with lns_first.model_share(stub, resume):
        inside = stub.budget.remaining(stub.margin)
        sub = stub.budget.cut(0.0)  # a sub-budget made in the model keeps the model's end
    after = stub.budget.remaining(stub.margin)
    if resume:
        cap = stub.extra[keys.LNS_FIRST][keys.MODEL_CAP_S]
        assert cap == pytest.approx(lns_first.MODEL_SHARE * left, abs=0.05)
        assert inside == pytest.approx(cap - stub.margin, abs=0.05)
        assert sub.deadline == pytest.approx(
            stub.budget.deadline - (left - cap) - stub.margin, abs=0.05
        )
    else:  # (release times: the LNS cannot resume) the whole time left
        assert keys.MODEL_CAP_S not in stub.extra[keys.LNS_FIRST]
        assert inside == pytest.approx(left, abs=0.05)
    assert after == pytest.approx(left, abs=0.05)  # restored


@pytest.mark.parametrize("info", [{"skipped": "option fallback=none"}, {"improvements": 0}])
def test_no_share_when_the_lns_first_did_not_run_or_improve(info):
    # (its windows found nothing: the model keeps the time its proof may need)
    stub = _Stub(after=None, bound=10.0)
    stub.extra[keys.LNS_FIRST] = dict(info)
    left = stub.budget.remaining()
    with lns_first.model_share(stub, True):
        assert stub.budget.remaining() == pytest.approx(left, abs=0.05)
    assert keys.MODEL_CAP_S not in stub.extra[keys.LNS_FIRST]


@dataclass
class _After(_Stub):
    """A stub whose incumbents are plans of ``tiny``: the LNS returns ``better`` (or nothing),
    :meth:`conclude` states the plan with the bound known."""

    better: Any = None
    raised: list[tuple[float, str]] = field(default_factory=list)

    def adopt(self, plan):
        return plan

    def hand_off(self, inc, limit: HandOff = WHOLE):
        super().hand_off(inc, limit)
        self.extra["improved_by"] = None if self.better is None else "lns"
        return inc if self.better is None else self.better

    def raise_bound(self, value: float, source: str) -> None:
        self.raised.append((value, source))
        self.bound = value

    def conclude(self, inc):
        return MethodOutput(inc, Status.FEASIBLE, self.bound, self.extra)


def _model_out(tiny, status=Status.FEASIBLE, bound=None):
    plan = solve(tiny, "single-task").plan
    return MethodOutput(plan, status, bound, {})


def test_the_lns_resumes_from_the_model_plan_with_the_model_bound(tiny):
    better = solve(tiny, "greedy-ce", seed=0).plan
    stub = _ran_first(_After(after=None, bound=10.0, better=better))
    stub.instance = tiny
    stub.extra[keys.LNS_FIRST][keys.MODEL_CAP_S] = 1.0
    stub.extra["improved_by"] = "model"
    out = lns_first.after_share(stub, _model_out(tiny, bound=20.0))
    assert out.plan is better and stub.raised == [(20.0, "model")]  # the model's bound kept
    assert stub.given == math.inf  # the whole time left (the hand-off's own limit)
    assert stub.limit.cut_share == 0.0  # no start plans cut again
    report = stub.extra[keys.LNS_AFTER]
    assert report["method"] == "lns" and report[keys.LNS_USED_S] >= 0.0
    assert stub.extra["improved_by"] == "lns" and "fallback" not in stub.extra


def test_the_lns_after_finding_nothing_keeps_improved_by(tiny):
    stub = _ran_first(_After(after=None, bound=10.0))
    stub.instance = tiny
    stub.extra[keys.LNS_FIRST][keys.MODEL_CAP_S] = 1.0
    stub.extra.update(improved_by="model", fallback={"kept": True})
    model = _model_out(tiny, bound=5.0)  # below the known bound: not raised
    out = lns_first.after_share(stub, model)
    assert out.plan is model.plan and stub.raised == []
    assert stub.extra["improved_by"] == "model" and stub.extra["fallback"] == {"kept": True}


def test_a_model_bound_above_its_plan_is_not_taken(tiny):
    stub = _ran_first(_After(after=None, bound=10.0))
    stub.instance = tiny
    stub.extra[keys.LNS_FIRST][keys.MODEL_CAP_S] = 1.0
    lns_first.after_share(stub, _model_out(tiny, bound=1e6))
    assert stub.raised == []


@pytest.mark.parametrize("ended", [{keys.SOLVER_STATUS: "optimal"}, {"optimal_axis_aligned": True}])
def test_no_lns_after_a_model_whose_search_ended(tiny, ended):
    # (optimal among the 0/90-degree plans: concluding the LNS's plan would drop that claim,
    # as the brute-force tests of cpsat and milp found)
    stub = _ran_first(_After(after=None, bound=10.0))
    stub.instance = tiny
    stub.extra[keys.LNS_FIRST][keys.MODEL_CAP_S] = 1.0
    stub.extra.update(ended)
    out = _model_out(tiny)
    assert lns_first.after_share(stub, out) is out and stub.given is None
    assert keys.LNS_AFTER not in stub.extra


@pytest.mark.parametrize(
    ("status", "plan", "cap", "limit"),
    [
        (Status.OPTIMAL, True, True, 10.0),  # proven: nothing to resume
        (Status.INFEASIBLE, False, True, 10.0),
        (Status.UNKNOWN, False, True, 10.0),  # no plan
        (Status.FEASIBLE, True, False, 10.0),  # the model had all the time (no share)
        (Status.FEASIBLE, True, True, 0.3),  # less than MIN_AFTER_S left
    ],
)
def test_no_lns_after(tiny, status, plan, cap, limit):
    stub = _ran_first(_After(after=None, bound=10.0))
    stub.instance, stub.budget = tiny, Budget(limit)
    if cap:
        stub.extra[keys.LNS_FIRST][keys.MODEL_CAP_S] = 1.0
    out = _model_out(tiny, status=status)
    if not plan:
        out = MethodOutput(None, status, None, {})
    assert lns_first.after_share(stub, out) is out and stub.given is None
    if limit < 1.0:
        assert "no time left" in stub.extra[keys.LNS_AFTER]["skipped"]
    else:
        assert keys.LNS_AFTER not in stub.extra


def test_a_conclusion_drops_the_model_status_reason():
    """The model's reason for a weaker claim goes with its claim: the LNS after the model (or
    the incumbent ``never_worse`` keeps) is concluded with claims of its own."""
    extra = {"keep": 1, **scope_claims(None)}  # the model's: a kit excluded without a proof
    claim_scope(extra, ANY_ANGLE)
    assert extra == {"keep": 1, "proof_scope": ANY_ANGLE}
    claim_scope(extra, AXIS_ALIGNED)
    assert extra["proof_scope"] == AXIS_ALIGNED and "0/90-degree" in extra["status_reason"]
