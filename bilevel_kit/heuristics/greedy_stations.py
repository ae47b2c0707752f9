"""greedy-ce with several assembly stations (docs/timeline.md#several-stations).

The rolling-horizon upper level decides which station's kit the robot builds next and what
goes in it, in that order:

* **which station**: the one whose human runs out of work first (the earliest end of its last
  kit so far, ties to the station listed first), among those with tasks left: the baselines'
  earliest need (:mod:`.baselines`);
* **what kit**: the paper's F (Eqs. 3-7) over that station's remaining tasks, with its
  ``d_s``, ``o_H,s`` and ``T_s`` (:func:`bilevel_kit.stations.station_instance`) and its
  human's remaining work ``H_rem = max(0, station_free - now)``, ``now`` being the robot's
  earliest start of a kit for that station (the previous kit of any station has arrived and a
  tray of the station is back).

Each station has a :class:`~.greedy_ce.GreedyCEPolicy` of its own; the lower level's memo is
shared (a part multiset gets the same layout, from the same seed, whatever its station). Past
the time limit each station's remaining tasks are single-task kits, interleaved the same way.
Without ``stations`` :func:`.greedy_ce.plan` is used unchanged.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import fields
from typing import Any, Protocol

from ..instance import Instance
from ..plan import Kit, Plan, TimelineBuilder
from ..stations import station_instance


class StationPolicy(Protocol):
    """What this module needs of :class:`~.greedy_ce.GreedyCEPolicy` (passed in, so that
    :mod:`.greedy_ce` may call this module without an import cycle)."""

    instance: Instance
    deadline: float | None
    stats: Any
    _arrangements: dict[Any, Any]
    _fit_memo: dict[bytes, tuple[float, bool]]

    def decide(self, state: Any) -> Kit | None: ...

    def finish(self, done: set[str]) -> Iterator[Kit]: ...

    def past_deadline(self) -> bool: ...


def station_policies(
    instance: Instance,
    make: Callable[[Instance], StationPolicy],
    deadline: float | None,
) -> dict[str, StationPolicy]:
    """One policy per station on its own tasks and parameters, sharing one layout memo."""
    out: dict[str, StationPolicy] = {}
    for s in instance.station_ids:
        policy = make(station_instance(instance, s))
        policy.deadline = deadline
        if out:  # same part types and tray: the memo is valid across stations
            first = next(iter(out.values()))
            policy._arrangements = first._arrangements
            policy._fit_memo = first._fit_memo
        out[s] = policy
    return out


def plan_greedy(
    instance: Instance,
    make: Callable[[Instance], StationPolicy],
    state: Callable[[frozenset[str], float], Any],
    plan_one: Callable[..., Plan],
    deadline: float | None,
) -> tuple[Plan, Any]:
    """greedy-ce's offline plan and its counters, past ``deadline`` with single-task kits:
    without stations ``plan_one`` (:func:`.greedy_ce.plan`) with one policy built by ``make``,
    unchanged; with several, the plan of the module docstring, one policy per station."""
    if not instance.stations:
        policy = make(instance)
        policy.deadline = deadline
        return plan_one(instance, policy=policy), policy.stats
    policies = station_policies(instance, make, deadline)
    plan = _plan(instance, policies, state)
    return plan, merged_stats(policies, plan)


def _plan(
    instance: Instance,
    policies: dict[str, StationPolicy],
    state: Callable[[frozenset[str], float], Any],
) -> Plan:
    """The offline plan (module docstring): at each epoch the station of earliest need, then
    its policy's next kit for ``state(done, H_rem)``, timed by the one evaluator."""
    timeline = TimelineBuilder(instance)
    done: dict[str, set[str]] = {s: set() for s in policies}
    left = {s: p.instance.n_tasks for s, p in policies.items()}
    tails: dict[str, Iterator[Kit]] = {}
    kits: list[Kit] = []
    while any(left.values()):
        ready = [s for s in policies if left[s]]
        station = min(ready, key=timeline.station_free)  # stable: file order
        policy = policies[station]
        if station in tails or policy.past_deadline():
            tail = tails.setdefault(station, policy.finish(done[station]))
            kit = next(tail)
        else:
            now = timeline.next_start(station)
            h_rem = max(0.0, timeline.station_free(station) - now)
            decided = policy.decide(state(frozenset(done[station]), h_rem))
            assert decided is not None
            kit = decided
        kits.append(kit)
        timeline.append(kit)
        done[station].update(kit.tasks)
        left[station] -= len(kit.tasks)
    return Plan(tuple(kits))


def merged_stats(policies: dict[str, StationPolicy], plan: Plan) -> Any:
    """The stations' counters summed (flags: any), and each kit's terms in plan order."""
    stats = [p.stats for p in policies.values()]
    out = type(stats[0])()
    for f in fields(out):
        if f.name != "objective_terms":
            values = [getattr(st, f.name) for st in stats]
            setattr(out, f.name, any(values) if isinstance(values[0], bool) else sum(values))
    terms = {s: iter(p.stats.objective_terms) for s, p in policies.items()}
    station_of = {t.id: s for s, p in policies.items() for t in p.instance.tasks}
    out.objective_terms = [next(terms[station_of[k.tasks[0]]]) for k in plan.kits]
    return out
