"""The LNS inside an exact model's budget (docs/formulations.md, "The LNS first"): before
``cpsat`` or ``milp`` build their model, the large-neighbourhood search improves their warm
start, so that their plan at a time limit is never worse than the LNS's. The model then
searches from the better incumbent (a tighter C <= U and a better hint) in the rest of the time.

The hand-off is adaptive, and counted in windows (so deterministic for a seed up to the cap):
the LNS stops after a sweep's worth of windows in a row without improvement
(:func:`stall_windows`), at a local optimum, or when its plan meets the proven bound;
:data:`SHARE` of the time left is only its cap. Small instances solve windows too: a window
that frees the whole plan is a smaller model than the exact one, and solved within its
deterministic time it found plans the model did not find in the rest of the time
(docs/formulations.md, "The LNS first", issue 37).
``extra["lns_first"]`` reports the rule and how it ran (:mod:`.keys`).

**The LNS after the model.** When the LNS first's windows improved the plan, the model gets
at most :data:`MODEL_SHARE` of the time left (:func:`model_share`), and unless it proves its
plan the LNS resumes from it in the rest (:func:`after_share`, ``extra["lns_after"]``): the
LNS's later, larger windows kept improving where the model's search found nothing.

When the LNS's plan meets the proven bound the model is not built (the plan is optimal by the
bound computed before the model, as in the driver's shortcut). Otherwise the status stays the
model's: a plan the LNS found is ``optimal`` only when the model proves it or it meets that
bound. With several stations the LNS is ``lns``'s station search
(docs/stations.md#lns-with-several-stations, :mod:`.station_lns`), here for the makespan.
Skipped (``extra["lns_first"]["skipped"]``) with option ``fallback=none``, several stations
with another objective, other objectives and release times (which the LNS does not model),
and in a
reproducible run (``deterministic``): the LNS's start is clock-bound, as for the no-model
hand-off (:mod:`.nomodel`).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from ...methods import Status
from ...plan import evaluate
from . import keys
from .backend import Backend, Inc
from .nomodel import HandOff

if TYPE_CHECKING:
    from ...methods import MethodOutput

#: The most of the time left (after the warm start and the proven bound) the LNS may use
#: before the model; measured in docs/formulations.md, "The LNS first" (0.5 left ``cpsat``
#: 15 % above ``lns`` at 10 s on a 100-task record whose LNS improved in every window).
SHARE = 0.8
#: Windows in a row without improvement that end the LNS first at least (:func:`stall_windows`),
#: and with several stations (sweeps of kit visits there, :mod:`.station_lns`).
STALL_WINDOWS = 4
#: The ``extra`` key the backends' :meth:`~.backend.Backend.hand_off` reports the LNS under.
HAND_OFF_KEY = "fallback"
#: Tolerance (s) of "the same makespan".
TOL = 1e-6
#: The most of the time left after the LNS first that the model may use when the LNS first's
#: windows improved the plan; the LNS resumes from the better plan in the rest unless the
#: model proved it (:func:`after_share`; docs/formulations.md, "The LNS after the model").
MODEL_SHARE = 0.5
#: The most of the LNS first's time its start plans cut from task orders may take
#: (:func:`limits`).
MAX_CUT_SHARE = 0.5
#: Seconds the LNS after the model needs at least (fewer left: it does not run).
MIN_AFTER_S = 0.5


def stall_windows(kits: int) -> int:
    """The LNS first's stall with a one-station incumbent of ``kits`` kits: the windows of one
    sweep of ``lns`` (one from every kit but the last, :mod:`..lns.method`), at least
    :data:`STALL_WINDOWS`; so it stops at a local optimum of the windows it solves, not within a
    sweep (``table_u5_tu_loose_d30`` at 10 s: 4 windows found nothing in 0.25 s, the model
    nothing in 7 s, while ``lns``'s fifth window improved the plan; docs/formulations.md,
    "The LNS first")."""
    return max(STALL_WINDOWS, kits - 1)


def limits(seconds: float, time_limit: float, kits: int = 0) -> HandOff:
    """The LNS first's limits with ``seconds`` at most (module docstring): no window cap, on
    small instances too; the stall of :func:`stall_windows` for an incumbent of ``kits`` kits
    (0: :data:`STALL_WINDOWS`, as with several stations). Its start plans cut from task orders
    get the seconds they get in ``lns`` at the run's ``time_limit`` (``CUT_SHARE`` of it), at
    most :data:`MAX_CUT_SHARE` of ``seconds``: within 25 % of the LNS first's cap they missed
    ``lns``'s start plan (docs/formulations.md, "The LNS first": ``sp_n100_s2_t1_loose_d10``
    at 10 s)."""
    from ..lns.start import CUT_SHARE  # (lns imports the exact models' warm start)

    share = CUT_SHARE if seconds <= 0 else CUT_SHARE * time_limit / seconds
    cut = min(MAX_CUT_SHARE, max(CUT_SHARE, share))
    return HandOff(seconds, stall_windows(kits), None, cut_share=cut)


def before_model(backend: Backend[Inc], inc: Inc, fallback: str) -> tuple[Inc, bool]:
    """The incumbent after the LNS from ``inc`` within :func:`limits`, and whether it meets
    the bound known before the model (then no model is needed). ``extra["lns_first"]`` gets
    the LNS's report, its limits and the time split."""
    extra, budget = backend.extra, backend.budget
    skipped = _skipped(backend, fallback)
    if skipped is not None:
        extra[keys.LNS_FIRST] = {"skipped": skipped}
        return inc, False
    seconds = SHARE * max(0.0, budget.remaining(backend.margin))
    # with several stations the station search counts its stall in sweeps of its own
    kits = 0 if backend.instance.stations else len(backend.plan(inc).kits)
    limit = limits(seconds, budget.time_limit, kits)
    inc, info = _reported_hand_off(backend, inc, limit)
    info.update(
        {
            "share": SHARE,
            "cut_share": limit.cut_share,
            keys.LNS_STALL: limit.stall,
            keys.LNS_MAX_WINDOWS: limit.windows,
        }
    )
    extra[keys.LNS_FIRST] = info
    after = info.get("makespan_after")
    met = after is not None and after <= backend.known_bound() + TOL
    if met and extra.get("improved_by") == "lns":  # the driver's shortcut, after the LNS
        keys.no_solve(extra, keys.PROVEN_BOUND)
        return inc, True
    return inc, False


