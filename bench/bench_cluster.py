"""Benchmark of the cell runner's executors on the Figure 6 grid (issue 16, docs/cluster.md).

The paper's grid (MAT x MTTF in {30, 60, 90, 120} s plus the no-delay reference: 17 cells,
10 tables per run, the paper's CE, ``--reps`` replications per policy) is run three ways:
in this process, on a ``LocalCluster`` of 2 worker processes (``--jobs 2``) and on an external
cluster (a ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1). Each mode
writes one row: sweep wall time, the cells' own time (the simulations' wall times each record
keeps), and the overhead per cell ``(wall x workers - sum of cell times) / cells``. The
cluster's start-up is timed apart. Then 500 empty cells measure Dask's per-task cost alone.

The timing model is the default one (no calibration): the cells cost the same, and the
benchmark is about where they run, not about the numbers.

Writes bench/results/cluster.csv. Run: python bench/bench_cluster.py [--reps 30]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from benchio import write_rows

from bilevel_kit.experiments.cells import DaskExecutor, SerialExecutor, run_sweep
from bilevel_kit.repro.common import CONDITIONS, DEFAULT_INSTANCE, FIG6_GRID, participant_seeds
from bilevel_kit.repro.fig6 import Fig6Cell, fig6_cell
from bilevel_kit.sim import TimingModel

ROOT = Path(__file__).resolve().parent.parent
N_EMPTY = 500


@dataclass(frozen=True)
class Empty:
    """A cell that does nothing: what is left of its time is the executor's."""

    i: int

    def key(self) -> str:
        return f"empty{self.i}"


def empty(cell: Empty) -> dict[str, Any]:
    return {"i": cell.i}


def grid(reps: int) -> list[Fig6Cell]:
    common: dict[str, Any] = {
        "instance": str(DEFAULT_INSTANCE),
        "seeds": tuple(participant_seeds(0, reps)),
        "policies": CONDITIONS,
        "timing": asdict(TimingModel()),
    }
    cells = [Fig6Cell(mat=None, mttf=None, **common)]
    return cells + [Fig6Cell(mat=a, mttf=b, **common) for a in FIG6_GRID for b in FIG6_GRID]


def start_cluster(folder: Path) -> tuple[str, list[subprocess.Popen[bytes]]]:
    """A scheduler and two single-threaded workers on 127.0.0.1 (stop them by PID)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    sfile = folder / "scheduler.json"
    log = open(folder / "cluster.log", "wb")  # noqa: SIM115 - open for the processes' lives
    procs = [
        subprocess.Popen(
            [
                *(sys.executable, "-m", "distributed.cli.dask_scheduler"),
                *("--host", "127.0.0.1", "--port", "0", "--no-dashboard"),
                *("--scheduler-file", str(sfile)),
            ],
            env=env,
            stdout=log,
            stderr=log,
        )
    ]
    while not sfile.exists() or not sfile.read_text().strip():
        time.sleep(0.1)
    address = json.loads(sfile.read_text())["address"]
    procs += [
        subprocess.Popen(
            [
                *(sys.executable, "-m", "distributed.cli.dask_worker", address),
                *("--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"),
            ],
            env=env,
            cwd=ROOT,
            stdout=log,
            stderr=log,
        )
        for _ in range(2)
    ]
    return address, procs


def measure(mode: str, workers: int, executor: Any, cells: list[Any], fn: Any) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        records, report = run_sweep(cells, fn, cell_dir=tmp, executor=executor, progress=True)
    assert report.failed == 0, [r["error"] for r in records if r.get("status") == "error"]
    cell_s = sum(sum(r.get("wall_s", {}).values()) for r in records)
    n = len(cells)
    return {
        "mode": mode,
        "workers": workers,
        "cells": n,
        "wall_s": round(report.wall_s, 3),
        "sum_cell_s": round(cell_s, 3),
        "mean_cell_s": round(cell_s / n, 4),
        "overhead_per_cell_s": round((report.wall_s * workers - cell_s) / n, 4),
        "speedup": None,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--reps", type=int, default=30, help="replications per cell (paper: 30)")
    args = ap.parse_args()
    cells = grid(args.reps)
    empties = [Empty(i) for i in range(N_EMPTY)]
    rows = [{**measure("in-process", 1, SerialExecutor(), cells, fig6_cell), "startup_s": 0.0}]
    t0 = time.perf_counter()
    local = DaskExecutor(jobs=2)
    local.client()
    startup = time.perf_counter() - t0
    try:
        rows.append({**measure("jobs-2", 2, local, cells, fig6_cell), "startup_s": startup})
        rows.append({**measure("jobs-2 empty", 2, local, empties, empty), "startup_s": startup})
    finally:
        local.close()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        address, procs = start_cluster(Path(tmp))
        ext = DaskExecutor(scheduler=address)
        ext.client().wait_for_workers(2, timeout=60)
        startup = time.perf_counter() - t0
        try:
            rows.append({**measure("external-2", 2, ext, cells, fig6_cell), "startup_s": startup})
            rows.append(
                {**measure("external-2 empty", 2, ext, empties, empty), "startup_s": startup}
            )
        finally:
            ext.close()
            for p in reversed(procs):
                os.kill(p.pid, signal.SIGTERM)
                p.wait(timeout=30)
    serial = rows[0]["wall_s"]
    for r in rows:
        r["reps"] = args.reps if "empty" not in r["mode"] else 0
        if "empty" not in r["mode"]:
            r["speedup"] = round(serial / r["wall_s"], 2)
        else:  # no cell time: the wall time per cell is the executor's throughput cost
            r["overhead_per_cell_s"] = round(r["wall_s"] / r["cells"], 5)
        r["startup_s"] = round(r["startup_s"], 2)
    out = write_rows(ROOT / "bench" / "results" / "cluster.csv", rows)
    print(out.read_text())


if __name__ == "__main__":
    main()
