"""The mean-optimal vs the CVaR(0.9)-optimal plan on the paper's table (issue 41, item 1;
docs/robust.md#planning-for-the-tail-cvar): 1 tray, cv 0.3, 20 scenarios of the OPTIMISE
stream of seed 0, ``lns`` 30 s each; both plans' mean and CVaR(0.9) of the makespan on 1,000
scenarios of the independent EVALUATE stream (bilevel_kit/stochastic.py), and the paired
differences (CVaR plan less mean plan): the mean's Student-t interval, the CVaR's bootstrap
interval (2,000 resamples of the evaluation scenarios, seed 0).

    PYTHONPATH=. python bench/bench_cvar.py [time_limit_s]
"""

from __future__ import annotations

import sys

import numpy as np

from bilevel_kit import stochastic as st
from bilevel_kit.methods import solve
from bilevel_kit.repro.robust import study_instance

ALPHA, CV, SCENARIOS, SEED, EVALUATION = 0.9, 0.3, 20, 0, 1000


def main(time_limit: float = 30.0) -> None:
    inst = study_instance("table", 1)
    ev = st.sample(inst, EVALUATION, SEED, cv=CV, stream=st.EVALUATE)
    opt = st.sample(inst, SCENARIOS, SEED, cv=CV, stream=st.OPTIMISE)
    common = {"scenarios": SCENARIOS, "scenario_seed": SEED, "cv": CV}
    evaluated = []
    for objective in ("expected_makespan", "cvar_makespan"):
        extra = {"alpha": ALPHA} if objective == "cvar_makespan" else {}
        res = solve(
            inst, "lns", time_limit=time_limit, seed=SEED, check=True,
            objective=objective, **common, **extra,
        )  # fmt: skip
        assert res.plan is not None and res.extra["violations"] == [], res.extra
        ins = st.makespans(inst, res.plan, opt)
        out = st.makespans(inst, res.plan, ev)
        m = st.estimate(out)
        evaluated.append(out)
        head = f"{objective}: status {res.status}, stated {res.objective:.3f}"
        model = f"bound {res.bound}, mean plan {res.extra.get(f'mean_plan_{objective}')}"
        print(
            f"{head} ({model}, {res.extra.get('saa_status')}), "
            f"in-sample mean {ins.mean():.3f} CVaR {st.cvar(ins, ALPHA):.3f}; "
            f"evaluation mean {m.mean:.3f} +- {m.half:.3f}, CVaR(0.9) {st.cvar(out, ALPHA):.3f}, "
            f"max {out.max():.3f}, kits {[k.tasks for k in res.plan.kits]}"
        )
    mean_plan, cvar_plan = evaluated
    d = st.paired(cvar_plan, mean_plan)
    rng = np.random.default_rng(0)
    boot = []
    for _ in range(2000):
        i = rng.integers(0, EVALUATION, EVALUATION)
        boot.append(st.cvar(cvar_plan[i], ALPHA) - st.cvar(mean_plan[i], ALPHA))
    low, high = np.percentile(boot, [2.5, 97.5])
    print(f"CVaR plan - mean plan: mean {d.mean:.3f} [{d.low:.3f}, {d.high:.3f}]")
    diff = st.cvar(cvar_plan, ALPHA) - st.cvar(mean_plan, ALPHA)
    print(f"CVaR(0.9) {diff:.3f} [{low:.3f}, {high:.3f}]")


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 30.0)
