"""The ``compare`` experiment: one cell per (instance file, method), run through the cell
runner (:mod:`.cells`), and the best known bound and gap of each row."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:
    from ..instance import Instance
    from ..methods import Result


class SolveCell:
    """The base of the comparison and benchmark cells (frozen dataclasses, one solve of one
    instance file each): the instance's digest and text, the key, the record's first fields,
    the solve.

    The cell carries the instance file's text (:attr:`document`), read when the cell is made,
    so a worker needs no file system shared with the client, nor the client's working folder
    (docs/cluster.md#a-cluster-by-hand); the path only names the file in records and messages.
    """

    __dataclass_fields__: ClassVar[dict[str, Any]]
    #: Fields left out of :meth:`key` (the document: :attr:`instance_sha256` is its digest).
    unkeyed: ClassVar[tuple[str, ...]] = ("instance", "document")
    #: Fields left out of an error record's copy of the cell (:func:`.cells.cell_config`).
    unrecorded: ClassVar[tuple[str, ...]] = ("document",)
    instance: str  # path of the instance file
    instance_sha256: str  # the file's content digest, filled in when the cell is made
    document: str  # the file's text, filled in when the cell is made
    method: str
    seed: int
    time_limit: float | None
    params: dict[str, Any]

    def __post_init__(self) -> None:
        if not self.instance_sha256 or not self.document:
            digest, text = instance_fields(self.instance)
            if not self.instance_sha256:
                object.__setattr__(self, "instance_sha256", digest)
            if not self.document and digest == self.instance_sha256:
                object.__setattr__(self, "document", text)

    def load(self) -> Instance:
        """The cell's instance, from the text it carries (from the file when it carries none:
        the file could not be read, and the loader says why)."""
        from ..instance import load, loads

        return loads(self.document, self.instance) if self.document else load(self.instance)

    def key(self) -> str:
        """A stable file-name key for this cell's saved result: the instance's stem, method
        and seed, and a digest of every field but :attr:`unkeyed`.

        The digest covers the instance file's bytes, not its path, so an edited file never
        reuses a saved result; the file's stem only makes the name readable.
        """
        config = {k: v for k, v in asdict(self).items() if k not in self.unkeyed}
        blob = json.dumps(config, sort_keys=True, default=str)
        digest = hashlib.sha1(blob.encode()).hexdigest()[:12]
        return f"{Path(self.instance).stem}__{self.method}__s{self.seed}__{digest}"

    def head(self, name: str) -> dict[str, Any]:
        """A record's first fields: the instance (``name``, file, digest) and the solve's
        configuration."""
        return {
            "instance": name,
            "instance_file": self.instance,
            "instance_sha256": self.instance_sha256,
            "method": self.method,
            "seed": self.seed,
            "time_limit": self.time_limit,
            "params": dict(self.params),
        }

    def solve(self, inst: Instance) -> Result:
        """The cell's solve, with the checker's verdict."""
        from ..methods import solve

        return solve(
            inst, self.method, seed=self.seed, time_limit=self.time_limit, check=True, **self.params
        )


@dataclass(frozen=True)
class CompareCell(SolveCell):
    """One solve of one instance with one method."""

    instance: str  # path of the instance file
    method: str
    seed: int = 0
    time_limit: float | None = None
    params: dict[str, Any] = field(default_factory=dict)
    overrides: dict[str, Any] = field(default_factory=dict)  # delivery_time, weights, ...
    instance_sha256: str = ""  # the file's content digest, filled in when the cell is made
    document: str = field(default="", repr=False)  # the file's text, filled in likewise


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's bytes (empty string when it cannot be read: the cell then fails
    with the loader's message)."""
    return instance_fields(path)[0]


def instance_fields(path: str | Path) -> tuple[str, str]:
    """The SHA-256 of a file's bytes and its text, read once (both empty when it cannot be
    read, the text empty when it is not UTF-8: the cell then fails with the loader's
    message). Cells of one file made from one call share its text."""
    try:
        data = Path(path).read_bytes()
    except OSError:
        return "", ""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = ""
    return hashlib.sha256(data).hexdigest(), text


def compare_cell(cell: CompareCell) -> dict[str, Any]:
    """Solve one cell and return its record (metrics, status, bound, checker verdict)."""
    from ..errors import BilevelKitError
    from .cells import cell_config

    inst = cell.load().with_overrides(**cell.overrides)
    record: dict[str, Any] = {**cell.head(inst.name), "n_tasks": inst.n_tasks}
    try:
        res = cell.solve(inst)
    except BilevelKitError as exc:  # a failed cell: its error and its configuration
        return {**record, "status": "error", "error": str(exc), "cell": cell_config(cell)}
    from ..solution import result_to_dict
    from ..validate import CLAIM_KINDS

    m = res.metrics or {}
    violations = res.extra.get("violations", [])
    claims = [v for v in violations if v["kind"] in CLAIM_KINDS]
    violations = [v for v in violations if v["kind"] not in CLAIM_KINDS]
    return {
        **record,
        "status": res.status_text,
        "makespan": m.get("makespan"),
        "human_idle": m.get("human_idle"),
        "robot_idle": m.get("robot_idle"),
        "n_kits": m.get("n_kits"),
        "bound": res.makespan_bound,
        "gap_own": res.makespan_gap,
        "wall_time_s": res.wall_time_s,
        # the run stopped at its time limit, not on its own (docs/cli.md#time-limits)
        "time_limit_hit": bool(res.extra.get("time_limit_hit")),
        # None: the method returned no plan (unknown/infeasible), which is not an invalid plan
        "valid": None if res.plan is None else not violations,
        "violations": len(violations),
        # the result's status, bound and gap against its own makespan (the checker's claims)
        "false_claims": [f"[{v['kind']}] {v['message']}" for v in claims],
        **objective_record(inst, res),
        "solution": result_to_dict(res, cell.overrides),
    }


