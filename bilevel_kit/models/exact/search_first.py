"""The ideal search inside an exact model's budget (docs/formulations.md, "Branch, bound and
remember", "In cpsat and milp"): with option ``search`` > 0, after the LNS first and before the
model, branch, bound and remember (:mod:`..bbr.search`) runs from the incumbent for that share
of the time left.

- Exhausted below the incumbent, relaxed kits included (:mod:`..bbr.search`: kits without a
  layout nor a proof for every layout count as fitting for the bound): the incumbent (or the
  better plan the search found) is optimal and no model is built (``bound_source`` ``bbr``).
- Otherwise a better plan becomes the incumbent, and the search's bound (the least bound of
  its open nodes, for every plan) joins the proven bound the model starts from
  (:func:`..relax.raised`).

With several stations the search runs on their space (:class:`..bbr.stations.StationSpace`,
as ``bbr`` does) and its bound raises the overall bound alone: the kit-count bounds are one
station's (:func:`..relax.raised`), so the model takes it as a lower bound on its makespan
and the result for its status, bound and gap (docs/stations.md#bbr-with-several-stations).

``extra["search_first"]`` reports its counters, stop, bound and time, or why it was skipped:
option ``search`` 0, another objective, release times (the search models neither) and a
reproducible run (``deterministic``: its stop is clock-bound).
"""

from __future__ import annotations

import time
from typing import Any

from ...plan import evaluate
from ..packing import ANY_ANGLE
from . import keys
from .backend import Backend, Inc

#: The ``extra`` key of the report.
SEARCH_FIRST = "search_first"


def before_model(backend: Backend[Inc], inc: Inc, share: float, releases: bool) -> tuple[Inc, bool]:
    """The incumbent after the search from ``inc`` (module docstring), and whether it is
    proven optimal (then no model is needed)."""
    from ..bbr.method import with_layouts
    from ..bbr.search import Space as SearchSpace
    from ..bbr.search import packer_fits, search
    from ..bbr.space import Space
    from ..bbr.stations import StationSpace

    extra, budget, instance = backend.extra, backend.budget, backend.instance
    skipped = _skipped(backend, share, releases)
    if skipped is not None:
        extra[SEARCH_FIRST] = {"skipped": skipped}
        return inc, False
    plan = backend.plan(inc)
    upper = evaluate(instance, plan).makespan
    t0 = budget.elapsed()
    seconds = share * max(0.0, budget.remaining(backend.margin))
    space: SearchSpace = StationSpace(instance) if instance.stations else Space(instance)
    out = search(
        space,
        packer_fits(backend.packer),
        upper=upper,
        deadline=time.perf_counter() + seconds,
    )
    info: dict[str, Any] = {
        "share": share,
        "stop": out.stop,
        "proven": out.exhausted,
        "bound": out.bound,
        "proof_scope": out.scope,
        **out.counters,
    }
    if out.kits is not None:
        better = with_layouts(instance, backend.packer, out.kits)
        if better is not None:
            inc = backend.adopt(better)
            info["makespan_after"] = evaluate(instance, better).makespan
    if out.scope == ANY_ANGLE:
        backend.raise_bound(out.bound, "bbr")
    info[keys.LNS_USED_S] = round(budget.elapsed() - t0, 3)
    extra[SEARCH_FIRST] = info
    proven = out.exhausted and out.scope == ANY_ANGLE
    if proven:
        keys.no_solve(extra, keys.PROVEN_BOUND)
    return inc, proven


def _skipped(backend: Backend[Any], share: float, releases: bool) -> str | None:
    """Why the search does not run (module docstring), or None."""
    if share <= 0:
        return "option search is 0"
    if not backend.is_makespan:
        return "the search minimises the makespan"
    if releases:
        return "the search does not model release times"
    if backend.budget.deterministic:
        return "a reproducible run: the search's stop is clock-bound"
    return None
