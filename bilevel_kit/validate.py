"""The independent checker: ``check(instance, plan) -> list[Violation]``.

It trusts no solver. It recomputes everything from the instance and the plan alone: every task
exactly once, precedence across and inside kits, each kit's parts against its tasks' parts,
every footprint inside the tray and no two footprints overlapping (exact rotated rectangles,
tolerance :data:`bilevel_kit.geometry.TOL`, by :func:`bilevel_kit.geometry.layout_violations`,
the same test every layout search applies), and, when a solution reports times, that they
agree with the timeline evaluator and that no kit starts before its tray is back (the tray
rule of docs/timeline.md, checked on the reported times themselves). What a solution file
claims besides (objective, bound, gap, status: :class:`Claims`) is recomputed too: a file
is never believed, only checked (docs/formats.md).

Every pass is linear in the plan's size; the overlap test only compares parts whose bounding
boxes meet (a grid hash, :func:`bilevel_kit.geometry.layout_violations`), so a long plan and a
dense kit check in about linear time and memory. Every number of a solution file comes through
one strict reader (:mod:`bilevel_kit.solution`): what it refuses is a ``bad_number`` violation,
and a ``status_objective`` that names no known objective is a ``status_mismatch``.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from . import geometry
from .instance import Instance
from .objectives import OBJECTIVES, is_top_level, relative_gap
from .plan import Kit, KitTimes, Placement, Plan, Timeline, evaluate, kitless

#: Absolute tolerance (s) when comparing reported times with the evaluator's.
TIME_TOL = 1e-6

#: The kinds that concern what a result claims about its plan (not the plan itself).
CLAIM_KINDS = (
    "objective_mismatch",
    "bound_above_makespan",
    "bound_above_objective",
    "gap_mismatch",
    "status_mismatch",
)

KINDS = (
    "empty_kit",
    "kit_without_parts",
    "unknown_task",
    "repeated_task",
    "missing_task",
    "precedence",
    "wrong_station",
    "unknown_part_type",
    "duplicate_part_id",
    "parts_mismatch",
    "footprint_mismatch",
    "rotation_not_allowed",
    "outside_tray",
    "overlap",
    "unreachable",
    "times_inconsistent",
    "tray_not_returned",
    *CLAIM_KINDS,
    "instance_mismatch",
    "bad_number",
)

#: Overlapping pairs listed per kit; more are summarised in one violation (a tampered file with
#: thousands of stacked parts would otherwise list every pair).
MAX_OVERLAPS_LISTED = 100


@dataclass(frozen=True)
class Claims:
    """What a solution file states about its plan besides the times: ``status``, ``objective``
    (the makespan, s), ``bound`` (a lower bound on the optimum, s) and ``gap`` (``(objective -
    bound) / objective``). ``None``: not stated. ``has_gap``: the file has a ``gap`` key (its
    null then claims that there is no gap to state)."""

    status: str | None = None
    objective: float | None = None
    bound: float | None = None
    gap: float | None = None
    has_gap: bool = False
    #: The objective ``status`` refers to; "optimal" only promises a zero makespan gap when it
    #: is ``makespan``.
    status_objective: str = "makespan"
    #: What the result states about ``status_objective`` when it is not the makespan (a
    #: format-2 file's ``objective`` block, a format-1 file's ``extra``): value, bound, gap
    #: (None: not stated) and whether a gap key is present.
    objective_claims: tuple[float | None, float | None, float | None, bool] | None = None
    #: Where those are stated, for the messages (None: a format-1 file's ``extra`` keys).
    objective_where: tuple[str, str] | None = None
    #: The instance parameters the times were computed for (:func:`timeline_params`).
    timeline: Mapping[str, Any] | None = None
    #: The claims whose number the strict reader refused (``bound``, ``gap`` ...): reported
    #: as such, so nothing is checked against them.
    refused: frozenset[str] = frozenset()


def timeline_params(instance: Instance) -> dict[str, Any]:
    """The instance parameters that shape the timeline beside the tasks (docs/timeline.md): a
    solution records them so that checking it against other parameters is named as such."""
    return {
        "delivery_time": instance.delivery_time,
        "kit_overhead": {
            "robot": instance.kit_overhead_robot,
            "human": instance.kit_overhead_human,
        },
        "trays": instance.trays,
        **({"stations": [st.to_dict() for st in instance.stations]} if instance.stations else {}),
    }


@dataclass(frozen=True)
class Violation:
    """One problem with a plan: a machine-readable ``kind`` and a readable ``message``."""

    kind: str
    message: str
    kit: int | None = None  # 1-based kit index, when the violation belongs to a kit

    def to_dict(self) -> dict[str, object]:
        return {"kind": self.kind, "message": self.message, "kit": self.kit}

    def __str__(self) -> str:
        return f"[{self.kind}] {self.message}"


def check(
    instance: Instance,
    plan: Plan,
    *,
    reported_kits: Sequence[KitTimes] | None = None,
    reported_metrics: Mapping[str, float] | None = None,
    claims: Claims | None = None,
    reported_stations: Mapping[str, Mapping[str, float]] | None = None,
    reported_kit_stations: Sequence[str | None] | None = None,
) -> list[Violation]:
    """All violations of ``plan`` on ``instance`` (empty list: the plan is valid).

    ``reported_kits``/``reported_metrics`` are the times a solution file claims; they are
    compared with :func:`bilevel_kit.plan.evaluate` within :data:`TIME_TOL`. ``claims`` are
    its headline numbers, recomputed likewise (see :func:`_check_claims`). With several
    stations, ``reported_stations`` (per station: ``completion``, ``human_idle``, ``n_kits``)
    and ``reported_kit_stations`` (each kit's stated station, None where not stated) are
    recomputed too (docs/timeline.md#several-stations).
    """
    out: list[Violation] = []
    if claims is not None:  # first: it explains every time that follows
        out += _check_instance(instance, claims)
    out += _check_tasks(instance, plan)
    out += _check_stations(instance, plan)
    for k, kit in enumerate(plan.kits, start=1):
        out += _check_layout(instance, kit, k)
    # times of unknown tasks are undefined (already reported): the claimed times are then
    # left alone; else the one evaluation serves every timed claim
    timed = (reported_kits, reported_metrics, reported_stations)
    known = instance.task_by_id
    if any(c is not None for c in timed) and all(t in known for t in plan.task_order):
        tl = evaluate(instance, plan)
        if reported_kits is not None or reported_metrics is not None:
            out += _check_times(instance, plan, tl, reported_kits, reported_metrics)
        if reported_stations is not None:
            out += _check_station_metrics(tl, reported_stations)
    if reported_kit_stations is not None:
        out += _check_kit_stations(instance, plan, reported_kit_stations)
    if claims is not None:
        out += _check_claims(instance, plan, claims, plan_valid=not out)
    return out


def _check_instance(instance: Instance, claims: Claims) -> list[Violation]:
    """The solution's times were computed for this instance's timeline parameters."""
    if claims.timeline is None:
        return []
    want = timeline_params(instance)
    out = []
    for key, value in want.items():
        got = claims.timeline.get(key, "absent")
        if _refused(got):
            continue  # a number the reader refused: a violation of its own
        if got != value:
            hint = " (pass --trays to check it as solved)" if key == "trays" else ""
            out.append(
                Violation(
                    "instance_mismatch",
                    f"the solution was computed with {key} = {_show(got)}, the instance has "
                    f"{_show(value)}{hint}",
                )
            )
    return out


def _show(value: Any) -> str:
    return "unlimited" if value is None else str(value)


def _refused(value: Any) -> bool:
    """A NaN the strict number reader left for a refused number (:mod:`.solution`), also
    inside a dict (the overheads)."""
    if isinstance(value, dict):
        return any(_refused(v) for v in value.values())
    return isinstance(value, float) and math.isnan(value)


def _close(got: float, want: float) -> bool:
    return math.isclose(got, want, abs_tol=TIME_TOL, rel_tol=1e-9)


def _check_claims(
    instance: Instance, plan: Plan, claims: Claims, *, plan_valid: bool
) -> list[Violation]:
    """The objective is the evaluator's makespan; the bound is no larger than the makespan of
    a valid plan; the gap is recomputed from the makespan and the bound; ``optimal`` needs a
    bound equal to the makespan; ``infeasible`` cannot come with a valid plan."""
    out: list[Violation] = []
    # the objectives a status may refer to: the registry's, a plugin's too, each checked by
    # _check_objective
    if claims.status_objective not in OBJECTIVES:
        msg = (
            f"status_objective {claims.status_objective!r} names no known objective "
            f"({', '.join(OBJECTIVES)}), so status {claims.status!r} claims nothing "
            "that can be checked"
        )
        out.append(Violation("status_mismatch", msg))
    if any(t not in instance.task_by_id for kit in plan.kits for t in kit.tasks):
        return out  # already reported; the makespan of unknown tasks is undefined
    if not plan.kits:
        if claims.objective is not None:
            msg = f"objective {claims.objective:.6g} s claimed for a solution without kits"
            out.append(Violation("objective_mismatch", msg))
        if claims.status == "optimal" and instance.n_tasks:
            out.append(Violation("status_mismatch", "status 'optimal' without a plan"))
        return out
    makespan = evaluate(instance, plan).makespan
    if claims.objective is not None and not _close(claims.objective, makespan):
        msg = f"objective {claims.objective:.6g} s, the plan's makespan is {makespan:.6g} s"
        out.append(Violation("objective_mismatch", msg))
    bound = claims.bound
    if plan_valid and bound is not None and bound > makespan and not _close(bound, makespan):
        msg = f"bound {bound:.6g} s is above the makespan {makespan:.6g} s of a valid plan"
        out.append(Violation("bound_above_makespan", msg))
    want = relative_gap(makespan, bound)
    if (
        claims.has_gap
        and not claims.refused & {"gap", "bound"}
        and (
            (want is None) != (claims.gap is None)
            or (want is not None and claims.gap is not None and abs(claims.gap - want) > 1e-9)
        )
    ):
        shown = "null" if claims.gap is None else f"{claims.gap:.6g}"
        msg = f"gap {shown}, recomputed from the makespan and the bound: " + (
            "null" if want is None else f"{want:.6g}"
        )
        out.append(Violation("gap_mismatch", msg))
    if "bound" in claims.refused:
        pass  # nothing to hold the status against
    elif claims.status == "optimal" and is_top_level(claims.status_objective):
        if bound is None:
            msg = "status 'optimal' without a bound"
            out.append(Violation("status_mismatch", msg))
        elif makespan - bound > TIME_TOL and not _close(bound, makespan):
            msg = (
                f"status 'optimal' but the makespan {makespan:.6g} s is above the bound "
                f"{bound:.6g} s (gap {makespan - bound:.6g} s)"
            )
            out.append(Violation("status_mismatch", msg))
    elif claims.status == "infeasible" and plan_valid:
        out.append(Violation("status_mismatch", "status 'infeasible' but the plan is valid"))
    return out + _check_objective(instance, plan, claims, plan_valid=plan_valid)


def _check_objective(
    instance: Instance, plan: Plan, claims: Claims, *, plan_valid: bool
) -> list[Violation]:
    """The claims on a ``status_objective`` stated in ``extra`` (every registered objective
    but the makespan, checked above): the value is the registry's evaluation of the plan, the
    bound is at most that value on a valid plan, the gap is the objective's gap of the two,
    and ``optimal`` needs a bound equal to the value (within :data:`TIME_TOL` plus the
    objective's ``rel_tol``). J is not a function of the timeline: its stated value stands in."""
    obj = OBJECTIVES.get(claims.status_objective)
    if obj is None or obj.top_level:
        return []
    value, bound, gap, has_gap = claims.objective_claims or (None, None, None, False)
    real = obj.value(evaluate(instance, plan))
    keys, bound_key = claims.objective_where or (
        f"extra.{obj.value_keys[0]}",
        f"extra.{obj.bound_keys[0]}",
    )
    out: list[Violation] = []
    if value is not None and real is not None and not _close(value, real):
        msg = f"{keys} {value:.6g} for {obj.name}, the plan's is {real:.6g}"
        out.append(Violation("objective_mismatch", msg))
    ref = value if real is None else real
    if ref is None:
        if claims.status == "optimal":
            msg = f"status 'optimal' for {obj.name} without its value ({keys})"
            out.append(Violation("status_mismatch", msg))
        return out
    tol = TIME_TOL + obj.rel_tol * max(1.0, abs(ref))
    if plan_valid and bound is not None and bound > ref + tol:
        msg = f"bound {bound:.6g} on {obj.name} is above its value {ref:.6g} for a valid plan"
        out.append(Violation("bound_above_objective", msg))
    want = None if bound is None else obj.gap(ref, bound)
    if has_gap and ((want is None) != (gap is None) or abs((gap or 0.0) - (want or 0.0)) > 1e-9):
        shown, wanted = (f"{g:.6g}" if g is not None else "null" for g in (gap, want))
        msg = f"{obj.name} gap {shown}, recomputed from its value and bound: {wanted}"
        out.append(Violation("gap_mismatch", msg))
    if claims.status == "optimal" and bound is None:
        msg = f"status 'optimal' for {obj.name} without a bound ({bound_key})"
        out.append(Violation("status_mismatch", msg))
    elif claims.status == "optimal" and bound is not None and ref - bound > tol:
        msg = f"status 'optimal' but {obj.name} {ref:.6g} is above its bound {bound:.6g}"
        out.append(Violation("status_mismatch", msg))
    return out


def _check_tasks(instance: Instance, plan: Plan) -> list[Violation]:
    out: list[Violation] = []
    known = instance.task_by_id
    position: dict[str, tuple[int, int]] = {}  # task -> (kit, index in kit), first occurrence
    for k, kit in enumerate(plan.kits, start=1):
        if not kit.tasks:
            out.append(Violation("empty_kit", f"kit {k} holds no task", k))
        elif kitless(instance, kit):  # docs/timeline.md#part-less-tasks
            out.append(
                Violation(
                    "kit_without_parts",
                    f"kit {k} holds only part-less tasks ({', '.join(kit.tasks)}): they need no "
                    "kit of their own and ride in a neighbouring kit of their station",
                    k,
                )
            )
        for j, t in enumerate(kit.tasks):
            if t not in known:
                out.append(Violation("unknown_task", f"kit {k} holds unknown task {t!r}", k))
            elif t in position:
                out.append(
                    Violation(
                        "repeated_task",
                        f"task {t!r} appears again in kit {k} (first in kit {position[t][0]})",
                        k,
                    )
                )
            else:
                position[t] = (k, j)
    missing = [t.id for t in instance.tasks if t.id not in position]
    if missing:
        shown = ", ".join(map(repr, missing[:8])) + (" ..." if len(missing) > 8 else "")
        out.append(Violation("missing_task", f"{len(missing)} task(s) in no kit: {shown}"))
    for a, b in instance.precedence:
        if a not in position or b not in position:
            continue
        (ka, ia), (kb, ib) = position[a], position[b]
        if ka > kb:
            out.append(
                Violation(
                    "precedence",
                    f"{a!r} must precede {b!r} but is delivered in kit {ka}, after kit {kb}",
                    kb,
                )
            )
        elif ka == kb and ia > ib:
            out.append(
                Violation(
                    "precedence", f"{a!r} must precede {b!r} but comes after it inside kit {ka}", ka
                )
            )
    return out


def _check_stations(instance: Instance, plan: Plan) -> list[Violation]:
    """Each kit holds tasks of one station (docs/timeline.md#several-stations); precedence
    never joins two stations, so the precedence pass above is per station already."""
    if not instance.stations:
        return []
    out = []
    for k, kit in enumerate(plan.kits, start=1):
        where = {instance.task_by_id[t].station for t in kit.tasks if t in instance.task_by_id}
        if len(where) > 1:
            shown = ", ".join(sorted(where))
            out.append(Violation("wrong_station", f"kit {k} mixes tasks of stations {shown}", k))
    return out


def _check_layout(instance: Instance, kit: Kit, k: int) -> list[Violation]:
    """Kit ``k``'s layout: each placement on its own, the parts against the tasks' parts,
    reachability (when the instance asks for it), then the overlapping pairs."""
    types = instance.part_types
    tray = instance.tray
    # The geometry (one test for the checker and every layout search) runs on the parts it can
    # place: a known type (its own footprint, not the drawn one) and a finite position.
    shapes = [
        Placement(pl.part, pl.type, pl.x, pl.y, pl.theta, pt.width, pt.height)
        for pl in kit.layout
        if (pt := types.get(pl.type)) is not None and _finite(pl)
    ]
    faults = geometry.layout_violations(
        shapes, tray.width, tray.height, limit=MAX_OVERLAPS_LISTED + 1
    )
    outside = {f.index for f in faults if f.kind == "outside_tray"}
    out = _check_placements(instance, kit, k, outside)
    out += _check_kit_parts(instance, kit, k)
    if instance.reachability:
        out += _check_reach(instance, kit, k)
    out += _list_overlaps(shapes, faults, k)
    return out


def _finite(pl: Placement) -> bool:
    return math.isfinite(pl.x) and math.isfinite(pl.y) and math.isfinite(pl.theta)


def _check_placements(instance: Instance, kit: Kit, k: int, outside: set[int]) -> list[Violation]:
    """Each placement: a fresh part id, a known type, its type's footprint, a finite position,
    no rotation of a part that may not rotate, inside the tray (``outside``: the indices, among
    the placeable parts, that the geometry found sticking out)."""
    out: list[Violation] = []
    types = instance.part_types
    tray = instance.tray
    ids: set[str] = set()
    n_shapes = 0
    for pl in kit.layout:
        if pl.part in ids:
            out.append(
                Violation("duplicate_part_id", f"kit {k}: part id {pl.part!r} used twice", k)
            )
        ids.add(pl.part)
        if pl.type not in types:
            out.append(
                Violation(
                    "unknown_part_type",
                    f"kit {k}: part {pl.part!r} has unknown type {pl.type!r}",
                    k,
                )
            )
            continue
        pt = types[pl.type]
        if math.isnan(pl.w) or math.isnan(pl.h):
            pass  # refused by the strict number reader (:mod:`.solution`): reported there
        elif not (
            math.isclose(pl.w, pt.width, abs_tol=geometry.TOL)
            and math.isclose(pl.h, pt.height, abs_tol=geometry.TOL)
        ):
            out.append(
                Violation(
                    "footprint_mismatch",
                    f"kit {k}: part {pl.part!r} is drawn {pl.w:g} x {pl.h:g} "
                    f"mm but type {pt.id!r} is {pt.width:g} x {pt.height:g} mm",
                    k,
                )
            )
        if not _finite(pl):
            out.append(
                Violation("outside_tray", f"kit {k}: part {pl.part!r} has a non-finite position", k)
            )
            continue
        if not pt.rotatable and abs(math.remainder(pl.theta, 180.0)) > 1e-9:
            out.append(
                Violation(
                    "rotation_not_allowed",
                    f"kit {k}: part {pl.part!r} of type {pt.id!r} may not "
                    f"rotate but lies at {pl.theta:g} deg",
                    k,
                )
            )
        if n_shapes in outside:
            out.append(
                Violation(
                    "outside_tray",
                    f"kit {k}: part {pl.part!r} at ({pl.x:g}, {pl.y:g}, "
                    f"{pl.theta:g} deg) sticks out of the {tray.width:g} x {tray.height:g} mm tray",
                    k,
                )
            )
        n_shapes += 1
    return out


def _check_kit_parts(instance: Instance, kit: Kit, k: int) -> list[Violation]:
    """The placed parts of known types, counted by type, against what the kit's tasks need."""
    need: Counter[str] = Counter()
    for t in kit.tasks:
        if t in instance.task_by_id:
            for p, n in instance.task_by_id[t].parts:
                need[p] += n
    have = Counter(pl.type for pl in kit.layout if pl.type in instance.part_types)
    if have == need:
        return []
    diff = [
        f"{p}: needs {need[p]}, has {have[p]}"
        for p in sorted(set(need) | set(have))
        if need[p] != have[p]
    ]
    return [
        Violation(
            "parts_mismatch",
            f"kit {k}: parts do not match its tasks (" + "; ".join(diff) + ")",
            k,
        )
    ]


def _check_reach(instance: Instance, kit: Kit, k: int) -> list[Violation]:
    """Parts whose centre the Sawyer cannot reach (docs/formats.md, ``reachability``)."""
    from .reachability import unreachable

    placed = [p for p in kit.layout if p.type in instance.part_types]
    return [
        Violation(
            "unreachable",
            f"kit {k}: part {part!r} lies where the Sawyer cannot place it "
            "(its centre is in an unreachable cell of the reach map)",
            k,
        )
        for part in unreachable(instance, placed)
    ]


def _list_overlaps(
    shapes: Sequence[Placement], faults: Sequence[geometry.LayoutViolation], k: int
) -> list[Violation]:
    """One violation per overlapping pair, up to :data:`MAX_OVERLAPS_LISTED`, then one that
    says more were left out."""
    out: list[Violation] = []
    listed = 0
    for f in faults:
        if f.kind == "overlap":
            assert f.other is not None
            if listed == MAX_OVERLAPS_LISTED:
                out.append(Violation("overlap", f"kit {k}: more overlapping parts, not listed", k))
                break
            listed += 1
            pa, pb = shapes[f.index].part, shapes[f.other].part
            out.append(
                Violation(
                    "overlap",
                    f"kit {k}: parts {pa!r} and {pb!r} overlap "
                    f"({f.area:.6g} mm^2, depth {f.depth:.3g} mm)",
                    k,
                )
            )
    return out


def _check_times(
    instance: Instance,
    plan: Plan,
    tl: Timeline,
    reported_kits: Sequence[KitTimes] | None,
    reported_metrics: Mapping[str, float] | None,
) -> list[Violation]:
    """The reported kit times and metrics are ``tl``'s, the evaluator's (within TIME_TOL)."""
    out: list[Violation] = []
    if reported_kits is not None:
        if len(reported_kits) != len(tl.kits):
            out.append(
                Violation(
                    "times_inconsistent",
                    f"{len(reported_kits)} kit times reported for {len(tl.kits)} kits",
                )
            )
        for k, (got, want) in enumerate(zip(reported_kits, tl.kits, strict=False), start=1):
            for name in ("robot_start", "robot_end", "arrive", "human_start", "human_end"):
                g, w = getattr(got, name), getattr(want, name)
                if math.isnan(g):
                    continue  # refused by the strict number reader: reported there
                if not math.isclose(g, w, abs_tol=TIME_TOL, rel_tol=1e-9):
                    out.append(
                        Violation(
                            "times_inconsistent",
                            f"kit {k}: reported {name} {g:.6g} s, evaluator gives {w:.6g} s",
                            k,
                        )
                    )
        out += _check_tray_rule(instance, plan, reported_kits)
    if reported_metrics is not None:
        for name, w in tl.metrics().items():
            if name not in reported_metrics:
                continue
            g = reported_metrics[name]
            if not math.isclose(float(g), float(w), abs_tol=TIME_TOL, rel_tol=1e-9):
                out.append(
                    Violation(
                        "times_inconsistent", f"reported {name} {g:.6g}, evaluator gives {w:.6g}"
                    )
                )
    return out


def _check_tray_rule(instance: Instance, plan: Plan, kits: Sequence[KitTimes]) -> list[Violation]:
    """``robot_start_k >= human_start_j + o_H`` on the reported times, ``j`` the ``T_s``-th
    previous kit of kit k's station ``s`` (one station: the ``T``-th previous kit)."""
    out = []
    seen: dict[str, list[int]] = {}  # station -> its kits' indices so far
    for k, (kt, kit) in enumerate(zip(kits, plan.kits, strict=False)):
        station = _station(instance, kit)
        own = seen.setdefault(station, [])
        params = instance.station_params.get(station)
        trays = params.tray_limit if params is not None else None
        if trays is not None and len(own) >= trays:
            j = own[-trays]
            back = kits[j].human_start + params.kit_overhead_human  # type: ignore[union-attr]
            if kt.robot_start < back - TIME_TOL:
                at = f" of station {station}" if station else ""
                out.append(
                    Violation(
                        "tray_not_returned",
                        f"kit {k + 1}: the robot starts at {kt.robot_start:.6g} s, before the "
                        f"tray of kit {j + 1} is back at {back:.6g} s ({trays} tray(s){at})",
                        k + 1,
                    )
                )
        own.append(k)
    return out


def _check_kit_stations(
    instance: Instance, plan: Plan, stated: Sequence[str | None]
) -> list[Violation]:
    """Each kit's stated station is its tasks' station."""
    out = []
    for k, (kit, s) in enumerate(zip(plan.kits, stated, strict=False), start=1):
        if s is not None and kit.tasks and s != _station(instance, kit):
            msg = (
                f"kit {k} is stated for station {s!r}, its tasks are of {_station(instance, kit)!r}"
            )
            out.append(Violation("wrong_station", msg, k))
    return out


def _check_station_metrics(
    tl: Timeline, stated: Mapping[str, Mapping[str, float]]
) -> list[Violation]:
    """The stated per-station completion, human idle and kit count are ``tl``'s."""
    want = tl.station_metrics()
    out = []
    for station, got in stated.items():
        if station not in want:
            msg = f"metrics are stated for station {station!r}, which has no kit in the plan"
            out.append(Violation("times_inconsistent", msg))
            continue
        for name, g in got.items():
            w = want[station][name]
            if not math.isnan(g) and not math.isclose(g, w, abs_tol=TIME_TOL, rel_tol=1e-9):
                out.append(
                    Violation(
                        "times_inconsistent",
                        f"station {station}: reported {name} {g:.6g}, evaluator gives {w:.6g}",
                    )
                )
    return out


def _station(instance: Instance, kit: Kit) -> str:
    """A kit's station as the checker sees it: its first known task's ("" without)."""
    known = [t for t in kit.tasks if t in instance.task_by_id]
    return instance.task_by_id[known[0]].station if known else ""
