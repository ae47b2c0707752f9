r"""The exact whole-horizon schedule as a Pyomo MILP (registered method ``milp``).

The same problem as :mod:`bilevel_kit.solvers.cpsat` (docs/timeline.md, docs/formulations.md),
written as a
position-based batching MILP so that an LP-based branch and bound (HiGHS by default, any Pyomo
solver by name) cross-checks the CP-SAT model. It shares only the packing oracle with it.

**Variables.** Kit positions k = 0..K-1. ``x[i,k]`` = task i is in kit k (only for
:math:`k < n - |\mathrm{desc}(i)|`, since every earlier kit needs a task that is not a
descendant of i), ``u[k]`` = kit k is used, ``E[k]`` = the human's end of kit k (continuous).

**Constraints.**

* assignment :math:`\sum_k x_{ik} = 1`; linking :math:`x_{ik} \le u_k \le \sum_i x_{ik}`;
  symmetry :math:`u_{k+1} \le u_k` (used kits first), :math:`\sum_k u_k \ge m_{\min}` (area);
* precedence, for every edge a -> b of the transitive reduction, in the disaggregated form
  :math:`\sum_{k' \le k} x_{b k'} \le \sum_{k' \le k} x_{a k'}` for all k (it implies
  :math:`\sum_k k\,x_{ak} \le \sum_k k\,x_{bk}` and has a stronger LP relaxation);
  inside a kit the human follows a topological order, which the returned plan lists;
* interchangeable precedence chains (same task data, same predecessors of the head and
  successors of the tail, e.g. the legs of one table) have lexicographically ordered kit
  vectors :math:`(p_{c_1}, .., p_{c_L})` (relabelling the chains maps any plan to one that
  satisfies it), written as one linear inequality: positions are < K, so lex order is the order
  of :math:`\sum_j K^{L-j} p_{c_j}` (a prefix of the chain when :math:`K^{L-1} > 10^6`); the
  heads' order is also added in the disaggregated form;
* the timeline of docs/timeline.md, exactly::

      R_k = o_R u_k + sum_i r_i x[i,k]        H_k = o_H u_k + sum_i h_i x[i,k]
      A_k = sum_{k' <= k} (R_k' + d u_k')     (arrival; the robot is busy while delivering)
      E_k >= A_k + H_k,   E_k >= E_{k-1} + H_k,   C = E_{K-1}

  An unused kit has R = H = 0 and adds no d and no overhead, so it adds no time; E only
  needs ``>=`` because the objective pushes C down to the max. No big-M is needed here; the
  variable bound :math:`E_k \le M = \sum_i (r_i + h_i) + K (o_R + o_H + d)` (a schedule
  without any overlap) is derived from the data, and ``C <= U`` with U the makespan of a
  quick feasible plan;
* the closed-form bounds of :mod:`bilevel_kit.bounds` on C, also with the model's own kit count
  :math:`m = \sum_k u_k` in place of :math:`m_{\min}` (redundant, they lift the LP bound).

The incumbent (the quick plan, then the best packable plan) is passed to the solver as a MIP
start, after relabelling its chains into the lexicographic order the model requires.

**Tray (logic-based Benders).** The master holds the area relaxation
:math:`\sum_i a_i x_{ik} \le W H` (areas on the packing grid of
:mod:`~bilevel_kit.layout.cpsat_packing`, sizes rounded up, tray down). Each kit of an
incumbent is checked with the memoised packing oracle :func:`.cpsat_packing.fit_counts`;
a part multiset M that provably does not fit is shrunk by a deletion filter to a minimal
non-fitting one and cut from **every** kit:
:math:`\bigvee_t c_{tk} \le M_t - 1` with :math:`c_{tk} = \sum_i n_{it} x_{ik}` the number of
parts of type t in kit k, linearised with one binary :math:`\lambda_{tkc}` per (type, kit,
threshold) as :math:`c_{tk} \le (c - 1) + (N_t - c + 1)(1 - \lambda_{tkc})` (big-M
:math:`N_t - c + 1` from the total count :math:`N_t` of type t) and
:math:`\sum_{t \in M} \lambda_{t k M_t} \ge 1`. Every super-multiset of M fails too, so no
feasible plan is cut off. The master is re-solved until its optimum packs (then it is optimal
for the full problem) or the time is up; kits that do not fit are split greedily to keep an
incumbent. ``tray="auto"`` first seeds cuts for every pair of tasks that does not fit;
``"benders"`` starts from the area relaxation alone. "Fits" means what the oracle means: an
axis-aligned layout on its grid, the same notion as the CP-SAT model.

**Objective.** ``makespan``: minimise C. ``human_idle``: minimise
:math:`C - o_H \sum_k u_k` (= human idle + the constant :math:`\sum_i h_i`).

**Result.** ``status`` optimal / feasible / infeasible / unknown; ``bound`` a proven lower
bound on the makespan in seconds (the master's best bound when every cut is proven, never below
the closed-form bounds); ``extra``: ``gap``, ``iterations`` (master solves), ``cuts``,
``solver``, ``termination``. The time limit covers everything (packing, model building and all
master solves), up to a small margin.

**Solvers.** ``solver="highs"`` (default) writes the model as MPS and runs highspy in a child
Python process (see :func:`run_solver` for why it cannot run in this one); any other name is a
Pyomo ``SolverFactory`` solver run in-process (``cbc``, ``glpk``, ``gurobi``, ``scip`` ...),
with its time-limit and gap options set when :data:`SOLVER_OPTIONS` knows them. On the table
(12 tasks) both exact models take about 1-3 s; on 5 tables (60 tasks) HiGHS needed 45-110 s
against 33 s for CP-SAT on this 2-core machine (bench/bench_milp.py).
"""

