"""Scale benchmark: every registered method x instance family x size at one time limit.

Families: ``table`` and ``mixed`` (units of the paper's products, 12 and 26 tasks per unit;
the size is divided accordingly), ``intree`` and ``series-parallel`` (``bilevel-kit generate
FAMILY --size N --seed 1``) and ``wide``: N tasks without precedence, one part type, robot
times given per task (built here, ``generate`` has no such family). Each case runs in a fresh
subprocess under ``/usr/bin/time -f "%e %M"`` (wall seconds and peak resident set of the
child); ``wall_s`` is the method call alone (``Result.wall_time_s``: without imports,
loading, evaluation and the checker), ``with_check_s`` the ``solve(..., check=True)`` call,
``process_s`` the whole child, ``peak_rss_mb`` its peak memory. A method that refuses the size (a
``UsageError``, exit 2 on the command line) is recorded as ``refused`` with its message. A
hard cap (``3 T + 60`` s) stops a runaway case (``stopped``). The CPU's load average at the
start of each case is recorded (the machine may be shared).

``--johnson`` instead measures the Johnson special case (one part type, d = 0, no overheads,
no precedence, unlimited trays; random integer times) for cpsat and milp at 20/50/200 tasks.

``--plot`` reads the CSV and writes the log-log figure (time and memory against tasks per
method) and a Markdown table with the growth exponents (least-squares slope of log time and
log memory on log tasks over the cases that ran).

Usage: python bench/bench_scale.py [--time-limit 10] [--sizes ...] [--families ...]
[--methods ...] [--out bench/results/scale.csv]; python bench/bench_scale.py --plot;
python bench/bench_scale.py --johnson
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import random
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench/results"
FAMILIES = ("table", "mixed", "intree", "series-parallel", "wide")
#: The methods of the committed scale table (the default set; every registered method can be
#: named with --methods, e.g. lns and bbr)
METHODS = ("single-task", "whole-assembly", "greedy-ce", "cpsat", "milp", "bilevel-milp")
sys.path.insert(0, str(ROOT))
from bilevel_kit.methods import method_names  # noqa: E402  (the registry, plugins included)

ALL_METHODS = tuple(method_names())
PER_UNIT = {"table": 12, "mixed": 26}

CHILD = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
from bilevel_kit import load, solve
from bilevel_kit.errors import UsageError
inst = load(sys.argv[2])
t0 = time.perf_counter()
try:
    res = solve(inst, sys.argv[3], seed=0, time_limit=float(sys.argv[4]), check=True)
except UsageError as exc:
    print(json.dumps({"tasks": inst.n_tasks, "status": "refused", "error": str(exc)}))
    sys.exit(2)
wall = time.perf_counter() - t0
e = res.extra
print(json.dumps({
    "tasks": inst.n_tasks, "wall_s": round(res.wall_time_s, 3),
    "with_check_s": round(wall, 3), "status": str(res.status),
    "status_objective": res.objective_name, "objective": res.makespan,
    "bound": res.makespan_bound, "gap": res.makespan_gap,
    "valid": None if res.plan is None else e["violations"] == [],
    "kits": None if res.plan is None else len(res.plan.kits),
    "note": e.get("reason", "") or e.get("solver_status") or "",
}))
"""


def _independent(
    name: str,
    tray: tuple[float, float],
    delivery: float,
    part: tuple[str, float, float, float],
    tasks: list[tuple[int, float, float]],
    **more: object,
) -> dict[str, object]:
    """A document of tasks without precedence on one part type ``part`` (id, width, height,
    pick time), each task (part count, robot time, human time); ``more``: other sections."""
    pid, width, height, pick = part
    return {
        "format": "bilevel-kit/1",
        "name": name,
        "tray": {"width": tray[0], "height": tray[1]},
        "delivery_time": delivery,
        **more,
        "part_types": [{"id": pid, "width": width, "height": height, "pick_time": pick}],
        "tasks": [
            {
                "id": f"t{j}",
                "parts": [{"type": pid, "count": count}],
                "robot_time": robot,
                "human_time": {"mean": human},
            }
            for j, (count, robot, human) in enumerate(tasks)
        ],
    }


