"""The large-neighbourhood search as the exact models' fallback (docs/formulations.md, "Model
too large").

When ``cpsat`` or ``milp`` do not build their model (over the memory limit, or not buildable
in the time left), they used to return their incumbent at once and leave the rest of the time
limit unused. With option ``fallback="lns"`` (the default) they hand the time left to
:func:`.method.lns`, started from that incumbent (so the result is never worse than it) and
given their proven bound (so the LNS stops when it meets it, and computes none of its own).
The caller keeps its own bound and status rules: the LNS's plan is only a better incumbent.
The same call improves their warm start before a model they do build, within a share of the
time left (:mod:`..exact.lns_first`, docs/formulations.md, "The LNS first").
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from ...instance import Instance
from ...plan import Plan, evaluate
from ...validate import check

#: The values of option ``fallback``.
FALLBACKS: tuple[str, ...] = ("lns", "none")
#: Seconds the LNS needs at least to be worth starting (its margins take 0.3 s and more).
MIN_S = 1.0


def improve(
    instance: Instance,
    plan: Plan,
    *,
    bound: float | None,
    seed: int,
    time_limit: float,
    stall: int | None = None,
    iterations: int | None = None,
    cut_share: float | None = None,
) -> tuple[Plan | None, dict[str, Any]]:
    """The LNS's plan from ``plan`` within ``time_limit`` s (and its options ``stall``,
    ``iterations`` and ``cut_share``, None: their defaults) when it is strictly better (else
    None), and what happened (``extra['fallback']`` of the caller): ``method``, ``time_s``
    (the time given), ``makespan_before``, ``makespan_after``, ``windows`` (windows solved),
    ``improvements``, ``start_method``, ``start_time_s``, ``stop``, ``window`` (its last
    window's size), ``skipped`` (why the LNS did not run) when it did not, and ``rejected``
    when :func:`bilevel_kit.validate.check` refused its plan."""
    from .method import LnsOptions, lns

    before = evaluate(instance, plan).makespan
    info: dict[str, Any] = {"method": "lns", "time_s": round(max(0.0, time_limit), 3)}
    info.update(makespan_before=before, makespan_after=before)
    if time_limit < MIN_S:
        info["skipped"] = f"less than {MIN_S:g} s left"
        return None, info
    if bound is not None and before <= bound + 1e-6:
        info["skipped"] = "the incumbent meets the bound"
        return None, info
    # the callers' warm starts ran greedy-ce already
    options = LnsOptions(start="quick", stall=stall, iterations=iterations)
    if cut_share is not None:
        options = replace(options, cut_share=cut_share)
    out = lns(
        instance, options, seed=seed, time_limit=time_limit, start_plan=plan, known_bound=bound
    )
    extra = out.extra
    info.update(
        windows=extra.get("iterations", 0),
        improvements=extra.get("improvements", 0),
        start_method=extra.get("start_method"),
        start_time_s=round(extra.get("start_time_s", 0.0), 3),
        stop=extra.get("stop"),
        window=extra.get("window"),
    )
    after = None if out.plan is None else evaluate(instance, out.plan).makespan
    if out.plan is None or after is None or after >= before - 1e-9:
        return None, info
    problems = check(instance, out.plan)  # the caller returns it as its own: checked
    if problems:
        info["rejected"] = f"the checker refused the LNS's plan: {problems[0]}"
        return None, info
    info["makespan_after"] = after
    return out.plan, info
