"""The ``extra`` keys the exact methods ``cpsat`` and ``milp`` share: one key per meaning and
one vocabulary (docs/formulations.md, "One driver for cpsat and milp"), and how a record
written before under a backend's own name is read (:func:`read`: solution files, KitBench
libraries and benchmark records keep the old names).

- ``solver_status``: how the run ended, one of :data:`NO_SOLVE` (no model solved) or
  :data:`SOLVE_OUTCOMES` (the last model solve's outcome: the embedded model's or the last
  Benders master's); ``backend_status`` is that solve's raw status (CP-SAT's status name,
  HiGHS's model status or Pyomo's termination condition; None when no model was solved).
- ``master_solves``: how many times the model (the embedded model, or a Benders master) was
  solved.
- ``lns_first``: the LNS run before the model (:mod:`.lns_first`): the LNS's report
  (``time_s`` the seconds given at most, ``windows``, ``improvements``, ``makespan_before``,
  ``makespan_after``), ``used_s`` the seconds it ran, ``stop`` why it stopped (one of
  :data:`LNS_STOPS`), its limits ``stall_windows`` and ``max_windows`` (None: no cap),
  ``share`` and ``model_s``; or ``skipped`` (why it did not run).
- ``search_first``: the ideal search run before the model (option ``search``,
  :mod:`.search_first`): ``share``, ``stop``, ``proven``, ``bound``, ``proof_scope``, its
  counters and
  ``used_s``, with ``makespan_after`` when it found a better plan; or ``skipped``.
- ``model_plan_worse``: present only when the model's plan was missing or worse than the
  incumbent it started from, which is returned instead (:func:`.driver.never_worse`): the
  model's ``makespan`` (None: no plan), ``status`` and ``bound``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

SOLVER_STATUS = "solver_status"
BACKEND_STATUS = "backend_status"
MASTER_SOLVES = "master_solves"

#: Outcomes without a model solve: the incumbent attains the closed-form, the proven or
#: (``cpsat``, which models release times) the release bound; the model was over the memory
#: limit or too slow to build (docs/formulations.md, "Model too large").
CLOSED_FORM_BOUND = "closed_form_bound"
PROVEN_BOUND = "proven_bound"
RELEASE_BOUND = "release_bound"
TOO_LARGE = "too_large"
NOT_BUILT = "not_built"
NO_SOLVE = (CLOSED_FORM_BOUND, PROVEN_BOUND, RELEASE_BOUND, TOO_LARGE, NOT_BUILT)
#: The last model solve's outcome (a Benders master's "optimal" is the master's own optimum).
SOLVE_OUTCOMES = ("optimal", "feasible", "infeasible", "unknown")

#: The LNS first's report, and its keys: seconds it ran, why it stopped, its limits.
LNS_FIRST = "lns_first"
LNS_USED_S = "used_s"
LNS_STOP = "stop"
LNS_STALL = "stall_windows"
LNS_MAX_WINDOWS = "max_windows"
#: Why the LNS first stopped: its plan met the bound, a local optimum, ``stall_windows``
#: windows without improvement, ``max_windows`` windows solved (0: a small instance), the cap.
LNS_STOPS = ("optimal", "local_optimum", "stall", "iterations", "time_limit")

#: The LNS after the model's share (:func:`.lns_first.after_share`): its report, and the
#: seconds the model was given (``model_cap_s``).
LNS_AFTER = "lns_after"
MODEL_CAP_S = "model_cap_s"

#: The model's plan, when it was missing or worse than its incumbent (:func:`.driver.never_worse`).
MODEL_PLAN_WORSE = "model_plan_worse"

#: The names ``cpsat`` and ``milp`` wrote before (read back by :func:`read`).
OLD_NAMES: dict[str, tuple[str, ...]] = {
    SOLVER_STATUS: ("cpsat_status", "termination"),
    MASTER_SOLVES: ("benders_iterations", "iterations"),
}


def solve_outcome(*, optimal: bool, has_solution: bool, infeasible: bool) -> str:
    """The ``solver_status`` of a model solve from what it proved and found."""
    if optimal:
        return "optimal"
    if infeasible:
        return "infeasible"
    return "feasible" if has_solution else "unknown"


def status_word(raw: object) -> str:
    """A status of either backend (CP-SAT's ``OPTIMAL``, ``NOT_BUILT``, milp's ``optimal``,
    ``infeasibleOrUnbounded``, ...) in the one vocabulary; what it does not name is
    ``unknown`` (a time limit without a plan, a killed solver, an error)."""
    word = str(raw).lower()
    if word in NO_SOLVE or word in SOLVE_OUTCOMES:
        return word
    return "infeasible" if word.startswith("infeasible") else "unknown"


def read(extra: Mapping[str, Any], key: str) -> Any:
    """The value of the shared ``key`` in a ``cpsat`` or ``milp`` record, read from its old
    name when the record predates it (``cpsat_status``/``termination`` put into the one
    vocabulary; an old embedded ``cpsat`` record's ``benders_iterations`` of 0 is its one
    solve); None when the record has neither."""
    if key in extra:
        return extra[key]
    for old in OLD_NAMES.get(key, ()):
        if old in extra and extra[old] is not None:
            value = extra[old]
            if key == SOLVER_STATUS:
                return status_word(value)
            solved = status_word(extra.get("cpsat_status")) in SOLVE_OUTCOMES
            embedded = extra.get("tray_mode") == "embedded" and old == "benders_iterations"
            return 1 if embedded and solved and value == 0 else value
    return None


def no_solve(extra: dict[str, Any], status: str) -> None:
    """``extra`` of a run that ends without a model solve (``status`` one of
    :data:`NO_SOLVE`): no build time, no cuts, no backend status."""
    extra.update({SOLVER_STATUS: status, BACKEND_STATUS: None, "build_time_s": 0.0, "cuts": 0})


def solved(extra: dict[str, Any], outcome: str, raw: str | None) -> None:
    """``extra`` of a run whose model was solved: the last solve's ``outcome`` (one of
    :data:`SOLVE_OUTCOMES`) and the backend's ``raw`` status."""
    extra.update({SOLVER_STATUS: outcome, BACKEND_STATUS: raw})
