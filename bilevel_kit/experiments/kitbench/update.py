"""``bench update DIR``: merge a run's improvements into the records (docs/kitbench.md#update).

Accepted: a plan with a lower makespan than the best-known that passes the independent checker
on the library's own instance file, and a higher lower bound reported by a registered method
(whose contract makes every bound it reports a proof, docs/extending.md). Everything is
checked before anything is written; any of these refuses the whole merge (exit 2), naming the
instance and what is wrong:

* a record that is not a ``bench run`` cell, or of an instance the library does not have, or
  of another version of its file (the instance's SHA-256 differs);
* a plan that fails the checker, or whose stated makespan is not its plan's;
* a bound above a known plan (the library's or the run's), or from an unregistered method;
* a library record that does not hold already (e.g. its plan file edited by hand so that plan
  and makespan disagree): fix or restore it first.

Cells that found nothing (refused, error, no plan and no bound) are skipped. The new solution
files and the index are written to temporary files first and renamed into place with Ctrl-C
and SIGTERM held back, the index last: a reader never sees half an index, and a merge that
fails writes nothing. Merging is idempotent, so a longer run can be merged over a shorter one.
"""

from __future__ import annotations

import contextlib
import json
import signal
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...errors import BilevelKitError, UsageError
from ..compare import file_digest
from .library import Library, Provenance, Record, bound_above, improves, same_time
from .run import CELL_FORMAT, read_cells
from .verify import Problem, check_record


class UpdateRefused(UsageError):
    """The merge was refused; ``problems`` says why, per instance."""

    def __init__(self, problems: Sequence[Problem]) -> None:
        self.problems = list(problems)
        lines = "\n  ".join(p.line() for p in self.problems)
        super().__init__(f"nothing merged, {len(self.problems)} problem(s):\n  {lines}")


@dataclass(frozen=True)
class Change:
    """One improved record: the plan or the bound, old and new value, and its method."""

    instance: str
    what: str  # "plan" or "bound"
    old: float | None
    new: float
    method: str

    def line(self) -> str:
        old = "none" if self.old is None else f"{self.old:.6g} s"
        return f"{self.instance}: {self.what} {old} -> {self.new:.6g} s ({self.method})"


@dataclass
class Merge:
    """A checked merge: the new records, the plans to write and what changed."""

    records: list[Record]
    solutions: dict[str, dict[str, Any]] = field(default_factory=dict)
    changes: list[Change] = field(default_factory=list)
    skipped: int = 0
    cells: int = 0


def _provenance(cell: dict[str, Any]) -> Provenance:
    wall = cell.get("wall_time_s")
    return Provenance(
        method=str(cell.get("method")),
        seed=cell.get("seed"),
        params=cell.get("params") or {},
        time_limit=cell.get("time_limit"),
        wall_s=None if wall is None else float(wall),
        commit=str(cell.get("commit") or ""),
        date=str(cell.get("date") or ""),
    )


class _Checker:
    """The library's instances, loaded once each, and the checks of one cell."""

    def __init__(self, library: Library, records: Sequence[Record]) -> None:
        self.library = library
        self.names = {r.instance for r in records}
        self._loaded: dict[str, Any] = {}
        self._digest: dict[str, str] = {}

    def instance(self, name: str) -> Any:
        from ...instance import load

        if name not in self._loaded:
            self._loaded[name] = load(self.library.instance_path(name))
        return self._loaded[name]

    def digest(self, name: str) -> str:
        if name not in self._digest:
            self._digest[name] = file_digest(self.library.instance_path(name))
        return self._digest[name]

    def cell_problem(self, cell: dict[str, Any]) -> str | None:
        """Why the cell cannot be merged at all (None: it can)."""
        if cell.get("format") != CELL_FORMAT:
            return f"{cell.get('_file')}: not a bench run cell (format {cell.get('format')!r})"
        name = cell.get("instance")
        if name not in self.names:
            return "unknown instance: the library's index has no such instance"
        if cell.get("instance_sha256") != self.digest(str(name)):
            theirs, ours = str(cell.get("instance_sha256"))[:12], self.digest(str(name))[:12]
            return (
                "the run solved another version of the instance file "
                f"(sha256 {theirs}, the library's {ours})"
            )
        return None

    def plan_problem(self, cell: dict[str, Any]) -> str | None:
        """Why the cell's plan is not a valid plan of its stated makespan (None: it is)."""
        from ...plan import evaluate
        from ...solution import from_dict

        inst = self.instance(str(cell["instance"]))
        method = cell.get("method")
        try:
            sol = from_dict(cell["solution"], f"{cell.get('_file')}: solution")
        except BilevelKitError as exc:
            return f"the plan of {method} does not load: {exc}"
        violations = sol.check(inst)
        if violations:
            shown = "; ".join(f"{v.kind}: {v.message}" for v in violations[:3])
            return f"the plan of {method} fails the checker: {shown}"
        makespan = evaluate(inst, sol.plan).makespan
        stated = cell.get("makespan")
        if not isinstance(stated, int | float) or not same_time(float(stated), makespan):
            return f"{method}'s record says makespan {stated!r} s, its plan gives {makespan!r} s"
        return None


def _bound_problem(cell: dict[str, Any]) -> str | None:
    from ...methods import REGISTRY

    method = str(cell.get("method"))
    if method not in REGISTRY:
        return (
            f"a bound from {method!r}, which is not a registered method here: only a "
            "registered method's bound is a proof (its contract)"
        )
    return None


#: Per instance, (value, cell) of every plan or bound a run offers.
Offers = dict[str, list[tuple[float, dict[str, Any]]]]


