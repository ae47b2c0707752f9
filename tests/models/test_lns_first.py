"""The LNS inside the exact models' budget (docs/formulations.md, "The LNS first"): ``cpsat``'s
and ``milp``'s plan at a time limit is never worse than ``lns``'s at the same limit and seed;
a plan the LNS found is ``optimal`` only with a proof (the model's, or the proven bound met);
the paper's table keeps its proven optimum."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import pytest

from bilevel_kit import solve
from bilevel_kit.generate import generate
from bilevel_kit.instance import from_dict
from bilevel_kit.methods import MethodOutput, Status
from bilevel_kit.models.budget import Budget
from bilevel_kit.models.exact import lns_first
from bilevel_kit.models.exact.nomodel import CPSAT, MILP, NoModelSpec
from bilevel_kit.validate import check

LIMIT = 6.0
STATUS_KEY = {"cpsat": "solver_status", "milp": "solver_status"}
#: The LNS inside gets at most half of what is left after the warm start; on these instances
#: ``lns`` alone reaches its local optimum (or the bound) within about a second, so the two
#: plans agree up to the windows' search order: 0.5 % covers a window cut off by the clock.
REL_TOL = 5e-3


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


@pytest.fixture(scope="module")
def lns_plans(generated):
    return {k: solve(inst, "lns", seed=0, time_limit=LIMIT) for k, inst in generated.items()}


@pytest.mark.parametrize("method", ["cpsat", "milp"])
@pytest.mark.parametrize("name", ["sparse60", "wide40"])
def test_the_exact_plan_is_never_worse_than_the_lns(method, name, generated, lns_plans):
    inst = generated[name]
    out = solve(inst, method, seed=0, time_limit=LIMIT)
    _honest(inst, out)
    alone = lns_plans[name]
    assert out.objective <= alone.objective * (1 + REL_TOL)
    if "lns_first" in out.extra:  # the model was built: the LNS ran first, within its share
        info = out.extra["lns_first"]
        assert info["method"] == "lns" and info["share"] == lns_first.SHARE
        assert 0 < info["time_s"] <= LIMIT and info["used_s"] <= info["time_s"] + 1.0
    else:  # no model (too slow to build): the whole time left went to the LNS
        info = out.extra["fallback"]
        assert out.extra[STATUS_KEY[method]] in ("not_built", "too_large")
    assert out.extra["improved_by"] in ("lns", "model", None)
    if out.extra["improved_by"] == "lns":  # the plan is the LNS's
        assert out.objective == pytest.approx(info["makespan_after"], abs=1e-6)
    assert out.extra["wall_time_s"] <= LIMIT + max(2.0, 0.05 * LIMIT)


def test_the_sparse_instance_is_proven_by_the_lns_plan_and_the_bound(generated):
    # the LNS's plan meets the bound of models.relax (1470 s, docs/formulations.md):
    # optimal without a model, the proof being that bound, never the LNS's incumbent
    inst = generated["sparse60"]
    out = solve(inst, "cpsat", seed=0, time_limit=LIMIT)
    _honest(inst, out)
    assert out.status == "optimal" and out.extra["improved_by"] == "lns"
    assert out.extra["solver_status"] == "proven_bound"
    assert out.bound == pytest.approx(max(out.extra["bound_sources"].values()), abs=1e-6)


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_the_table_stays_optimal(method, table):
    out = solve(table, method, seed=0, time_limit=20.0)
    assert out.status == "optimal"
    assert out.objective == pytest.approx(435.085, abs=1e-6)
    assert check(table, out.plan) == []


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
    margin: float = 0.1

    def __post_init__(self) -> None:
        self.budget = Budget(10.0, stretch=2.0 if self.deterministic else 1.0)
        self.instance = type("I", (), {"stations": self.stations})()

    def known_bound(self) -> float:
        return self.bound

    def hand_off(self, inc: int, seconds: float = float("inf")) -> int:
        self.given = seconds
        info = {"method": "lns", "time_s": seconds, "makespan_before": 100.0}
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
    assert stub.extra["lns_first"]["makespan_after"] == 90.0
    assert "solver_status" not in stub.extra  # no status claimed: the model decides


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
        ({"stations": ("s1", "s2")}, "lns", "several stations"),
        ({"deterministic": True}, "lns", "reproducible"),
    ],
)
def test_skipped_cleanly(kw, fallback, why):
    stub = _Stub(after=50.0, bound=10.0, **kw)
    assert lns_first.before_model(stub, 0, fallback) == (0, False)
    assert stub.given is None and why in stub.extra["lns_first"]["skipped"]


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
