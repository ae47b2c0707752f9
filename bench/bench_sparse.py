"""greedy-ce on sparse wide graphs, before and after (issue 27, item 3; docs/scaling.md).

The generator's ``sparse`` family (each task has a one-in-five chance of an arc to a task up
to 40 positions later, 6 part types), seed 1, no delivery time, unlimited trays, the tray of
KitBench's ``sparse_n1000_s1_tu_tight_d0`` at every size (tightness 166.7 at 1,000 tasks,
scaled with the size); the 1,000-task instance is that KitBench instance. Each case runs in
a fresh child process, OLD (another checkout, ``--old-code``, with its interpreter
``--old-python``) and NEW (this checkout) alternating case by case, so both see the same
load. A row: wall time of the solve alone, its CPU time, the child's peak resident memory
(``ru_maxrss``, imports and compiled kernels included), with ``--tracemalloc`` also the peak
of Python allocations during the solve (it slows the solve: a second child, not timed), the
makespan, kits, the closed-form bound and the gap to it, and a digest of the
plan (kits, their tasks and layouts to 1e-6 mm/deg): the same digest is the same plan. The
load average at the start of each case is recorded.

``--limit T`` runs greedy-ce with that time limit instead (its plan is then the gap to
compare: a faster heuristic gets further before its remaining kits are single tasks).

Writes bench/results/sparse.csv (``--out``) and the same rows as a table in sparse.md. Usage:
python bench/bench_sparse.py --old-code OLD_CHECKOUT [--old-python PY] [--sizes 250 500 1000]
[--rounds 1] [--limit 10] [--tracemalloc] [--versions old new] [--out FILE] [--append]
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from benchio import write_rows

ROOT = Path(__file__).resolve().parent.parent
SRC = Path(__file__).resolve().parent

CHILD = r"""
import hashlib, json, resource, sys, time, tracemalloc
sys.path.insert(0, sys.argv[1])
from bilevel_kit import load, solve
inst = load(sys.argv[2])
limit = None if sys.argv[3] == "none" else float(sys.argv[3])
memory = sys.argv[4] == "memory"
solve(load(sys.argv[1] + "/instances/hrc_table.json"), "greedy-ce", seed=0)  # compiled kernels
if memory:
    tracemalloc.start()
t0, c0 = time.perf_counter(), time.process_time()
res = solve(inst, "greedy-ce", seed=0, time_limit=limit)
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
peak = tracemalloc.get_traced_memory()[1] if memory else 0
plan = [[list(k.tasks), [[p.part, round(p.x, 6), round(p.y, 6), round(p.theta, 6)]
                          for p in k.layout]] for k in res.plan.kits]
print(json.dumps({
    "tasks": inst.n_tasks, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
    "makespan": res.makespan, "bound": res.makespan_bound, "kits": len(res.plan.kits),
    "time_limit_hit": res.extra["time_limit_hit"], "epoch_F_sum": res.extra["epoch_F_sum"],
    "plan_sha": hashlib.sha256(json.dumps(plan).encode()).hexdigest()[:16],
    "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
    "py_peak_mb": round(peak / 2**20, 1),
}))
"""


def write_instance(size: int, path: Path) -> None:
    """The sparse instance of ``size`` tasks (module docstring), as KitBench names it."""
    sys.path.insert(0, str(ROOT))
    from bilevel_kit.generate import generate

    doc = generate(
        "sparse",
        size,
        seed=1,
        tightness=round(166.7 * size / 1000, 4),
        delivery_time=0.0,
        trays="unlimited",
        name=f"sparse_n{size}_s1_tu_tight_d0",
    )
    path.write_text(json.dumps(doc))


def run_case(python: str, code: Path, inst: Path, limit: float | None, memory: bool) -> dict:
    """One solve in a fresh child; with ``memory`` the Python peak comes from a second one."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    load = round(os.getloadavg()[0], 2)
    lim = "none" if limit is None else str(limit)
    row: dict[str, Any] = {"load_avg": load}
    for mode in ("plain", "memory") if memory else ("plain",):
        cmd = [python, "-c", CHILD, str(code), str(inst), lim, mode]
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
        if out.returncode != 0:
            tail = (out.stderr.strip().splitlines() or ["?"])[-1]
            return {**row, "error": tail[:200]}
        got = json.loads(out.stdout.strip().splitlines()[-1])
        if mode == "plain":
            row.update({k: v for k, v in got.items() if k != "py_peak_mb"})
        else:
            row["py_peak_mb"] = got["py_peak_mb"]
            row["same_plan_under_tracemalloc"] = got["plan_sha"] == row["plan_sha"]
    bound = row.get("bound")
    if bound:
        row["gap_pct"] = round(100 * (row["makespan"] - bound) / bound, 2)
    return row


