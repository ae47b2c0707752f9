"""Benchmark of ``bilevel-kit check`` on long chains: it must scale linearly.

For each size n it writes a chain of n tasks (t0 -> t1 -> ... , one 10 x 10 mm part each), its
single-task solution (n kits, with every time and metric), then times the parts of ``check``:
reading the instance (JSON, schema, semantics), reading the solution, and the checker itself.
The time per task should stay flat as n grows; a quadratic step shows as a rising column.

Usage: python bench/bench_check.py [--sizes 5000,20000,80000] [--repeats 3]
       [--out bench/results/check.csv]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchio import write_rows  # noqa: E402

from bilevel_kit import instance, solution, solve  # noqa: E402


def chain(n: int) -> dict:
    """A chain of ``n`` tasks: the shape of the 180,000-task file of issue 14."""
    return instance.document(
        f"chain{n}",
        [{"id": "a", "width": 10.0, "height": 10.0, "pick_time": 1.0}],
        [
            {"id": f"t{i}", "parts": [{"type": "a", "count": 1}], "human_time": {"mean": 2.0}}
            for i in range(n)
        ],
        precedence=[[f"t{i}", f"t{i + 1}"] for i in range(n - 1)],
    )


def measure(n: int, folder: Path) -> dict[str, float]:
    inst_path, sol_path = folder / f"chain{n}.json", folder / f"chain{n}_sol.json"
    inst_path.write_text(json.dumps(chain(n)))
    solution.write(sol_path, solve(instance.load(inst_path), "single-task"))
    t0 = time.perf_counter()
    inst = instance.load(inst_path)
    t1 = time.perf_counter()
    sol = solution.read(sol_path)
    t2 = time.perf_counter()
    found = sol.check(inst)
    t3 = time.perf_counter()
    assert not found, found[:3]
    return {"read_instance_s": t1 - t0, "read_solution_s": t2 - t1, "check_s": t3 - t2}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="5000,20000,80000")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(ROOT / "bench" / "results" / "check.csv"))
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in args.sizes.split(",")):
            runs = [measure(n, Path(tmp)) for _ in range(args.repeats)]
            row: dict[str, float | int] = {"n_tasks": n}
            for key in runs[0]:
                row[key] = statistics.median(r[key] for r in runs)
            total = sum(float(row[k]) for k in runs[0])
            row["total_s"] = total
            row["us_per_task"] = 1e6 * total / n
            rows.append(row)
            print(
                ", ".join(
                    f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()
                )
            )
    write_rows(args.out, rows)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
