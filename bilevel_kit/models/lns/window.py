r"""One neighbourhood of the large-neighbourhood search: a window of kits re-optimised exactly.

The tasks of the kits ``[k0, k1)`` are freed and assigned again to kit positions by CP-SAT,
the rest of the plan fixed (docs/formulations.md, "Large-neighbourhood search"):

* ``x[j,p]``: task j of the window in position p; precedence inside the window as
  :math:`p_a \le p_b` (a window of consecutive kits holds every task between two of its tasks,
  and its tasks' other predecessors are in earlier kits, their other successors in later ones);
* with unlimited trays or one tray the number of kits may change: used positions first
  (:math:`u_p \ge u_{p+1}`), an unused one copies the state of the one before; with T >= 2
  trays the window keeps its number of kits (the tray rule then indexes kits by position);
* the timeline of docs/timeline.md from the prefix's state (:class:`.state.Edge`), exactly on
  the integer times, and the makespan as the suffix's max-plus response to the window's end
  state (:func:`.state.tail_response`), so the objective is the whole plan's makespan;
* the tray: the area relaxation per kit, the no-good cuts of every part multiset found not
  to fit so far and, for each one a pair of dual-feasible functions proves, that pair's
  inequality over every kit's part counts (:func:`..packing_bounds.dff_cut`); a solution's
  kits are packed by the oracle, a kit that does not fit is cut and the window solved again
  (:data:`PACK_ROUNDS` times at most).

The current assignment is the hint and :math:`C \le` the current makespan, so a solve returns
the plan or a better one. CP-SAT runs with a deterministic time limit (``dtime``) and the
given workers (``interleave_search`` when more than one, which keeps it deterministic),
and the packing oracle decides the kits of its solutions with a deterministic limit too
(:class:`..common.Packer`, one worker; its wall-clock limit is a safety net), so a window's
result does not depend on the machine load (docs/formulations.md, "Determinism").
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from ...instance import Instance
from .. import packing, stoppable
from ..common import chain_groups_idx, kit_order, relabel_chains
from ..cpsat.model import add_lex_leq
from ..cpsat.scaling import Scaled
from .fit import FastFit
from .state import Edge, tail_response, window_edge

#: Times a window is solved again after cutting kits that did not fit.
PACK_ROUNDS = 4
#: A multiset proven not to fit is shrunk to a minimal one up to this many parts ...
SHRINK_PARTS = 16
#: ... within this share of the time left: a safety net (it finishes far sooner), so that a
#: loaded machine shrinks a cut as an idle one does (was 0.05 before the windows' packing
#: became reproducible).
SHRINK_SHARE = 0.5


@dataclass
class Context:
    """What every window of one run shares: the instance, its integer times, the packing
    oracle, the grid areas, the part counts of each task, the reduced precedence edges, the
    cuts found so far and CP-SAT's settings."""

    instance: Instance
    sc: Scaled
    fit: FastFit
    workers: int
    dtime: float
    area: list[int] = field(default_factory=list)
    tray_area: int = 0
    parts: list[dict[str, int]] = field(default_factory=list)
    edges: list[tuple[int, int]] = field(default_factory=list)
    cuts: list[dict[str, int]] = field(default_factory=list)
    cut_keys: set[frozenset[tuple[str, int]]] = field(default_factory=set)
    #: the dual-feasible-function inequalities learnt so far, each as every task's weight (its
    #: parts' coefficients) and the capacity: a kit's weights sum to at most the capacity
    dff_rows: list[tuple[list[int], int]] = field(default_factory=list)
    #: each part type's size on the packing grid and rotatability, and the tray's grid size
    grid_types: dict[str, tuple[int, int, bool]] = field(default_factory=dict)
    grid_tray: tuple[int, int] = (0, 0)

    @classmethod
    def of(
        cls, instance: Instance, sc: Scaled, fit: FastFit, workers: int, dtime: float
    ) -> Context:
        from ..common import reduced_edges

        res = fit.packer.res
        tray = instance.tray
        types = {
            p.id: (packing.grid_up(p.width, res), packing.grid_up(p.height, res), p.rotatable)
            for p in instance.part_types.values()
        }
        W, H = packing.grid_down(tray.width, res), packing.grid_down(tray.height, res)
        idx = instance.index
        return cls(
            instance,
            sc,
            fit,
            workers,
            dtime,
            area=[sum(types[p][0] * types[p][1] * c for p, c in t.parts) for t in instance.tasks],
            tray_area=W * H,
            parts=[dict(t.parts) for t in instance.tasks],
            edges=[(idx[a], idx[b]) for a, b in reduced_edges(instance)],
            grid_types=types,
            grid_tray=(W, H),
        )

    def add_cut(self, counts: Mapping[str, int]) -> None:
        key = frozenset((t, c) for t, c in counts.items() if c)
        if key not in self.cut_keys:
            self.cut_keys.add(key)
            self.cuts.append(dict(key))
            self._dff_row(dict(key))

    def _dff_row(self, counts: dict[str, int]) -> None:
        """The dual-feasible-function inequality that proves ``counts`` misfit, if one does:
        it cuts every kit it proves, not only supersets of ``counts``."""
        from ..packing_bounds import dff_cut

        row = dff_cut(self.grid_types, counts, *self.grid_tray)
        if row is None:
            return
        coef, cap = row
        weights = [sum(coef.get(t, 0) * c for t, c in parts.items()) for parts in self.parts]
        if (weights, cap) not in self.dff_rows:
            self.dff_rows.append((weights, cap))

    def fits(self, kit: Sequence[int]) -> bool:
        """Does the kit pack (an unknown verdict counts as no); cuts it if not (a proven misfit
        of at most :data:`SHRINK_PARTS` parts shrunk to a minimal one first). The oracle's
        calls are limited by deterministic time (module docstring), the shrinking by
        :data:`SHRINK_SHARE` of the time left, a safety net."""
        ids = [self.instance.tasks[i].id for i in kit]
        counts = dict(self.instance.kit_parts(ids))
        ok = self.fit.counts(counts, deterministic=True)
        if ok is not True:
            packer = self.fit.packer
            if ok is False and sum(counts.values()) <= SHRINK_PARTS:
                until = packer.budget.share(SHRINK_SHARE)
                counts = packer.minimal_nofit(counts, until, deterministic=True)
            self.add_cut(counts)
        return ok is True


