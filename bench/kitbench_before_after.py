"""KitBench before and after a change, side by side (docs/kitbench.md#before-and-after-a-change):
two passes of ``bench run`` over the same records, methods, limit and seed, started together on
this machine (one ``--jobs 1`` process per code version, so both see the same load), compared
cell by cell: each method's plan, status, bound and wall time before and after, and per record
the best plan and bound of the pass.

    python bench/kitbench_before_after.py --commit BEFORE_DIR AFTER_DIR LABEL
    python bench/kitbench_before_after.py [--check]

``--commit`` copies the passes' ``results.csv`` and ``run.json`` to
``bench/results/kitbench_LABEL_{before,after}.csv`` and ``..._run.json`` (with the wall time,
``wall_s``, read from ``/usr/bin/time -v``'s report when its log is given by ``--time-log``).
Then (and without it) the ``kitbench-before-after:LABEL`` blocks of docs/kitbench.md and
``bench/results/kitbench_LABEL.md`` are rendered from the committed rows, with every other
generated KitBench block, by ``bench/kitbench_docs.py``'s one loop; ``--check`` exits 1 when a
page disagrees (tests/experiments/test_kitbench_before_after.py checks the same).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import shutil
import statistics
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from bilevel_kit.experiments.kitbench.profiles import methods_of, plan_makespan, read_rows  # noqa: E402
from bilevel_kit.experiments.kitbench.versus import number, run_text  # noqa: E402
from bilevel_kit.experiments.tables import fill_blocks, markdown_lines, marked_blocks  # noqa: E402

RESULTS = ROOT / "bench" / "results"
#: Relative change below which two makespans or bounds are the same (equal plans computed in
#: another order differ in the last bits).
SAME = 1e-9
Row = Mapping[str, Any]


def change(after: float | None, before: float | None) -> float | None:
    """(after - before) / before; ``inf`` when the plan was lost, ``-inf`` when one was found,
    None when neither pass has one; 0 within :data:`SAME`."""
    if before is None or after is None:
        return (
            None if before is None and after is None else (math.inf if after is None else -math.inf)
        )
    rel = (after - before) / before
    return 0.0 if abs(rel) <= SAME else rel


def cells(before: Sequence[Row], after: Sequence[Row]) -> list[dict[str, Any]]:
    """Per (record, method) of the before pass, in its order: both plans, statuses, bounds and
    wall times, and the plan's relative change."""
    later = {(r["instance"], r["method"]): r for r in after}
    out = []
    for b in before:
        a = later.get((b["instance"], b["method"]))
        if a is None:
            continue
        mb, ma = plan_makespan(b), plan_makespan(a)
        out.append(
            {
                "instance": b["instance"],
                "tasks": int(b["tasks"]),
                "method": b["method"],
                "before": mb,
                "after": ma,
                "change": change(ma, mb),
                "status_before": b["status"],
                "status_after": a["status"],
                "bound_before": number(b.get("bound")),
                "bound_after": number(a.get("bound")),
                "time_before": number(b.get("wall_time_s")),
                "time_after": number(a.get("wall_time_s")),
            }
        )
    return out


def method_summary(table: Sequence[Row], method: str) -> dict[str, Any]:
    """One method's cells: better, same, worse (worst first), proven optimal before and after,
    and the wall time before and after (sum, and the median of after / before over cells that
    took at least 1 s before, where the ratio is not the clock's noise)."""
    mine = [c for c in table if c["method"] == method]
    moved = [c for c in mine if c["change"] is not None]
    ratios = [
        c["time_after"] / c["time_before"]
        for c in mine
        if c["time_before"] is not None and c["time_after"] is not None and c["time_before"] >= 1
    ]
    return {
        "cells": len(mine),
        "better": sum(c["change"] < 0 for c in moved),
        "same": sum(c["change"] == 0 for c in moved),
        "worse": sorted(
            ((c["instance"], c["change"]) for c in moved if c["change"] > 0), key=lambda t: -t[1]
        ),
        "optimal_before": sum(c["status_before"] == "optimal" for c in mine),
        "optimal_after": sum(c["status_after"] == "optimal" for c in mine),
        "time_before": sum(c["time_before"] or 0.0 for c in mine),
        "time_after": sum(c["time_after"] or 0.0 for c in mine),
        "median_ratio": statistics.median(ratios) if ratios else None,
    }


