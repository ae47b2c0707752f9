"""The large-neighbourhood search ``lns`` (docs/formulations.md, "Large-neighbourhood search"):
valid plans, a bound that is the proven bound (never above the brute-force optimum, never the
search's own incumbent), the same plan for a seed at a fixed number of windows."""

from __future__ import annotations

import pytest
from brute import best_makespan
from test_exact_trays import random_doc

from bilevel_kit import load, solve
from bilevel_kit.instance import from_dict
from bilevel_kit.models.relax import proven_bound
from bilevel_kit.validate import check


@pytest.mark.parametrize("trays", [1, 2, None])
@pytest.mark.parametrize("seed", range(4))
def test_lns_bound_is_proven_and_never_above_the_optimum(seed, trays):
    inst = from_dict(random_doc(seed, trays))
    opt, _ = best_makespan(inst)
    out = solve(inst, "lns", seed=seed, time_limit=20, iterations=30)
    assert out.plan is not None and check(inst, out.plan) == []
    assert out.bound is not None and out.bound <= opt + 1e-6
    assert out.bound <= out.objective + 1e-9
    assert out.bound == pytest.approx(proven_bound(inst, time_limit=30.0).value, abs=1e-6)
    assert out.extra["bound_source"] in out.extra["bound_sources"]
    if out.status == "optimal":  # only when the plan meets the proven bound
        assert out.objective == pytest.approx(out.bound, abs=1e-6)
    else:
        assert out.status == "feasible" and out.objective > out.bound


def test_lns_is_deterministic_at_a_fixed_number_of_windows(root):
    inst = load(root / "instances" / "hrc_table.json")
    opts = {"iterations": 6, "start": "quick", "window": 8}
    a = solve(inst, "lns", seed=3, time_limit=60, **opts)
    b = solve(inst, "lns", seed=3, time_limit=60, **opts)
    assert a.extra["stop"] in ("iterations", "local_optimum", "optimal")
    assert [k.tasks for k in a.plan.kits] == [k.tasks for k in b.plan.kits]
    assert a.extra["iterations"] == b.extra["iterations"]
    assert check(inst, a.plan) == []


def test_lns_improves_on_its_start_or_proves_it(root):
    inst = load(root / "instances" / "hrc_table.json")
    out = solve(inst, "lns", seed=0, time_limit=30, iterations=40, start="quick")
    assert out.objective <= out.extra["start_makespan"] + 1e-9
    assert out.extra["iterations"] >= 1


def test_lns_options_are_checked(tiny):
    from bilevel_kit import UsageError

    with pytest.raises(UsageError, match="lns"):
        solve(tiny, "lns", window=1)
    with pytest.raises(UsageError, match="lns"):
        solve(tiny, "lns", start="all")
    with pytest.raises(UsageError, match="cut_share"):
        solve(tiny, "lns", cut_share=1.5)


@pytest.mark.parametrize(
    ("share", "names"),
    [
        (0.0, ["single-task", "topological one-tray cut", "johnson one-tray cut"]),
        (
            0.25,
            [
                *("single-task", "topological one-tray cut", "topological fixed cut"),
                *("johnson one-tray cut", "johnson fixed cut"),
            ],
        ),
    ],
)
def test_the_cut_share_bounds_the_start_plans_cut_from_task_orders(root, share, names):
    """Option ``cut_share``: the fixed-size cuts run within it (none at 0; the exact one-tray
    cuts then take no fit probe); whole-assembly's plan does not fit this tray."""
    from bilevel_kit.models.budget import Budget
    from bilevel_kit.models.common import Packer
    from bilevel_kit.models.lns.fit import FastFit
    from bilevel_kit.models.lns.start import start_plans

    inst = load(root / "instances" / "kitbench" / "intree_n25_s1_t1_tight_d10.json")
    budget = Budget(60.0)
    fit = FastFit(inst, Packer(inst, 0.5, budget))
    plans = start_plans(inst, fit, budget, greedy=False, share=0.1, seed=0, cut_share=share)
    assert [name for name, _ in plans] == names
    every = sorted(t.id for t in inst.tasks)
    assert all(sorted(t for k in plan.kits for t in k.tasks) == every for _, plan in plans)


