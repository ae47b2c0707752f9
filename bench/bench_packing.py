"""Packing decisions: ``bilevel-kit pack`` against a plain CP-SAT model, side by side.

Run from the repository root: ``python bench/bench_packing.py [--time-limit S] [--workers N]``
(the instance set is built by ``python bench/packing_data.py``; see bench/data/packing/README.md).
Every (instance, solver) pair runs in its own process, killed at the time limit + 30 s.

* ``plain``: fixed-size intervals (two optional ones per orientation for rotatable parts) and
  one ``add_no_overlap_2d``, CP-SAT's default parameters: the reference point of issue 13;
* ``pack``: :func:`bilevel_kit.models.packing.pack` (``objective="feasible"``), the
  model behind ``bilevel-kit pack``.

A ``feasible`` answer is checked on its layout (inside the tray, no overlap), so it is never
wrong; an ``infeasible`` answer is wrong when the instance is known to be feasible (the
literature's answer, a construction, or a layout found by any run, including the reference).
``--reference S`` first answers the instances without a known answer by a long plain run and
stores them in bench/data/packing/reference.csv. Writes bench/results/packing.csv (one row per
run) and packing.md (per class: decided, wrong, total time per solver).
"""

from __future__ import annotations

import argparse
import csv
import json
import multiprocessing as mp
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "bench" / "data" / "packing"

Sizes = list[tuple[int, int, bool]]


def load(path: Path) -> tuple[int, int, Sizes]:
    doc = json.loads(path.read_text())
    sizes = []
    for it in doc["items"]:
        sizes += [(int(it["width"]), int(it["height"]), bool(it.get("rotatable", True)))] * int(
            it.get("count", 1)
        )
    return int(doc["tray"]["width"]), int(doc["tray"]["height"]), sizes


def plain(W: int, H: int, sizes: Sizes, T: float, workers: int, seed: int) -> dict[str, Any]:
    """The plain model: intervals and one no-overlap-2D, nothing else."""
    from ortools.sat.python import cp_model

    m = cp_model.CpModel()
    xs, ys, rots, xi, yi = [], [], [], [], []
    for j, (w, h, r) in enumerate(sizes):
        x = m.new_int_var(0, W, f"x{j}")
        y = m.new_int_var(0, H, f"y{j}")
        xs.append(x)
        ys.append(y)
        if r and w != h:
            rot = m.new_bool_var(f"r{j}")
            for sx, sy, lit in ((w, h, rot.Not()), (h, w, rot)):
                xe = m.new_int_var(0, W, "")
                ye = m.new_int_var(0, H, "")
                xi.append(m.new_optional_interval_var(x, sx, xe, lit, ""))
                yi.append(m.new_optional_interval_var(y, sy, ye, lit, ""))
            rots.append(rot)
        else:
            m.add(x <= W - w)
            m.add(y <= H - h)
            xi.append(m.new_fixed_size_interval_var(x, w, ""))
            yi.append(m.new_fixed_size_interval_var(y, h, ""))
            rots.append(0)
    m.add_no_overlap_2d(xi, yi)
    s = cp_model.CpSolver()
    s.parameters.max_time_in_seconds = T
    s.parameters.num_workers = workers
    s.parameters.random_seed = seed
    st = s.solve(m)
    if st in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        corners = [
            (s.value(xs[j]), s.value(ys[j]), bool(s.value(rots[j])) if j < len(rots) else False)
            for j in range(len(sizes))
        ]
        return {"status": "feasible", "corners": corners}
    return {"status": "infeasible" if st == cp_model.INFEASIBLE else "unknown"}