def objective_record(inst: Instance, res: Result) -> dict[str, Any]:
    """What a row needs for the cross-method test of every registered objective
    (:func:`objective_conflicts`): ``objective_values``, each objective's value on the plan
    (the registry's evaluation; empty without a plan), and ``objective_claim``, the status
    objective, whether it is claimed optimal and the bound stated on it."""
    from ..objectives import OBJECTIVES, evaluated
    from ..plan import evaluate

    values = {}
    if res.plan is not None and res.plan.kits:
        tl = evaluate(inst, res.plan)
        values = {o.name: o.value(tl) for o in evaluated()}
    obj = OBJECTIVES.get(res.objective_name)
    bound = res.bound if obj is not None and obj.bound_holds_for_every_plan else None
    claim = {"name": res.objective_name, "optimal": res.status == "optimal", "bound": bound}
    return {"objective_values": values, "objective_claim": claim}


def _file_of(record: dict[str, Any]) -> str:
    """The group of a row: its instance file (several files may share an instance name)."""
    return str(record.get("instance_file", record.get("instance")))


def add_best_bound_gap(records: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """Add ``best_bound`` (max bound over the rows of the same instance file), ``above_best`` (the
    lead figure, (makespan - best bound) / best bound, docs/timeline.md#terms) and ``gap`` to it
    ((makespan - best bound) / makespan), as fractions. A best bound above the makespan of a valid
    plan of the same file is no bound: its rows get ``inconsistent`` (the message
    :func:`inconsistencies` lists) and no best bound or gap."""
    from ..methods import above_bound, gap
    from ..validate import TIME_TOL

    rows = list(records)
    best: dict[str, float] = {}
    low: dict[str, float] = {}  # the least makespan of a valid plan
    for r in rows:
        f = _file_of(r)
        if r.get("bound") is not None:
            best[f] = max(best.get(f, r["bound"]), r["bound"])
        if r.get("valid") is True and r.get("makespan") is not None:
            low[f] = min(low.get(f, r["makespan"]), r["makespan"])
    for r in rows:
        f = _file_of(r)
        b, ms = best.get(f), r.get("makespan")
        if b is not None and f in low and b > low[f] + max(TIME_TOL, 1e-9 * low[f]):
            r["inconsistent"] = _inconsistency(rows, f, b, low[f])
            b = None
        r["best_bound"] = b
        r["above_best"] = above_bound(ms, b)
        r["gap"] = gap(ms, b)
    return rows


def _inconsistency(rows: list[dict[str, Any]], f: str, bound: float, makespan: float) -> str:
    """Which methods claim the bound, and which found the plan below it."""
    same = [r for r in rows if _file_of(r) == f]
    claim = sorted({str(r["method"]) for r in same if r.get("bound") == bound})
    plan = sorted(
        {str(r["method"]) for r in same if r.get("valid") is True and r.get("makespan") == makespan}
    )
    return (
        f"{same[0].get('instance', f)}: the bound {bound:.6g} s of {', '.join(claim)} is above "
        f"the makespan {makespan:.6g} s of a valid plan of {', '.join(plan)}: a lower bound "
        "cannot be"
    )


def objective_conflicts(records: Iterable[dict[str, Any]]) -> list[str]:
    """For every registered objective a row claims (:mod:`bilevel_kit.objectives`): a claimed
    optimum above the value of another row's valid plan of the same file, or a bound stated
    on it (besides the ``bound`` column, which :func:`add_best_bound_gap` holds) above such a
    value, one line naming both methods. A row without these keys (an older cell) claims
    nothing here."""
    from ..objectives import OBJECTIVES
    from ..validate import TIME_TOL

    rows = list(records)
    out: list[str] = []
    for r in rows:
        claim = r.get("objective_claim") or {}
        obj = OBJECTIVES.get(str(claim.get("name")))
        if obj is None or obj.evaluate is None:
            continue
        own = (r.get("objective_values") or {}).get(obj.name)
        said = [("claims the optimum", own)] if claim.get("optimal") and own is not None else []
        if not obj.top_level and claim.get("bound") is not None:
            said.append(("states the bound", claim["bound"]))
        others = [
            (o["objective_values"][obj.name], str(o["method"]))
            for o in rows
            if _file_of(o) == _file_of(r)
            and o.get("valid") is True
            and (o.get("objective_values") or {}).get(obj.name) is not None
        ]
        if not others:
            continue
        low, by = min(others)
        for what, v in said:
            if v > low + max(TIME_TOL, 1e-9 * abs(low)):
                out.append(
                    f"{r.get('instance')}: {r['method']} {what} {v:.6g} on {obj.name}, above "
                    f"the {obj.name} {low:.6g} of a valid plan of {by}"
                )
    return out


def inconsistencies(records: Iterable[dict[str, Any]]) -> list[str]:
    """Every false claim of a comparison, one line each: a best bound above a valid plan's
    makespan (:func:`add_best_bound_gap`), a claimed optimum or bound of any registered
    objective above another method's valid plan (:func:`objective_conflicts`), and a row's
    own status, bound or gap against its own plan (the checker's claims)."""
    rows = list(records)
    out: list[str] = []
    for r in rows:
        if r.get("inconsistent") and r["inconsistent"] not in out:
            out.append(r["inconsistent"])
    out += [c for c in objective_conflicts(rows) if c not in out]
    for r in rows:
        out += [f"{r['instance']} / {r['method']}: {c}" for c in r.get("false_claims") or ()]
    return out
