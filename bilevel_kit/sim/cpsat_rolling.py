"""The ``cpsat-rolling`` policy: re-plan a window of the remaining work exactly at each epoch.

At each decision epoch the robot takes the first ``window`` remaining tasks in the
deterministic topological order (a set closed under predecessors), solves their segmentation
and scheduling with the exact CP-SAT model (:func:`bilevel_kit.solvers.cpsat.solve`,
short time limit, warm-started from the best heuristic plan) and commits the first kit of the
optimum (or of the best plan found in time). Online information enters the sub-problem as:

* **the human's remaining work** ``h0`` (``SimState.human_remaining``; ignored when the
  instance enforces reachability, whose reach map the token below could not satisfy): a dummy
  first task that
  every window task follows, with human time ``h0 - o_H`` and one part as large as the tray,
  so no other task can share its kit. It shifts the robot's and the human's timelines by the
  same ``o_R + d``, so the window's makespan is exactly the one that starts from the current
  state (up to that constant);
* **parts not in stock**: each task's robot time is its parts' pick times plus the expected
  wait for the parts the stock lacks (``SimState.expected_wait``), the stock being consumed by
  the window's tasks in topological order. This is an estimate: waits are added to picking
  time, not overlapped with it.

Options (:class:`CPSATRollingOptions`, given as ``SimParams.policy_options`` or ``-p`` on the
command line): ``window`` (12 tasks), ``time_limit`` (1.0 s per epoch), ``workers`` (1, so that
simulation cells can run in parallel), ``tray`` ("benders").
Decisions are memoised on (window, rounded times, rounded ``h0``), so runs without supply
delays and with deterministic times re-use them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Literal

from ..instance import Instance, from_dict, topological_order
from ..plan import Kit
from .policies import LayoutCache
from .state import SimState

if TYPE_CHECKING:
    from .params import SimParams

_TOKEN = "__human_busy__"


@dataclass(frozen=True)
class CPSATRollingOptions:
    """Options of the ``cpsat-rolling`` policy (see the module docstring)."""

    window: int = field(default=12, metadata={"help": "tasks re-planned per epoch", "min": 1})
    time_limit: float = field(
        default=1.0, metadata={"help": "CP-SAT time limit per epoch (s)", "min": 0.0}
    )
    workers: int = field(default=1, metadata={"help": "CP-SAT workers", "min": 1})
    tray: Literal["auto", "embedded", "benders"] = field(
        default="benders", metadata={"help": "tray feasibility in the CP-SAT model"}
    )


class CPSATRollingPolicy:
    """Rolling-horizon exact re-planning with CP-SAT (see the module docstring)."""

    name: ClassVar[str] = "cpsat-rolling"

    def __init__(
        self,
        instance: Instance,
        *,
        seed: int = 0,
        params: SimParams | None = None,
        options: CPSATRollingOptions | None = None,
    ) -> None:
        self.instance = instance
        self.seed = seed
        self.options = options if options is not None else CPSATRollingOptions()
        self._order = topological_order(instance)
        self._layouts = LayoutCache(instance)
        self._memo: dict[tuple[Any, ...], Kit] = {}
        self.solves = 0

    def reset(self) -> None:
        """Decisions are a pure function of the sub-problem, so the memo is kept."""

    def decide(self, state: SimState) -> Kit | None:
        remaining = [t for t in self._order if t not in state.done]
        if not remaining:
            return None
        window = remaining[: self.options.window]
        times = self._robot_times(window, state)
        h0 = max(0.0, state.human_remaining)
        key = (tuple(window), tuple(round(times[t], 3) for t in window), round(h0, 3))
        kit = self._memo.get(key)
        if kit is None:
            kit = self._solve(window, times, h0)
            self._memo[key] = kit
        return kit

    def _robot_times(self, window: list[str], state: SimState) -> dict[str, float]:
        """Pick times plus the expected wait for missing parts, stock consumed in order."""
        inst = self.instance
        used: dict[str, int] = {}
        out = {}
        for t in window:
            wait = 0.0
            for ptype, n in inst.task_by_id[t].parts:
                if ptype in state.supply:
                    before = state.expected_wait(ptype, used.get(ptype, 0))
                    used[ptype] = used.get(ptype, 0) + n
                    wait += state.expected_wait(ptype, used[ptype]) - before
            out[t] = inst.robot_time(t) + wait
        return out

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
                "id": t.replace("@", "_u"),
                "parts": [{"type": p, "count": n} for p, n in inst.task_by_id[t].parts],
                "human_time": {"mean": inst.human_time(t)},
                "robot_time": times[t],
            }
            for t in window
        ]
        sub_ids = {t: t.replace("@", "_u") for t in window}
        edges = [
            [sub_ids[a], sub_ids[b]] for a, b in inst.precedence if a in sub_ids and b in sub_ids
        ]
        busy = h0 - inst.kit_overhead_human
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
            edges += [[_TOKEN, sub_ids[t]] for t in window]
        doc = {
            "format": "bilevel-kit/1",
            "name": f"{inst.name}-window",
            "tray": {"width": inst.tray.width, "height": inst.tray.height},
            "delivery_time": inst.delivery_time,
            "kit_overhead": {"robot": inst.kit_overhead_robot, "human": inst.kit_overhead_human},
            "part_types": types,
            "tasks": tasks,
            "precedence": edges,
        }
        if inst.station is not None:
            doc["station"] = inst.station.to_dict()
        if inst.reachability:
            doc["reachability"] = True
            doc["reach_resolution"] = inst.reach_resolution
        return from_dict(doc, f"<{inst.name} cpsat-rolling window>")

    def _solve(self, window: list[str], times: dict[str, float], h0: float) -> Kit:
        from ..solvers.cpsat import best_heuristic_plan, solve

        sub = self._sub_instance(window, times, h0)
        back = {t.replace("@", "_u"): t for t in window}
        hint, _ = best_heuristic_plan(sub, ("single-task", "whole-assembly"), self.seed)
        out = solve(
            sub,
            seed=self.seed,
            time_limit=self.options.time_limit,
            workers=self.options.workers,
            tray=self.options.tray,
            hint=hint,
        )
        self.solves += 1
        plan = out.plan or hint
        if plan is None:  # no plan at all in time: fall back to the next single task
            return self._layouts.kit((window[0],), f"cpsat-rolling fallback {window[0]}")
        first = next(k for k in plan.kits if _TOKEN not in k.tasks)
        return Kit(tuple(back[t] for t in first.tasks), first.layout)