@pytest.mark.parametrize("trays", [1, 2, 3, None])
@pytest.mark.parametrize("seed", range(5))
def test_suffix_response_equals_the_timeline(seed, trays):
    """The window's objective: the suffix's max-plus response to the window's end state (both
    read off the evaluator's timeline, on the integer grid) is the evaluator's makespan, at
    every cut point."""
    import random

    from bilevel_kit.models.cpsat.scaling import scale_times
    from bilevel_kit.models.lns.state import tail_response
    from bilevel_kit.plan import Kit, Plan, evaluate

    inst = from_dict(random_doc(seed, trays, n=9))
    sc = scale_times(inst, 0.1, True)
    assert sc.exact  # every evaluated time is a whole number of steps, up to float sums
    rng = random.Random(seed)
    order = list(range(inst.n_tasks))
    cuts = sorted(rng.sample(range(1, len(order)), 4))
    kits = [order[a:b] for a, b in zip([0, *cuts], [*cuts, len(order)], strict=True)]
    ids = [t.id for t in inst.tasks]
    tl = evaluate(inst, Plan(tuple(Kit(tuple(ids[i] for i in k)) for k in kits)))
    for k1 in range(1, len(kits) + 1):
        last = tl.kits[k1 - 1]
        state = {"A": last.arrive / sc.res, "E": last.human_end / sc.res}
        state.update({f"HS{j}": tl.kits[k1 - j].human_start / sc.res for j in range(1, k1 + 1)})
        form = tail_response(sc, kits[k1:], k1)
        value = max(state[v] + c for v, c in form.items())
        # 1e-6 grid steps: far below one step, far above the float error of a few sums
        assert value == pytest.approx(tl.makespan / sc.res, abs=1e-6), (k1, form)


def test_window_packing_does_not_depend_on_the_clock(monkeypatch):
    """The windows' packing calls are limited by deterministic time: with a clock under which
    every wall-clock packing limit has passed, a window still packs the kit b + c that only
    CP-SAT lays out, and the run reaches the same optimum (170 s) as without it."""
    from slowclock import hard_instance, slow_packing_clock

    from bilevel_kit.models import packing_oracle

    inst = hard_instance()
    ends = []
    for slow in (False, True):
        packing_oracle.clear_cache()
        if slow:
            slow_packing_clock(monkeypatch)
        res = solve(inst, "lns", time_limit=30, iterations=6, start="quick")
        ends.append(res.objective)
    packing_oracle.clear_cache()
    assert ends == [pytest.approx(170.0)] * 2


def test_the_windows_learn_each_dff_proof_as_task_weights(root, monkeypatch):
    """A misfit that a pair of dual-feasible functions proves becomes one inequality over
    every task (:meth:`bilevel_kit.models.lns.window.Context.add_cut`): each task's weight is
    its parts' coefficients of :func:`~bilevel_kit.models.packing_bounds.dff_cut`, learnt once;
    the run's plan, on a tight tray where windows meet such misfits, passes the checker and
    every kit of it meets every inequality learnt."""
    from bilevel_kit.models import packing_bounds
    from bilevel_kit.models.lns import method as lns_method
    from bilevel_kit.models.lns import window

    inst = load(root / "instances" / "kitbench" / "mixed_u2_tu_tight_d0.json")
    made: list[window.Context] = []
    of = window.Context.of.__func__

    def capture(cls, *args, **kwargs):
        made.append(of(cls, *args, **kwargs))
        return made[-1]

    monkeypatch.setattr(window.Context, "of", classmethod(capture))
    opts = lns_method.LnsOptions(start="quick", iterations=12)
    out = lns_method.lns(inst, opts, seed=0, time_limit=120.0)
    assert out.plan is not None and check(inst, out.plan) == []
    (ctx,) = made
    assert ctx.dff_rows, "the windows met no misfit a dual-feasible pair proves"
    index = inst.index
    for weights, cap in ctx.dff_rows:
        assert len(weights) == len(inst.tasks)
        for kit in out.plan.kits:
            assert sum(weights[index[t]] for t in kit.tasks) <= cap
    # the same misfit again adds nothing; the weights are the parts' coefficients
    learnt = [dict(c) for c in ctx.cuts]
    proven = next(c for c in learnt if packing_bounds.dff_cut(ctx.grid_types, c, *ctx.grid_tray))
    coef, cap = packing_bounds.dff_cut(ctx.grid_types, proven, *ctx.grid_tray)
    weights = [sum(coef.get(t, 0) * n for t, n in parts.items()) for parts in ctx.parts]
    assert (weights, cap) in ctx.dff_rows
    rows = list(ctx.dff_rows)
    ctx._dff_row(proven)
    assert ctx.dff_rows == rows