def record_summary(table: Sequence[Row]) -> dict[str, Any]:
    """Per record, the pass's best plan and best bound before and after: how many are better,
    the same, worse (worst first)."""
    best: dict[str, dict[str, float]] = {}
    for c in table:
        b = best.setdefault(c["instance"], {})
        for key in ("before", "after", "bound_before", "bound_after"):
            value = c[key]
            if value is not None:
                pick = max if key.startswith("bound") else min
                b[key] = pick(value, b.get(key, value))
    plans = {n: change(b.get("after"), b.get("before")) for n, b in best.items()}
    bounds = {n: change(b.get("bound_after"), b.get("bound_before")) for n, b in best.items()}
    return {
        "records": len(best),
        "better": sum(x is not None and x < 0 for x in plans.values()),
        "worse": sorted(((n, x) for n, x in plans.items() if x and x > 0), key=lambda t: -t[1]),
        "bound_higher": sum(x is not None and x > 0 for x in bounds.values()),
        "bound_lower": sorted(
            ((n, x) for n, x in bounds.items() if x and x < 0), key=lambda t: t[1]
        ),
    }


#: "Within" the reference's plan: at most this relative amount above it (issue 37's goal for
#: the exact models against ``lns`` at the same limit).
WITHIN = 1e-3
#: The method the exact models are held to in the same pass, and those models.
REFERENCE = "lns"
HELD = ("cpsat", "milp")


def versus_reference(table: Sequence[Row], method: str) -> dict[str, Any]:
    """On how many records ``method``'s plan is within :data:`WITHIN` of :data:`REFERENCE`'s
    plan of the same pass, before and after, and the records missing it after (worst first;
    ``inf``: no plan where the reference has one)."""
    ref = {c["instance"]: c for c in table if c["method"] == REFERENCE}
    mine = [c for c in table if c["method"] == method and c["instance"] in ref]
    out: dict[str, Any] = {"records": len(mine)}
    for side in ("before", "after"):
        misses = []
        for c in mine:
            theirs = ref[c["instance"]][side]
            if theirs is None:
                continue
            mine_s = c[side]
            over = math.inf if mine_s is None else mine_s / theirs - 1
            if over > WITHIN + 1e-12:
                misses.append((c["instance"], over))
        out[side] = len(mine) - len(misses)
        out[f"misses_{side}"] = sorted(misses, key=lambda t: -t[1])
    return out


def _pct(x: float | None) -> str:
    if x is None:
        return "-"
    if math.isinf(x):
        return "plan lost" if x > 0 else "plan found"
    return "0" if x == 0 else f"{100 * x:+.3f} %"


def _listed(pairs: Sequence[tuple[str, float]]) -> str:
    return ", ".join(f"`{n}` {_pct(x)}" for n, x in pairs) or "none"


def before_after_text(before: Sequence[Row], after: Sequence[Row], runs: Sequence[Row]) -> str:
    """The prose of one side-by-side run: what ran, per record and per method."""
    table = cells(before, after)
    rec = record_summary(table)
    lines = [f"Before: {run_text(runs[0])}", "", f"After: {run_text(runs[1])}", ""]
    lines.append(
        f"**Records** ({rec['records']}, the best plan and bound of each pass): the best plan "
        f"better on {rec['better']}, worse on {len(rec['worse'])} ({_listed(rec['worse'])}); "
        f"the best bound higher on {rec['bound_higher']}, lower on {len(rec['bound_lower'])} "
        f"({_listed(rec['bound_lower'])})."
    )
    for m in methods_of(before):
        s = method_summary(table, m)
        ratio = "-" if s["median_ratio"] is None else f"{s['median_ratio']:.2f}"
        lines += [
            "",
            f"**{m}** ({s['cells']} cells): better on {s['better']}, the same on {s['same']}, "
            f"worse on {len(s['worse'])} ({_listed(s['worse'])}); proven optimal on "
            f"{s['optimal_before']} before, {s['optimal_after']} after; wall time "
            f"{s['time_before']:,.0f} s before, {s['time_after']:,.0f} s after, median ratio "
            f"after / before {ratio} (cells of 1 s or more before).",
        ]
    if REFERENCE in methods_of(before):
        parts = []
        for m in (m for m in methods_of(before) if m in HELD):
            v = versus_reference(table, m)
            parts.append(
                f"{m} {v['before']} before, {v['after']} after"
                + (
                    f" (missing it after: {_listed(v['misses_after'])})"
                    if v["misses_after"]
                    else ""
                )
            )
        lines += [
            "",
            f"**Against {REFERENCE} in the same pass** (records where the method's plan is at "
            f"most {100 * WITHIN:g} % above {REFERENCE}'s): " + "; ".join(parts) + ".",
        ]
    return "\n".join(lines) + "\n"


