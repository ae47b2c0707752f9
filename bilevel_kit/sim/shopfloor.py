"""The shop-floor discrete-event simulation (paper Section V-B) on SimPy.

Processes:

* **Feeders** (:mod:`.feeders`): one per part type with a supply process.
* **Robot**: at each decision epoch (t = 0, then each time it is back from a delivery) it
  first waits for a free tray (below), then asks its policy for the next kit with a
  :class:`~.state.SimState`; spends the kit overhead ``o_R``; picks the kit's parts one by one
  (each part's pick time, :mod:`.timing`), and when a part is out of stock waits until its
  feeder delivers one (recorded as a wait); then delivers in ``d`` (busy while delivering) and
  is free again.
* **Human**: takes a kit when it arrives if idle, otherwise the kit waits in a FIFO queue at the
  assembly station; spends ``o_H`` retrieving its parts, which frees the tray, and assembles the
  kit's tasks in order with the sampled durations. The run ends when the human finishes the
  last task. With several stations (docs/simulation.md#several-stations) each station has a
  human of its own, with its queue, ``o_H``, trays and delivery time ``d_s``; the run ends
  when the last of them finishes.
* **Trays**: the instance's ``trays`` (docs/timeline.md): the robot starts kit k only once the
  tray of kit k - trays is back, ``o_H`` after the human started that kit, the evaluator's
  ``robot_start_k >= human_start_{k-trays} + o_H``. The wait is ``robot_blocked`` in the
  record. With unlimited trays a fast robot can stack several kits at a slow human
  (``max_queue`` in the record says how many).

With no supply process and deterministic times this is exactly the timeline of
:func:`bilevel_kit.plan.evaluate` (docs/timeline.md) on the plan of kits the simulation
produced, for any number of trays; the tests check it to 1e-9 for every policy. This module is
the engine; :mod:`.runs` builds a run's policy and sampled times and turns the engine's log
into a :class:`~.runs.SimResult`.

Choices (also in :class:`.params.SimParams`):

* ``human_remaining`` in the state is observed progress plus expected durations: the robot
  sees which step of which kit the human is on and since when, and adds the instance's mean
  times for the rest (``human_estimate="oracle"`` uses the sampled durations instead).
* Parts are picked in kit order (tasks in order, each task's parts in file order);
  ``pick_order="available-first"`` picks in-stock parts first and waits only when none of the
  remaining parts is in stock.
* Robot idle = makespan - sum(R_k + d), as in the evaluator: time spent waiting for parts is
  robot idle time (and is also reported on its own as ``robot_wait``).

Randomness: :func:`.runs.run` is a pure function of (instance, policy, params, seed). Each run's
:class:`numpy.random.SeedSequence` ``[seed, 0x5EED, stream]`` feeds separate streams for the
human times, the robot times and each feeder (by the part type's index in sorted order), all
drawn independently of the policy's decisions: the same seed gives every policy the same
participants and the same arrivals (common random numbers for paired comparisons).
"""

from __future__ import annotations

from collections import Counter, deque
from collections.abc import Callable, Generator, Mapping
from typing import Any

import numpy as np
import simpy

from ..errors import BilevelKitError
from ..instance import Instance, StationParams
from ..plan import Kit, kit_station
from .feeders import Feeder
from .params import SimParams
from .state import UNLIMITED, HumanProgress, Policy, SimState
from .timing import SampledTimes

#: Stream tag of every run's random numbers (``SeedSequence([seed, STREAM, stream])``).
STREAM = 0x5EED


class SimulationError(BilevelKitError):
    """A policy did something the shop floor cannot execute (or the run did not finish)."""