def packed(W: int, H: int, sizes: Sizes, T: float, workers: int, seed: int) -> dict[str, Any]:
    from bilevel_kit.instance import PartType, Tray
    from bilevel_kit.models.packing import pack

    items = [
        (
            f"i{j}",
            PartType(
                id=f"t{w}x{h}{'r' if r else ''}", width=w, height=h, pick_time=1.0, rotatable=r
            ),
        )
        for j, (w, h, r) in enumerate(sizes)
    ]
    res = pack(Tray(float(W), float(H)), items, time_limit=T, workers=workers, seed=seed)
    out: dict[str, Any] = {"status": res.status, "reason": res.extra.get("reason", "")}
    if res.layout is not None:
        corners = []
        for p in res.layout:
            rot = p.theta == 90.0
            ww, hh = (p.h, p.w) if rot else (p.w, p.h)
            corners.append((round(p.x - ww / 2), round(p.y - hh / 2), rot))
        out["corners"] = corners
    return out


SOLVERS = {"plain": plain, "pack": packed}


def valid(W: int, H: int, sizes: Sizes, corners: list[tuple[int, int, bool]]) -> bool:
    rects = []
    for (w, h, r), (x, y, rot) in zip(sizes, corners, strict=True):
        if rot and not r:
            return False
        ww, hh = (h, w) if rot else (w, h)
        if x < 0 or y < 0 or x + ww > W or y + hh > H:
            return False
        rects.append((x, y, x + ww, y + hh))
    for a in range(len(rects)):
        for b in range(a + 1, len(rects)):
            p, q = rects[a], rects[b]
            if p[0] < q[2] and q[0] < p[2] and p[1] < q[3] and q[1] < p[3]:
                return False
    return True


def _child(solver: str, path: str, T: float, workers: int, seed: int, q: Any) -> None:
    sys.path.insert(0, str(ROOT))
    W, H, sizes = load(Path(path))
    t0 = time.perf_counter()
    out = SOLVERS[solver](W, H, sizes, T, workers, seed)
    out["time"] = time.perf_counter() - t0
    if "corners" in out:
        out["valid"] = valid(W, H, sizes, out["corners"])
        del out["corners"]
    q.put(out)


def run(solver: str, path: Path, T: float, workers: int, seed: int) -> dict[str, Any]:
    ctx = mp.get_context("spawn")
    q = ctx.Queue()
    p = ctx.Process(target=_child, args=(solver, str(path), T, workers, seed, q))
    t0 = time.perf_counter()
    p.start()
    try:
        out = q.get(timeout=T + 30.0)
    except Exception:
        out = {"status": "killed", "time": time.perf_counter() - t0}
    p.join(5)
    if p.is_alive():
        p.kill()
    out["wall"] = time.perf_counter() - t0
    return out


def read_index() -> list[dict[str, str]]:
    with open(DATA / "index.csv") as fh:
        rows = list(csv.DictReader(fh))
    ref = DATA / "reference.csv"
    if ref.exists():
        with open(ref) as fh:
            known = {r["name"]: r["answer"] for r in csv.DictReader(fh)}
        for r in rows:
            if not r["answer"] and known.get(r["name"]):
                r["answer"] = known[r["name"]]
                r["source"] = "reference"
    for r in rows:
        if not r["answer"]:
            W, H, sizes = load(DATA / r["file"])
            if sum(w * h for w, h, _ in sizes) > W * H:
                r["answer"] = "infeasible"  # arithmetic: more part area than tray area
    return rows