def write_markdown(rows: list[dict[str, Any]], path: Path) -> Path:
    """The rows as a short table beside the CSV, OLD and NEW of a case on adjacent lines."""
    lines = [
        "# greedy-ce on sparse wide graphs, before and after",
        "",
        "Written by `python bench/bench_sparse.py` (module docstring: instances, columns).",
        "A peak RSS near 300 MB is a child that compiled kernels in its warm-up (sources "
        "changed since numba cached them); the solve itself is timed after it.",
        "",
        "| tasks | limit (s) | code | wall (s) | CPU (s) | peak RSS (MB) | makespan | kits "
        "| gap to bound (%) | plan digest | load |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    def key(r: dict[str, Any]) -> tuple[int, str, str, str]:
        return int(r["size"]), str(r.get("limit_s") or ""), str(r["rep"]), r["code"]

    for r in sorted(rows, key=key):
        cells = [r["size"], r.get("limit_s") or "none", r["code"]]
        cells += [r.get(k, "") for k in ("wall_s", "cpu_s", "peak_rss_mb", "makespan", "kits")]
        cells += [r.get("gap_pct", ""), r.get("plan_sha", r.get("error", "")), r["load_avg"]]
        lines.append("| " + " | ".join(str(c) for c in cells) + " |")
    path.write_text("\n".join(lines) + "\n")
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-code", type=Path, required=True, help="the checkout before")
    ap.add_argument("--old-python", default=sys.executable, help="its interpreter")
    ap.add_argument("--sizes", type=int, nargs="+", default=[250, 500, 1000])
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--limit", type=float, help="greedy-ce's time limit (s); default none")
    ap.add_argument("--tracemalloc", action="store_true", help="also the Python peak (a child)")
    ap.add_argument("--out", type=Path, default=ROOT / "bench/results/sparse.csv")
    ap.add_argument("--append", action="store_true", help="keep the rows already in --out")
    ap.add_argument(
        "--versions", nargs="+", default=["old", "new"], choices=["old", "new"], help="run these"
    )
    args = ap.parse_args()
    versions = [
        v
        for v in (("old", args.old_python, args.old_code), ("new", sys.executable, ROOT))
        if v[0] in args.versions
    ]
    rows: list[dict[str, Any]] = []
    if args.append and args.out.exists():  # short runs, one CSV (the machine is shared)
        with open(args.out, newline="") as fh:
            rows.extend(csv.DictReader(fh))
    with tempfile.TemporaryDirectory() as tmp:
        for size in sorted(args.sizes):
            inst = Path(tmp) / f"sparse_{size}.json"
            write_instance(size, inst)
            for rep in range(args.rounds):
                for code, python, path in versions:
                    memory = args.tracemalloc and args.limit is None
                    row = run_case(python, path, inst, args.limit, memory)
                    row = {"code": code, "size": size, "rep": rep, "limit_s": args.limit, **row}
                    print(row, flush=True)
                    rows.append(row)
    for size in sorted(args.sizes):
        got = {r["code"]: r for r in rows if r["size"] == size and r["rep"] == 0}
        got = {k: v for k, v in got.items() if v.get("limit_s") == args.limit}
        if "wall_s" in got.get("old", {}) and "wall_s" in got.get("new", {}):
            old, new = got["old"], got["new"]
            same = old["plan_sha"] == new["plan_sha"] and old["makespan"] == new["makespan"]
            print(
                f"{size} tasks: {old['wall_s']:.1f} s -> {new['wall_s']:.1f} s, "
                f"gap {old.get('gap_pct', math.nan)} % -> {new.get('gap_pct', math.nan)} %, "
                f"same plan: {same}"
            )
    print(f"wrote {write_rows(args.out, rows)}")
    print(f"wrote {write_markdown(rows, args.out.with_suffix('.md'))}")


if __name__ == "__main__":
    main()