def wide_instance(n: int, seed: int) -> dict[str, object]:
    """n tasks without precedence, one part type, robot times given per task."""
    rng = random.Random(seed)
    tasks = [
        (rng.randint(1, 3), float(rng.randint(3, 30)), float(rng.randint(5, 40))) for _ in range(n)
    ]
    return _independent(f"wide_n{n}_s{seed}", (300.0, 200.0), 2.0, ("part", 40.0, 30.0, 3.0), tasks)


def johnson_instance(n: int, seed: int) -> dict[str, object]:
    """The Johnson special case: F2||Cmax is exact (bilevel_kit/bounds.py, bound (d))."""
    rng = random.Random(seed)
    tasks = [(1, float(rng.randint(1, 30)), float(rng.randint(1, 30))) for _ in range(n)]
    return _independent(
        f"johnson_n{n}_s{seed}",
        (100.0, 100.0),
        0.0,
        ("p", 10.0, 10.0, 1.0),
        tasks,
        kit_overhead={"robot": 0.0, "human": 0.0},
    )


def make_instance(family: str, size: int, path: Path) -> None:
    write_instance(
        family, max(1, round(size / PER_UNIT[family])) if family in PER_UNIT else size, path
    )


def write_instance(family: str, arg: int, path: Path) -> None:
    """The instance of ``family`` with ``arg`` tasks (units for table and mixed) at ``path``:
    ``wide`` built here, the others by ``bilevel-kit generate`` (``--seed 1`` for the random
    families)."""
    if family == "wide":
        path.write_text(json.dumps(wide_instance(arg, 1)))
        return
    seed = [] if family in PER_UNIT else ["--seed", "1"]
    cmd = [sys.executable, "-m", "bilevel_kit.cli", "generate", family, "--size", str(arg)]
    subprocess.run(
        [*cmd, *seed, "--out", str(path)],
        check=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
    )


def run_case(path: Path, method: str, time_limit: float) -> dict[str, object]:
    with tempfile.TemporaryDirectory() as tmp:
        timing = Path(tmp) / "time.txt"
        load = round(os.getloadavg()[0], 2)
        cap = 3 * time_limit + 60
        cmd = ["/usr/bin/time", "-f", "%e %M", "-o", str(timing), "timeout", str(cap)]
        cmd += [sys.executable, "-c", CHILD, str(ROOT), str(path), method, str(time_limit)]
        env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
        out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
        lines = timing.read_text().split("\n") if timing.exists() else []
        rows = [ln.split() for ln in lines if ln and ln[0].isdigit()]
        elapsed, peak_kb = (float(rows[-1][0]), float(rows[-1][1])) if rows else (math.nan, 0.0)
        if out.returncode in (0, 2) and out.stdout.strip():
            row: dict[str, object] = json.loads(out.stdout.strip().splitlines()[-1])
        elif out.returncode == 124:
            row = {"status": "stopped", "error": f"stopped at the {cap:g} s cap"}
        else:
            tail = (out.stderr.strip().splitlines() or ["?"])[-1]
            row = {"status": "error", "error": tail[:300]}
        row["process_s"] = elapsed
        row["peak_rss_mb"] = round(peak_kb / 1024, 1)
        row["load_avg"] = load
    return row


def read_rows(path: Path) -> list[dict[str, str]]:
    if not path.exists():
        return []
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


FIELDS = [
    "family", "size", "tasks", "method", "time_limit", "status", "status_objective",
    "objective", "bound", "gap", "valid", "kits", "wall_s", "with_check_s", "process_s",
    "peak_rss_mb",
    "load_avg", "note", "error",
]  # fmt: skip


def run_grid(args: argparse.Namespace) -> None:
    done = {(r["family"], r["size"], r["method"]) for r in read_rows(args.out)}
    new = not args.out.exists()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("a", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        if new:
            w.writeheader()
        for fam in args.families:
            for size in sorted(args.sizes):
                with tempfile.TemporaryDirectory() as tmp:
                    path = Path(tmp) / "inst.json"
                    make_instance(fam, size, path)
                    for method in args.methods:
                        if (fam, str(size), method) in done:
                            continue
                        row = {"family": fam, "size": size, "method": method}
                        row |= {"time_limit": args.time_limit}
                        row |= run_case(path, method, args.time_limit)
                        print(row, flush=True)
                        w.writerow(row)
                        fh.flush()


def run_johnson(args: argparse.Namespace) -> None:
    out = RESULTS / "scale_johnson.csv"
    with out.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["tasks", "seed", "method", *FIELDS[5:]],
                           extrasaction="ignore")  # fmt: skip
        w.writeheader()
        for n in (20, 50, 200):
            for seed in range(3):
                with tempfile.TemporaryDirectory() as tmp:
                    path = Path(tmp) / "inst.json"
                    path.write_text(json.dumps(johnson_instance(n, seed)))
                    for method in ("cpsat", "milp"):
                        row = {"tasks": n, "seed": seed, "method": method, "time_limit": 60.0}
                        row |= run_case(path, method, 60.0)
                        print(row, flush=True)
                        w.writerow(row)
    print(f"wrote {out}")


