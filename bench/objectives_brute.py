"""Every exact method x every registered objective x trays 1, 2, unlimited against the brute
force, on random two- and three-station instances (issue 35, item 1; the suite's smaller
version is tests/models/test_objectives_brute.py).

    python bench/objectives_brute.py --seeds 0 200 --tasks 6 --time-limit 60 > out.jsonl

One JSON line per (instance, objective, trays, method): the status, the value and the bound
the result states on its status objective, the brute force's optimum (tests/brute.py,
``station_optima``: a timeline of its own from docs/timeline.md) and the false claims found
(a value below the optimum, a bound above it, "optimal" above it). The last line counts them
per objective x trays x method.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "models")]

from brute import station_optima  # noqa: E402
from test_objectives_brute import false_claims, instance_doc  # noqa: E402

from bilevel_kit.instance import from_dict  # noqa: E402
from bilevel_kit.methods import solve  # noqa: E402
from bilevel_kit.objectives import MODEL_OBJECTIVES  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs=2, default=(0, 100))
    ap.add_argument("--stations", type=int, nargs="+", default=(2, 3))
    ap.add_argument("--tasks", type=int, default=5)
    ap.add_argument("--methods", nargs="+", default=("cpsat", "milp"))
    ap.add_argument("--time-limit", type=float, default=60.0)
    args = ap.parse_args()
    counts: Counter[str] = Counter()
    for seed in range(*args.seeds):
        for n_st in args.stations:
            for trays in (1, 2, None):
                inst = from_dict(instance_doc(seed, n_st, trays, args.tasks))
                opt = station_optima(inst)
                for objective in MODEL_OBJECTIVES:
                    for method in args.methods:
                        t0 = time.perf_counter()
                        res = solve(inst, method, time_limit=args.time_limit, objective=objective)
                        bad = [] if res.plan is None else false_claims(inst, res, opt)
                        key = f"{objective}/{trays}/{method}"
                        counts[f"{key}/runs"] += 1
                        counts[f"{key}/false"] += bool(bad)
                        row = {
                            "seed": seed,
                            "stations": n_st,
                            "trays": trays,
                            "objective": objective,
                            "method": method,
                            "status": res.status_text,
                            "optimum": opt[objective],
                            "false_claims": bad,
                            "time_s": round(time.perf_counter() - t0, 2),
                        }
                        print(json.dumps(row), flush=True)
    print(json.dumps(dict(sorted(counts.items()))), flush=True)


if __name__ == "__main__":
    main()
