"""The KitBench library on disk: instance files, the index of records and the best-known plans.

A library is a folder (docs/kitbench.md): ``NAME.json`` per instance, ``index.csv`` with one
row per instance (what it is, its best-known makespan and best lower bound, their status and
where each came from) and ``solutions/NAME.json``, the best-known plan as a solution file
(docs/formats.md). The index is read strictly (a hand edit that breaks a number or a status is
an error naming the instance and the column) and written atomically, so a reader never sees
half of it.

A record is ``optimal`` when its bound meets its plan within :data:`OPTIMAL_RTOL` (relative,
the zero gap of the method contract, docs/extending.md), else ``open``.
"""

from __future__ import annotations

import csv
import io
import json
import math
import subprocess
from dataclasses import dataclass, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ...errors import UsageError
from ...objectives import relative_gap

INDEX = "index.csv"
SOLUTIONS = "solutions"
#: ``optimal`` when best_known - best_bound <= OPTIMAL_RTOL x best_known.
OPTIMAL_RTOL = 1e-6
#: The shares of a run's summary: within 1 % and 5 % of the best-known.
SHARES = (0.01, 0.05)
#: A bound may exceed a plan by this much (the checker's time tolerance) before it is refused.
BOUND_ATOL = 1e-6

META_COLUMNS = ("instance", "family", "tasks", "trays", "delivery_time", "tray")
RECORD_COLUMNS = ("best_known", "best_bound", "status", "gap")
PROVENANCE_KEYS = ("method", "seed", "params", "time_limit", "wall_s", "commit", "date")
COLUMNS = (
    META_COLUMNS
    + RECORD_COLUMNS
    + tuple(f"plan_{k}" for k in PROVENANCE_KEYS)
    + tuple(f"bound_{k}" for k in PROVENANCE_KEYS)
)


@dataclass(frozen=True)
class Provenance:
    """Who made a plan or a bound: method, seed, options, time limit, wall time, code, date."""

    method: str
    seed: int | None = None
    params: dict[str, Any] | None = None
    time_limit: float | None = None
    wall_s: float | None = None
    commit: str = ""
    date: str = ""

    def cells(self, prefix: str) -> dict[str, str]:
        """The index cells of this provenance (``plan_`` or ``bound_`` columns)."""
        values = {
            "method": self.method,
            "seed": _text(self.seed),
            "params": json.dumps(self.params or {}, sort_keys=True),
            "time_limit": _text(self.time_limit),
            "wall_s": _text(self.wall_s),
            "commit": self.commit,
            "date": self.date,
        }
        return {f"{prefix}{k}": v for k, v in values.items()}


@dataclass(frozen=True)
class Record:
    """One instance of the library and its best-known plan and bound (``None``: none yet)."""

    instance: str
    family: str
    tasks: int
    trays: int | None  # None: unlimited
    delivery_time: float
    tray: str  # "tight" or "loose"
    best_known: float | None = None
    best_bound: float | None = None
    plan: Provenance | None = None
    bound: Provenance | None = None

    @property
    def status(self) -> str:
        """``optimal`` when the bound meets the plan (:data:`OPTIMAL_RTOL`), else ``open``."""
        return record_status(self.best_known, self.best_bound)

    @property
    def gap(self) -> float | None:
        """The certified gap (best_known - best_bound) / best_known, clipped at 0 (the one
        gap, :func:`bilevel_kit.objectives.relative_gap`)."""
        return relative_gap(self.best_known, self.best_bound)

    def row(self) -> dict[str, str]:
        """The record as index cells (floats in full precision, so they read back exactly)."""
        out = {
            "instance": self.instance,
            "family": self.family,
            "tasks": str(self.tasks),
            "trays": trays_text(self.trays),
            "delivery_time": _text(self.delivery_time),
            "tray": self.tray,
            "best_known": _text(self.best_known),
            "best_bound": _text(self.best_bound),
            "status": self.status,
            "gap": _text(self.gap),
        }
        for prefix, prov in (("plan_", self.plan), ("bound_", self.bound)):
            out.update(
                prov.cells(prefix) if prov else {f"{prefix}{k}": "" for k in PROVENANCE_KEYS}
            )
        return out

    def with_plan(self, makespan: float, prov: Provenance) -> Record:
        return replace(self, best_known=makespan, plan=prov)

    def with_bound(self, bound: float, prov: Provenance) -> Record:
        return replace(self, best_bound=bound, bound=prov)


