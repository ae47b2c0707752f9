"""Rerun the reproduction, copy its summary CSVs and figures into the repository, record the
run times in results/timing.csv and render the documents (paper_repro/README.md, "Rerunning").

python paper_repro/rerun.py [--only calibration,user_study,...] [--jobs 2] [--fresh]

Steps, in order: calibration (the one calibration every other step reads: run it first, its
CSVs are copied before the next step starts), user_study, fig6, fig6_cached (the same command
again, every cell saved: what a rerun costs), fig6_r100, fig6_cpsat, horizon, adaptive,
stations, robust, robust_kitbench, robust_sim.
``--fresh`` deletes a step's output folder first, so its time is a full rerun. Each step runs
``python -m bilevel_kit.cli repro ...`` in a subprocess; its wall time, the load average
before and after and the date are written to results/timing.csv (one row per step, replaced
when the step reruns).
"""

from __future__ import annotations

import argparse
import csv
import datetime as dt
import io
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"
FIGURES = ROOT / "docs" / "figures"
sys.path.insert(0, str(ROOT))  # a plain checkout works too

#: step -> (arguments after `repro`, output folder, {file in it: name in results/ or figures/})
#: the stations study's lines, one figure each (docs/stations.md)
LINE_FIGURES = ("table", "stool", "chair", "mix")
STEPS: dict[str, tuple[list[str], str, dict[str, str]]] = {
    "calibration": (
        ["calibrate"],
        "out/repro/calibration",
        {f: f for f in ("calibration.csv", "calibration_targets.csv", "calibration_bootstrap.csv")},
    ),
    "user_study": (
        ["user-study"],
        "out/repro/user_study",
        {
            **{
                f"user_study_{x}.csv": f"user_study_{x}.csv"
                for x in (
                    "predictions",
                    "parameters",
                    "summary",
                    "within",
                    "sensitivity",
                    "model_sensitivity",
                )
            },
            "fig5_top.png": "figures/fig5_top.png",
        },
    ),
    "fig6": (
        ["fig6"],
        "out/repro/fig6",
        {
            **{
                f"fig6_{x}.csv": f"fig6_{x}.csv"
                for x in ("cells", "improvements", "verdicts", "trends")
            },
            "fig6.png": "figures/fig6.png",
        },
    ),
    "fig6_cached": (["fig6"], "out/repro/fig6", {}),
    "fig6_r100": (
        ["fig6", "--reps", "100"],
        "out/repro/fig6_r100",
        # its trends with the replications' t-test (df = R - 1; paper_repro/README.md)
        {f"fig6_{x}.csv": f"fig6_r100_{x}.csv" for x in ("improvements", "verdicts", "trends")},
    ),
    "fig6_cpsat": (
        ["fig6", "--with-cpsat", "--reps", "10"],
        "out/repro/fig6_cpsat",
        {f"fig6_{x}.csv": f"fig6_cpsat_{x}.csv" for x in ("improvements", "verdicts")},
    ),
    "horizon": (
        ["horizon"],
        "out/repro/horizon",
        {
            "horizon.csv": "horizon.csv",
            "horizon_window.csv": "horizon_window.csv",
            "horizon.png": "figures/horizon.png",
        },
    ),
    "adaptive": (["adaptive"], "out/repro/adaptive", {"adaptive.csv": "adaptive.csv"}),
    "stations": (
        ["stations"],
        "out/repro/stations",
        {
            "stations.csv": "stations.csv",
            "stations_served.csv": "stations_served.csv",
            **{f"stations_{x}.png": f"figures/stations-{x}.png" for x in LINE_FIGURES},
        },
    ),
    "robust": (
        ["robust"],
        "out/repro/robust",
        {"robust.csv": "robust.csv", "robust.png": "figures/robust.png"},
    ),
    "robust_kitbench": (
        ["robust-kitbench"],
        "out/repro/robust_kitbench",
        {"robust_kitbench.csv": "robust_kitbench.csv"},
    ),
    "robust_sim": (["robust-sim"], "out/repro/robust_sim", {"robust_sim.csv": "robust_sim.csv"}),
}
COLUMNS = (
    "run",
    "command",
    "wall_s",
    "jobs",
    "cells",
    "computed",
    "load_start",
    "load_end",
    "cpus",
    "measured",
    "detail",
)