from __future__ import annotations

import itertools
import logging
import math
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from ..bounds import best_bound, lower_bounds, min_kits
from ..errors import UsageError
from ..instance import Instance, topological_order
from ..layout import cpsat_packing as packing
from ..methods import gap as relative_gap
from ..plan import Kit, Plan, evaluate
from .common import Packer, chain_groups, kit_order, quick_plan, reduced_edges

TRAY_MODES = ("auto", "benders")
OBJECTIVES = ("makespan", "human_idle")
#: Seconds kept back from the time limit for extraction and the final layouts.
_MARGIN = 0.2
#: Relative tolerance when comparing float objectives (the MILP works on real seconds).
_TOL = 1e-6

#: Option names (time limit, relative MIP gap, random seed) of the in-process Pyomo solvers we
#: know; any other Pyomo solver runs with its own defaults and ``time_limit_enforced = False``.
SOLVER_OPTIONS: dict[str, tuple[str, str, str | None]] = {
    "appsi_highs": ("time_limit", "mip_rel_gap", "random_seed"),
    "cbc": ("sec", "ratioGap", "randomCbcSeed"),
    "glpk": ("tmlim", "mipgap", None),
    "gurobi": ("TimeLimit", "MIPGap", "Seed"),
    "gurobi_direct": ("TimeLimit", "MIPGap", "Seed"),
    "gurobi_persistent": ("TimeLimit", "MIPGap", "Seed"),
    "appsi_gurobi": ("TimeLimit", "MIPGap", "Seed"),
    "cplex": ("timelimit", "mipgap", None),
    "cplex_direct": ("timelimit", "mipgap", None),
    "scip": ("limits/time", "limits/gap", "randomization/randomseedshift"),
}
#: Seconds a HiGHS subprocess may run past its own time limit before it is killed.
_KILL_GRACE = 5.0


# ---------------------------------------------------------------------------------------------
# Running a MILP solver (shared with kit_columns)
# ---------------------------------------------------------------------------------------------
#
# Why HiGHS runs in a subprocess: OR-Tools 9.15 and highspy 1.15 each bundle their own
# ``libhighs.so.1`` (same soname, different versions). Whichever is loaded first is reused by
# the other and the second import fails with an undefined symbol, in either order. The packing
# oracle needs OR-Tools in this process, so ``solver="highs"`` writes the Pyomo model as MPS
# and solves it with highspy in a fresh Python process (which never imports OR-Tools).

_HIGHS_WORKER = r"""
import json, sys
import highspy
path, out, tl, seed, log, opts, start = sys.argv[1:8]
h = highspy.Highs()
h.setOptionValue("output_flag", log == "1")
h.setOptionValue("time_limit", max(0.01, float(tl)))
h.setOptionValue("mip_rel_gap", 0.0)
h.setOptionValue("random_seed", int(seed))
for key, value in json.loads(opts).items():
    h.setOptionValue(key, value)
h.readModel(path)
if start:
    import numpy as np
    with open(start) as f:
        given = json.load(f)
    col = {name: j for j, name in enumerate(h.getLp().col_names_)}
    pairs = sorted((col[k], v) for k, v in given.items() if k in col)
    if pairs:
        h.setSolution(
            len(pairs),
            np.array([j for j, _ in pairs], dtype=np.int32),
            np.array([v for _, v in pairs], dtype=np.float64),
        )
h.run()
st = h.getModelStatus()
info = h.getInfo()
S = highspy.HighsModelStatus
res = {
    "status": h.modelStatusToString(st),
    "optimal": st == S.kOptimal,
    "infeasible": st in (S.kInfeasible, S.kUnboundedOrInfeasible),
    "has_solution": int(info.primal_solution_status) == 2,
    "objective": info.objective_function_value,
    "bound": info.mip_dual_bound,
}
if res["has_solution"]:
    res["values"] = dict(zip(h.getLp().col_names_, list(h.getSolution().col_value)))
with open(out, "w") as f:
    json.dump(res, f)
"""