def reference(rows: list[dict[str, str]], T: float, workers: int) -> None:
    out = []
    for r in rows:
        if r["answer"]:
            continue
        res = run("plain", DATA / r["file"], T, workers, 0)
        ans = res["status"] if res["status"] in ("feasible", "infeasible") else ""
        if ans == "feasible" and not res.get("valid"):
            ans = ""
        print(f"reference {r['name']}: {ans or 'unknown'} in {res['wall']:.1f} s", flush=True)
        out.append((r["name"], ans, f"plain CP-SAT {T:g} s, {workers} workers"))
    with open(DATA / "reference.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["name", "answer", "how"])
        w.writerows(out)


def summary(results: list[dict[str, Any]], solvers: list[str], T: float) -> str:
    classes = sorted({r["class"] for r in results})
    lines = [
        "| class | n | "
        + " | ".join(f"{s} decided | {s} wrong | {s} time (s)" for s in solvers)
        + " |",
        "|---|---|" + "---|---|---|" * len(solvers),
    ]
    for cls in [*classes, "all"]:
        rows = [r for r in results if cls in ("all", r["class"])]
        n = len({r["name"] for r in rows})
        cells = []
        for s in solvers:
            mine = [r for r in rows if r["solver"] == s]
            dec = sum(r["status"] in ("feasible", "infeasible") for r in mine)
            wrong = sum(r["wrong"] for r in mine)
            tt = sum(min(float(r["wall"]), T + 30) for r in mine)
            cells += [str(dec), str(wrong), f"{tt:.1f}"]
        lines.append(f"| {cls} | {n} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--time-limit", type=float, default=20.0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--solvers", default="plain,pack")
    parser.add_argument("--classes", default="", help="comma-separated classes (default all)")
    parser.add_argument("--only", default="", help="comma-separated instance names")
    parser.add_argument("--reference", type=float, default=0.0, metavar="S")
    parser.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "packing.csv")
    parser.add_argument(
        "--from-csv", type=Path, default=None, help="re-summarise a results CSV (no runs)"
    )
    args = parser.parse_args(argv)
    if args.from_csv is not None:
        with open(args.from_csv) as fh:
            old = list(csv.DictReader(fh))
        answers = {r["name"]: r["answer"] or "unknown" for r in read_index()}
        for r in old:
            r["answer"] = answers[r["name"]]
            r["wrong"] = int(
                (r["status"] == "infeasible" and r["answer"] == "feasible")
                or (r["status"] == "feasible" and r["answer"] == "infeasible")
                or r["status"] == "invalid"
            )
        return finish(old, args.from_csv.stem, args)
    rows = read_index()
    if args.classes:
        rows = [r for r in rows if r["class"] in args.classes.split(",")]
    if args.only:
        rows = [r for r in rows if r["name"] in args.only.split(",")]
    if args.reference > 0:
        reference(rows, args.reference, args.workers)
        rows = [r for r in read_index() if r["name"] in {x["name"] for x in rows}]
    solvers = args.solvers.split(",")
    results = []
    for r in rows:
        for s in solvers:
            res = run(s, DATA / r["file"], args.time_limit, args.workers, args.seed)
            if res["status"] == "feasible" and not res.get("valid", False):
                res["status"] = "invalid"
            wrong = (
                (res["status"] == "infeasible" and r["answer"] == "feasible")
                or (res["status"] in ("feasible", "invalid") and r["answer"] == "infeasible")
                or res["status"] == "invalid"
            )
            row = {
                "name": r["name"],
                "class": r["class"],
                "answer": r["answer"] or "unknown",
                "solver": s,
                "status": res["status"],
                "wrong": int(wrong),
                "wall": round(res["wall"], 3),
                "reason": res.get("reason", ""),
            }
            results.append(row)
            print(" ".join(f"{k}={v}" for k, v in row.items()), flush=True)
    return finish(results, "", args)


def finish(results: list[dict[str, Any]], _: str, args: argparse.Namespace) -> int:
    solvers = list(dict.fromkeys(r["solver"] for r in results))
    # an open instance on which some run found a checked layout is feasible
    found = {r["name"] for r in results if r["status"] == "feasible"}
    for r in results:
        if r["answer"] == "unknown" and r["name"] in found:
            r["answer"] = "feasible"
            r["wrong"] = int(r["status"] == "infeasible")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(results[0]))
        w.writeheader()
        w.writerows(results)
    table = summary(results, solvers, args.time_limit)
    print(table)
    args.out.with_suffix(".md").write_text(
        f"# Packing decisions (time limit {args.time_limit:g} s, {args.workers} workers)\n\n"
        + table
        + "\n"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
