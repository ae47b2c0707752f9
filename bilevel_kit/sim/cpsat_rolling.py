"""The ``cpsat-rolling`` policy: re-plan a window of the remaining work exactly at each epoch.

At each decision epoch the robot takes the first ``window`` remaining tasks in the
deterministic topological order (a set closed under predecessors), solves their segmentation
and scheduling with the exact CP-SAT model (:func:`bilevel_kit.models.cpsat.solve`, under the
instance's tray limit) and commits the first kit of the optimum (or of the best plan found
within the limit). Online information enters the sub-problem as:

* **the human's remaining work** ``h0`` (``SimState.human_remaining``; ignored when the
  instance enforces reachability, whose reach map the token below could not satisfy): a dummy
  first task that every window task follows, with one part as large as the tray, so no other
  task can share its kit. With unlimited trays (or T >= 2) its human time is ``h0 - o_H``:
  it shifts the robot's and the human's timelines by the same ``o_R + d``, so the window's
  makespan is exactly the one that starts from the current state (up to that constant);
* **the tray** (docs/timeline.md): the robot decides once a tray is free (the simulator waits
  for it first). With **one tray** the dummy kit holds it: its human time is ``h0``, so its
  tray comes back at ``o_R + d + o_H``, exactly when the robot may start the first real kit,
  and the human finishes it ``h0`` later, both shifted by the same constant; the next trays
  come back as the model's own timeline says, so the sub-model is exact. With T >= 2 trays
  the dummy's tray stands for the last delivered kit's and the older delivered kits' trays are
  taken as back: an optimistic approximation;
* **parts not in stock**: a task whose parts the stock lacks gets a **release time**, the
  expected wait until they are all there (``SimState.expected_wait``, the stock consumed by
  the window's tasks in topological order), counted from the model's "now" (after the dummy
  kit); the model does not pick it earlier and picks each kit in the order of release
  (:func:`bilevel_kit.models.cpsat.solve`, docs/formulations.md), so the robot's wait
  overlaps the human's work and the other tasks' picking. The committed kit lists its tasks in
  that order (the simulator's robot picks in kit order). This is an estimate: the arrivals
  are random, a release is their expectation. Waiting for parts leaves slack, so many plans
  tie; when the window has releases, the next kits of the plan are merged into the first
  while their tasks need nothing the stock lacks, the kit fits and the released makespan does
  not grow (fewer kits: less overhead, fewer decisions).

**Determinism** (docs/simulation.md#determinism). Every CP-SAT schedule solve is limited in
deterministic units (``max_deterministic_time`` = ``deterministic_time``) with ``workers``
fixed (1: CP-SAT is then deterministic), and the solve runs in its reproducible mode
(:func:`bilevel_kit.models.cpsat.solve`, ``deterministic=True``): its packing calls are
limited by deterministic time too, with one worker, and its other steps (quick plans,
Benders seed cuts, cut shrinking, the kit-count LP bound) by work, not by the clock, within
``time_limit``. So a simulation run is a function of (instance, policy, parameters, seed)
on an idle or a loaded machine alike; ``time_limit`` and the packing calls' wall-clock limits
are safety nets only: a decision that hits one (a pathologically loaded machine) is no longer
reproducible, and is counted in :attr:`CPSATRollingPolicy.safety_nets`.

**Layouts** (docs/simulation.md#layouts-of-committed-kits). The committed kit's layout is the
shelf packer's when it has one (the policy's own cache, by part multiset). It is not
exact: the model may keep a kit that its packing oracle laid out and the shelf packer cannot
(``sp_n12_s1_t1_tight_d10``: t4-t6). Such a kit gets the model's own layout of it, else the
oracle's (:class:`~bilevel_kit.models.common.Packer` with a deterministic limit, the model's
packing calls' one, so it reuses their memoised answers); ``oracle_layouts`` counts these
decisions. Where neither has a layout (the model's plans have layouts and a merged first kit
is kept only if the shelf packer lays it out, so: the hint's first kit, when the solve found
no plan, and the oracle's answer is unknown within its limit) the kit is split greedily, in
its order, into consecutive kits that have one (the first is committed, the others lead the
next hint; a task nothing lays out alone raises
:class:`~bilevel_kit.errors.KitDoesNotFit`), counted in
:attr:`~CPSATRollingPolicy.layout_fallbacks` and ``SimResult.layout_fallbacks``. An oracle
layout's placements may depend on which multisets the process-wide cache saw first; the
simulated times do not depend on placements.

**Warm start.** Each decision is hinted with the previous decision's plan minus the kit it
committed (restricted to the window, the window's new tasks appended as single kits), or a
baseline plan when that is worse (both evaluated with the releases). Decisions are memoised
on (window, rounded times, rounded releases, rounded ``h0``, hint): a pure function of that
key, so the memo never changes an answer.

**Window.** The first ``window`` remaining tasks (12), or the first ``supply_window`` (8) when
one of them waits for parts: their releases are expectations, and planning further on them
costs solve time for little (measured on the Figure 6 grid, paper_repro/README.md).

Options (:class:`CPSATRollingOptions`, given as ``SimParams.policy_options`` or ``-p`` on the
command line): ``window`` (12 tasks), ``supply_window`` (8), ``deterministic_time`` (0.1 per
solve, about 0.1 s), ``time_limit`` (10 s per epoch, safety net), ``workers`` (1), ``tray``
("benders").
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Literal

from ..errors import KitDoesNotFit
from ..instance import Instance, document, from_dict, topological_order
from ..options import option
from ..plan import Kit, Plan
from .policies import LayoutCache
from .state import PolicyBase, SimState

if TYPE_CHECKING:
    from ..models.packing_oracle import TypedLayout
    from .params import SimParams

_TOKEN = "__human_busy__"
#: Where a committed kit's layout came from (module docstring, "Layouts").
SHELF, MODEL, ORACLE, SPLIT = "shelf", "model", "oracle", "split"
#: A decision: the committed kit, the plan's other kits (task ids), its layout's source.
_Decision = tuple[Kit, tuple[tuple[str, ...], ...], str]


@dataclass(frozen=True)
class CPSATRollingOptions:
    """Options of the ``cpsat-rolling`` policy (see the module docstring)."""

    window: int = option(12, "tasks re-planned per epoch", min=1)
    supply_window: int = option(
        8, "tasks re-planned when a part is missing (at most window; 0: window)", min=0
    )
    deterministic_time: float = option(
        0.1, "CP-SAT deterministic time per solve (reproducible)", min=0.0
    )
    time_limit: float = option(
        10.0, "wall-clock safety net per epoch (s); not reproducible", min=0.0
    )
    workers: int = option(1, "CP-SAT workers (1: deterministic)", min=1)
    tray: Literal["auto", "embedded", "benders"] = option(
        "benders", "tray feasibility in the CP-SAT model"
    )


class CPSATRollingPolicy(PolicyBase):
    """Rolling-horizon exact re-planning with CP-SAT (see the module docstring)."""

    name: ClassVar[str] = "cpsat-rolling"

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        #: its one station's d, o_H and trays (several: a policy per station,
        #: :mod:`.stations`, so several are refused here)
        self.station = instance.params_of()
        self.seed = seed
        self.options: CPSATRollingOptions = (
            options if options is not None else CPSATRollingOptions()
        )
        self._order = topological_order(instance)
        self._layouts = LayoutCache(instance)
        self._memo: dict[tuple[Any, ...], _Decision] = {}
        self._rest: tuple[tuple[str, ...], ...] = ()  # the previous plan after its first kit
        self.solves = 0
        #: decisions whose solve a wall-clock safety net cut short (not reproducible)
        self.safety_nets = 0
        #: committed kits laid out by the model or the packing oracle, not the shelf packer
        self.oracle_layouts = 0
        #: committed kits split because nothing laid out the plan's first kit (module
        #: docstring, "Layouts"); counted per decision, memo hits included
        self.layout_fallbacks = 0
        #: the human time of a task in the window's model: the mean (the adaptive variants,
        #: :mod:`.adaptive`, set their pace estimate here before each decision)
        self.human_time: Callable[[str], float] = instance.human_time

    def reset(self) -> None:
        """Forget the previous plan; decisions are a pure function of the memo's key, so the
        memo is kept."""
        self._rest = ()

    def decide(self, state: SimState) -> Kit | None:
        remaining = [t for t in self._order if t not in state.done]
        if not remaining:
            return None
        window = remaining[: self.options.window]
        waits = self._waits(window, state)
        if any(waits.values()) and self.options.supply_window:
            # a prefix: its waits are the same (stock consumed in order)
            window = window[: self.options.supply_window]
        times = {t: self.instance.robot_time(t) for t in window}
        h0 = max(0.0, state.human_remaining)
        now = self._now(h0)
        releases = {t: round(now + waits[t], 3) for t in window if waits[t] > 0}
        hint = self._warm_kits(window)
        key = (
            tuple(window),
            tuple(round(times[t], 3) for t in window),
            tuple(round(self.human_time(t), 3) for t in window),
            tuple(sorted(releases.items())),
            round(h0, 3),
            hint,
        )
        hit = self._memo.get(key)
        if hit is None:
            hit = self._solve(window, times, h0, hint, releases)
            self._memo[key] = hit
        kit, self._rest, source = hit
        self.oracle_layouts += source in (MODEL, ORACLE)
        self.layout_fallbacks += source == SPLIT
        return kit

    def _warm_kits(self, window: list[str]) -> tuple[tuple[str, ...], ...]:
        """The previous plan's remaining kits on the window, then the window's new tasks one
        per kit (a precedence-feasible plan: new tasks come later in the topological order)."""
        inside = set(window)
        kits = [tuple(t for t in k if t in inside) for k in self._rest]
        kits = [k for k in kits if k]
        seen = {t for k in kits for t in k}
        kits += [(t,) for t in window if t not in seen]
        return tuple(kits)

    def _waits(self, window: list[str], state: SimState) -> dict[str, float]:
        """The expected wait until each task's parts are all in stock, the stock consumed by
        the window's tasks in order."""
        inst = self.instance
        used: dict[str, int] = {}
        out = {}
        for t in window:
            wait = 0.0
            for ptype, n in inst.task_by_id[t].parts:
                if ptype in state.supply:
                    used[ptype] = used.get(ptype, 0) + n
                    wait = max(wait, state.expected_wait(ptype, used[ptype]))
            out[t] = wait
        return out

    def _now(self, h0: float) -> float:
        """The model time of the current state: the first real kit's earliest robot start
        (after the dummy kit, with one tray after its tray came back; module docstring)."""
        inst = self.instance
        if self._busy(h0) <= 0 or inst.reachability:
            return 0.0
        st = self.station
        tray = st.kit_overhead_human if st.tray_limit == 1 else 0.0
        return inst.kit_overhead_robot + st.delivery_time + tray

    def _busy(self, h0: float) -> float:
        """The dummy task's human time (module docstring)."""
        st = self.station
        return h0 if st.tray_limit == 1 else h0 - st.kit_overhead_human

    def _sub_instance(self, window: list[str], times: dict[str, float], h0: float) -> Instance:
        inst = self.instance
        types = [
            {
                "id": p.id,
                "width": p.width,
                "height": p.height,
                "pick_time": p.pick_time,
                "rotatable": p.rotatable,
            }
            for p in inst.part_types.values()
        ]
        tasks = [
            {
                "id": _sub_id(t),
                "parts": [{"type": p, "count": n} for p, n in inst.task_by_id[t].parts],
                "human_time": {"mean": self.human_time(t)},
                "robot_time": times[t],
            }
            for t in window
        ]
        edges = [
            [_sub_id(a), _sub_id(b)]
            for a, b in inst.precedence
            if a in set(window) and b in set(window)
        ]
        # one tray: the dummy kit holds it (module docstring), else it only shifts time
        busy = self._busy(h0)
        if busy > 0 and not inst.reachability:  # (with reachability h0 is ignored)
            # a part filling the (whole-mm) tray: nothing else can share the dummy kit
            w, h = math.floor(inst.tray.width), math.floor(inst.tray.height)
            types.append(
                {"id": _TOKEN, "width": w, "height": h, "pick_time": 0.0, "rotatable": False}
            )
            tasks.insert(
                0,
                {
                    "id": _TOKEN,
                    "parts": [{"type": _TOKEN, "count": 1}],
                    "human_time": {"mean": busy},
                    "robot_time": 0.0,
                },
            )
            edges += [[_TOKEN, _sub_id(t)] for t in window]
        doc = document(
            f"{inst.name}-window",
            types,
            tasks,
            tray=(inst.tray.width, inst.tray.height),
            delivery_time=self.station.delivery_time,
            overhead=(inst.kit_overhead_robot, self.station.kit_overhead_human),
            precedence=edges,
        )
        if self.station.tray_limit is not None:
            doc["trays"] = self.station.tray_limit
        doc.update(inst.work_cell_fields())
        return from_dict(doc, f"<{inst.name} cpsat-rolling window>")

    def _solve(
        self,
        window: list[str],
        times: dict[str, float],
        h0: float,
        warm: tuple[tuple[str, ...], ...],
        releases: dict[str, float],
    ) -> _Decision:
        """The first kit of the window's plan, the plan's other kits (task ids), and where the
        first kit's layout came from."""
        from ..models.cpsat import best_heuristic_plan, released_makespan, solve

        sub = self._sub_instance(window, times, h0)
        back = {_sub_id(t): t for t in window}
        rel = {_sub_id(t): v for t, v in releases.items()}
        dummy = (Kit((_TOKEN,)),) if _TOKEN in sub.task_by_id else ()
        hint = Plan(dummy + tuple(Kit(tuple(_sub_id(t) for t in k)) for k in warm))
        base, _ = best_heuristic_plan(sub, ("single-task", "whole-assembly"), self.seed)
        if base is not None and released_makespan(sub, base, rel) < released_makespan(
            sub, hint, rel
        ):
            hint = base
        opts = self.options
        out = solve(
            sub,
            seed=self.seed,
            time_limit=opts.time_limit,
            workers=opts.workers,
            tray=opts.tray,
            hint=hint,
            cpsat_params={"max_deterministic_time": opts.deterministic_time},
            releases=rel,
            deterministic=True,
        )
        self.solves += 1
        self.safety_nets += bool(out.extra.get("safety_net"))
        plan = out.plan or hint
        if any(rel.values()):  # (else the model's plan as it is: no-delay decisions unchanged)
            plan = self._merge_first(sub, plan, len(dummy), rel, back)
        kits = [tuple(back[t] for t in k.tasks) for k in plan.kits if _TOKEN not in k.tasks]
        return self._commit(sub, kits, _model_layouts(out.plan, back))

    def _commit(
        self, sub: Instance, kits: list[tuple[str, ...]], model: dict[frozenset[str], TypedLayout]
    ) -> _Decision:
        """The first kit laid out (module docstring, "Layouts"), the plan's other kits, and
        where the layout came from; a first kit nothing lays out is split."""
        from ..models.common import split_greedily

        first = kits[0]
        hit = self._laid_out(sub, first, model)
        if hit is not None:
            return hit[0], tuple(kits[1:]), hit[1]
        parts = split_greedily(
            list(first), lambda ts: self._laid_out(sub, tuple(ts), model) is not None
        )
        if parts is None:  # a task alone has no layout either: single-task kits
            parts = [[t] for t in first]
        head = tuple(parts[0])
        got = self._laid_out(sub, head, model)
        # (else no method lays out this task alone: the shelf packer's error says so)
        kit = got[0] if got is not None else self._layouts.kit(head, f"cpsat-rolling {head}")
        rest = tuple(tuple(p) for p in parts[1:]) + tuple(kits[1:])
        return kit, rest, SPLIT

    def _laid_out(
        self, sub: Instance, tasks: tuple[str, ...], model: dict[frozenset[str], TypedLayout]
    ) -> tuple[Kit, str] | None:
        """The kit with a layout and its source: the shelf packer's, else the model's own,
        else the packing oracle's (deterministic limit); None if none has one."""
        from ..models import packing_oracle
        from ..models.budget import Budget
        from ..models.common import Packer, pack_time_limit

        try:
            return self._layouts.kit(tasks, f"cpsat-rolling {tasks}"), SHELF
        except KitDoesNotFit:
            pass
        typed = model.get(frozenset(tasks))
        source = MODEL
        if typed is None:  # the model's packing calls' limit, so its answers are reused
            budget = Budget(self.options.time_limit, stretch=packing_oracle.SAFETY_NET)
            packer = Packer(sub, pack_time_limit(budget), budget, deterministic=True)
            nets = packing_oracle.safety_nets()
            ok, typed = packer.counts(sub.kit_parts([_sub_id(t) for t in tasks]))
            self.safety_nets += packing_oracle.safety_nets() > nets
            source = ORACLE
            if not ok or typed is None:
                return None
        placed = packing_oracle.typed_to_placements(self.instance, tasks, typed)
        return Kit(tasks, placed), source

    def _merge_first(
        self, sub: Instance, plan: Plan, j: int, rel: dict[str, float], back: dict[str, str]
    ) -> Plan:
        """Merge the next kits into the first real kit (position ``j``) while their tasks
        need no part the stock lacks, the kit fits and the released makespan does not grow
        (module docstring)."""
        from ..models.cpsat import released_makespan
        from ..models.cpsat.scaling import released

        order = dict(zip([t.id for t in sub.tasks], released(sub, rel), strict=True))
        kits = [k.tasks for k in plan.kits]
        best = released_makespan(sub, plan, rel)
        while j + 1 < len(kits) and not any(rel.get(t, 0.0) > 0 for t in kits[j + 1]):
            # a topological order: releases are monotone along precedence, kit j comes first
            tasks = tuple(sorted(kits[j] + kits[j + 1], key=order.__getitem__))
            cand = Plan(tuple(Kit(k) for k in (*kits[:j], tasks, *kits[j + 2 :])))
            if released_makespan(sub, cand, rel) > best + 1e-9:
                break
            try:
                ids = tuple(back[t] for t in tasks)
                self._layouts.kit(ids, f"cpsat-rolling {ids}")
            except KitDoesNotFit:
                break
            kits = [k.tasks for k in cand.kits]
        return Plan(tuple(Kit(k) for k in kits))


def _model_layouts(plan: Plan | None, back: dict[str, str]) -> dict[frozenset[str], TypedLayout]:
    """The model's own layouts of its plan's kits, by task set (original ids), by part type:
    any slot of a type fits any part of that type."""
    out: dict[frozenset[str], TypedLayout] = {}
    for k in plan.kits if plan is not None else ():
        if k.layout and _TOKEN not in k.tasks:
            typed: TypedLayout = {}
            for p in k.layout:
                typed.setdefault(p.type, []).append((p.x, p.y, p.theta))
            out[frozenset(back[t] for t in k.tasks)] = typed
    return out


def _sub_id(task: str) -> str:
    """A task id of the window's instance (unit copies ``x@2`` become ``x_u2``)."""
    return task.replace("@", "_u")