@dataclass
class SolveInfo:
    """What one MILP solve gave: ``has_solution`` (values are loaded into the model),
    ``optimal`` (proven), ``infeasible`` (proven), the best ``bound`` and ``objective``."""

    termination: str
    has_solution: bool
    optimal: bool
    infeasible: bool
    bound: float | None
    objective: float | None
    wall_time_s: float


@contextmanager
def _quiet_pyomo() -> Iterator[None]:
    """Silence Pyomo's warnings about loading a time-limited solution (we check it ourselves)."""
    logger = logging.getLogger("pyomo")
    old = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(old)


def ensure_ortools() -> None:
    """Load OR-Tools (the packing oracle) before anything can load highspy in-process.

    Whichever of the two is loaded first wins the ``libhighs.so.1`` soname; once highspy is in
    (cvxpy imports it on its first solve, Pyomo's in-process HiGHS interfaces too), OR-Tools
    can no longer be imported in this process, which deserves a clear message.
    """
    try:
        from ortools.sat.python import cp_model  # noqa: F401
    except ImportError as exc:
        raise UsageError(
            "OR-Tools cannot be loaded in this process: highspy (imported by cvxpy or an "
            "in-process Pyomo HiGHS interface) was loaded first and both bundle "
            f"libhighs.so.1; import ortools.sat.python.cp_model before them ({exc})"
        ) from None


def make_solver(name: str) -> Any:
    """The solver ``name``: None for the HiGHS subprocess (``highs``), else the Pyomo
    ``SolverFactory`` object. A missing solver is a clear UsageError naming it."""
    import importlib.util

    if name == "highs":
        if importlib.util.find_spec("highspy") is None:
            raise UsageError("MILP solver 'highs' needs the highspy package (pip install highspy)")
        return None
    import pyomo.environ as pyo

    reason = "not installed or not on PATH"
    with _quiet_pyomo():
        try:
            opt = pyo.SolverFactory(name)
            ok = opt is not None and bool(opt.available(exception_flag=False))
        except Exception as exc:  # unknown names or broken imports raise inside Pyomo
            ok, reason = False, f"{exc.__class__.__name__}: {exc}"
    if not ok:
        hint = ""
        if "highs" in name:
            hint = " (in-process HiGHS clashes with OR-Tools' bundled libhighs; use 'highs')"
        raise UsageError(f"MILP solver {name!r} is not available to Pyomo ({reason}){hint}")
    return opt


def run_solver(
    model: Any,
    opt: Any,
    name: str,
    *,
    deadline: float,
    seed: int = 0,
    log: bool = False,
    objective: Any = None,
    options: Mapping[str, Any] | None = None,
    warmstart: bool = False,
) -> SolveInfo:
    """Minimise ``model`` until ``deadline`` (perf_counter) with a zero relative gap and load
    the best solution into its variables. ``warmstart``: the variables' current values are a
    MIP start (HiGHS completes a partial one).

    ``opt=None`` (``solver="highs"``) runs HiGHS in a child process: OR-Tools and highspy each
    bundle a different ``libhighs.so.1``; the first one loaded wins the soname and the other
    import then fails (undefined symbol), in either order, and the packing oracle needs
    OR-Tools in this process.
    """
    import pyomo.environ as pyo

    t0 = time.perf_counter()
    if opt is None:
        info = _run_highs_subprocess(model, deadline, seed, log, options, warmstart)
    else:
        info = _run_pyomo(model, opt, name, deadline, seed, log, options, warmstart)
    if info.has_solution and objective is not None:
        info.objective = pyo.value(objective, exception=False)
        info.has_solution = info.objective is not None
    if info.optimal and info.objective is not None:
        obj = info.objective
        info.bound = obj if info.bound is None else min(max(info.bound, obj - _TOL), obj)
    info.optimal = info.optimal and info.has_solution
    info.wall_time_s = time.perf_counter() - t0
    return info