def _load() -> str:
    return f"{os.getloadavg()[0]:.1f}"


def _detail(folder: Path) -> dict[str, object]:
    """The run's cell counts and per-policy simulation seconds, from its JSON summary."""
    found = sorted(folder.glob("*.json"))
    if not found:
        return {}
    res = json.loads(found[0].read_text())
    detail: dict[str, object] = {}
    if res.get("simulation_wall_s"):
        detail["sim_s"] = {k: round(v, 1) for k, v in res["simulation_wall_s"].items()}
        if res.get("rows") and "units" in res:
            detail["tables"] = len(res["rows"]) * res.get("reps", 0) * res["units"]
    return {"cells": res.get("cells", ""), "computed": res.get("computed", ""), "detail": detail}


def run_step(name: str, jobs: int, fresh: bool) -> dict[str, object]:
    """Run one step, copy its files; returns its timing row."""
    args, out, copies = STEPS[name]
    folder = ROOT / out
    if fresh and name != "fig6_cached" and folder.exists():
        shutil.rmtree(folder)
    argv = ["repro", *args, "--jobs", str(jobs), "--out", out]
    load0, t0 = _load(), time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "bilevel_kit.cli", *argv, "-q"],
        cwd=ROOT,
        check=True,
        stdout=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - t0
    for src, dst in copies.items():
        target = FIGURES / dst.split("/", 1)[1] if dst.startswith("figures/") else RESULTS / dst
        shutil.copyfile(folder / src, target)
    drawn = [dst.split("/", 1)[1] for dst in copies.values() if dst.startswith("figures/")]
    if drawn:  # record the redrawn figures' digests (docs/figures.md, committed figures)
        stamp = [sys.executable, str(FIGURES / "regenerate.py"), "--stamp", *drawn]
        subprocess.run(stamp, cwd=ROOT, check=True)
    info = _detail(folder)
    return {
        "run": name,
        "command": "bilevel-kit " + " ".join(argv[:-2]),
        "wall_s": round(wall, 1),
        "jobs": jobs,
        "cells": info.get("cells", ""),
        "computed": info.get("computed", ""),
        "load_start": load0,
        "load_end": _load(),
        "cpus": os.cpu_count(),
        "measured": dt.date.today().isoformat(),
        "detail": json.dumps(info.get("detail", {}), sort_keys=True),
    }


def write_timing(rows: list[dict[str, object]]) -> None:
    """Replace the rows of the steps run now in results/timing.csv (in the steps' order)."""
    path = RESULTS / "timing.csv"
    old = {}
    if path.exists():
        with open(path, newline="", encoding="utf-8") as fh:
            old = {r["run"]: r for r in csv.DictReader(fh)}
    old.update({str(r["run"]): r for r in rows})
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    w.writeheader()
    for name in STEPS:
        if name in old:
            w.writerow(old[name])
    path.write_text(buf.getvalue())


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", help="comma-separated steps (default: all)")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--fresh", action="store_true", help="delete each step's output folder first")
    p.add_argument("--no-render", action="store_true", help="do not render the documents")
    a = p.parse_args()
    names = a.only.split(",") if a.only else list(STEPS)
    unknown = [n for n in names if n not in STEPS]
    if unknown:
        raise SystemExit(f"unknown step(s) {unknown}; steps are {', '.join(STEPS)}")
    for name in names:
        print(f"rerun: {name} ...", file=sys.stderr, flush=True)
        row = run_step(name, a.jobs, a.fresh)
        write_timing([row])
        print(f"rerun: {name} took {row['wall_s']} s", file=sys.stderr, flush=True)
    if a.no_render:
        return
    from bilevel_kit.repro.template import write_all

    for path in write_all(ROOT):
        print(f"rendered {path.relative_to(ROOT)}", file=sys.stderr)


if __name__ == "__main__":
    main()
