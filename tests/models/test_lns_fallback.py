"""The exact models' fallback when they build no model (docs/formulations.md, "Model too
large"): the time left goes to the LNS from the incumbent, so the plan is valid and never
worse than the incumbent, the bound and the model's status value stay as they were, and
``fallback="none"`` returns the incumbent as before."""

from __future__ import annotations

import pytest

from bilevel_kit import UsageError, load, solve
from bilevel_kit.models import budget
from bilevel_kit.validate import check

#: A 25-task one-tray in-tree whose quick plans the LNS's own starts already beat.
INSTANCE = ("instances", "kitbench", "intree_n25_s1_t1_tight_d10.json")
LIMIT = 10.0


@pytest.fixture(scope="module")
def intree(root):
    return load(root.joinpath(*INSTANCE))


def _honest(inst, out) -> None:
    """A valid plan, a bound below it, ``optimal`` only when the plan meets the bound."""
    assert out.plan is not None and check(inst, out.plan) == []
    assert out.bound is not None and out.bound <= out.objective + 1e-6
    assert (out.status == "optimal") == (out.objective <= out.bound + 1e-6)


def _wall_ok(out, limit: float) -> bool:
    """The time limit kept end to end, generously (the machine may be busy)."""
    return out.extra["wall_time_s"] <= limit + max(2.0, 0.05 * limit) + 5.0


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_a_model_too_large_hands_the_time_left_to_the_lns(method, intree, monkeypatch):
    monkeypatch.setattr(budget, "MEMORY_LIMIT", budget.BASE_MEMORY + 1)
    out = solve(intree, method, seed=0, time_limit=LIMIT)
    before = solve(intree, method, seed=0, time_limit=LIMIT, fallback="none")
    extra = out.extra
    _honest(intree, out)
    assert extra["solver_status"] == "too_large"
    assert "memory limit" in extra["reason"]
    # never worse than the incumbent; here better (the LNS's one-tray cut beats it)
    assert out.objective <= extra["upper_start"] + 1e-9
    assert out.objective < before.objective - 1e-9
    assert extra["improved_by"] == "lns"
    info = extra["fallback"]
    assert info["method"] == "lns" and info["time_s"] > 0
    assert info["makespan_before"] == pytest.approx(extra["upper_start"])
    assert info["makespan_after"] == pytest.approx(out.objective)
    # the bound is the proven bound, never the LNS's incumbent
    assert out.bound == pytest.approx(before.bound, abs=1e-6)
    assert out.bound == pytest.approx(max(extra["bound_sources"].values()), abs=1e-6)
    assert _wall_ok(out, LIMIT)


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_fallback_none_returns_the_incumbent_as_before(method, intree, monkeypatch):
    monkeypatch.setattr(budget, "MEMORY_LIMIT", budget.BASE_MEMORY + 1)
    out = solve(intree, method, seed=0, time_limit=LIMIT, fallback="none")
    _honest(intree, out)
    assert out.status == "feasible"
    assert out.objective == pytest.approx(out.extra["upper_start"])
    assert "improved_by" not in out.extra and "fallback" not in out.extra
    assert out.extra["solver_status"] == "too_large"


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_a_model_too_slow_to_build_hands_over_too(method, intree, monkeypatch):
    # both methods decide through budget.no_model_reason (one rule, docs/formulations.md)
    monkeypatch.setattr(budget, "too_slow_to_build", lambda *args: True)
    limit = 6.0
    out = solve(intree, method, seed=1, time_limit=limit)
    _honest(intree, out)
    assert out.extra["solver_status"] == "not_built"
    assert out.objective <= out.extra["upper_start"] + 1e-9
    assert out.extra["improved_by"] in ("lns", None)
    if out.objective < out.extra["upper_start"] - 1e-9:
        assert out.extra["improved_by"] == "lns"
    assert _wall_ok(out, limit)


def test_the_fallback_option_is_checked(tiny):
    for method in ("cpsat", "milp"):
        with pytest.raises(UsageError, match="fallback"):
            solve(tiny, method, fallback="greedy")


def test_lns_from_a_given_plan_is_never_worse(intree):
    """``lns(start_plan=...)``: the given plan is the first start (its layouts kept)."""
    from bilevel_kit.models.lns import LnsOptions, lns
    from bilevel_kit.plan import evaluate

    given = solve(intree, "single-task", seed=0).plan
    out = lns(
        intree, LnsOptions(iterations=2, start="quick"), seed=0, time_limit=20, start_plan=given
    )
    assert out.plan is not None and check(intree, out.plan) == []
    assert evaluate(intree, out.plan).makespan <= evaluate(intree, given).makespan + 1e-9
    assert out.extra["start_method"] is not None


def test_the_fallback_reports_its_last_window_and_takes_a_cut_share(intree):
    """The report names the size of the LNS's last windows; ``cut_share`` 0 (the LNS after
    the model, docs/formulations.md) leaves no fixed-size cut as its start."""
    from bilevel_kit.models.lns.fallback import improve

    given = solve(intree, "single-task", seed=0).plan
    better, info = improve(
        intree, given, bound=None, seed=0, time_limit=20.0, iterations=1, cut_share=0.0
    )
    # one window (its plan may meet the LNS's own bound: optimal)
    assert info["windows"] == 1 and info["stop"] in ("iterations", "optimal")
    assert info["window"] == 24 and "fixed cut" not in info["start_method"]
    assert better is None or check(intree, better) == []