def _finite(v: Any) -> float | None:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def _run_highs_subprocess(
    model: Any,
    deadline: float,
    seed: int,
    log: bool,
    options: Mapping[str, Any] | None,
    warmstart: bool,
) -> SolveInfo:
    import json
    import os
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory(prefix="bilevel_milp_") as tmp:
        path = os.path.join(tmp, "model.mps")
        out = os.path.join(tmp, "result.json")
        _, smap_id = model.write(path, format="mps", io_options={"symbolic_solver_labels": False})
        smap = model.solutions.symbol_map[smap_id]
        start = ""
        if warmstart:
            given = {
                sym: var.value
                for sym, var in smap.bySymbol.items()
                if getattr(var, "value", None) is not None
            }
            if given:
                start = os.path.join(tmp, "start.json")
                with open(start, "w") as f:
                    json.dump(given, f)
        left = deadline - time.perf_counter()
        argv = [
            sys.executable,
            "-c",
            _HIGHS_WORKER,
            path,
            out,
            repr(max(0.01, left)),
            str(int(seed)),
            "1" if log else "0",
            json.dumps(dict(options or {})),
            start,
        ]
        try:
            proc = subprocess.run(
                argv,
                timeout=max(1.0, left) + _KILL_GRACE,
                stdout=None if log else subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                text=True,
            )
        except subprocess.TimeoutExpired:
            return SolveInfo("killed", False, False, False, None, None, 0.0)
        if proc.returncode != 0 or not os.path.exists(out):
            raise RuntimeError(f"HiGHS subprocess failed: {proc.stderr.strip()[-2000:]}")
        with open(out) as f:
            res = json.load(f)
    values = res.get("values", {})
    for sym, var in smap.bySymbol.items():
        if sym in values and hasattr(var, "set_value"):
            var.set_value(values[sym], skip_validation=True)
    return SolveInfo(
        termination=str(res["status"]),
        has_solution=bool(res["has_solution"]),
        optimal=bool(res["optimal"]),
        infeasible=bool(res["infeasible"]),
        bound=_finite(res["bound"]),
        objective=_finite(res["objective"]),
        wall_time_s=0.0,
    )


def _takes_warmstart(opt: Any) -> bool:
    try:
        return bool(opt.warm_start_capable())
    except Exception:
        return False


def _run_pyomo(
    model: Any,
    opt: Any,
    name: str,
    deadline: float,
    seed: int,
    log: bool,
    options: Mapping[str, Any] | None,
    warmstart: bool,
) -> SolveInfo:
    from pyomo.opt import TerminationCondition

    left = max(0.01, deadline - time.perf_counter())
    opts: dict[str, Any] = {}
    names = SOLVER_OPTIONS.get(name)
    if names is not None:
        tl_key, gap_key, seed_key = names
        opts[tl_key] = max(1, math.ceil(left)) if name == "glpk" else left
        opts[gap_key] = 0.0
        if seed_key is not None:
            opts[seed_key] = int(seed)
    opts.update(options or {})
    with _quiet_pyomo():
        kw: dict[str, Any] = {"warmstart": True} if warmstart and _takes_warmstart(opt) else {}
        res = opt.solve(model, tee=log, load_solutions=False, options=opts, **kw)
    tc = res.solver.termination_condition
    infeasible = tc in (
        TerminationCondition.infeasible,
        TerminationCondition.infeasibleOrUnbounded,
    )
    has_solution = False
    if not infeasible and len(getattr(res, "solution", ())) > 0:
        with _quiet_pyomo():
            try:
                model.solutions.load_from(res)
                has_solution = True
            except Exception:  # a solver reporting a solution it does not have
                has_solution = False
    return SolveInfo(
        termination=str(tc),
        has_solution=has_solution,
        optimal=tc == TerminationCondition.optimal,
        infeasible=infeasible,
        bound=_finite(res.problem.lower_bound),
        objective=None,
        wall_time_s=0.0,
    )


# ---------------------------------------------------------------------------------------------
# Graph helpers (own code: the MILP is a cross-check of the CP-SAT model, so it shares little)
# ---------------------------------------------------------------------------------------------


human_order = kit_order  # the human's order inside a kit (one definition: common.py)


# ---------------------------------------------------------------------------------------------
# Packing under the deadline
# ---------------------------------------------------------------------------------------------


def _objective_value(instance: Instance, kits: Sequence[Sequence[str]], objective: str) -> float:
    """The model's objective of a plan: makespan, or makespan - o_H * kits."""
    c = evaluate(instance, Plan(tuple(Kit(tuple(k)) for k in kits))).makespan
    return c if objective == "makespan" else c - instance.kit_overhead_human * len(kits)


# ---------------------------------------------------------------------------------------------
# The master model
# ---------------------------------------------------------------------------------------------


