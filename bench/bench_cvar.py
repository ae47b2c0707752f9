"""The mean-optimal vs the CVaR(0.9)-optimal plan on the paper's table (issue 41, item 1;
docs/robust.md#planning-for-the-tail-cvar): 1 tray, cv 0.3, 20 scenarios of the OPTIMISE
stream of seed 0, ``lns`` with each time limit; both plans' mean and CVaR(0.9) of the makespan
on 1,000 scenarios of the independent EVALUATE stream (bilevel_kit/stochastic.py), and the
paired differences (CVaR plan less mean plan): the mean's Student-t interval, the CVaR's
bootstrap interval (2,000 resamples of the evaluation scenarios, seed 0).

``lns`` stops on the wall clock, so a row depends on the machine's load: each row records the
load average and the CPU count beside its numbers, and docs/robust.md's sentences
(:mod:`bilevel_kit.repro.robust_facts`) follow the row's statuses, not a typed outcome.

    PYTHONPATH=. python bench/bench_cvar.py [time_limit_s ...]   # default: 30 120
    PYTHONPATH=. python bench/bench_cvar.py --render            # the page only

writes bench/results/cvar.csv (one row per time limit) and renders docs/robust.md's CVaR
paragraph from it (the block ``robust:cvar``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from bilevel_kit import stochastic as st
from bilevel_kit.methods import solve
from bilevel_kit.repro.robust import study_instance

ALPHA, CV, SCENARIOS, SEED, EVALUATION = 0.9, 0.3, 20, 0, 1000
ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "bench" / "results" / "cvar.csv"
#: objective -> the CSV's column prefix
PREFIX = {"expected_makespan": "sa", "cvar_makespan": "cvar"}


def _plan_row(inst: Any, objective: str, time_limit: float) -> tuple[dict[str, Any], Any]:
    """One objective's ``lns`` plan: its status, whether it improved on the mean-value plan in
    sample, its in-sample and evaluation numbers; and its evaluation makespans."""
    ev = st.sample(inst, EVALUATION, SEED, cv=CV, stream=st.EVALUATE)
    opt = st.sample(inst, SCENARIOS, SEED, cv=CV, stream=st.OPTIMISE)
    extra = {"alpha": ALPHA} if objective == "cvar_makespan" else {}
    res = solve(
        inst, "lns", time_limit=time_limit, seed=SEED, check=True, objective=objective,
        scenarios=SCENARIOS, scenario_seed=SEED, cv=CV, **extra,
    )  # fmt: skip
    assert res.plan is not None and res.extra["violations"] == [], res.extra
    ins, out = st.makespans(inst, res.plan, opt), st.makespans(inst, res.plan, ev)
    m, p = st.estimate(out), PREFIX[objective]
    mean_plan = float(res.extra[f"mean_plan_{objective}"])
    row = {
        f"{p}_status": str(res.status),
        f"{p}_objective": round(float(res.objective), 3),
        f"{p}_mean_value_plan_objective": round(mean_plan, 3),
        f"{p}_improved": bool(res.objective < mean_plan - 1e-6),
        f"{p}_in_sample_mean": round(float(ins.mean()), 3),
        f"{p}_in_sample_cvar": round(st.cvar(ins, ALPHA), 3),
        f"{p}_eval_mean": round(m.mean, 3),
        f"{p}_eval_half": round(m.half, 3),
        f"{p}_eval_cvar": round(st.cvar(out, ALPHA), 3),
        f"{p}_kits": [list(k.tasks) for k in res.plan.kits],
    }
    return row, out


def run(time_limit: float) -> dict[str, Any]:
    """Both objectives' plans at ``time_limit`` and their paired differences (one CSV row)."""
    inst = study_instance("table", 1)
    row: dict[str, Any] = {"time_limit": time_limit, "load": round(os.getloadavg()[0], 1)}
    row |= {"cpus": os.cpu_count(), "alpha": ALPHA, "cv": CV, "scenarios": SCENARIOS}
    row |= {"evaluation": EVALUATION}
    sa_row, sa = _plan_row(inst, "expected_makespan", time_limit)
    cvar_row, tail = _plan_row(inst, "cvar_makespan", time_limit)
    d = st.paired(tail, sa)
    rng = np.random.default_rng(SEED)
    boot = []
    for _ in range(2000):
        i = rng.integers(0, EVALUATION, EVALUATION)
        boot.append(st.cvar(tail[i], ALPHA) - st.cvar(sa[i], ALPHA))
    low, high = np.percentile(boot, [2.5, 97.5])
    row |= sa_row | cvar_row
    row |= {"same_plan": sa_row["sa_kits"] == cvar_row["cvar_kits"]}
    row |= {"diff_mean": round(d.mean, 3), "diff_low": round(d.low, 3)}
    row |= {"diff_high": round(d.high, 3)}
    row |= {"diff_cvar": round(st.cvar(tail, ALPHA) - st.cvar(sa, ALPHA), 3)}
    row |= {"diff_cvar_low": round(float(low), 3), "diff_cvar_high": round(float(high), 3)}
    return row


def render() -> None:
    """docs/robust.md's CVaR paragraph rewritten from the CSV (tests/repro/test_robust_facts.py
    fails when they disagree)."""
    from bilevel_kit.repro.robust_facts import CVAR_PAGE, cvar_page

    now, want = cvar_page(ROOT)
    if now != want:
        (ROOT / CVAR_PAGE).write_text(want)
        print(f"rendered {CVAR_PAGE}")


def main(time_limits: list[float]) -> None:
    from benchio import write_rows

    rows = []
    for t in time_limits:
        rows.append(run(t))
        print({k: v for k, v in rows[-1].items() if not k.endswith("_kits")}, flush=True)
    print(f"wrote {write_rows(OUT, rows)}")
    render()


if __name__ == "__main__":
    if sys.argv[1:] == ["--render"]:
        render()
    else:
        main([float(a) for a in sys.argv[1:]] or [30.0, 120.0])