@dataclass
class Outcome:
    """A window's result: the new kits (None: no plan found), whether CP-SAT proved them
    optimal for the window, and whether the wall clock stopped it (then it is not used)."""

    kits: list[list[int]] | None
    optimal: bool
    stopped: bool


def solve_window(
    ctx: Context,
    kits: Sequence[Sequence[int]],
    k0: int,
    k1: int,
    upper: int,
    seed: int,
    wall_left: float,
) -> Outcome:
    """Re-optimise the kits ``[k0, k1)`` of ``kits`` (scaled makespan ``upper``); the new kits
    of the window, each in the human's order (module docstring)."""
    import time

    end = time.perf_counter() + wall_left
    optimal = False
    for _ in range(PACK_ROUNDS):
        left = end - time.perf_counter()
        if left <= 0.01:
            return Outcome(None, False, True)
        new, optimal, stopped = _WindowModel.of(ctx, kits, k0, k1, upper).solve(seed, left)
        if stopped or new is None:
            return Outcome(None, False, stopped)
        if all([ctx.fits(k) for k in new]):
            return Outcome(new, optimal, False)
    return Outcome(None, False, False)


class _WindowModel:
    """The CP-SAT model of one window (module docstring)."""

    @classmethod
    def of(
        cls, ctx: Context, kits: Sequence[Sequence[int]], k0: int, k1: int, upper: int
    ) -> _WindowModel:
        """The model of the kits ``[k0, k1)`` of ``kits``: timeline, objective and hint."""
        sc = ctx.sc
        tasks = [i for k in kits[k0:k1] for i in k]
        flexible = sc.trays is None or sc.trays == 1
        n_pos = min(len(tasks), k1 - k0 + max(2, (k1 - k0) // 2)) if flexible else k1 - k0
        win = cls(ctx, tasks, n_pos, flexible, k0, upper, kits[k0:k1])
        win.timeline(window_edge(sc, kits, k0))
        # the suffix's first kit: at k1 when the count is fixed; with one tray at 1 or later
        win.objective(tail_response(sc, kits[k1:], k0 + 1 if flexible else k1))
        win.hint(kits[k0:k1])
        return win

    def solve(self, seed: int, wall_left: float) -> tuple[list[list[int]] | None, bool, bool]:
        """One CP-SAT solve of the window: (kits or None, optimal, stopped by the wall clock)."""
        import time

        from ortools.sat.python import cp_model

        ctx = self.ctx
        solver = cp_model.CpSolver()
        p = solver.parameters
        p.num_workers = max(1, ctx.workers)
        if ctx.workers > 1:
            p.interleave_search = True
        p.random_seed = seed
        p.max_deterministic_time = ctx.dtime
        p.max_time_in_seconds = max(0.01, wall_left)
        t0 = time.perf_counter()
        st = stoppable.solve(solver, self.m)  # Ctrl-C and SIGTERM stop it (docs/cli.md)
        stopped = (
            st not in (cp_model.OPTIMAL, cp_model.INFEASIBLE)
            and time.perf_counter() - t0 >= wall_left - 1e-3
        )
        if st not in (cp_model.OPTIMAL, cp_model.FEASIBLE) or stopped:
            return None, False, stopped
        return self.kits(solver), st == cp_model.OPTIMAL, False

    def __init__(
        self,
        ctx: Context,
        tasks: list[int],
        n_pos: int,
        flexible: bool,
        k0: int,
        upper: int,
        current: Sequence[Sequence[int]] = (),
    ) -> None:
        from ortools.sat.python import cp_model

        self.ctx, self.tasks, self.P, self.flexible, self.k0 = ctx, tasks, n_pos, flexible, k0
        self.upper = upper
        m = self.m = cp_model.CpModel()
        local = {i: j for j, i in enumerate(tasks)}
        self.x = [[m.new_bool_var("") for _ in range(n_pos)] for _ in tasks]
        pos = []
        for xs in self.x:
            m.add_exactly_one(xs)
            pv = m.new_int_var(0, n_pos - 1, "")
            m.add(pv == sum(p * v for p, v in enumerate(xs)))
            pos.append(pv)
        inside = [(local[a], local[b]) for a, b in ctx.edges if a in local and b in local]
        for a, b in inside:
            m.add(pos[a] <= pos[b])
        sc = ctx.sc
        sig = [(sc.r[i], sc.h[i], tuple(sorted(ctx.parts[i].items()))) for i in tasks]
        self.groups = chain_groups_idx(len(tasks), inside, sig)
        for group in self.groups:
            for c1, c2 in itertools.pairwise(group):
                add_lex_leq(m, [pos[j] for j in c1], [pos[j] for j in c2])
        self.u: list[Any] = [1] * n_pos
        if flexible:
            self.u = [m.new_bool_var("") for _ in range(n_pos)]
            m.add(self.u[0] == 1)
            for p in range(n_pos):
                col = [xs[p] for xs in self.x]
                for v in col:
                    m.add_implication(v, self.u[p])
                m.add_bool_or(col).only_enforce_if(self.u[p])
                if p:
                    m.add_implication(self.u[p], self.u[p - 1])
        else:
            for p in range(n_pos):
                m.add_bool_or([xs[p] for xs in self.x])
        self._tray(current)

    def _tray(self, current: Sequence[Sequence[int]]) -> None:
        """The area relaxation, the cuts and the dual-feasible-function inequalities that can
        bind in this window; an inequality a ``current`` kit breaks (a kit laid out at another
        angle than 0/90 degrees, known from a warm start) is left out, so that the current
        kits stay a solution."""
        ctx, m = self.ctx, self.m
        for p in range(self.P):
            m.add(
                sum(ctx.area[i] * xs[p] for i, xs in zip(self.tasks, self.x, strict=True))
                <= ctx.tray_area
            )
        for weights, cap in ctx.dff_rows:
            w = [weights[i] for i in self.tasks]
            if sum(w) <= cap:
                continue  # the whole window fits this inequality in one kit
            if any(sum(weights[i] for i in kit) > cap for kit in current):
                continue
            for p in range(self.P):
                m.add(sum(wi * xs[p] for wi, xs in zip(w, self.x, strict=True) if wi) <= cap)
        total: dict[str, int] = {}
        for i in self.tasks:
            for t, c in ctx.parts[i].items():
                total[t] = total.get(t, 0) + c
        lits: dict[tuple[str, int, int], Any] = {}
        for cut in ctx.cuts:
            if any(total.get(t, 0) < c for t, c in cut.items()):
                continue  # the window cannot hold this multiset in one kit
            for p in range(self.P):
                row = []
                for t, c in cut.items():
                    key = (t, p, c)
                    if key not in lits:
                        lit = lits[key] = m.new_bool_var("")
                        count = sum(
                            ctx.parts[i].get(t, 0) * xs[p]
                            for i, xs in zip(self.tasks, self.x, strict=True)
                            if ctx.parts[i].get(t, 0)
                        )
                        m.add(count <= c - 1).only_enforce_if(lit)
                    row.append(lits[key])
                m.add_bool_or(row)

    def timeline(self, edge: Edge) -> None:
        """Robot start, arrival, human start and end of every position (module docstring)."""
        m, sc = self.m, self.ctx.sc
        hz = self.upper
        prev_a: Any = edge.arrive
        prev_e: Any = edge.end
        self.hs: list[Any] = []
        self.edge = edge
        self.arrive: list[Any] = []
        self.end: list[Any] = []
        for p in range(self.P):
            k = self.k0 + p
            xs = [xv[p] for xv in self.x]
            r = sc.o_r * self.u[p] + sum(sc.r[i] * v for i, v in zip(self.tasks, xs, strict=True))
            h = sc.o_h * self.u[p] + sum(sc.h[i] * v for i, v in zip(self.tasks, xs, strict=True))
            a, hs, e = (m.new_int_var(0, hz, "") for _ in range(3))
            starts = [prev_a]
            if sc.trays is not None and k >= sc.trays:
                back = k - sc.trays  # the kit whose tray this one needs
                hs_back = (
                    self.hs[back - self.k0] if back >= self.k0 else edge.starts[back - self.k0]
                )
                starts.append(hs_back + sc.o_h)
            used = [] if not self.flexible else [self.u[p]]
            for s in starts:
                m.add(a >= s + r + sc.d * self.u[p]).only_enforce_if(used)
            m.add(hs >= prev_e).only_enforce_if(used)
            m.add(e == hs + h).only_enforce_if(used)
            # valid for unused positions too (they copy the last used one): linear, no
            # enforcement, so CP-SAT's relaxation sees the timeline
            m.add(a >= prev_a + r + sc.d * self.u[p])
            m.add(hs >= a)
            m.add(e >= prev_e + h)
            m.add(e >= a + h)
            if self.flexible:  # an unused position copies the one before
                off = self.u[p].Not()
                m.add(a == prev_a).only_enforce_if(off)
                m.add(e == prev_e).only_enforce_if(off)
                prev_hs = self.hs[-1] if self.hs else (edge.starts[-1] if edge.starts else 0)
                m.add(hs == prev_hs).only_enforce_if(off)
            self.arrive.append(a)
            self.end.append(e)
            self.hs.append(hs)
            prev_a, prev_e = a, e

    def objective(self, form: dict[str, int]) -> None:
        """C >= each term of the suffix's response to the window's end state; C <= U."""
        m = self.m
        self.C = C = m.new_int_var(0, self.upper, "")
        last = self.P - 1
        for key, c in form.items():
            if key in ("A", "E"):
                var: Any = (self.arrive if key == "A" else self.end)[last]
            else:
                j = int(key[2:])  # HSj: the j-th last kit up to the window's end
                if j <= self.P:
                    var = self.hs[self.P - j]
                elif j - self.P <= len(self.edge.starts):
                    var = self.edge.starts[self.P - j]
                else:
                    continue  # no such kit: the tray rule never refers to it
            m.add(var + c <= C)
        m.minimize(C)

    def hint(self, current: Sequence[Sequence[int]]) -> None:
        """The current kits as the hint, interchangeable chains relabelled into the model's
        lexicographic order (the same kits)."""
        local = {i: j for j, i in enumerate(self.tasks)}
        where = relabel_chains(
            {local[i]: p for p, kit in enumerate(current) for i in kit}, self.groups
        )
        for j, xs in enumerate(self.x):
            for p, v in enumerate(xs):
                self.m.add_hint(v, where[j] == p)
        if self.flexible:
            for p, u in enumerate(self.u):
                self.m.add_hint(u, p < len(current))

    def kits(self, solver: Any) -> list[list[int]]:
        """The solution's kits in position order, each in the human's order."""
        inst = self.ctx.instance
        by_pos: dict[int, list[int]] = {}
        for i, xs in zip(self.tasks, self.x, strict=True):
            p = next(p for p, v in enumerate(xs) if solver.boolean_value(v))
            by_pos.setdefault(p, []).append(i)
        out = []
        for p in sorted(by_pos):
            ids = kit_order(inst, [inst.tasks[i].id for i in by_pos[p]])
            out.append([inst.index[t] for t in ids])
        return out
