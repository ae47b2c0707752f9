"""``bench verify``: every record of the library holds (docs/kitbench.md#verify).

For every row of the index: the instance file loads and is what the row says (name, tasks,
trays, delivery time); the best-known plan (``solutions/NAME.json``) passes the independent
checker (``bilevel_kit.validate``) with every number it states; its makespan is the
evaluator's and equals ``best_known``; the bound is at most ``best_known``; the status and the
gap are what the numbers give (checked when the index is read). Every instance file has a row
and every solution file an instance. Only the checker and the evaluator run: no solver.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from ...errors import BilevelKitError
from ...instance import Instance, load
from ...plan import evaluate
from ...solution import read
from .filters import Term, select
from .library import Library, Record, bound_above, same_time, trays_text


@dataclass(frozen=True)
class Problem:
    """Something that does not hold, for one instance."""

    instance: str
    what: str

    def line(self) -> str:
        return f"{self.instance}: {self.what}"


def check_record(library: Library, rec: Record, *, require_plan: bool = True) -> list[Problem]:
    """The problems of one record (an empty list: it holds); ``require_plan=False``: a record
    without a plan yet is not one."""
    try:
        inst = load(library.instance_path(rec.instance))
    except (BilevelKitError, OSError) as exc:
        return [Problem(rec.instance, f"the instance file does not load: {exc}")]
    out = [
        Problem(rec.instance, f"{what}: index says {said}, the instance file {has}")
        for what, said, has in (
            ("name", rec.instance, inst.name),
            ("tasks", rec.tasks, inst.n_tasks),
            ("trays", trays_text(rec.trays), trays_text(inst.trays)),
            ("delivery_time", rec.delivery_time, inst.delivery_time),
        )
        if said != has
    ]
    if rec.best_known is None:
        return [*out, Problem(rec.instance, "no best-known plan")] if require_plan else out
    if rec.best_bound is not None and bound_above(rec.best_bound, rec.best_known):
        what = f"best_bound {rec.best_bound!r} s is above best_known {rec.best_known!r} s"
        out.append(Problem(rec.instance, what))
    return out + check_plan(library.solution_path(rec.instance), inst, rec.best_known)


def check_plan(path: Path, inst: Instance, best_known: float) -> list[Problem]:
    """The solution file at ``path`` passes the checker on ``inst`` and its makespan is
    ``best_known``."""
    name = inst.name
    try:
        sol = read(path)
    except (BilevelKitError, OSError) as exc:
        return [Problem(name, f"the best-known plan does not load: {exc}")]
    violations = sol.check(inst)
    if violations:
        shown = "; ".join(f"{v.kind}: {v.message}" for v in violations[:3])
        more = f" (and {len(violations) - 3} more)" if len(violations) > 3 else ""
        return [Problem(name, f"the best-known plan fails the checker: {shown}{more}")]
    makespan = evaluate(inst, sol.plan).makespan
    if not same_time(makespan, best_known):
        what = f"the best-known plan's makespan is {makespan!r} s, index says {best_known!r} s"
        return [Problem(name, what)]
    return []


def stray_files(library: Library, records: Iterable[Record]) -> list[Problem]:
    """Instance files without a row, and solution files without an instance."""
    names = {r.instance for r in records}
    out = [
        Problem(p.stem, "instance file without a row in index.csv")
        for p in library.instance_files()
        if p.stem not in names
    ]
    solutions = library.solution_path("x").parent
    out += [
        Problem(p.stem, f"solution file {p.name} without a row in index.csv")
        for p in sorted(solutions.glob("*.json"))
        if p.stem not in names
    ]
    return out


def verify(library: Library, terms: Sequence[Term] = ()) -> tuple[list[Record], list[Problem]]:
    """The records and every problem of the library (the index is read strictly first);
    with filter ``terms``, only the records they select (and no search for stray files)."""
    records = library.read()
    problems = [] if terms else stray_files(library, records)
    records = select(records, terms)
    for rec in records:
        problems += check_record(library, rec)
    return records, problems
