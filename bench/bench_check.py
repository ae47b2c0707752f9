"""Benchmark of ``bilevel-kit check``: it must scale linearly, in plans and in kits.

Chains (``--sizes``): for each size n it writes a chain of n tasks (t0 -> t1 -> ... , one
10 x 10 mm part each), its single-task solution (n kits, with every time and metric), then
times the parts of ``check``: reading the instance (JSON, schema, semantics), reading the
solution, and the checker itself. The time per task should stay flat as n grows; a quadratic
step shows as a rising column.

Dense kits (``--parts``): one task whose kit holds n parts of 10 x 6 mm, each in its own
12 mm cell of a square tray, at angles 0, 30, 45, 90 degrees (so the overlap test meets
rotated neighbours that touch nothing): a valid solution. Each size runs ``bilevel-kit check``
in a child process and records its wall time and peak memory (the overlap test used to build
every pair: 16 s and 2.5 GB at 8,000 parts, no allocation at 30,000).

Usage: python bench/bench_check.py [--sizes 5000,20000,80000] [--parts 8000,30000]
       [--repeats 3] [--out bench/results/check.csv]
       [--parts-out bench/results/check_parts.csv]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
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


def dense_kit(n: int) -> tuple[dict, dict]:
    """An instance with one task of ``n`` parts and its valid one-kit solution (docstring)."""
    from bilevel_kit.methods import Result, Status
    from bilevel_kit.plan import Kit, Placement, Plan, evaluate
    from bilevel_kit.validate import timeline_params

    side = math.ceil(math.sqrt(n))
    cell = 12.0  # a 10 x 6 mm part (diagonal 11.7 mm) turns freely inside its cell
    doc = instance.document(
        f"dense{n}",
        [{"id": "p", "width": 10.0, "height": 6.0, "pick_time": 1.0}],
        [{"id": "t", "parts": [{"type": "p", "count": n}], "human_time": {"mean": 2.0}}],
        tray=(side * cell, side * cell),
    )
    layout = tuple(
        Placement(
            f"t:p:{j + 1}",
            "p",
            (j % side + 0.5) * cell,
            (j // side + 0.5) * cell,
            (0.0, 30.0, 45.0, 90.0)[j % 4],
            10.0,
            6.0,
        )
        for j in range(n)
    )
    inst = instance.from_dict(doc, f"dense{n}")
    plan = Plan((Kit(("t",), layout),))
    timeline = evaluate(inst, plan)
    result = Result(
        "bench",
        Status.FEASIBLE,
        plan,
        timeline,
        timeline.makespan,
        None,
        None,
        0.0,
        0,
        {},
        inst.name,
        timeline_params=timeline_params(inst),
    )
    return doc, solution.result_to_dict(result)


def measure_parts(n: int, folder: Path) -> dict[str, float | int]:
    """``bilevel-kit check`` on the dense kit of ``n`` parts, in a child process: its wall
    time (s) and peak resident memory (MB)."""
    inst_path, sol_path = folder / f"dense{n}.json", folder / f"dense{n}_sol.json"
    doc, sol = dense_kit(n)
    inst_path.write_text(json.dumps(doc))
    sol_path.write_text(json.dumps(sol))
    code = (
        "import resource, sys, time; from bilevel_kit.cli import main; t = time.perf_counter(); "
        "rc = main(['check', sys.argv[1], sys.argv[2]]); "
        "print(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss); "
        "sys.exit(rc)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(inst_path), str(sol_path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]
    wall, rss_kb = out.stdout.split()[-2:]
    return {"n_parts": n, "check_s": float(wall), "peak_rss_mb": int(rss_kb) / 1024}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="5000,20000,80000")
    ap.add_argument("--parts", default="8000,30000")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(ROOT / "bench" / "results" / "check.csv"))
    ap.add_argument("--parts-out", default=str(ROOT / "bench" / "results" / "check_parts.csv"))
    args = ap.parse_args()
    if args.parts:
        with tempfile.TemporaryDirectory() as tmp:
            part_rows = []
            for n in (int(s) for s in args.parts.split(",")):
                runs = [measure_parts(n, Path(tmp)) for _ in range(args.repeats)]
                part_rows.append(
                    {
                        "n_parts": n,
                        "check_s": statistics.median(float(r["check_s"]) for r in runs),
                        "peak_rss_mb": max(float(r["peak_rss_mb"]) for r in runs),
                    }
                )
                print(
                    ", ".join(
                        f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                        for k, v in part_rows[-1].items()
                    )
                )
            write_rows(args.parts_out, part_rows)
            print(f"wrote {args.parts_out}")
    if not args.sizes:
        return
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