class ShopFloor:
    """One run's processes and bookkeeping (use :func:`.runs.simulate`)."""

    def __init__(
        self,
        inst: Instance,
        policy: Policy,
        params: SimParams,
        times: SampledTimes,
        seed: int,
    ) -> None:
        self.inst = inst
        self.policy = policy
        self.params = params
        self.times = times
        self.env = env = simpy.Environment()
        types = sorted(inst.part_types)
        init = params.initial_stock
        self.feeders: dict[str, Feeder] = {}
        for t, s in sorted(inst.supply.items()):
            n0 = init.get(t, 0) if isinstance(init, Mapping) else init
            rng = np.random.default_rng(np.random.SeedSequence([seed, STREAM, 2, types.index(t)]))
            self.feeders[t] = Feeder(env, t, s, rng, int(n0))
        if params.human_estimate == "oracle":
            self._dur: Callable[[str], float] = times.human.__getitem__
        else:
            self._dur = inst.human_time
        self.kits: list[Kit] = []
        self.kit_stations: list[str] = []
        self.kit_times: list[dict[str, float]] = []
        self.kit_waits: list[float] = []
        self.done: set[str] = set()
        self.max_queue = 0
        self._tray_back: simpy.Event | None = None
        self.robot_blocked = 0.0
        #: one human per station ("" alone without ``stations``), docs/timeline.md
        self.humans = {s: _Human(s, inst.params_of(s)) for s in inst.station_ids}
        self.left = Counter(t.station for t in inst.tasks)  # tasks not kitted, per station
        self.task_start: dict[str, float] = {}
        self.task_end: dict[str, float] = {}
        self.observed: dict[str, float] = {}  # measured durations of finished tasks
        self.human_work = 0.0
        self.robot_work = 0.0
        self.robot_wait = 0.0
        self.n_waits = 0
        self.finished_tasks = 0
        self.finished = env.event()
        env.process(self._robot())
        for human in self.humans.values():
            env.process(self._human(human))

    # -- the robot's view ----------------------------------------------------------------------
    def _progress(self, human: _Human) -> HumanProgress:
        """A human's position now: task ids and clock times only."""
        k = human.in_hand
        return HumanProgress(
            now=self.env.now,
            overhead=human.params.kit_overhead_human,
            in_hand=self.kits[k].tasks if k is not None else (),
            phase=human.phase,
            phase_start=human.phase_start,
            queued=tuple(self.kits[q].tasks for q in human.queue),
        )

    def state(self) -> SimState:
        avail = dict.fromkeys(self.inst.part_types, UNLIMITED)
        for t, f in self.feeders.items():
            avail[t] = f.stock
        progress = self._progress(self.humans[self.inst.station_ids[0]])
        true_speed: tuple[float, ...] = ()
        if getattr(self.policy, "sees_true_speed", False):  # the oracle references only
            sf = self.params.timing.session_factor
            true_speed = tuple(s * sf for s in self.times.speed)
        return SimState(
            time=self.env.now,
            done=frozenset(self.done),
            human_remaining=progress.remaining(self._dur),
            available=avail,
            expected_arrival={t: f.expected_time_to_arrival() for t, f in self.feeders.items()},
            repair_remaining={t: f.repair_remaining() for t, f in self.feeders.items()},
            supply=dict(self.inst.supply),
            kits_delivered=len(self.kits),
            observed=dict(self.observed),
            progress=progress,
            true_speed=true_speed,
            **(self._station_views() if self.inst.stations else {}),
        )

    def _station_views(self) -> dict[str, Any]:
        """The stations' fields of :class:`SimState` (docs/timeline.md#several-stations)."""
        progress = {s: self._progress(h) for s, h in self.humans.items()}
        remaining = {s: p.remaining(self._dur) for s, p in progress.items()}
        free = {}
        for s, h in self.humans.items():
            busy = h.in_hand is not None or h.queue
            free[s] = self.env.now + remaining[s] if busy else h.last_end
        return {
            "station_progress": progress,
            "station_remaining": remaining,
            "station_free": free,
            "station_left": {s: self.left[s] for s in self.humans},
            "trays_free": {s: h.trays_free() for s, h in self.humans.items()},
        }

    def _check_kit(self, kit: Kit) -> None:
        name = getattr(self.policy, "name", type(self.policy).__name__)
        if not kit.tasks:
            raise SimulationError(f"policy {name!r} returned an empty kit")
        seen = set(self.done)
        for t in kit.tasks:
            if t not in self.inst.task_by_id:
                raise SimulationError(f"policy {name!r} kitted unknown task {t!r}")
            if t in seen:
                raise SimulationError(f"policy {name!r} kitted task {t!r} twice")
            missing = self.inst.predecessors[t] - seen
            if missing:
                raise SimulationError(
                    f"policy {name!r} kitted {t!r} before its predecessor(s) {sorted(missing)}"
                )
            seen.add(t)
        stations = {self.inst.station_of(t) for t in kit.tasks}
        if len(stations) > 1:
            raise SimulationError(
                f"policy {name!r} kitted tasks of several stations {sorted(stations)} in one kit"
            )

    # -- processes -----------------------------------------------------------------------------
    def _all_blocked(self) -> bool:
        """No station with tasks left has a tray back (with one station: kit k waits for the
        tray of kit k - T, docs/timeline.md)."""
        return len(self.done) < self.inst.n_tasks and all(
            h.blocked() for s, h in self.humans.items() if self.left[s] > 0
        )

    def _robot(self) -> Generator[simpy.Event, Any, None]:
        env, inst = self.env, self.inst
        o_r = inst.kit_overhead_robot
        while True:
            # the robot decides once a tray of some station with work left is back
            yield from self._wait_trays(self._all_blocked)
            kit = self.policy.decide(self.state())
            if kit is None:
                if len(self.done) < inst.n_tasks:
                    raise SimulationError(
                        f"policy stopped with {inst.n_tasks - len(self.done)} task(s) not kitted"
                    )
                return
            self._check_kit(kit)
            human = self.humans[kit_station(inst, kit.tasks)]
            # several stations: the policy may choose a station whose trays are all out
            yield from self._wait_trays(human.blocked)
            k = len(self.kits)
            self.kits.append(kit)
            self.kit_stations.append(human.station)
            human.kits_out += 1
            self.done.update(kit.tasks)
            self.left[human.station] -= len(kit.tasks)
            start = env.now
            if o_r:
                yield env.timeout(o_r)
            picks = [p for t in kit.tasks for p in self.times.picks[t]]
            busy = o_r + sum(dur for _, dur in picks)
            if self.params.pick_order == "kit":
                wait = yield from self._pick_in_order(picks)
            else:
                wait = yield from self._pick_available_first(picks)
            end = env.now
            d = human.params.delivery_time
            if d:
                yield env.timeout(d)
            self.robot_work += busy + d
            self.robot_wait += wait
            self.kit_waits.append(wait)
            self.kit_times.append({"robot_start": start, "robot_end": end, "arrive": env.now})
            human.queue.append(k)
            self.max_queue = max(self.max_queue, len(human.queue))
            ev = human.kit_ready
            if ev is not None:
                human.kit_ready = None
                ev.succeed()

    def _wait_trays(self, blocked: Callable[[], bool]) -> Generator[simpy.Event, Any, None]:
        """Wait while ``blocked()`` (each tray back wakes the robot); counted as blocked."""
        if not blocked():
            return
        t0 = self.env.now
        while blocked():
            self._tray_back = self.env.event()
            yield self._tray_back
        self.robot_blocked += self.env.now - t0

    def _pick_in_order(
        self, picks: list[tuple[str | None, float]]
    ) -> Generator[simpy.Event, Any, float]:
        """Pick in kit order, waiting for each out-of-stock part; returns the time waited."""
        env = self.env
        wait = 0.0
        for ptype, dur in picks:
            f = self.feeders.get(ptype) if ptype is not None else None
            if f is not None:
                if f.stock == 0:
                    t0 = env.now
                    self.n_waits += 1
                    while f.stock == 0:
                        yield f.arrival()
                    wait += env.now - t0
                f.take()
            if dur:
                yield env.timeout(dur)
        return wait

    def _pick_available_first(
        self, picks: list[tuple[str | None, float]]
    ) -> Generator[simpy.Event, Any, float]:
        """Pick in-stock parts first; wait only when none of the remaining parts is in stock."""
        env = self.env
        wait = 0.0
        pending = list(picks)
        while pending:
            idx = next(
                (
                    i
                    for i, (p, _) in enumerate(pending)
                    if p is None or p not in self.feeders or self.feeders[p].stock > 0
                ),
                None,
            )
            if idx is None:
                t0 = env.now
                self.n_waits += 1
                needed = dict.fromkeys(p for p, _ in pending)
                yield env.any_of([self.feeders[p].arrival() for p in needed])  # type: ignore[index]
                wait += env.now - t0
                continue
            ptype, dur = pending.pop(idx)
            if ptype is not None and ptype in self.feeders:
                self.feeders[ptype].take()
            if dur:
                yield env.timeout(dur)
        return wait

    def _human(self, human: _Human) -> Generator[simpy.Event, Any, None]:
        env, inst = self.env, self.inst
        oh = human.params.kit_overhead_human
        h = self.times.human
        while True:
            if not human.queue:
                human.kit_ready = env.event()
                yield human.kit_ready
            k = human.queue.popleft()
            tasks = self.kits[k].tasks
            human.in_hand, human.phase, human.phase_start = k, -1, env.now
            self.kit_times[k]["human_start"] = env.now
            work = oh
            if oh:
                yield env.timeout(oh)
            # the parts are off the tray: it goes back to the robot
            human.trays_back += 1
            back = self._tray_back
            if back is not None:
                self._tray_back = None
                back.succeed()
            for j, t in enumerate(tasks):
                human.phase, human.phase_start = j, env.now
                self.task_start[t] = env.now
                work += h[t]
                yield env.timeout(h[t])
                self.task_end[t] = env.now
                self.observed[t] = h[t]
            self.kit_times[k]["human_end"] = env.now
            self.human_work += work
            human.in_hand = None
            human.last_end = env.now
            self.finished_tasks += len(tasks)
            if self.finished_tasks == inst.n_tasks:
                self.finished.succeed()
                return


class _Human:
    """The human of one station: the kits waiting there (FIFO), the one in hand, the trays
    (docs/timeline.md#several-stations)."""

    def __init__(self, station: str, params: StationParams) -> None:
        self.station = station
        self.params = params
        self.queue: deque[int] = deque()
        self.kit_ready: simpy.Event | None = None
        self.kits_out = 0  # kits built for this station
        self.trays_back = 0  # of them, those whose parts the human retrieved (tray free)
        self.in_hand: int | None = None
        self.phase = -1
        self.phase_start = 0.0
        self.last_end = 0.0  # when the human finished the last kit (0 before the first)

    def trays_free(self) -> int:
        """Trays back at the robot now (:data:`UNLIMITED` without a binding limit)."""
        limit = self.params.tray_limit
        return UNLIMITED if limit is None else limit - (self.kits_out - self.trays_back)

    def blocked(self) -> bool:
        """Every tray of the station is out: its next kit must wait for one to come back."""
        return self.trays_free() <= 0