def slope(points: list[tuple[float, float]]) -> float:
    pts = [(math.log(x), math.log(y)) for x, y in points if x > 0 and y > 0]
    if len(pts) < 2:
        return math.nan
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    den = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / den if den else math.nan


def plot(args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = read_rows(args.out)
    ran = [r for r in rows if r.get("wall_s") not in ("", None) and r["status"] != "refused"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    lines = ["| method | time exponent | memory exponent | max wall (s) | max peak RSS (MB) "
             "| refused sizes |", "|---|---|---|---|---|---|"]  # fmt: skip
    for method in ALL_METHODS:
        mine = [r for r in ran if r["method"] == method]
        if not mine:
            continue
        pts_t = [(float(r["tasks"]), float(r["wall_s"])) for r in mine]
        pts_m = [(float(r["tasks"]), float(r["peak_rss_mb"])) for r in mine]
        axes[0].scatter(*zip(*pts_t, strict=True), label=method, s=14)
        axes[1].scatter(*zip(*pts_m, strict=True), label=method, s=14)
        refused = sorted(
            {
                int(r["tasks"] or r["size"])
                for r in rows
                if r["method"] == method and r["status"] == "refused"
            }
        )
        lines.append(
            f"| {method} | {slope(pts_t):.2f} | {slope(pts_m):.2f} "
            f"| {max(p[1] for p in pts_t):.1f} | {max(p[1] for p in pts_m):.0f} "
            f"| {', '.join(map(str, refused)) or '-'} |"
        )
    for ax, what in zip(axes, ("wall time of the call (s)", "peak RSS (MB)"), strict=True):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("tasks")
        ax.set_ylabel(what)
        ax.grid(True, which="both", alpha=0.3)
    axes[1].axhline(2048, color="k", lw=0.8, ls="--")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(RESULTS / "scale.png", dpi=120)
    table = ["| family | tasks | method | status | objective | bound | gap | wall (s) | "
             "peak RSS (MB) | note |", "|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in rows:

        def num(key: str, fmt: str, r: dict[str, str] = r) -> str:
            v = r.get(key)
            return format(float(v), fmt) if v not in (None, "", "None") else "-"

        note = (r.get("error") or r.get("note") or "").replace("|", "/")[:90]
        table.append(
            f"| {r['family']} | {r['tasks'] or r['size']} | {r['method']} | {r['status']} "
            f"| {num('objective', '.1f')} | {num('bound', '.1f')} | {num('gap', '.2%')} "
            f"| {num('wall_s', '.2f')} | {num('peak_rss_mb', '.0f')} | {note} |"
        )
    (RESULTS / "scale.md").write_text(
        "# Scale benchmark (bench/bench_scale.py)\n\n"
        + "Growth exponents: least-squares slope of log(wall time) and log(peak RSS) on "
        + "log(tasks) over the cases that ran.\n\n"
        + "\n".join(lines)
        + "\n\n## Every case\n\n"
        + "\n".join(table)
        + "\n"
    )
    print("wrote bench/results/scale.png and scale.md")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[12, 60, 120, 500, 1000])
    ap.add_argument("--families", nargs="+", default=list(FAMILIES), choices=FAMILIES)
    ap.add_argument("--methods", nargs="+", default=list(METHODS), choices=ALL_METHODS)
    ap.add_argument("--time-limit", type=float, default=10.0)
    ap.add_argument("--out", type=Path, default=RESULTS / "scale.csv")
    ap.add_argument("--plot", action="store_true", help="only write the figure and table")
    ap.add_argument("--johnson", action="store_true", help="the Johnson special case")
    args = ap.parse_args()
    if args.johnson:
        run_johnson(args)
    elif args.plot:
        plot(args)
    else:
        run_grid(args)


if __name__ == "__main__":
    main()