def record_status(best_known: float | None, best_bound: float | None) -> str:
    if best_known is None or best_bound is None:
        return "open"
    return "optimal" if best_known - best_bound <= OPTIMAL_RTOL * abs(best_known) else "open"


def bound_above(bound: float, makespan: float) -> bool:
    """``bound`` is above the makespan of a plan, beyond the checker's tolerance."""
    return bound > makespan and not math.isclose(bound, makespan, abs_tol=BOUND_ATOL, rel_tol=1e-9)


def same_time(a: float, b: float) -> bool:
    """Two makespans agree to the checker's tolerance (1e-6 s or 1e-9 relative)."""
    return math.isclose(a, b, abs_tol=BOUND_ATOL, rel_tol=1e-9)


def improves(new: float, old: float | None, *, lower: bool) -> bool:
    """``new`` is strictly better than ``old`` beyond the tolerance (``lower``: a plan)."""
    if old is None:
        return True
    if same_time(new, old):
        return False
    return new < old if lower else new > old


def trays_text(trays: int | None) -> str:
    return "unlimited" if trays is None else str(trays)


def _text(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return str(value)


# ---------------------------------------------------------------------------------------------
# Reading the index strictly
# ---------------------------------------------------------------------------------------------


class _Row:
    """Typed access to one index row; a bad cell is a :class:`UsageError` naming the
    instance (or line) and the column."""

    def __init__(self, row: dict[str, str], where: str) -> None:
        self.row, self.where = row, where

    def fail(self, column: str, what: str) -> UsageError:
        return UsageError(f"{self.where}: column {column!r}: {what}")

    def text(self, column: str, required: bool = True) -> str:
        value = (self.row.get(column) or "").strip()
        if required and not value:
            raise self.fail(column, "is empty")
        return value

    def number(self, column: str, required: bool = False) -> float | None:
        value = self.text(column, required)
        if not value:
            return None
        try:
            x = float(value)
        except ValueError:
            raise self.fail(column, f"{value!r} is not a number") from None
        if not math.isfinite(x) or x < 0:
            raise self.fail(column, f"{value!r} is not a finite number >= 0")
        return x

    def integer(self, column: str, required: bool = False) -> int | None:
        value = self.text(column, required)
        if not value:
            return None
        if not value.isdigit():
            raise self.fail(column, f"{value!r} is not an integer >= 0")
        return int(value)

    def provenance(self, prefix: str) -> Provenance | None:
        method = self.text(f"{prefix}method", required=False)
        if not method:
            return None
        try:
            params = json.loads(self.text(f"{prefix}params", required=False) or "{}")
        except json.JSONDecodeError:
            raise self.fail(f"{prefix}params", "is not a JSON object") from None
        if not isinstance(params, dict):
            raise self.fail(f"{prefix}params", "is not a JSON object")
        return Provenance(
            method,
            self.integer(f"{prefix}seed"),
            params,
            self.number(f"{prefix}time_limit"),
            self.number(f"{prefix}wall_s"),
            self.text(f"{prefix}commit", required=False),
            self.text(f"{prefix}date", required=False),
        )


def parse_row(row: dict[str, str], line: int) -> Record:
    """One index row as a :class:`Record`; its stated status and gap must be the ones its
    numbers give (a hand edit of one without the other is refused)."""
    name = (row.get("instance") or "").strip()
    r = _Row(row, f"index.csv line {line} ({name or 'no instance name'})")
    trays = r.text("trays")
    if trays != "unlimited" and not (trays.isdigit() and int(trays) >= 1):
        raise r.fail("trays", f"{trays!r} is not an integer >= 1 or 'unlimited'")
    best_known, best_bound = r.number("best_known"), r.number("best_bound")
    rec = Record(
        instance=r.text("instance"),
        family=r.text("family"),
        tasks=r.integer("tasks", required=True) or 0,
        trays=None if trays == "unlimited" else int(trays),
        delivery_time=r.number("delivery_time", required=True) or 0.0,
        tray=r.text("tray"),
        best_known=best_known,
        best_bound=best_bound,
        plan=r.provenance("plan_"),
        bound=r.provenance("bound_"),
    )
    if (rec.best_known is None) != (rec.plan is None):
        raise r.fail("plan_method", "a best_known makespan and its plan_method go together")
    if (rec.best_bound is None) != (rec.bound is None):
        raise r.fail("bound_method", "a best_bound and its bound_method go together")
    if r.text("status") != rec.status:
        raise r.fail("status", f"says {r.text('status')!r}, its numbers give {rec.status!r}")
    gap = r.number("gap")
    if (gap is None) != (rec.gap is None) or (
        gap is not None and rec.gap is not None and abs(gap - rec.gap) > 1e-9
    ):
        raise r.fail(
            "gap",
            f"says {r.text('gap', False) or 'nothing'}, its numbers give "
            f"{_text(rec.gap) or 'nothing'}",
        )
    return rec


# ---------------------------------------------------------------------------------------------
# The library folder
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Library:
    """A KitBench folder: instances, ``index.csv`` and ``solutions/``."""

    folder: Path

    @classmethod
    def at(cls, folder: str | Path) -> Library:
        path = Path(folder)
        if not (path / INDEX).is_file():
            raise UsageError(
                f"{path}: not a KitBench library (no {INDEX}); give --library, e.g. "
                "instances/kitbench from the repository root"
            )
        return cls(path)

    @property
    def index_path(self) -> Path:
        return self.folder / INDEX

    def instance_path(self, name: str) -> Path:
        return self.folder / f"{name}.json"

    def solution_path(self, name: str) -> Path:
        return self.folder / SOLUTIONS / f"{name}.json"

    def instance_files(self) -> list[Path]:
        return sorted(self.folder.glob("*.json"))

    def read(self) -> list[Record]:
        """Every record, in the index's order; a malformed index is a :class:`UsageError`."""
        try:  # a spreadsheet's UTF-8 byte order mark is no part of the first column's name
            text = self.index_path.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeError) as exc:
            raise UsageError(f"{self.index_path}: cannot read file ({exc})") from None
        reader = csv.DictReader(io.StringIO(text))
        missing = [c for c in COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise UsageError(f"{self.index_path}: missing column(s) {', '.join(missing)}")
        records = [parse_row(row, i) for i, row in enumerate(reader, start=2)]
        seen: set[str] = set()
        for rec in records:
            if rec.instance in seen:
                raise UsageError(f"{self.index_path}: instance {rec.instance!r} listed twice")
            seen.add(rec.instance)
        return records

    def index_text(self, records: list[Record]) -> str:
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=list(COLUMNS), lineterminator="\n")
        writer.writeheader()
        for rec in records:
            writer.writerow(rec.row())
        return buf.getvalue()

    def write(self, records: list[Record]) -> None:
        """The index, written atomically (a temporary file renamed over the old one)."""
        from ...atomic import write_text

        write_text(self.index_path, self.index_text(records))


def code_version() -> str:
    """The commit of the code that runs (``+dirty`` when the package differs from it), or
    ``unknown`` outside a git checkout."""
    root = Path(__file__).resolve().parents[3]

    def git(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            ["git", "-C", str(root), *args], capture_output=True, text=True, check=False
        )

    try:
        head = git("rev-parse", "--short=12", "HEAD")
        if head.returncode != 0:
            return "unknown"
        dirty = git("diff", "--quiet", "HEAD", "--", "bilevel_kit").returncode != 0
    except OSError:
        return "unknown"
    return head.stdout.strip() + ("+dirty" if dirty else "")


def now() -> str:
    """The current time in UTC, to the second (ISO 8601)."""
    return datetime.now(UTC).replace(microsecond=0).isoformat().replace("+00:00", "Z")
