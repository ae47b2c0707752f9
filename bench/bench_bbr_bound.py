"""The ideal search's speed against a baseline commit, side by side in one run.

Run from the repository root: ``python bench/bench_bbr_bound.py [--baseline REV] [--reps N]
[--expansions N]``. Each repetition runs, for each KitBench record below, the search of
``bbr`` (``bilevel_kit.models.bbr.search.search``, the packing oracle with its deterministic
limit, from the record's best-known makespan as the first upper bound) for a fixed number of
expansions, once with this checkout's code and once with ``REV``'s (a temporary
``git worktree``), alternately, each in a fresh process, so that the shared machine's load
falls on both alike. The two must report the same counters (the search is deterministic at a
fixed expansion count); the table gives each side's median wall time and their ratio. Writes
bench/results/bbr_bound.csv (one row per run) and bbr_bound.md.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from benchio import write_rows

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
RECORDS = ("table_u5_t1_tight_d10", "mixed_u2_tu_tight_d0", "sparse_n25_s2_t1_tight_d30")

#: One search in a fresh process: prints its wall time and counters as JSON.
CHILD = """
import json, sys, time
from bilevel_kit import load
from bilevel_kit.experiments.kitbench.library import Library
from bilevel_kit.models.bbr.search import packer_fits, search
from bilevel_kit.models.bbr.space import Space
from bilevel_kit.models.budget import Budget
from bilevel_kit.models.common import Packer

name, expansions, library = sys.argv[1], int(sys.argv[2]), sys.argv[3]
inst = load(f"{library}/{name}.json")
upper = {r.instance: r for r in Library.at(library).read()}[name].best_known
packer = Packer(inst, 2.0, Budget(3600.0), deterministic=True)
t0 = time.perf_counter()
out = search(Space(inst), packer_fits(packer), upper=upper, max_expansions=expansions)
wall = time.perf_counter() - t0
print(json.dumps({"wall_s": wall, "bound": out.bound, **out.counters}))
"""


def run_one(code: Path, name: str, expansions: int) -> dict[str, object]:
    """One search with the package at ``code``, in its own process."""
    library = str(ROOT / "instances" / "kitbench")
    done = subprocess.run(
        [sys.executable, "-c", CHILD, name, str(expansions), library],
        capture_output=True,
        text=True,
        check=True,
        cwd=code,
        env={**os.environ, "PYTHONPATH": str(code)},
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="HEAD~1", help="the commit to compare against")
    parser.add_argument("--reps", type=int, default=3, help="repetitions (default 3)")
    parser.add_argument("--expansions", type=int, default=300, help="nodes expanded per run")
    args = parser.parse_args()
    rows: list[dict[str, object]] = []
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "baseline"
        subprocess.run(
            ["git", "worktree", "add", "--detach", "-q", str(base), args.baseline],
            cwd=ROOT,
            check=True,
        )
        try:
            for rep in range(args.reps):
                for name in RECORDS:
                    for side, code in (("baseline", base), ("this", ROOT)):
                        got = run_one(code, name, args.expansions)
                        rows.append({"record": name, "side": side, "rep": rep, **got})
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT)
    write_rows(RESULTS / "bbr_bound.csv", rows)
    lines = [
        f"Ideal search, {args.expansions} expansions, baseline {args.baseline}, "
        f"{args.reps} repetitions (median wall time)",
        "",
        "| record | expanded | generated | baseline (s) | this (s) | ratio | same counters |",
        "|---|---:|---:|---:|---:|---:|---|",
    ]
    keys = ("expanded", "generated", "kept", "dominated", "oracle", "bound")
    for name in RECORDS:
        mine = [r for r in rows if r["record"] == name]
        walls = {
            s: statistics.median(float(r["wall_s"]) for r in mine if r["side"] == s)
            for s in ("baseline", "this")
        }
        same = len({tuple(r[k] for k in keys) for r in mine}) == 1
        lines.append(
            f"| {name} | {mine[0]['expanded']} | {mine[0]['generated']} | "
            f"{walls['baseline']:.2f} | {walls['this']:.2f} | "
            f"{walls['baseline'] / walls['this']:.1f} | {'yes' if same else 'no'} |"
        )
    (RESULTS / "bbr_bound.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
