"""Running a MILP solver on a Pyomo model: HiGHS in a child process, or any Pyomo solver.

``solver="highs"`` (the default) writes the model as MPS and solves it with highspy in a
child Python process (:mod:`.highs_child`): OR-Tools 9.15 and highspy 1.15 each bundle their
own ``libhighs.so.1`` (same soname, different versions); whichever is loaded first is reused
by the other and the second import fails with an undefined symbol, in either order
(:mod:`bilevel_kit._native`). The packing oracle needs OR-Tools in this process. Any other
name is a Pyomo ``SolverFactory`` solver run in-process (``cbc``, ``glpk``, ``gurobi``,
``scip`` ...), with its time-limit and gap options set when :data:`SOLVER_OPTIONS` knows them.
Shared by the ``milp`` and ``bilevel-milp`` methods.
"""

from __future__ import annotations

import logging
import math
import sys
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from ...errors import UsageError
from ...interrupt import kill_pid, on_forced_exit, remove_path
from ..budget import Budget

#: Relative tolerance when comparing float objectives (the MILP works on real seconds).
TOL = 1e-6
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
#: Seconds kept back for writing, reading and loading a child's solution.
RESULT_LOAD_S = 0.3
#: Seconds a HiGHS child needs to start (Python, highspy) and read a model: with less time
#: left it is not started (1.9 s with a 0.01 s limit on a loaded machine).
CHILD_START_S = 1.0
#: Seconds a HiGHS child process may run past the time left before it is killed (the method's
#: contract allows max(2 s, 5 %) past its limit in all). A killed child loses its incumbent.
KILL_GRACE = 1.5
#: HiGHS is asked to stop this share of the time left early (at most ``HIGHS_RESERVE_S``):
#: it overruns its own limit inside long nodes and presolve (5 s on 10 table units with one
#: tray at 60 s; over 1.4 s on bilevel-milp's 9,847-binary table model), and stopping by itself
#: keeps its incumbent.
HIGHS_RESERVE = 0.2
HIGHS_RESERVE_S = 4.0


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


def ensure_ortools(solver: str | None = None) -> None:
    """Load OR-Tools (the packing oracle) before anything can load highspy in-process.

    Whichever of the two is loaded first wins the ``libhighs.so.1`` soname; once highspy is in
    (cvxpy imports it on its first solve, Pyomo's in-process HiGHS interfaces too), OR-Tools
    can no longer be imported in this process, which deserves a clear message. ``solver``
    ``"highs"`` runs HiGHS in a subprocess, so highspy never enters this process and OR-Tools
    is left to load when the oracle first needs it: its import (pandas with it) takes 1-3 s,
    which a short time limit cannot pay up front (docs/cli.md#shared-options).
    """
    if solver == "highs" and "highspy" not in sys.modules:
        return
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


#: Called with the solver's primal and dual bound (None: none yet) while it runs.
OnBounds = Callable[[float | None, float | None], None]


@dataclass(frozen=True)
class _Request:
    """One solve: until the end of ``budget``, with this seed, log flag, extra solver
    ``options``, (``warmstart``) the variables' current values as a MIP start and
    (``on_bounds``) a listener for the bounds while it runs (the HiGHS child only)."""

    budget: Budget
    seed: int
    log: bool
    options: Mapping[str, Any]
    warmstart: bool
    on_bounds: OnBounds | None = None


def run_solver(
    model: Any,
    opt: Any,
    name: str,
    *,
    budget: Budget,
    seed: int = 0,
    log: bool = False,
    objective: Any = None,
    options: Mapping[str, Any] | None = None,
    warmstart: bool = False,
    on_bounds: OnBounds | None = None,
) -> SolveInfo:
    """Minimise ``model`` until the end of ``budget`` with a zero relative gap and load the
    best solution into its variables. ``warmstart``: the variables' current values are a MIP
    start (HiGHS completes a partial one). ``opt=None`` (``solver="highs"``) runs HiGHS in a
    child process (module docstring); ``on_bounds`` then hears its primal and dual bounds
    while it runs (from a reader thread).
    """
    import pyomo.environ as pyo

    t0 = time.perf_counter()
    req = _Request(budget, seed, log, dict(options or {}), warmstart, on_bounds)
    info = _run_highs_child(model, req) if opt is None else _run_pyomo(model, opt, name, req)
    if info.has_solution and objective is not None:
        info.objective = pyo.value(objective, exception=False)
        info.has_solution = info.objective is not None
    if info.optimal and info.objective is not None:
        obj = info.objective
        info.bound = obj if info.bound is None else min(max(info.bound, obj - TOL), obj)
    info.optimal = info.optimal and info.has_solution
    info.wall_time_s = time.perf_counter() - t0
    return info


def _finite(v: Any) -> float | None:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def _child_env() -> dict[str, str]:
    """The environment of the child: this process's, with the directory that holds this copy
    of ``bilevel_kit`` first on ``PYTHONPATH`` (so the child runs the same code)."""
    import os
    from pathlib import Path

    root = str(Path(__file__).resolve().parents[3])
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    return env


def _write_start(smap: Any, tmp: str) -> str:
    """The variables' current values as a JSON MIP start file (``""`` if none has a value)."""
    import json
    import os

    given = {
        sym: var.value
        for sym, var in smap.bySymbol.items()
        if getattr(var, "value", None) is not None
    }
    if not given:
        return ""
    start = os.path.join(tmp, "start.json")
    with open(start, "w") as f:
        json.dump(given, f)
    return start


