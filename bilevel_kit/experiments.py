"""Experiment cells: each is a pure function of (config, seed) returning a plain record.

Why: ``compare`` (and later ``simulate`` and the paper reproductions) must scale out to a Dask
cluster and resume after an interruption. A cell therefore takes only plain data (an instance
path, a method name, options, a seed), returns a JSON-serialisable dict, and is saved on its own
file as soon as it finishes; :func:`run_cells` skips cells whose file already exists.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from . import atomic


@dataclass(frozen=True)
class CompareCell:
    """One solve of one instance with one method."""

    instance: str  # path of the instance file
    method: str
    seed: int = 0
    time_limit: float | None = None
    params: dict[str, Any] = field(default_factory=dict)
    overrides: dict[str, Any] = field(default_factory=dict)  # delivery_time, weights, ...

    def key(self) -> str:
        """A stable file-name key for this cell's saved result."""
        blob = json.dumps(asdict(self), sort_keys=True, default=str)
        digest = hashlib.sha1(blob.encode()).hexdigest()[:10]
        return f"{Path(self.instance).stem}__{self.method}__s{self.seed}__{digest}"


def compare_cell(cell: CompareCell) -> dict[str, Any]:
    """Solve one cell and return its record (metrics, status, bound, checker verdict)."""
    from .errors import BilevelKitError
    from .instance import load
    from .methods import solve

    inst = load(cell.instance).with_overrides(**cell.overrides)
    record: dict[str, Any] = {
        "instance": inst.name,
        "instance_file": cell.instance,
        "method": cell.method,
        "seed": cell.seed,
        "time_limit": cell.time_limit,
        "params": dict(cell.params),
        "n_tasks": inst.n_tasks,
    }
    try:
        res = solve(
            inst, cell.method, seed=cell.seed, time_limit=cell.time_limit, check=True, **cell.params
        )
    except BilevelKitError as exc:
        return {**record, "status": "error", "error": str(exc)}
    from .solution import result_to_dict

    m = res.metrics or {}
    violations = res.extra.get("violations", [])
    return {
        **record,
        "status": res.status,
        "makespan": m.get("makespan"),
        "human_idle": m.get("human_idle"),
        "robot_idle": m.get("robot_idle"),
        "n_kits": m.get("n_kits"),
        "bound": res.bound,
        "gap_own": res.gap,
        "wall_time_s": res.wall_time_s,
        "valid": res.plan is not None and not violations,
        "violations": len(violations),
        "solution": result_to_dict(res),
    }


def run_cells(
    cells: Sequence[Any],
    fn: Callable[[Any], dict[str, Any]],
    *,
    cell_dir: str | Path | None = None,
    progress: bool | None = None,
    desc: str = "cells",
) -> list[dict[str, Any]]:
    """Run ``fn`` on every cell in order, saving each record under ``cell_dir`` (resumable).

    ``progress=None`` shows a bar only on a terminal.
    """
    from tqdm import tqdm

    out: list[dict[str, Any]] = []
    folder = Path(cell_dir) if cell_dir is not None else None
    for cell in tqdm(
        cells, desc=desc, disable=None if progress is None else not progress, leave=False
    ):
        path = folder / f"{cell.key()}.json" if folder is not None else None
        if path is not None and path.exists():
            out.append(json.loads(path.read_text()))
            continue
        record = fn(cell)
        if path is not None:
            atomic.write_text(path, json.dumps(record, indent=1) + "\n")
        out.append(record)
    return out


def add_best_bound_gap(records: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """Add ``best_bound`` (max bound over the instance's rows) and ``gap`` to it (fraction)."""
    rows = list(records)
    best: dict[str, float] = {}
    for r in rows:
        if r.get("bound") is not None:
            best[r["instance"]] = max(best.get(r["instance"], r["bound"]), r["bound"])
    for r in rows:
        b = best.get(r["instance"])
        r["best_bound"] = b
        ms = r.get("makespan")
        r["gap"] = None if b is None or not ms else max(0.0, (ms - b) / ms)
    return rows


COMPARE_COLUMNS = [
    ("instance", "instance", "{}"),
    ("method", "method", "{}"),
    ("makespan", "makespan (s)", "{:.2f}"),
    ("human_idle", "human idle (s)", "{:.2f}"),
    ("n_kits", "kits", "{}"),
    ("status", "status", "{}"),
    ("best_bound", "bound (s)", "{:.2f}"),
    ("gap", "gap (%)", "{:.2%}"),
    ("valid", "valid", "{}"),
    ("wall_time_s", "time (s)", "{:.3f}"),
]


def _cell_text(value: Any, fmt: str) -> str:
    if value is None:
        return "-"
    if fmt == "{:.2%}":
        return f"{100 * value:.2f}"
    return fmt.format(value)


def table_rows(records: Sequence[dict[str, Any]]) -> tuple[list[str], list[list[str]]]:
    header = [h for _, h, _ in COMPARE_COLUMNS]
    rows = [[_cell_text(r.get(k), f) for k, _, f in COMPARE_COLUMNS] for r in records]
    return header, rows


def format_table(records: Sequence[dict[str, Any]]) -> str:
    """A fixed-width text table of compare records."""
    header, rows = table_rows(records)
    widths = [max(len(x) for x in col) for col in zip(header, *rows, strict=True)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) for row in rows]
    return "\n".join(lines)


def format_markdown(records: Sequence[dict[str, Any]]) -> str:
    """A Markdown table of compare records."""
    header, rows = table_rows(records)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def write_csv(path: str | Path, records: Sequence[dict[str, Any]]) -> None:
    """All record fields as CSV, written atomically."""
    import csv
    import io

    keys: list[str] = []
    for r in records:
        keys += [k for k in r if k not in keys and k != "solution"]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=keys, extrasaction="ignore")
    writer.writeheader()
    for r in records:
        writer.writerow(
            {
                k: json.dumps(v) if isinstance(v, dict | list) else v
                for k, v in r.items()
                if k != "solution"
            }
        )
    atomic.write_text(path, buf.getvalue())
