"""The proven makespan bound of :mod:`bilevel_kit.models.relax` in ``cpsat`` (docs/
formulations.md, "Stronger lower bounds"): computed once per run within its share of the time
limit, fed to the model per kit count, used to cap the kit count (with the model's own caps:
:func:`kit_cap`) and reported with its source.
"""

from __future__ import annotations

import math
from typing import Any

from ...bounds import best_bound, end_tasks, kit_slacks
from ...objectives import is_top_level
from ..exact.driver import bound_source as exact_source
from ..exact.driver import known_bound as exact_known
from ..exact.driver import proven_bound
from .context import Context
from .model import tray_wait


def strong_bound(ctx: Context, upper_s: float | None, extra: dict[str, Any]) -> None:
    """The proven bound into ``ctx.proven`` (makespan objective without release times only;
    ``upper_s``: the incumbent's makespan in s, :func:`..exact.driver.proven_bound`)."""
    if not is_top_level(ctx.objective) or any(ctx.sc.rel):  # a bound on the makespan
        return
    if ctx.instance.stations:  # the kit-count LP models one station
        return
    ctx.proven = proven_bound(ctx.instance, ctx.budget, upper_s, extra)


def known_bound(ctx: Context) -> float:
    """The best makespan bound known before the model (s), for every plan."""
    return exact_known(best_bound(ctx.instance), ctx.proven)


def bound_source(ctx: Context, any_s: float | None) -> str:
    """Which bound is the best (:func:`..exact.driver.bound_source`; ``any_s``: the model's
    bound for every plan)."""
    return exact_source(best_bound(ctx.instance), ctx.proven, any_s, 1e-9)


def scaled_kit_bounds(ctx: Context) -> dict[int, int] | None:
    """The kit-count LP bounds on the model's grid (None: none computed)."""
    if ctx.proven is None:
        return None
    from ..relax import scaled_kit_bounds as on_grid

    return on_grid(ctx.proven, ctx.sc.res, ctx.sc.exact)


def scaled_lower(ctx: Context) -> int | None:
    """Several stations, the makespan: the proven bound (the ideal search's,
    :func:`..relax.raised`) as a lower bound on the model's makespan, on an exact grid only (as
    the closed form, :func:`.station_model.build_stations`); None: none. One station's reaches
    the model per kit count instead (:func:`scaled_kit_bounds`)."""
    sc = ctx.sc
    if ctx.proven is None or not sc.station or not sc.exact or not ctx.minimised.is_makespan:
        return None
    return math.ceil(ctx.proven.value / sc.res - 1e-6)


def proven_kit_cap(ctx: Context, upper: int, K: int) -> int:
    """K lowered to the most kits a plan of scaled makespan at most ``upper`` can have by the
    kit-count LP (on an exact grid only: then scaled and real makespans agree)."""
    if ctx.proven is None or not ctx.sc.exact or ctx.sc.station:  # (closed_at: one station)
        return K
    from ..relax import closed_at

    cap = ctx.proven.kit_cap(upper * ctx.sc.res + 1e-6, closed_at(ctx.instance))
    return K if cap is None else max(1, min(K, cap))


def kit_cap(ctx: Context, upper: int | None) -> int:
    """The largest kit count of a plan with scaled makespan <= ``upper`` (:mod:`.method`,
    "Kit count")."""
    sc = ctx.sc
    n = len(sc.r)
    K = n
    if upper is None:
        return K
    K = proven_kit_cap(ctx, upper, K)
    kit = (sc.o_r, sc.d, sc.o_h, tray_wait(sc))  # one tray: the robot waits o_H per kit
    slacks = kit_slacks(upper, (sc.r, sc.h), kit, end_tasks(ctx.instance))
    if sc.station:  # several stations: the robot's alone (sc.d, sc.o_h: the least), the
        slacks = slacks[:1]  # humans work in parallel (docs/timeline.md#several-stations)
    for slack, per_kit in slacks:
        if per_kit > 0:
            K = min(K, max(1, slack // per_kit))
    return K
