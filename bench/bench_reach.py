"""Benchmark of the Sawyer subpackage: reachability-map build time and IK success rate.

Run from the repository root: ``python bench/bench_reach.py [--repeats N] [--targets N]``.
Prints a table and writes ``bench/results/reach.csv`` (metric, value, unit, note).

* map build time (wall and CPU: CPU time does not grow with the machine's load): 600 x 400 mm
  tray at 10 mm = 60 x 40 cells, default work cell (goal < 2 s),
  and the same tray 900 mm ahead (partly reachable, the slow case: cells near the edge of the
  reach fail every seed);
* IK success rate over random *reachable* top-down targets: draw a uniform configuration,
  turn the tool straight down with the 5-D CLIK started there, and keep the tool point when
  that converges, so a top-down solution is known to exist; then solve it cold;
* the same for full 6-D poses of uniformly random configurations;
* time of one pick-and-place estimate.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="map builds to time")
    parser.add_argument("--targets", type=int, default=1000, help="random IK targets")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "reach.csv")
    args = parser.parse_args(argv)
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))

    import numpy as np

    import bilevel_kit.sawyer as sawyer
    from bilevel_kit.sawyer.ik import clik_down, converged

    rows: list[tuple[str, float, str, str]] = []

    def timed_maps(work_cell: sawyer.WorkCell, label: str) -> None:
        times, cpu, fraction = [], [], 0.0
        for _ in range(args.repeats):
            start = time.process_time()
            m = sawyer.build_reach_map(work_cell, 600.0, 400.0, 10.0)
            cpu.append(time.process_time() - start)
            times.append(m.build_time)
            fraction = m.fraction
        ny, nx = m.shape
        note = f"{nx} x {ny} cells, {args.repeats} runs"
        rows.append((f"map_build_median_{label}", statistics.median(times), "s", note))
        rows.append((f"map_build_max_{label}", max(times), "s", note))
        # CPU time does not grow with other processes on the machine, wall time does.
        rows.append((f"map_build_cpu_median_{label}", statistics.median(cpu), "s", note))
        rows.append((f"map_reachable_fraction_{label}", fraction, "", note))

    sawyer.build_reach_map(sawyer.DEFAULT_WORK_CELL, 60.0, 40.0, 10.0)  # import / warm-up
    timed_maps(sawyer.DEFAULT_WORK_CELL, "default")
    timed_maps(sawyer.WorkCell(tray_x=900.0), "tray_900mm_ahead")

    arm = sawyer.Arm(sawyer.DEFAULT_WORK_CELL.tool_offset_m)
    rng = np.random.default_rng(args.seed)
    targets: list[np.ndarray] = []
    while len(targets) < args.targets:
        q = rng.uniform(sawyer.Q_LOWER, sawyer.Q_UPPER)
        qd, pe, tilt = clik_down(arm, arm.position(q), q)
        if converged(pe, tilt):
            targets.append(arm.position(qd))
    ok, worst = 0, 0.0
    start = time.perf_counter()
    for p in targets:
        sol = sawyer.solve_top_down(arm, p, (0.0, 90.0, 180.0, -90.0))
        if sol is not None:
            ok += 1
            worst = max(worst, float(np.linalg.norm(arm.position(sol.q) - p)))
    elapsed = time.perf_counter() - start
    note = f"{args.targets} witnessed targets, cold start, tool offset {arm.tool_offset:g} m"
    rows.append(("ik_top_down_success_rate", ok / len(targets), "", note))
    rows.append(("ik_top_down_mean_time", 1000.0 * elapsed / len(targets), "ms", note))
    rows.append(("ik_top_down_worst_pos_err", 1000.0 * worst, "mm", note))

    n_pose = max(1, args.targets // 2)
    ok = 0
    start = time.perf_counter()
    for q in rng.uniform(sawyer.Q_LOWER, sawyer.Q_UPPER, size=(n_pose, 7)):
        if sawyer.solve_pose(arm, arm.fk(q)) is not None:
            ok += 1
    elapsed = time.perf_counter() - start
    note = f"{n_pose} poses of uniform random configurations"
    rows.append(("ik_pose_success_rate", ok / n_pose, "", note))
    rows.append(("ik_pose_mean_time", 1000.0 * elapsed / n_pose, "ms", note))

    slots = rng.uniform((0.0, 0.0), (600.0, 400.0), size=(200, 2))
    start = time.perf_counter()
    cycle = [sawyer.pick_place_time(sawyer.DEFAULT_WORK_CELL, "part", s) for s in slots]
    elapsed = time.perf_counter() - start
    note = "200 random slots on the default 600 x 400 mm tray, default bin"
    rows.append(("pick_place_time_call", 1000.0 * elapsed / len(slots), "ms", note))
    rows.append(("pick_place_cycle_min", min(cycle), "s", note))
    rows.append(("pick_place_cycle_max", max(cycle), "s", note))

    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["metric", "value", "unit", "note"])
        writer.writerows((name, f"{value:.6g}", unit, note) for name, value, unit, note in rows)
    width = max(len(r[0]) for r in rows)
    for name, value, unit, note in rows:
        print(f"{name:<{width}}  {value:10.4g} {unit:<3} {note}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
