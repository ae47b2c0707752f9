"""Lower bounds stronger than the closed forms, time-boxed (docs/formulations.md, "Stronger
lower bounds").

:func:`proven_bound` takes the best of the closed forms of :mod:`bilevel_kit.bounds`, the
precedence bounds of :mod:`.precedence` (heads and tails) and the kit-count LP bound of
:mod:`.kit_lp` (the LP relaxation with the kit count fixed, scanned over the counts), rounded
up to the makespan's time grid when every time lies on one. The exact models add it to their
objective (per kit count) and report it with its source; ``lns`` reports it as its bound.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from ...bounds import (
    best_bound,
    instance_times,
    johnson_lines,
    lines_value,
    lower_bounds,
    makespan_grid,
    min_kits,
    on_grid,
    tray_wait,
)
from ...instance import Instance
from .kit_lp import kit_count_bound
from .precedence import head_tail_bounds

#: Divisors tried to make every time an exact multiple of the time grid (the makespan's, and
#: the CP-SAT model's integer times: :func:`..cpsat.scaling.scale_times`).
REFINE = (1, 2, 4, 5, 10, 20, 25, 50, 100, 200, 250, 500, 1000)


@dataclass(frozen=True)
class ProvenBound:
    """A proven lower bound on the makespan: ``value`` (s), its ``source`` (a key of
    ``sources``, every bound computed), the kit-count LP values ``per_kits`` (m -> s, on the
    grid; m below ``stop`` scanned) and the makespan's time grid ``grid`` (None: none found)."""

    value: float
    source: str
    sources: dict[str, float]
    per_kits: dict[int, float] = field(default_factory=dict)
    stop: int = 1
    grid: float | None = None
    #: a reproducible scan cut by its wall-clock safety net (:func:`proven_bound`)
    safety_net: bool = False

    def at(self, m: int, closed: Callable[[int], float]) -> float:
        """A lower bound on the makespan of every plan of exactly ``m`` kits."""
        return max(closed(m), self.per_kits.get(m, -math.inf))

    def kit_cap(self, upper: float, closed: Callable[[int], float]) -> int | None:
        """The most kits a plan of makespan at most ``upper`` can have by the kit-count LP,
        or None when the scan does not decide it (the closed-form caps apply)."""
        if closed(self.stop) <= upper:
            return None
        ok = [m for m, v in self.per_kits.items() if v <= upper + 1e-9]
        return max(ok) if ok else min(self.per_kits, default=1)


def raised(
    proven: ProvenBound | None, value: float, source: str, instance: Instance
) -> ProvenBound:
    """``proven`` with a bound found later (e.g. the ideal search's, :mod:`..bbr`) for every
    plan: its value and source when higher, and every kit count's bound raised to it, so a
    model built afterwards (whose bound is per kit count) starts from it too. Several
    stations: the overall value alone (:func:`_per_kits_stations`; :func:`closed_at` and the
    kit-count LP model one station)."""
    if instance.stations:
        proven, per = _per_kits_stations(proven, value, instance)
    else:
        closed = closed_at(instance)
        if proven is None:
            m0 = int(lower_bounds(instance)["min_kits"])
            proven = ProvenBound(closed(m0), "closed_form", {}, {}, m0)
        per = {m: max(proven.at(m, closed), value) for m in range(1, instance.n_tasks + 1)}
    sources = {**proven.sources, source: value}
    if value > proven.value:
        return replace(proven, value=value, source=source, sources=sources, per_kits=per)
    return replace(proven, sources=sources, per_kits=per)


def _per_kits_stations(
    proven: ProvenBound | None, value: float, instance: Instance
) -> tuple[ProvenBound, dict[int, float]]:
    """:func:`raised` with several stations: ``proven``, or the closed form of the stations
    (:func:`bilevel_kit.bounds.best_bound`) when nothing was proven yet, and the kit counts'
    bounds already known (none from the kit-count LP, which models one station) raised to
    ``value``, which holds for every plan and so for every plan of m kits; no new one is
    made."""
    if proven is None:
        proven = ProvenBound(best_bound(instance), "closed_form", {}, {})
    return proven, {m: max(v, value) for m, v in proven.per_kits.items()}


