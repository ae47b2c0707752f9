"""A long chain checks completely and in linear time (bench/bench_check.py measures it)."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

from bench_check import chain  # noqa: E402

from bilevel_kit import instance, solution, solve  # noqa: E402
from bilevel_kit.cli import main  # noqa: E402
from bilevel_kit.validate import check  # noqa: E402


def test_a_20000_task_chain_is_checked_completely(tmp_path, capsys):
    inst_path, sol_path = tmp_path / "chain.json", tmp_path / "sol.json"
    inst_path.write_text(json.dumps(chain(20_000)))
    solution.write(sol_path, solve(instance.load(inst_path), "single-task"))
    assert main(["check", str(inst_path), str(sol_path)]) == 0
    assert "valid: 20000 kits, 20000 tasks" in capsys.readouterr().out
    doc = json.loads(sol_path.read_text())
    doc["kits"][-1]["human_end"] += 1  # one tampered time at the very end is still found
    sol = solution.from_dict(doc)
    found = check(instance.load(inst_path), sol.plan, reported_kits=sol.reported_kits)
    assert [v.message for v in found] == [
        "kit 20000: reported human_end 60004 s, evaluator gives 60003 s"
    ]


def _check_time(n: int) -> float:
    inst = instance.from_dict(chain(n))
    sol = solution.from_dict(solution.result_to_dict(solve(inst, "single-task")))
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        check(inst, sol.plan, reported_kits=sol.reported_kits, claims=sol.claims)
        best = min(best, time.perf_counter() - t0)
    return best


def test_check_scales_linearly():
    # 4x the tasks: about 4x the time when linear, 16x when quadratic; 8x leaves room for noise
    assert _check_time(4_000) < 8 * _check_time(1_000)
