"""A long chain checks completely (its time against size is measured by bench/bench_check.py,
not in a unit test)."""

from __future__ import annotations

import json
import sys
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