def _die_with_parent(parent: int) -> None:
    """In the HiGHS child before it runs (Linux): ask the kernel to send it SIGKILL when its
    parent dies, even by SIGKILL, so no solver runs on past the command that started it."""
    import ctypes
    import os
    import signal

    pr_set_pdeathsig = 1
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(pr_set_pdeathsig, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # the parent died before the request took effect
        os._exit(1)


@contextmanager
def _scratch_dir(prefix: str) -> Iterator[str]:
    """A private temporary folder, removed on every way out (docs/cli.md#interrupting-a-command):
    its removal is armed before the folder exists, so a signal that lands right after it is
    made cannot leave it behind (``tempfile.TemporaryDirectory`` can, when the signal lands in
    its constructor and the interrupted command ends without the interpreter's teardown), and
    a stuck process ended by the guard removes it too (:func:`on_forced_exit`)."""
    import os
    import secrets
    import tempfile

    path = os.path.join(tempfile.gettempdir(), f"{prefix}{secrets.token_hex(8)}")
    with on_forced_exit(remove_path(path)):
        try:
            os.mkdir(path, 0o700)
            yield path
        finally:
            remove_path(path)()


def _run_highs_child(model: Any, req: _Request) -> SolveInfo:
    """Write ``model`` as MPS, solve it with ``python -m bilevel_kit.models.milp.highs_child``
    and load its solution back into the model's variables."""
    import functools
    import json
    import os
    import subprocess
    import sys

    with _scratch_dir("bilevel_milp_") as tmp:
        path = os.path.join(tmp, "model.mps")
        out = os.path.join(tmp, "result.json")
        _, smap_id = model.write(path, format="mps", io_options={"symbolic_solver_labels": False})
        smap = model.solutions.symbol_map[smap_id]
        start = _write_start(smap, tmp) if req.warmstart else ""
        left = req.budget.remaining() - RESULT_LOAD_S
        if left < CHILD_START_S:  # writing the model used the time: starting HiGHS would overrun
            return SolveInfo("time limit before the solve", False, False, False, None, None, 0.0)
        argv = [
            sys.executable,
            "-m",
            "bilevel_kit.models.milp.highs_child",
            path,
            out,
            repr(max(0.01, left - min(HIGHS_RESERVE_S, HIGHS_RESERVE * left))),
            str(int(req.seed)),
            "1" if req.log else "0",
            json.dumps(dict(req.options)),
            start,
            repr(time.time()),  # the limit includes the child's start-up and model reading
        ]
        pipe = _BoundsPipe(req.on_bounds) if req.on_bounds is not None else None
        if pipe is not None:
            argv.append(str(pipe.child_fd))
        try:
            proc = subprocess.Popen(
                argv,
                stdout=None if req.log else subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                text=True,
                env=_child_env(),
                pass_fds=() if pipe is None else (pipe.child_fd,),
                preexec_fn=(
                    functools.partial(_die_with_parent, os.getpid())
                    if sys.platform == "linux"
                    else None
                ),
            )
        except BaseException:
            if pipe is not None:  # never started: close both ends of the pipe
                pipe.join()
            raise
        if pipe is not None:
            pipe.start()
        try:  # the child never outlives this call: killed on a timeout, an error or a signal
            with on_forced_exit(kill_pid(proc.pid)):
                _, err = proc.communicate(timeout=max(1.0, left) + KILL_GRACE)
        except subprocess.TimeoutExpired:
            return SolveInfo("killed", False, False, False, None, None, 0.0)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
            if pipe is not None:
                pipe.join()
        if proc.returncode != 0 or not os.path.exists(out):
            raise RuntimeError(f"HiGHS subprocess failed: {err.strip()[-2000:]}")
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


class _BoundsPipe:
    """The pipe the HiGHS child writes its ``PRIMAL DUAL`` lines to, read by a thread that
    passes them on (non-finite values as None)."""

    def __init__(self, on_bounds: OnBounds) -> None:
        import os

        self.on_bounds = on_bounds
        self.read_fd, self.child_fd = os.pipe()
        self.thread: Any = None

    def start(self) -> None:
        """Close this process's copy of the write end (the child has its own), then read."""
        import os
        import threading

        os.close(self.child_fd)
        self.thread = threading.Thread(target=self._read, name="highs-bounds", daemon=True)
        self.thread.start()

    def _read(self) -> None:
        listening = True
        with open(self.read_fd) as lines:  # ends when the child exits
            for line in lines:  # read to the end even if the listener failed: never block HiGHS
                primal, _, dual = line.partition(" ")
                try:
                    if listening:
                        self.on_bounds(_finite(primal), _finite(dual))
                except Exception:  # a broken progress display must not break the solve
                    listening = False

    def join(self) -> None:
        if self.thread is not None:
            self.thread.join()
        else:  # the child never started: close both ends here
            import os

            os.close(self.read_fd)
            os.close(self.child_fd)


def _takes_warmstart(opt: Any) -> bool:
    try:
        return bool(opt.warm_start_capable())
    except Exception:
        return False


def _run_pyomo(model: Any, opt: Any, name: str, req: _Request) -> SolveInfo:
    """Solve in-process with the Pyomo solver ``opt`` (its limits set when known)."""
    from pyomo.opt import TerminationCondition

    left = max(0.01, req.budget.remaining())
    opts: dict[str, Any] = {}
    names = SOLVER_OPTIONS.get(name)
    if names is not None:
        tl_key, gap_key, seed_key = names
        opts[tl_key] = max(1, math.ceil(left)) if name == "glpk" else left
        opts[gap_key] = 0.0
        if seed_key is not None:
            opts[seed_key] = int(req.seed)
    opts.update(req.options)
    with _quiet_pyomo():
        kw: dict[str, Any] = {"warmstart": True} if req.warmstart and _takes_warmstart(opt) else {}
        res = opt.solve(model, tee=req.log, load_solutions=False, options=opts, **kw)
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
