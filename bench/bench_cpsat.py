"""Benchmark of the exact CP-SAT schedule (issue 4).

1. Time to proven optimum for the table at d in {0, 10, 30} s (goal: < 2 s each).
2. 1, 2, 5, 10 units of the table (up to 120 tasks): time to optimum, or the gap at the time
   limit (default 60 s), for both tray modes (goal: 10 units within 1 % gap in 60 s).

Writes bench/results/cpsat.csv and prints a Markdown table.
Run: python bench/bench_cpsat.py [--time-limit 60] [--workers 2] [--seed 0]

With ``--trays 1`` (issue 11, the study's one-tray protocol) it runs the one-tray suite
instead and writes bench/results/cpsat_trays.csv: the table in each tray mode (goal: proven
in < 2 s), 1, 2, 5, 10 units with Benders (goal: 10 units within 1 % in 60 s), greedy-ce's
gap to the one-tray optimum of the table, and the unlimited-tray rows of the table and of
1, 2, 10 units again (they must match bench/results/cpsat.csv).
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path
from typing import Any

from bilevel_kit.instance import Instance, load
from bilevel_kit.models import packing_oracle as cpsat_packing
from bilevel_kit.models.cpsat import solve
from bilevel_kit.models.exact import keys
from bilevel_kit.validate import check

ROOT = Path(__file__).resolve().parent.parent


def table_instance() -> Instance:
    """The paper's table, instances/hrc_table.json (docs/paper-data.md)."""
    return load(ROOT / "instances/hrc_table.json")


def run(inst: Instance, label: str, mode: str, args: argparse.Namespace) -> dict[str, Any]:
    """Solve one case (fresh packing cache) and return its row."""
    cpsat_packing.clear_cache()  # every row pays for its own packing
    t0 = time.perf_counter()
    out = solve(inst, tray=mode, time_limit=args.time_limit, workers=args.workers, seed=args.seed)
    wall = time.perf_counter() - t0
    valid = out.plan is not None and check(inst, out.plan) == []
    ex = out.extra
    benders = ex.get("tray_mode", mode) == "benders"
    return {
        "case": label,
        "tasks": inst.n_tasks,
        "trays": inst.trays if inst.trays is not None else "unlimited",
        "d": inst.delivery_time,
        "tray_mode": ex.get("tray_mode", mode),
        "status": out.status,
        "makespan": round(ex["makespan"], 4) if "makespan" in ex else "",
        "bound": round(out.bound, 4) if out.bound is not None else "",
        "gap_pct": round(100 * ex["gap"], 3) if ex.get("gap") is not None else "",
        "wall_time_s": round(wall, 2),
        "n_kits": ex.get("n_kits", ""),
        # the committed CSVs' column: the master solves of the Benders mode (embedded: 0)
        "benders_iterations": keys.read(ex, keys.MASTER_SOLVES) if benders else 0,
        "cuts": ex.get("cuts", ""),
        "time_resolution": ex.get("time_resolution"),
        "valid": valid,
        "time_limit": args.time_limit,
        "workers": args.workers,
        "seed": args.seed,
    }


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--time-limit", type=float, default=60.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--trays", type=int, default=None, help="run the one-tray suite (1)")
    args = ap.parse_args()
    table = table_instance()
    if args.trays is not None:
        args.out = args.out or ROOT / "bench/results/cpsat_trays.csv"
        write(tray_rows(table, args), args)
        return
    args.out = args.out or ROOT / "bench/results/cpsat.csv"
    rows = []
    for d in (0.0, 10.0, 30.0):
        for mode in ("auto", "embedded", "benders"):
            rows.append(run(table.with_overrides(delivery_time=d), f"table d={d:g}", mode, args))
            print(rows[-1], flush=True)
    for units in (1, 2, 5, 10):
        for mode in ("embedded", "benders"):
            rows.append(run(table.with_overrides(units=units), f"table x{units}", mode, args))
            print(rows[-1], flush=True)
    write(rows, args)


def tray_rows(table: Instance, args: argparse.Namespace) -> list[dict[str, Any]]:
    """The one-tray suite (module docstring)."""
    from bilevel_kit.methods import solve as method_solve

    one = table.with_overrides(trays=args.trays)
    rows = []
    for mode in ("auto", "embedded", "benders"):
        rows.append(run(one, "table", mode, args))
        print(rows[-1], flush=True)
    for units in (1, 2, 5, 10):
        rows.append(run(one.with_overrides(units=units), f"table x{units}", "benders", args))
        print(rows[-1], flush=True)
    optimum = rows[0]["makespan"]
    t0 = time.perf_counter()
    greedy = method_solve(one, "greedy-ce", seed=args.seed)
    rows.append(
        {
            "case": f"table greedy-ce (gap to the one-tray optimum {optimum})",
            "tasks": one.n_tasks,
            "trays": args.trays,
            "d": one.delivery_time,
            "tray_mode": "",
            "status": greedy.status,
            "makespan": round(greedy.makespan, 4),
            "bound": optimum,
            "gap_pct": round(100 * (greedy.makespan - optimum) / greedy.makespan, 3),
            "wall_time_s": round(time.perf_counter() - t0, 2),
            "n_kits": len(greedy.plan.kits),
        }
    )
    print(rows[-1], flush=True)
    free = table.with_overrides(trays="unlimited")
    for units in (1, 2, 10):
        for mode in ("embedded", "benders") if units < 10 else ("benders",):
            inst = free.with_overrides(units=units)
            rows.append(run(inst, f"table x{units}", mode, args))
            print(rows[-1], flush=True)
    return rows


def write(rows: list[dict[str, Any]], args: argparse.Namespace) -> None:
    """The CSV and a Markdown table on stdout."""
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]), restval="")
        w.writeheader()
        w.writerows(rows)
    cols = [
        "case",
        "tasks",
        "trays",
        "d",
        "tray_mode",
        "status",
        "makespan",
        "bound",
        "gap_pct",
        "wall_time_s",
        "n_kits",
        "benders_iterations",
        "cuts",
        "valid",
    ]
    print("\n| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join(str(r.get(c, "")) for c in cols) + " |")
    print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