def after_model(backend: Backend[Any], out: MethodOutput, t_model: float) -> MethodOutput:
    """``out`` with the model's share of the time and ``improved_by``: ``lns`` when the plan is
    the LNS's, ``model`` when the model improved on the LNS's plan (None: the LNS did not
    improve the warm start)."""
    info = backend.extra.get(keys.LNS_FIRST)
    if info is None or "skipped" in info:
        return out
    info["model_s"] = round(backend.budget.elapsed() - t_model, 3)
    if out.extra.get("improved_by") == "lns" and out.plan is not None:
        makespan = evaluate(backend.instance, out.plan).makespan
        if makespan < info["makespan_after"] - TOL:
            out.extra["improved_by"] = "model"
    return out


@contextlib.contextmanager
def model_share(backend: Backend[Any], resume: bool) -> Iterator[None]:
    """The model's time: at most :data:`MODEL_SHARE` of what is left when the LNS first's
    windows improved the plan and the LNS may ``resume`` after the model (:func:`after_share`),
    else all of it: where its windows found nothing (a local optimum of small windows, as on
    most small records) the model keeps the time its proof may need."""
    info = backend.extra.get(keys.LNS_FIRST)
    if not resume or info is None or not info.get("improvements"):
        yield
        return
    end = backend.budget.share(MODEL_SHARE, backend.margin)
    info[keys.MODEL_CAP_S] = round(end - time.perf_counter(), 3)
    with backend.budget.capped(end):
        yield


