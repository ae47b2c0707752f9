"""The proven bound of bilevel_kit.models.relax in the exact models (docs/formulations.md,
"Stronger lower bounds"): ``cpsat`` and ``milp`` report at least it, name its source, never
exceed the brute-force optimum; a model over the memory limit returns the incumbent as
feasible with that bound, not nothing."""

from __future__ import annotations

import pytest
from brute import best_makespan
from test_exact_trays import random_doc

from bilevel_kit import UsageError, solve
from bilevel_kit.bounds import best_bound
from bilevel_kit.instance import from_dict
from bilevel_kit.models import budget
from bilevel_kit.models.relax import proven_bound
from bilevel_kit.validate import check

SOURCES = {"model", "closed_form", "closed_form_human", "closed_form_robot", "closed_form_flow"}


def _known_source(source: str, sources: dict[str, float]) -> bool:
    return source in SOURCES or source in sources


@pytest.mark.parametrize("method", ["cpsat", "milp"])
@pytest.mark.parametrize("trays", [1, None])
@pytest.mark.parametrize("seed", range(3))
def test_models_report_the_proven_bound_and_its_source(method, seed, trays):
    inst = from_dict(random_doc(seed, trays))
    opt, _ = best_makespan(inst)
    out = solve(inst, method, seed=0, time_limit=20)
    extra = out.extra
    assert out.plan is not None and check(inst, out.plan) == []
    assert out.bound is not None and out.bound <= opt + 1e-6
    assert out.bound >= best_bound(inst) - 1e-9
    assert _known_source(extra["bound_source"], extra["bound_sources"]), extra
    assert extra["bound_time_s"] >= 0.0
    # the pre-model bound is the proven bound of models.relax (computed within the share)
    pre = max(extra["bound_sources"].values())
    assert pre <= proven_bound(inst, time_limit=30.0).value + 1e-6
    assert out.bound >= min(pre, out.objective) - 1e-6


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_a_model_over_the_memory_limit_returns_the_incumbent(method, table, monkeypatch):
    monkeypatch.setattr(budget, "MEMORY_LIMIT", budget.BASE_MEMORY + 1)
    out = solve(table, method, seed=0, time_limit=20)
    assert out.status == "feasible" and out.plan is not None
    assert check(table, out.plan) == []
    assert "memory limit" in out.extra["reason"]
    assert out.extra["solver_status"] == "too_large" and out.extra["backend_status"] is None
    assert out.bound is not None and out.bound <= out.objective
    assert out.bound >= best_bound(table) - 1e-9
    assert out.extra["bound_source"]


def test_memory_refusal_names_the_size_and_the_limit():
    assert budget.memory_refusal("cpsat", 10, 1.0, "cells") is None
    text = budget.memory_refusal("cpsat", 10**9, 6_000.0, "task x kit variables")
    assert text is not None and "memory limit" in text and "1,000,000,000" in text
    with pytest.raises(UsageError, match="memory limit"):
        budget.check_model_memory("cpsat", 10**9, 6_000.0, "task x kit variables")


def test_milp_takes_a_hint_method_and_refuses_an_unknown_one(stool):
    out = solve(stool, "milp", seed=0, time_limit=20, hint="lns")
    assert out.plan is not None and check(stool, out.plan) == []
    assert out.extra["hint_method"] in (None, "lns")
    with pytest.raises(UsageError, match="hint"):
        solve(stool, "milp", hint="no-such-method")
