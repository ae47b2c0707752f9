"""Benchmark of greedy-ce at scale: wall time and peak memory by family and size.

Families: ``table``, ``mixed``, ``intree``, ``series-parallel`` (``bilevel-kit generate``) and
``wide``: tasks without precedence, one part type, robot times given per task (built here,
since ``generate`` has no such family). Sizes are tasks (units for ``table``/``mixed``:
12 tasks per table unit, the size is divided accordingly). Each case runs in a fresh
subprocess under ``/usr/bin/time -f "%e %M"`` (wall seconds and peak resident set of the
child, also when it is stopped at the per-case time cap ``--timeout``); ``wall_s`` is the
solve alone (without imports and loading), ``cpu_s`` its process CPU time (less sensitive to
a busy machine), ``process_s`` the whole child. ``--code`` runs another checkout's package (a
before/after comparison with the same script). The growth exponent
of each family is the least-squares slope of log(wall_s) on log(tasks) over the finished cases.
The CPU's load average at the start of each case is recorded (the machine may be shared).

Writes bench/results/greedy_scale.csv. Usage:
python bench/bench_greedy_scale.py [--sizes 12 60 120 500 1000] [--families ...]
[--timeout 120] [--out bench/results/greedy_scale.csv]
[--against OTHER_CHECKOUT --rounds 3]  (before/after, alternating case by case)
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_scale import slope as scale_slope
from bench_scale import write_instance  # the scale benchmark's families
from benchio import write_rows

ROOT = Path(__file__).resolve().parent.parent
FAMILIES = ("table", "mixed", "intree", "series-parallel", "wide")

CHILD = r"""
import json, sys, time, resource
sys.path.insert(0, sys.argv[1])
from bilevel_kit import load, solve
inst = load(sys.argv[2])
t0, c0 = time.perf_counter(), time.process_time()
res = solve(inst, "greedy-ce", seed=0, check=True)
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
e = res.extra
print(json.dumps({
    "tasks": inst.n_tasks, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
    "makespan": res.makespan,
    "kits": len(res.plan.kits), "valid": e["violations"] == [],
    **{k: e[k] for k in ("prefix_sets", "evaluated", "beam_epochs", "rest_capped",
                         "ce_calls", "time_limit_hit")},
}))
"""


def make_instance(family: str, size: int, path: Path) -> None:
    # whole units as this benchmark has always sized them: size // 12 tables, size // 30 mixed
    divisor = {"table": 12, "mixed": 30}.get(family)
    write_instance(family, size if divisor is None else max(1, size // divisor), path)


def run_case(family: str, size: int, timeout: float, code: Path = ROOT) -> dict[str, object]:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "inst.json"
        make_instance(family, size, path)
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
        timing = Path(tmp) / "time.txt"
        load = round(os.getloadavg()[0], 2)
        cmd = ["/usr/bin/time", "-f", "%e %M", "-o", str(timing)]
        cmd += ["timeout", str(timeout), sys.executable, "-c", CHILD, str(code), str(path)]
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
        lines = timing.read_text().split("\n") if timing.exists() else []
        rows = [ln.split() for ln in lines if ln and ln[0].isdigit()]
        elapsed, peak_kb = (float(rows[-1][0]), float(rows[-1][1])) if rows else (math.nan, 0.0)
        if out.returncode == 0:
            row: dict[str, object] = json.loads(out.stdout.strip().splitlines()[-1])
        elif out.returncode == 124:
            row = {"wall_s": math.inf, "error": f"stopped at the {timeout:g} s cap"}
        else:
            tail = (out.stderr.strip().splitlines() or ["?"])[-1]
            row = {"wall_s": math.nan, "error": tail[:200]}
        row["process_s"] = elapsed
        row["peak_rss_mb"] = round(peak_kb / 1024, 1)
        row["load_avg"] = load
    return {"family": family, "size": size, **row}


def slope(rows: list[dict[str, object]]) -> float:
    """The log-log slope of wall time against task count over the rows with a finite time."""
    return scale_slope(
        [
            (float(r["tasks"]), float(r["wall_s"]))
            for r in rows
            if "tasks" in r and math.isfinite(float(r["wall_s"]))
        ]
    )


def side_by_side(args: argparse.Namespace) -> None:
    """Before/after on a shared machine: the two checkouts alternate case by case, so both
    see the same load; the medians are printed, every run is written."""
    rows: list[dict[str, object]] = []
    for rep in range(args.rounds):
        for fam in args.families:
            for size in sorted(args.sizes):
                for code, path in (("against", args.against), ("this", args.code)):
                    row = {"code": code, "rep": rep, **run_case(fam, size, args.timeout, path)}
                    print(row, flush=True)
                    rows.append(row)
    for fam in args.families:
        for size in sorted(args.sizes):
            med = {
                code: statistics.median(
                    float(r["cpu_s"])
                    for r in rows
                    if r["family"] == fam and r["size"] == size and r["code"] == code
                )
                for code in ("against", "this")
            }
            print(f"{fam} {size}: cpu s {med['against']:.3f} (against) -> {med['this']:.3f}")
    print(f"wrote {write_rows(args.out, rows)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[12, 60, 120, 500, 1000])
    ap.add_argument("--families", nargs="+", default=list(FAMILIES), choices=FAMILIES)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--out", type=Path, default=ROOT / "bench/results/greedy_scale.csv")
    ap.add_argument(
        "--code",
        type=Path,
        default=ROOT,
        help="checkout whose bilevel_kit runs (e.g. a worktree of an older commit)",
    )
    ap.add_argument(
        "--against",
        type=Path,
        help="another checkout: run every case alternately with it and with --code, "
        "--rounds times, and write one row per run (column code: 'this' or 'against')",
    )
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    if args.against is not None:
        side_by_side(args)
        return
    rows: list[dict[str, object]] = []
    for fam in args.families:
        fam_rows = []
        for size in sorted(args.sizes):  # increasing sizes: ru_maxrss grows with them
            row = run_case(fam, size, args.timeout, args.code)
            print(row, flush=True)
            fam_rows.append(row)
        k = slope(fam_rows)
        for row in fam_rows:
            row["time_exponent"] = round(k, 2) if math.isfinite(k) else ""
        rows.extend(fam_rows)
    print(f"wrote {write_rows(args.out, rows)}")


if __name__ == "__main__":
    main()
