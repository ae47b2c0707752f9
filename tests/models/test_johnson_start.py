"""The Johnson-order quick plan as a candidate incumbent of the exact models
(docs/formulations.md, "Closed-form lower bounds"): the closed-form check computes it once, and when
it does not attain the bound it still competes with the topological order's quick plan."""

from __future__ import annotations

import pytest
from paths import ROOT

from bilevel_kit import load, solve
from bilevel_kit.models.budget import Budget
from bilevel_kit.models.common import Packer, johnson_plan, quick_plan
from bilevel_kit.plan import Kit, Plan, evaluate
from bilevel_kit.validate import check

#: The record where the two orders' quick plans differ (the numbers docs/formulations.md cites).
WIDE = ROOT / "instances" / "kitbench" / "wide_n50_s1_t1_tight_d30.json"


def _makespan(instance, kits) -> float:
    return evaluate(instance, Plan(tuple(Kit(tuple(k)) for k in kits))).makespan


@pytest.fixture(scope="module")
def wide():
    return load(WIDE)


def test_the_johnson_order_beats_the_topological_order_on_the_wide_record(wide) -> None:
    """1,327 s against 1,336 s, neither at the closed-form bound (1,258 s)."""
    kits, optimal = johnson_plan(wide, Packer(wide, 0.2, Budget(60.0)))
    assert kits is not None and not optimal
    assert _makespan(wide, kits) == pytest.approx(1327.0, abs=1e-6)
    topo = quick_plan(wide, Packer(wide, 0.2, Budget(60.0)))
    assert topo is not None and _makespan(wide, topo) == pytest.approx(1336.0, abs=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_the_exact_models_start_from_the_johnson_plan(wide, method) -> None:
    """Without a warm start or the LNS first, the incumbent the model starts from is the
    Johnson order's plan (it was the topological order's, 1,336 s)."""
    out = solve(wide, method, time_limit=6, hint="none", fallback="none")
    assert out.extra["upper_start"] == pytest.approx(1327.0, abs=1e-6)
    assert out.makespan <= 1327.0 + 1e-6
    assert out.plan is not None and check(wide, out.plan) == []


def test_cpsat_runs_the_closed_form_check_once(tiny, monkeypatch) -> None:
    """cpsat's check before its warm start hands its plan to the run, which does not compute
    it again; the check's plan is the incumbent when it attains the bound."""
    from bilevel_kit.models.cpsat import method

    calls = []

    def counted(*args, **kwargs):
        calls.append(1)
        return johnson_plan(*args, **kwargs)

    monkeypatch.setattr(method, "johnson_plan", counted)
    out = solve(tiny, "cpsat", time_limit=5, fallback="none")
    assert len(calls) == 1 and out.plan is not None
    assert check(tiny, out.plan) == []