def before_after_markdown(before: Sequence[Row], after: Sequence[Row]) -> str:
    """Every cell: plan, status, bound and wall time before and after, and the plan's change."""
    header = ["instance", "tasks", "method", "before (s)", "after (s)", "change"]
    header += ["status before", "status after", "bound before (s)", "bound after (s)"]
    header += ["time before (s)", "time after (s)"]

    def secs(x: float | None) -> str:
        return "-" if x is None else f"{x:,.2f}"

    body = [
        [f"`{c['instance']}`", str(c["tasks"]), c["method"], secs(c["before"]), secs(c["after"])]
        + [_pct(c["change"]), c["status_before"], c["status_after"]]
        + [secs(c[k]) for k in ("bound_before", "bound_after", "time_before", "time_after")]
        for c in cells(before, after)
    ]
    return "\n".join(markdown_lines(header, body)) + "\n"


_TEXT = marked_blocks("kitbench-before-after")
_TABLE = marked_blocks("kitbench-before-after-table")


def render(text: str, results: Path = RESULTS) -> str:
    """``text`` with its ``kitbench-before-after`` blocks rendered from the committed rows."""

    def rows(label: str, side: str) -> list[dict[str, Any]]:
        return read_rows(results / f"kitbench_{label}_{side}.csv")

    def runs(label: str) -> list[dict[str, Any]]:
        return [
            json.loads((results / f"kitbench_{label}_{s}_run.json").read_text())
            for s in ("before", "after")
        ]

    text = fill_blocks(
        _TEXT, text, lambda x: before_after_text(rows(x, "before"), rows(x, "after"), runs(x))
    )
    return fill_blocks(
        _TABLE, text, lambda x: before_after_markdown(rows(x, "before"), rows(x, "after"))
    )


def wall_seconds(log: Path) -> float:
    """The elapsed time ``/usr/bin/time -v`` reported in ``log`` (h:mm:ss or m:ss)."""
    found = re.search(r"Elapsed \(wall clock\) time.*: ([\d:.]+)", log.read_text())
    if found is None:
        raise SystemExit(f"{log}: no '/usr/bin/time -v' report")
    seconds = 0.0
    for part in found.group(1).split(":"):
        seconds = 60 * seconds + float(part)
    return seconds


def commit(before: Path, after: Path, label: str, logs: Sequence[Path] | None) -> None:
    """Copy the two passes' rows and metadata into bench/results (module docstring)."""
    for i, (side, run) in enumerate((("before", before), ("after", after))):
        shutil.copyfile(run / "results.csv", RESULTS / f"kitbench_{label}_{side}.csv")
        meta = json.loads((run / "run.json").read_text())
        if logs:
            meta["wall_s"] = wall_seconds(logs[i])
        path = RESULTS / f"kitbench_{label}_{side}_run.json"
        path.write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
    table = RESULTS / f"kitbench_{label}.md"
    if not table.exists():
        table.write_text(
            f"# KitBench before and after, side by side ({label})\n\n"
            f"<!-- kitbench-before-after:{label} -->\n<!-- /kitbench-before-after:{label} -->\n\n"
            f"<!-- kitbench-before-after-table:{label} -->\n"
            f"<!-- /kitbench-before-after-table:{label} -->\n",
            encoding="utf-8",
        )


def labels() -> list[str]:
    """The committed side-by-side runs (each ``kitbench_LABEL_before.csv``)."""
    return sorted(p.name[9:-11] for p in RESULTS.glob("kitbench_*_before.csv"))


def tables() -> list[Path]:
    """Each committed run's per-cell page (``bench/results/kitbench_LABEL.md``)."""
    return [RESULTS / f"kitbench_{x}.md" for x in labels()]


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--commit", nargs=3, metavar=("BEFORE_DIR", "AFTER_DIR", "LABEL"))
    ap.add_argument("--time-log", nargs=2, type=Path, metavar=("BEFORE_LOG", "AFTER_LOG"))
    args = ap.parse_args()
    if args.commit:
        commit(Path(args.commit[0]), Path(args.commit[1]), args.commit[2], args.time_log)
    import kitbench_docs

    stale = kitbench_docs.rewrite(
        kitbench_docs.Library.at(ROOT / "instances" / "kitbench"), args.check
    )
    if args.check and stale:
        raise SystemExit(f"out of date: {', '.join(str(p) for p in stale)}")