@dataclass
class _Master:
    model: Any
    K: int
    ids: list[str]
    x: dict[tuple[int, int], Any]
    counts: dict[tuple[str, int], Any] = field(default_factory=dict)
    total: dict[str, int] = field(default_factory=dict)
    lam: dict[tuple[str, int, int], Any] = field(default_factory=dict)
    n_cuts: int = 0


def _build(instance: Instance, K: int, upper: float | None, objective: str) -> _Master:
    import pyomo.environ as pyo

    ids = [t.id for t in instance.tasks]
    n = len(ids)
    idx = instance.index
    r = [instance.robot_time(t) for t in ids]
    h = [instance.human_time(t) for t in ids]
    d, o_r, o_h = instance.delivery_time, instance.kit_overhead_robot, instance.kit_overhead_human
    n_desc = [0] * n
    for t in ids:
        for a in instance.ancestors[t]:
            n_desc[idx[a]] += 1
    ub = [min(K, n - n_desc[i]) for i in range(n)]
    keys = [(i, k) for i in range(n) for k in range(ub[i])]
    at_k: list[list[int]] = [[] for _ in range(K)]
    for i, k in keys:
        at_k[k].append(i)

    m = pyo.ConcreteModel(name="milp_schedule")
    m.x = pyo.Var(keys, domain=pyo.Binary)
    m.u = pyo.Var(range(K), domain=pyo.Binary)
    big_m = sum(r) + sum(h) + K * (o_r + o_h + d)  # a schedule without any overlap
    m.E = pyo.Var(range(K), bounds=(0.0, big_m))
    m.u[0].fix(1)
    m.cons = pyo.ConstraintList()
    add = m.cons.add
    for i in range(n):
        add(sum(m.x[i, k] for k in range(ub[i])) == 1)
    for k in range(K):
        for i in at_k[k]:
            add(m.x[i, k] <= m.u[k])
        add(m.u[k] <= sum(m.x[i, k] for i in at_k[k]))
        if k:
            add(m.u[k] <= m.u[k - 1])
    add(sum(m.u[k] for k in range(K)) >= min(K, min_kits(instance)))

    # precedence, disaggregated: y_b(k) <= y_a(k) with y_i(k) = sum_{k' <= k} x[i,k']
    for a_id, b_id in reduced_edges(instance):
        a, b = idx[a_id], idx[b_id]
        for k in range(min(ub[a], ub[b]) - 1):
            add(sum(m.x[b, q] for q in range(k + 1)) <= sum(m.x[a, q] for q in range(k + 1)))

    # symmetry: interchangeable chains in lexicographic order of their kit vectors, as one
    # linear inequality (positions < K, so lex order = order of sum_j K^(L-1-j) p_{c_j}),
    # plus the heads' order in the disaggregated (LP-stronger) form
    def pos(i: int) -> Any:
        return sum(k * m.x[i, k] for k in range(1, ub[i]))

    for group in chain_groups(instance):
        chains = sorted([idx[t] for t in c] for c in group)
        length = len(chains[0])
        while length > 1 and K ** (length - 1) > 1e6:  # a lex prefix is valid too
            length -= 1
        for c1, c2 in itertools.pairwise(chains):
            add(sum(K ** (length - 1 - j) * (pos(c1[j]) - pos(c2[j])) for j in range(length)) <= 0)
            a, b = c1[0], c2[0]
            for k in range(min(ub[a], ub[b]) - 1):
                add(sum(m.x[b, q] for q in range(k + 1)) <= sum(m.x[a, q] for q in range(k + 1)))

    # timeline
    arrive = 0.0
    for k in range(K):
        R = o_r * m.u[k] + sum(r[i] * m.x[i, k] for i in at_k[k])
        Hk = o_h * m.u[k] + sum(h[i] * m.x[i, k] for i in at_k[k])
        arrive = arrive + R + d * m.u[k]
        add(m.E[k] >= arrive + Hk)
        if k:
            add(m.E[k] >= m.E[k - 1] + Hk)
    cmax = m.E[K - 1]
    lb = lower_bounds(instance)
    add(cmax >= max(lb["human"], lb["robot"]))
    # the same bounds with the model's own kit count m = sum_k u_k (valid for integer plans:
    # the last kit holds a sink, the first a source; see :mod:`bilevel_kit.bounds`)
    has_pred = {b for _, b in instance.precedence}
    has_succ = {a for a, _ in instance.precedence}
    n_used = sum(m.u[k] for k in range(K))
    add(
        cmax
        >= sum(r) + (o_r + d) * n_used + o_h + min(h[i] for i in range(n) if ids[i] not in has_succ)
    )
    add(
        cmax
        >= min(r[i] for i in range(n) if ids[i] not in has_pred) + o_r + d + sum(h) + o_h * n_used
    )
    if upper is not None:
        add(cmax <= upper)
    if objective == "makespan":
        m.obj = pyo.Objective(expr=cmax, sense=pyo.minimize)
    else:
        m.obj = pyo.Objective(expr=cmax - o_h * sum(m.u[k] for k in range(K)), sense=pyo.minimize)

    # tray: area relaxation on the packing grid (the oracle's notion of "fits")
    tray = instance.tray
    W = packing.grid_down(tray.width, 1.0)
    H = packing.grid_down(tray.height, 1.0)
    garea = {
        p.id: packing.grid_up(p.width, 1.0) * packing.grid_up(p.height, 1.0)
        for p in instance.part_types.values()
    }
    area = [sum(garea[p] * c for p, c in t.parts) for t in instance.tasks]
    if sum(area) > W * H:
        for k in range(K):
            terms = [area[i] * m.x[i, k] for i in at_k[k] if area[i]]
            if terms:
                add(sum(terms) <= W * H)
    master = _Master(m, K, ids, {key: m.x[key] for key in keys})
    total = instance.kit_parts(ids)
    master.total = dict(total)
    for t in instance.part_types:
        for k in range(K):
            terms = [c * m.x[i, k] for i in at_k[k] for q, c in instance.tasks[i].parts if q == t]
            if terms:
                master.counts[(t, k)] = sum(terms)
    return master


