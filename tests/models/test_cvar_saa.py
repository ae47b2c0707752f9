"""CVaR of the makespan (docs/formulations.md#cvar-of-the-makespan, issue 41 item 1): the
closed form equals Rockafellar-Uryasev's minimum over eta, alpha = 0 is the sample average,
CVaR >= mean >= the mean-time makespan (Jensen) plan by plan, the exact CVaR model equals a
brute force over plans on the same scenarios (test_saa_brute.py's), and ``lns -p
objective=cvar_makespan`` states the evaluator's value and passes the checker."""

from __future__ import annotations

import numpy as np
import pytest
import strategies
from brute import fits, segmentations

from bilevel_kit import stochastic as st
from bilevel_kit.instance import from_dict
from bilevel_kit.plan import Kit, Plan, evaluate

pytest.importorskip("ortools")

#: The model rounds scenario times down on a 1 ms grid: n tasks x 1 ms per scenario at most.
TOL = 0.01


def ru(values: np.ndarray, alpha: float) -> float:
    """Rockafellar-Uryasev's minimum over eta, taken over the values (the piecewise linear
    function of eta has its minimum at one of them)."""
    n = len(values)
    return min(
        eta + np.maximum(values - eta, 0).sum() / ((1 - alpha) * n) for eta in values.tolist()
    )


@pytest.mark.parametrize("alpha", [0.0, 0.1, 0.5, 0.75, 0.9, 0.93, 0.99])
@pytest.mark.parametrize("n", [1, 4, 5, 7, 20])
def test_cvar_equals_rockafellar_uryasev(alpha, n):
    rng = np.random.default_rng(n)
    v = rng.lognormal(3, 0.4, n)
    assert st.cvar(v, alpha) == pytest.approx(ru(v, alpha), rel=1e-12)
    assert st.cvar(v, alpha) >= v.mean() - 1e-12
    assert st.cvar(v, alpha) <= v.max() + 1e-12


def test_cvar_by_hand_and_at_the_ends():
    v = np.array([1.0, 2.0, 3.0, 4.0, 10.0])
    assert st.cvar(v, 0.0) == v.mean()  # the sample average, the same float
    assert st.cvar(v, 0.6) == pytest.approx((10 + 4) / 2)  # the worst 2 of 5
    assert st.cvar(v, 0.7) == pytest.approx((10 + 0.5 * 4) / 1.5)  # 1.5 of 5: fractional
    assert st.cvar(v, 0.8) == pytest.approx(10.0)
    assert st.cvar(v, 0.95) == pytest.approx(10.0)
    for bad in (-0.1, 1.0, float("nan")):
        with pytest.raises(ValueError, match="alpha must be in"):
            st.cvar(v, bad)


def cvar_brute(inst, scenarios, alpha) -> float:
    """The least CVaR over every valid plan; asserts CVaR >= mean >= mean-time makespan."""
    means = st.mean_times(scenarios, inst)
    best = np.inf
    for kits in segmentations(inst):
        if not all(fits(inst, k) for k in kits):
            continue
        plan = Plan(tuple(Kit(k) for k in kits))
        values = st.makespans(inst, plan, scenarios)
        value = st.cvar_makespan(inst, plan, scenarios, alpha)
        assert value >= values.mean() - 1e-9
        assert values.mean() >= evaluate(inst, plan, human_times=means).makespan - 1e-9
        best = min(best, value)
    return best


def instance(seed: int, trays: int | None):
    doc = strategies.random_doc(seed, 5)
    if trays is not None:
        doc["trays"] = trays
    return from_dict(doc)


def check_case(seed: int, trays: int | None, n: int, alpha: float, cv: float = 0.4) -> None:
    from bilevel_kit.models.cpsat.saa import solve_saa

    inst = instance(seed, trays)
    scenarios = st.sample(inst, n, seed, cv=cv)
    opt = cvar_brute(inst, scenarios, alpha)
    out = solve_saa(inst, scenarios, time_limit=60, alpha=alpha)
    assert out.proven, out.info
    assert out.value == pytest.approx(opt, abs=TOL), (seed, trays, out.info)
    assert out.value >= opt - 1e-9  # a plan cannot beat the brute force
    assert out.bound is not None and out.bound <= opt + 1e-9
    plan = Plan(tuple(Kit(k) for k in out.kits or ()))
    assert st.cvar_makespan(inst, plan, scenarios, alpha) == pytest.approx(out.value)


# 5 tasks, 4-6 scenarios, trays 1, 2 and unlimited; (1 - alpha) S integer and not
CASES = [(0, 1, 4, 0.75), (1, 2, 5, 0.9), (2, None, 6, 0.5), (4, 1, 6, 0.7)]


@pytest.mark.parametrize(("seed", "trays", "n", "alpha"), CASES)
def test_cvar_model_equals_the_brute_force(seed, trays, n, alpha):
    check_case(seed, trays, n, alpha)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(5, 15))
@pytest.mark.parametrize("trays", [1, 2, None])
def test_cvar_model_equals_the_brute_force_many(seed, trays):
    """30 more random cases, S in 4..6, alpha 0.6 / 0.8 / 0.9."""
    check_case(seed, trays, 4 + seed % 3, (0.6, 0.8, 0.9)[seed % 3])


def test_cvar_at_alpha_0_is_the_sample_average_model():
    from bilevel_kit.models.cpsat.saa import solve_saa

    inst = instance(3, 1)
    scenarios = st.sample(inst, 5, 3, cv=0.4)
    mean = solve_saa(inst, scenarios, time_limit=60)
    zero = solve_saa(inst, scenarios, time_limit=60, alpha=0.0)
    assert mean.proven and zero.proven
    assert zero.value == mean.value
    assert zero.bound == pytest.approx(mean.bound, abs=1e-9)


def test_lns_cvar_states_the_evaluators_value_and_passes_the_checker():
    from bilevel_kit.methods import solve

    inst = instance(2, 1)
    res = solve(
        inst,
        "lns",
        time_limit=6,
        check=True,
        objective="cvar_makespan",
        alpha=0.8,
        scenarios=5,
        cv=0.3,
    )
    assert res.status_objective == "cvar_makespan"
    assert res.plan is not None and res.extra["violations"] == [], res.extra
    scenarios = st.sample(inst, 5, 0, cv=0.3, stream=st.OPTIMISE)
    assert res.objective == pytest.approx(st.cvar_makespan(inst, res.plan, scenarios, 0.8))
    assert res.objective <= res.extra["mean_plan_cvar_makespan"] + 1e-9
    assert res.objective >= st.expected_makespan(inst, res.plan, scenarios) - 1e-9
    assert res.extra["alpha"] == 0.8
    # a 5-task instance: the CVaR model proves its plan within the time limit
    assert str(res.status) == "optimal", res.extra
    assert res.bound is not None and res.objective - TOL <= res.bound <= res.objective + 1e-9


@pytest.mark.parametrize("alpha", ["1", "-0.5", "x"])
def test_a_bad_alpha_is_a_one_line_exit_2(alpha, capsys, tmp_path, root):
    from bilevel_kit.cli import main

    out = tmp_path / "out.json"
    table = str(root / "instances/hrc_table.json")
    argv = ["solve", table, "-m", "lns", "-p", "objective=cvar_makespan", "-p", f"alpha={alpha}"]
    code = main([*argv, "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "alpha" in err and "Traceback" not in err
    assert not out.exists()
