"""Every exact method x every registered objective x trays 1, 2, unlimited against the brute
force, on random two- and three-station instances (issue 35, item 1; the suite's smaller
version is tests/models/test_objectives_brute.py).

    python bench/objectives_brute.py --seeds 0 200 --tasks 6 --time-limit 60 > out.jsonl

One JSON line per (instance, objective, trays, method): the status, the value and the bound
the result states on its status objective, the brute force's optimum (tests/brute.py,
``station_optima``: a timeline of its own from docs/timeline.md) and the false claims found
(a value below the optimum, a bound above it, "optimal" above it). ``--tray two`` gives every
task one part on a tray that holds two (``two_per_kit``), ``--tray mixed`` alternates the two
trays by seed; ``--regime long`` a fast robot and long human overheads (``fast_robot``: the
regime of issue 35's first-kit tray bug), ``mixed`` every other pair of seeds. The last line
counts them per objective x trays x method (``summarize``).

    python bench/objectives_brute.py --summarize out*.jsonl --results bench/results/objectives_brute

reads the JSON lines of one or more runs (a run cut short counts what it finished) and writes
the counts per objective x trays x method as CSV and Markdown (``.csv``, ``.md``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

from benchio import write_rows

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "models")]

from brute import station_optima  # noqa: E402
from test_objectives_brute import false_claims, instance_doc  # noqa: E402

from bilevel_kit.instance import from_dict  # noqa: E402
from bilevel_kit.methods import solve  # noqa: E402
from bilevel_kit.objectives import MODEL_OBJECTIVES  # noqa: E402


def summarize(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The counts of the JSON lines ``rows``: instances (seed, stations, tray, regime), runs,
    false claims and statuses per ``objective/trays/method``."""
    counts: Counter[str] = Counter()
    instances: Counter[tuple[Any, ...]] = Counter()
    for row in rows:
        instances[(row["seed"], row["stations"], row.get("tray"), row.get("long_overhead"))] += 1
        key = f"{row['objective']}/{row['trays']}/{row['method']}"
        counts[f"{key}/runs"] += 1
        counts[f"{key}/false"] += bool(row["false_claims"])
        counts[f"{key}/status/{row['status'].split(' ')[0]}"] += 1
    per_instance = 3 * len(MODEL_OBJECTIVES) * len({r["method"] for r in rows})
    return {
        "instances": len(instances),
        "complete_instances": sum(n == per_instance for n in instances.values()),
        "runs": len(rows),
        "false_claims": sum(bool(r["false_claims"]) for r in rows),
        "counts": dict(sorted(counts.items())),
    }


def rows_for(seed: int, n_st: int, tray: str, args: argparse.Namespace):
    """The JSON lines of one instance at every tray count, objective and method."""
    for trays in (1, 2, None):
        long = args.regime == "long" or (args.regime == "mixed" and seed // 2 % 2 == 1)
        inst = from_dict(instance_doc(seed, n_st, trays, args.tasks, tray, long))
        opt = station_optima(inst)
        for objective in MODEL_OBJECTIVES:
            for method in args.methods:
                t0 = time.perf_counter()
                res = solve(inst, method, time_limit=args.time_limit, objective=objective)
                bad = [] if res.plan is None else false_claims(inst, res, opt)
                value, bound = res.objective, res.bound  # the minimised objective's
                yield {
                    "seed": seed,
                    "stations": n_st,
                    "tray": tray,
                    "long_overhead": long,
                    "tasks": args.tasks,
                    "trays": trays,
                    "objective": objective,
                    "method": method,
                    "status": res.status_text,
                    "value": value,
                    "bound": bound,
                    "optimum": opt[objective],
                    "false_claims": bad,
                    "time_s": round(time.perf_counter() - t0, 2),
                }


def _status(row: dict[str, Any]) -> str:
    return str(row["status"]).split(" ")[0]


def write_results(paths: list[str], out: str, note: str = "") -> dict[str, Any]:
    """The counts of the run rows in the JSON-lines files ``paths`` (summary lines skipped)
    as ``out.csv`` and ``out.md`` (``note``: a paragraph after the header); the totals."""
    rows = [
        row
        for path in paths
        for line in Path(path).read_text().splitlines()
        if line.strip() and "seed" in (row := json.loads(line))
    ]
    total = summarize(rows)
    statuses = sorted({_status(r) for r in rows})
    table = []
    for objective in MODEL_OBJECTIVES:
        for trays in (1, 2, None):
            for method in sorted({r["method"] for r in rows}):
                cell = [
                    r
                    for r in rows
                    if (r["objective"], r["trays"], r["method"]) == (objective, trays, method)
                ]
                table.append(
                    {
                        "objective": objective,
                        "trays": "unlimited" if trays is None else trays,
                        "method": method,
                        "runs": len(cell),
                        "false_claims": sum(bool(r["false_claims"]) for r in cell),
                        **{s: sum(_status(r) == s for r in cell) for s in statuses},
                    }
                )
    write_rows(f"{out}.csv", table)
    seeds = sorted({r["seed"] for r in rows})
    head = [
        "# No false claim on any objective: cpsat and milp against the brute force",
        "",
        "Written by `python bench/objectives_brute.py --summarize` (module docstring) from "
        f"{len(paths)} run(s): {total['instances']} instances (seed x stations x tray x regime; "
        f"seeds {seeds[0]}..{seeds[-1]}), {total['complete_instances']} of them with every run "
        f"(trays 1, 2 and unlimited x objective x method), {total['runs']} runs, "
        f"{total['false_claims']} false "
        "claims. A false claim: a value below the brute force's optimum, a bound above it, or "
        '"optimal" above it (tests/models/test_objectives_brute.py, `false_claims`).',
        "",
        *([note, ""] if note else []),
    ]
    keys = list(table[0])
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(str(r[k]) for k in keys) + " |" for r in table]
    Path(f"{out}.md").write_text("\n".join(head + lines) + "\n")
    return total


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--summarize", nargs="+", metavar="JSONL")
    ap.add_argument("--results", default="bench/results/objectives_brute")
    ap.add_argument("--note", default="", help="a paragraph for the Markdown (--summarize)")
    ap.add_argument("--seeds", type=int, nargs=2, default=(0, 100))
    ap.add_argument("--stations", type=int, nargs="+", default=(2, 3))
    ap.add_argument("--tasks", type=int, default=5)
    ap.add_argument("--tray", choices=("binding", "two", "mixed"), default="binding")
    ap.add_argument("--regime", choices=("default", "long", "mixed"), default="default")
    ap.add_argument("--methods", nargs="+", default=("cpsat", "milp"))
    ap.add_argument("--time-limit", type=float, default=60.0)
    args = ap.parse_args()
    if args.summarize:
        print(json.dumps(write_results(args.summarize, args.results, args.note)))
        return
    rows = []
    for seed in range(*args.seeds):
        tray = ("binding", "two")[seed % 2] if args.tray == "mixed" else args.tray
        for n_st in args.stations:
            for row in rows_for(seed, n_st, tray, args):
                rows.append(row)
                print(json.dumps(row), flush=True)
    print(json.dumps(summarize(rows)), flush=True)


if __name__ == "__main__":
    main()