def _add_cut(master: _Master, counts: Mapping[str, int]) -> None:
    """Forbid the multiset ``counts`` (and every super-multiset) in every kit."""
    import pyomo.environ as pyo

    m = master.model
    for k in range(master.K):
        lits = []
        for t, c in counts.items():
            expr = master.counts.get((t, k))
            if expr is None:
                lits = []
                break  # kit k can never hold a part of type t: the cut holds there
            key = (t, k, c)
            if key not in master.lam:
                name = f"lam_{len(master.lam)}"
                var = pyo.Var(domain=pyo.Binary)
                m.add_component(name, var)
                m.cons.add(expr <= (c - 1) + (master.total[t] - c + 1) * (1 - var))
                master.lam[key] = var
            lits.append(master.lam[key])
        if lits:
            m.cons.add(sum(lits) >= 1)
    master.n_cuts += 1


def _set_start(master: _Master, instance: Instance, kits: Sequence[Sequence[str]]) -> None:
    """Load a plan into the master's variables (a MIP start); its kits are put into the
    canonical chain order first, so the start satisfies the symmetry constraints."""
    m = master.model
    if len(kits) > master.K:
        return
    kits = canonical_kits(instance, kits)
    where = {t: k for k, kit in enumerate(kits) for t in kit}
    for (i, k), v in master.x.items():
        v.set_value(float(where[master.ids[i]] == k), skip_validation=True)
    tl = evaluate(instance, Plan(tuple(Kit(tuple(k)) for k in kits)))
    end = 0.0
    for k in range(master.K):
        if k < len(kits):
            end = tl.kits[k].human_end
        if k:
            m.u[k].set_value(float(k < len(kits)), skip_validation=True)
        m.E[k].set_value(end, skip_validation=True)
    for (t, k, c), var in master.lam.items():
        have = instance.kit_parts(kits[k]).get(t, 0) if k < len(kits) else 0
        var.set_value(float(have <= c - 1), skip_validation=True)


def canonical_kits(instance: Instance, kits: Sequence[Sequence[str]]) -> list[list[str]]:
    """Relabel interchangeable chains so that their kit vectors are in lexicographic order
    (what the model's symmetry constraints require); kit contents stay the same multisets."""
    pos = {t: k for k, kit in enumerate(kits) for t in kit}
    new = dict(pos)
    for group in chain_groups(instance):
        vectors = sorted(tuple(pos[t] for t in chain) for chain in group)
        order = sorted(group, key=lambda c: [instance.index[t] for t in c])
        for chain, vec in zip(order, vectors, strict=True):
            for t, k in zip(chain, vec, strict=True):
                new[t] = k
    out: list[list[str]] = [[] for _ in kits]
    for t in topological_order(instance):
        out[new[t]].append(t)
    return out


def _extract(master: _Master) -> list[list[str]]:
    kits: dict[int, list[str]] = {}
    for (i, k), v in master.x.items():
        if v.value is not None and v.value > 0.5:
            kits.setdefault(k, []).append(master.ids[i])
    return [kits[k] for k in sorted(kits)]