def _offers(
    checker: _Checker, cells: Sequence[dict[str, Any]], merge: Merge
) -> tuple[Offers, Offers, list[Problem]]:
    """The valid plans and the proven bounds of the run, and the problems found."""
    plans: Offers = {}
    bounds: Offers = {}
    problems: list[Problem] = []
    for cell in cells:
        name = str(cell.get("instance", Path(str(cell.get("_file"))).stem))
        why = checker.cell_problem(cell)
        if why is not None:
            problems.append(Problem(name, why))
            continue
        found = False
        if cell.get("solution") and cell["solution"].get("kits"):
            why = checker.plan_problem(cell)
            if why is not None:
                problems.append(Problem(name, why))
            else:
                plans.setdefault(name, []).append((float(cell["makespan"]), cell))
                found = True
        if cell.get("bound") is not None and cell.get("status") not in ("error", "refused"):
            why = _bound_problem(cell)
            if why is not None:
                problems.append(Problem(name, why))
            else:
                bounds.setdefault(name, []).append((float(cell["bound"]), cell))
                found = True
        merge.skipped += not found
    return plans, bounds, problems


def _merge_one(
    rec: Record, plans: Offers, bounds: Offers, merge: Merge, problems: list[Problem]
) -> Record:
    """``rec`` with the run's best plan and bound when they improve it; a bound above the
    best plan known (the library's or the run's) is a problem."""
    new = rec
    best = min(plans.get(rec.instance, []), key=lambda x: x[0], default=None)
    if best is not None and improves(best[0], rec.best_known, lower=True):
        prov = _provenance(best[1])
        new = new.with_plan(best[0], prov)
        merge.solutions[rec.instance] = _library_solution(best[1]["solution"])
        merge.changes.append(Change(rec.instance, "plan", rec.best_known, best[0], prov.method))
    for value, cell in bounds.get(rec.instance, []):
        if new.best_known is not None and bound_above(value, new.best_known):
            what = (
                f"bound {value!r} s from {cell.get('method')} is above the best-known plan "
                f"{new.best_known!r} s: no lower bound can be"
            )
            problems.append(Problem(rec.instance, what))
    top = max(bounds.get(rec.instance, []), key=lambda x: x[0], default=None)
    if top is not None and improves(top[0], rec.best_bound, lower=False):
        prov = _provenance(top[1])
        new = new.with_bound(top[0], prov)
        merge.changes.append(Change(rec.instance, "bound", rec.best_bound, top[0], prov.method))
    return new


#: Entries of a solution's ``extra`` longer than this (as JSON) stay out of the library.
EXTRA_MAX_CHARS = 200


def _library_solution(doc: dict[str, Any]) -> dict[str, Any]:
    """The solution document as the library keeps it: the method's long diagnostics in
    ``extra`` (per-kit terms, traces) are left out and named, the rest is as solved."""
    extra = dict(doc.get("extra") or {})
    long = sorted(k for k, v in extra.items() if len(json.dumps(v)) > EXTRA_MAX_CHARS)
    for key in long:
        del extra[key]
    if long:
        extra["left_out_of_library"] = long
    return {**doc, "extra": extra}


def plan_merge(library: Library, run_dirs: Sequence[str | Path]) -> Merge:
    """Check every cell of the runs against the library and compute the merged records;
    :class:`UpdateRefused` (nothing written) on any problem."""
    records = library.read()
    cells = [c for d in run_dirs for c in read_cells(d)]
    merge = Merge(records=[], cells=len(cells))
    problems = [
        Problem(p.instance, f"the library's record does not hold: {p.what}")
        for r in records
        for p in check_record(library, r, require_plan=False)
    ]
    plans, bounds, found = _offers(_Checker(library, records), cells, merge)
    problems += found
    merge.records = [_merge_one(r, plans, bounds, merge, problems) for r in records]
    if problems:
        raise UpdateRefused(problems)
    return merge


def solution_text(doc: dict[str, Any]) -> str:
    """A solution document as the library stores it: one kit per line (compact, and a
    changed plan is a readable diff), every other key on a line of its own."""
    head = json.dumps({k: v for k, v in doc.items() if k != "kits"}, indent=1, allow_nan=False)
    kits = ",\n".join(
        "  " + json.dumps(kit, separators=(",", ":"), allow_nan=False) for kit in doc["kits"]
    )
    return head[:-2] + ',\n "kits": [\n' + kits + "\n ]\n}\n"


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Ctrl-C and SIGTERM wait until the files are in place (the renames take microseconds)."""
    held = {signal.SIGINT, signal.SIGTERM}
    old = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def apply_merge(library: Library, merge: Merge) -> None:
    """Write the merge: every file to a temporary file first, then all renamed, index last."""
    from ...atomic import atomic_path

    texts = [
        (library.solution_path(name), solution_text(doc))
        for name, doc in sorted(merge.solutions.items())
    ]
    texts.insert(0, (library.index_path, library.index_text(merge.records)))
    with contextlib.ExitStack() as stack:
        stack.enter_context(_signals_held())  # exited last: held until every rename is done
        for path, text in texts:  # the index is entered first, so it is renamed last
            tmp = stack.enter_context(atomic_path(path))
            tmp.write_text(text, encoding="utf-8")


def update(library: Library, run_dirs: Sequence[str | Path], *, dry_run: bool = False) -> Merge:
    """Check and (unless ``dry_run``) write the merge of ``run_dirs`` into ``library``."""
    merge = plan_merge(library, run_dirs)
    if merge.changes and not dry_run:
        apply_merge(library, merge)
    return merge