def after_share(backend: Backend[Inc], out: MethodOutput) -> MethodOutput:
    """``out``, or the better plan the LNS finds from ``out``'s plan in the time the model's
    share left (:func:`model_share`): the model's search stalls where the LNS's windows still
    improve (``mixed_u2_t1_tight_d10`` at 60 s: the model's 47 s left the LNS first's 1,703.9 s
    plan, ``lns`` alone found 1,651.9 s). Not after a proof (``optimal``, ``infeasible``), nor
    when the model's search ended (``solver_status`` ``optimal``, e.g. optimal among the
    0/90-degree plans, ``optimal_axis_aligned``: a claim the LNS's result would drop), nor
    without a plan; the model's bound, which holds for every plan, concludes the result (as
    :func:`.driver.never_worse`). It cuts no start plans from task orders again (the LNS
    first had them: option ``cut_share`` 0). ``extra["lns_after"]`` reports the LNS (as the
    LNS first's) and ``improved_by`` is ``lns`` when it improved the plan."""
    extra, budget = backend.extra, backend.budget
    info = extra.get(keys.LNS_FIRST)
    if info is None or "skipped" in info or keys.MODEL_CAP_S not in info:
        return out
    if out.plan is None or out.status in (Status.OPTIMAL, Status.INFEASIBLE):
        return out
    if extra.get(keys.SOLVER_STATUS) == "optimal" or extra.get("optimal_axis_aligned"):
        return out  # the model's search ended: its plan optimal among the plans it proves for
    if budget.remaining(backend.margin) < MIN_AFTER_S:
        extra[keys.LNS_AFTER] = {"skipped": "no time left after the model"}
        return out
    take_model_bound(backend, out.bound, evaluate(backend.instance, out.plan).makespan)
    before = extra.get("improved_by")
    resume = HandOff(cut_share=0.0)  # no start plans cut again: the LNS first had them
    inc, extra[keys.LNS_AFTER] = _reported_hand_off(backend, backend.adopt(out.plan), resume)
    if extra.get("improved_by") is None:
        extra["improved_by"] = before
    return backend.conclude(inc)


def take_model_bound(backend: Backend[Any], bound: float | None, makespan: float) -> bool:
    """Conclude with the model's ``bound`` (it holds for every plan,
    :func:`..common.scope_claims`) where it is above the bound known before the model; not
    taken (False) when it is above ``makespan``, a plan's it would contradict."""
    if bound is None or bound > makespan + TOL:
        return False
    if bound > backend.known_bound() + TOL:
        backend.raise_bound(bound, "model")
    return True


def _reported_hand_off(
    backend: Backend[Inc], inc: Inc, limit: HandOff
) -> tuple[Inc, dict[str, Any]]:
    """The backend's LNS from ``inc`` within ``limit``, and its report (``used_s`` added),
    taken from ``extra["fallback"]``, which keeps what it held before (the no-model hand-off's
    key)."""
    extra, budget = backend.extra, backend.budget
    t0, saved = budget.elapsed(), extra.pop(HAND_OFF_KEY, None)
    inc = backend.hand_off(inc, limit)
    report: dict[str, Any] = extra.pop(HAND_OFF_KEY, None) or {"skipped": "the LNS did not run"}
    if saved is not None:
        extra[HAND_OFF_KEY] = saved
    report[keys.LNS_USED_S] = round(budget.elapsed() - t0, 3)
    return inc, report


def _skipped(backend: Backend[Any], fallback: str) -> str | None:
    """Why the LNS does not run first (None: it does)."""
    if fallback != "lns":
        return "option fallback=none"
    if backend.instance.stations and not backend.is_makespan:
        # (the bound the LNS's plan is held to after it is the makespan's)
        return "several stations with another objective than the makespan"
    if backend.budget.deterministic:
        return "a reproducible run (the LNS's start is clock-bound)"
    return None