# ---------------------------------------------------------------------------------------------
# The method
# ---------------------------------------------------------------------------------------------


def solve(
    instance: Instance,
    *,
    seed: int = 0,
    time_limit: float | None = 60.0,
    solver: str = "highs",
    objective: str = "makespan",
    tray: str = "auto",
    log: bool = False,
    solver_options: Mapping[str, Any] | None = None,
) -> Any:
    """Minimise makespan (or human idle) over all segmentations and orders with a MILP.

    Returns a :class:`bilevel_kit.methods.MethodOutput` (module docstring): ``bound`` is a
    proven lower bound on the makespan in seconds, every kit has a topological human order and
    a non-overlapping layout from the packing oracle. ``solver`` is any Pyomo solver name
    (``highs``, ``appsi_highs``, ``cbc``, ``gurobi`` ...); ``solver_options`` are passed to it.
    """
    from ..methods import MethodOutput

    t0 = time.perf_counter()
    time_limit = 60.0 if time_limit is None else float(time_limit)
    deadline = t0 + time_limit
    if tray not in TRAY_MODES:
        raise UsageError(f"milp: tray must be one of {', '.join(TRAY_MODES)}, not {tray!r}")
    if objective not in OBJECTIVES:
        raise UsageError(
            f"milp: objective must be one of {', '.join(OBJECTIVES)}, not {objective!r}"
        )
    ensure_ortools()
    opt = make_solver(str(solver))
    ids = [t.id for t in instance.tasks]
    n = len(ids)
    closed = best_bound(instance)
    pack_tl = max(0.2, min(2.0, 0.05 * time_limit))
    packer = Packer(instance, pack_tl, deadline - _MARGIN)
    extra: dict[str, Any] = {
        "solver": str(solver),
        "objective": objective,
        "tray_mode": tray,
        "iterations": 0,
        "cuts": 0,
        "unproven_cuts": 0,
        "time_limit_enforced": str(solver) == "highs" or str(solver) in SOLVER_OPTIONS,
    }

    def finish(plan: Plan | None, status: str, bound: float | None) -> Any:
        extra["wall_time_s"] = time.perf_counter() - t0
        return MethodOutput(plan, status, bound, extra)

    unfit = packer.task_not_fitting()  # then no plan exists
    if unfit is not None:
        extra["reason"] = f"the parts of task {unfit!r} alone do not fit the tray"
        return finish(None, "infeasible", None)

    # incumbent, upper bound and the kit cap (only valid for plans at least as good)
    inc = quick_plan(instance, Packer(instance, min(0.2, pack_tl), t0 + 0.1 * time_limit))
    inc_obj = None if inc is None else _objective_value(instance, inc, objective)
    upper = None
    K = n
    if inc is not None and objective == "makespan":
        upper = inc_obj
        K = min(K, _kit_cap(instance, upper))
        K = max(K, len(inc))
    extra["max_kits"] = K
    extra["upper_start"] = inc_obj

    master = _build(instance, K, upper, objective)
    extra["build_time_s"] = time.perf_counter() - t0
    seen: set[frozenset[tuple[str, int]]] = set()
    unproven = 0

    def left() -> float:
        return deadline - time.perf_counter() - _MARGIN

    def cut(counts: Mapping[str, int], proven: bool) -> bool:
        mini = (
            packer.minimal_nofit(counts, time.perf_counter() + max(0.0, left() / 4))
            if proven
            else dict(counts)
        )
        key = frozenset(mini.items())
        if key in seen:
            return False
        seen.add(key)
        _add_cut(master, mini)
        return True

    if tray == "auto":  # seed cuts: every pair of tasks (distinct part multisets) not fitting
        seed_until = time.perf_counter() + max(0.0, 0.1 * left())
        reps = list({frozenset(instance.kit_parts([t]).items()): t for t in ids}.values())
        for a, b in itertools.combinations_with_replacement(reps, 2):
            if time.perf_counter() > seed_until:
                break
            counts = instance.kit_parts([a, b])
            if packer.counts(counts)[0] is False:
                cut(counts, True)

    lower: float | None = None
    proven = False
    infeasible = False
    it = 0
    info: SolveInfo | None = None
    while left() > 0.05:
        it += 1
        if inc is not None:
            _set_start(master, instance, inc)
        info = run_solver(
            master.model,
            opt,
            str(solver),
            deadline=deadline - _MARGIN,
            seed=seed,
            log=log,
            objective=master.model.obj,
            options=solver_options,
            warmstart=inc is not None,
        )
        if info.infeasible:
            # the master holds C <= U: without unproven cuts the incumbent is optimal
            if unproven == 0:
                if inc is not None:
                    proven, lower = True, inc_obj
                else:
                    infeasible = True
            break
        if unproven == 0 and info.bound is not None:
            lower = info.bound if lower is None else max(lower, info.bound)
        if not info.has_solution:
            break
        kits = _extract(master)
        verdicts = []
        for kit in kits:
            counts = instance.kit_parts(kit)
            ok = packer.counts(counts)[0]
            if ok is None:  # a hard packing: one more try with a longer limit
                ok = packer.counts(counts, max(pack_tl, min(10 * pack_tl, left() / 3)))[0]
            verdicts.append(ok)
        if all(v is True for v in verdicts):
            obj = _objective_value(instance, kits, objective)
            if inc_obj is None or obj <= inc_obj + _TOL * max(1.0, abs(obj)):
                inc, inc_obj = kits, obj
            proven = info.optimal and unproven == 0
            break  # optimal, or the master ran out of time on a packable incumbent
        new = 0
        for kit, ok in zip(kits, verdicts, strict=True):
            if ok is not True:
                added = cut(instance.kit_parts(kit), ok is False)
                new += added
                unproven += int(added and ok is None)
        repaired: list[list[str]] = []
        for kit in kits:
            parts = packer.split(human_order(instance, kit))
            if parts is None:
                repaired = []
                break
            repaired += parts
        if repaired:
            obj = _objective_value(instance, repaired, objective)
            if inc_obj is None or obj < inc_obj - _TOL * max(1.0, abs(obj)):
                inc, inc_obj = repaired, obj
        if inc_obj is not None and lower is not None and lower >= inc_obj - _TOL * abs(inc_obj):
            proven = True
            break
        if not new:
            break  # nothing new to cut (only possible with unknown packings)
    extra.update(
        iterations=it,
        cuts=master.n_cuts,
        unproven_cuts=unproven,
        termination=None if info is None else info.termination,
        master_time_s=None if info is None else info.wall_time_s,
    )
    if inc is None:
        if infeasible:
            return finish(None, "infeasible", None)
        return finish(None, "unknown", closed)

    kits_out = []
    for kit in inc:
        tasks = human_order(instance, kit)
        layout = packer.layout(tasks)
        if layout is None and instance.kit_parts(tasks):
            extra["reason"] = "no layout for some kit within the time limit"
            return finish(None, "unknown", closed)
        kits_out.append(Kit(tasks, layout or ()))
    plan = Plan(tuple(kits_out))
    real = evaluate(instance, plan)
    if objective == "makespan":
        bound = closed if lower is None else max(closed, lower)
    else:
        w_min = sum(instance.human_time(t) for t in ids)
        idle_lb = None if lower is None else lower - w_min
        extra["idle_bound"] = idle_lb
        bound = closed
        if lower is not None:  # C = idle + sum h + o_H m >= idle_lb + sum h + o_H m_min
            bound = max(closed, lower + instance.kit_overhead_human * min_kits(instance))
    if bound > real.makespan:  # only float noise of the solver can do this
        bound = real.makespan
    status = "optimal" if proven else "feasible"
    extra.update(
        gap=relative_gap(real.makespan, bound) or 0.0,
        makespan=real.makespan,
        human_idle=real.human_idle,
        n_kits=len(plan.kits),
        bound_closed_form=closed,
        bound_model=lower,
    )
    return finish(plan, status, bound)


def _kit_cap(instance: Instance, upper: float) -> int:
    """Largest kit count m of a plan with makespan <= U, from the closed-form bounds with m:

    .. math:: m (o_R + d) \\le U - \\sum r - o_H - \\min_{snk} h,\\qquad
              m\\, o_H \\le U - \\min_{src} r - o_R - d - \\sum h.
    """
    ids = [t.id for t in instance.tasks]
    n = len(ids)
    has_pred = {b for _, b in instance.precedence}
    has_succ = {a for a, _ in instance.precedence}
    r = {t: instance.robot_time(t) for t in ids}
    h = {t: instance.human_time(t) for t in ids}
    d, o_r, o_h = instance.delivery_time, instance.kit_overhead_robot, instance.kit_overhead_human
    cap = n
    eps = _TOL * max(1.0, upper)
    if o_r + d > 0:
        slack = upper - sum(r.values()) - o_h - min(h[t] for t in ids if t not in has_succ)
        cap = min(cap, max(1, math.floor((slack + eps) / (o_r + d))))
    if o_h > 0:
        slack = upper - min(r[t] for t in ids if t not in has_pred) - o_r - d - sum(h.values())
        cap = min(cap, max(1, math.floor((slack + eps) / o_h)))
    return cap
