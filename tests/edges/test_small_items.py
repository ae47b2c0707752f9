"""Issue 35, item 9, where a row of the edge table cannot say it: the status line of another
objective than the makespan, and a time limit shorter than the back-ends' imports."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from bilevel_kit import load, solve
from bilevel_kit.cli.solve import summary

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "instances" / "tiny.json"


def test_a_status_about_another_objective_stands_on_its_own_line() -> None:
    """ "optimal" never stands beside the makespan's bound and gap it is not about."""
    tiny = load(TINY)
    res = solve(tiny, "single-task")
    res = replace(
        res, status="optimal", objective_name="sum_completion", objective=25.0, bound=25.0, gap=0.0
    )
    lines = summary(tiny, res, True).splitlines()
    assert lines[0].startswith("tiny: single-task  makespan 25.50 s")
    assert "optimal" not in lines[0] and "makespan bound 24.50 s  makespan gap 3.92%" in lines[0]
    assert lines[-1] == "  sum_completion: optimal  25.00 s  bound 25.00 s  gap 0.00%"
    plain = summary(tiny, solve(tiny, "single-task"), True).splitlines()
    assert plain[0].startswith("tiny: single-task feasible  makespan") and len(plain) == 1


PROBE = """
import json, sys, time
from bilevel_kit import load, solve
inst = load({path!r})
t = time.perf_counter()
res = solve(inst, {method!r}, time_limit=1e-6)
print(json.dumps({{"wall": time.perf_counter() - t, "status": str(res.status),
    "method_wall": res.wall_time_s, "prepared": "prepare_s" in res.extra,
    "loaded": sorted(m for m in ("ortools", "pandas", "numba") if m in sys.modules)}}))
"""


@pytest.mark.parametrize(
    ("method", "status", "never"),
    [("milp", "feasible", ("ortools", "pandas")), ("bilevel-milp", "unknown", ())],
)
def test_a_spent_time_limit_loads_no_back_end(method, status, never) -> None:
    """``--time-limit 1e-6``: what ran before the limit was looked at was the import of
    OR-Tools with pandas (milp with HiGHS in a subprocess) or numba (bilevel-milp's lower
    level), 1-3 s each; now the method ends within T + max(2 s, 5 %) (slack for a busy
    machine). numba is loaded all the same, by the methods' prepare step, which compiles or
    loads greedy-ce's kernels before the clock starts (docs/scaling.md#first-run)."""
    code = PROBE.format(path=str(TINY), method=method)
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    assert got["status"] == status
    assert not set(never) & set(got["loaded"]), got
    assert got["prepared"], got  # the kernels were loaded outside the method's clock
    assert got["method_wall"] < 1e-6 + 2.0 + 3.0, got  # T + 2 s, plus 3 s of slack