def closed_at(instance: Instance) -> Callable[[int], float]:
    """The closed-form bound of :mod:`bilevel_kit.bounds` for plans of m kits: (a), (b) with
    the one-tray wait and (d), each with m in place of m_min (each is non-decreasing in m)."""
    lb = lower_bounds(instance)
    m0 = int(lb["min_kits"])
    one = instance.params_of()  # one station's bound
    o_h = one.kit_overhead_human
    a0 = instance.kit_overhead_robot + one.delivery_time
    w = tray_wait(instance)
    ids = [t.id for t in instance.tasks]
    lines = johnson_lines(
        [instance.robot_time(i) for i in ids], [instance.human_time(i) for i in ids], a0, o_h
    )

    def at(m: int) -> float:
        human = lb["human"] + (m - m0) * o_h
        robot = lb["robot"] + (m - m0) * (a0 + w)
        return max(human, robot, lines_value(lines, m))

    return at


def time_grid(
    instance: Instance, resolution: float = 0.1, refine: tuple[int, ...] = REFINE
) -> float | None:
    """The coarsest grid ``resolution / q`` (q in ``refine``) holding every time of the
    instance, each station's delivery time and overhead (then every makespan is on it), or
    None."""
    from ..packing import is_grid_exact

    values = instance_times(instance)
    for q in refine:
        if is_grid_exact(values, resolution / q):
            return resolution / q
    return None


def proven_bound(
    instance: Instance,
    *,
    time_limit: float = 1.0,
    upper: float | None = None,
    lp: bool = True,
    deterministic: bool = False,
) -> ProvenBound:
    """The best of the closed forms, the precedence bounds and (``lp``) the kit-count LP
    bound, this one scanned for at most ``time_limit`` s; ``upper`` (a known plan's makespan)
    ends the scan at the counts whose closed-form bound exceeds it. ``deterministic``
    (docs/simulation.md#determinism): the scan is limited by work instead, the LPs' task x kit
    variables that ``time_limit`` allows at :data:`.kit_lp.LP_S_PER_CELL`, with
    :data:`~..packing_oracle.SAFETY_NET` times ``time_limit`` as a wall-clock safety net
    (``ProvenBound.safety_net`` when it fires), so the bound does not depend on the load."""
    from ..packing_oracle import SAFETY_NET
    from .kit_lp import LP_S_PER_CELL

    lb = lower_bounds(instance)
    sources = {
        "closed_form_human": lb["human"],
        "closed_form_robot": lb["robot"],
        "closed_form_flow": lb["flow"],
    }
    sources.update(head_tail_bounds(instance))
    grid = makespan_grid(instance)
    per: dict[int, float] = {}
    stop = int(lb["min_kits"])
    net = False
    if lp:
        closed = closed_at(instance)
        scan = kit_count_bound(
            instance,
            closed,
            m_min=min_kits(instance),
            deadline=time.perf_counter() + (SAFETY_NET if deterministic else 1.0) * time_limit,
            upper=upper,
            work=int(time_limit / LP_S_PER_CELL) if deterministic else None,
        )
        per = {m: on_grid(v, grid) for m, v in scan.per_kits.items()}
        stop = scan.stop
        net = scan.safety_net
        if per:  # no LP solved in time: its value is a closed form's, named as such
            sources["kit_lp"] = scan.value
    sources = {k: on_grid(v, grid) for k, v in sources.items()}
    source = max(sources, key=lambda k: (sources[k], k == "kit_lp"))
    return ProvenBound(sources[source], source, sources, per, stop, grid, net)


#: The share of a run's time limit the exact models give :func:`proven_bound` (at least
#: :data:`MIN_BOUND_S`, never more than a tenth of what is left).
BOUND_SHARE, MIN_BOUND_S = 0.05, 0.2


def for_model(
    instance: Instance,
    time_limit: float,
    left: float,
    upper: float | None,
    deterministic: bool = False,
) -> ProvenBound:
    """:func:`proven_bound` within an exact model's share of its run (:data:`BOUND_SHARE` of
    ``time_limit``, at least :data:`MIN_BOUND_S`, at most a tenth of the ``left`` seconds).
    ``deterministic``: the share of ``time_limit`` alone (what is left depends on the clock),
    as work (:func:`proven_bound`)."""
    share = max(BOUND_SHARE * time_limit, MIN_BOUND_S)
    if not deterministic:
        share = min(share, 0.1 * max(0.0, left))
    return proven_bound(
        instance, time_limit=share, upper=upper, lp=share > 0.02, deterministic=deterministic
    )


def scaled_kit_bounds(bound: ProvenBound, res: float, exact: bool) -> dict[int, int]:
    """The kit-count LP bounds on a model's integer time grid of ``res`` s: rounded up when
    the grid holds every time (``exact``: the makespan is a multiple of ``res``), else down
    (then the model's times are rounded down and its bound stays valid, docs/formulations.md)."""
    out = {}
    for m, v in bound.per_kits.items():
        if math.isfinite(v):
            out[m] = math.ceil(v / res - 1e-6) if exact else math.floor(v / res + 1e-9)
    return out
