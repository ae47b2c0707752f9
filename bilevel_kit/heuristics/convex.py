r"""Convex polishing of a kit layout: a convex-concave procedure of SOCPs (cvxpy + Clarabel).

Why: the cross-entropy method (paper Algorithm 1) ends near a good layout but not at a local
optimum of the kit fitness (its samples are noisy and it stops on a plateau of the elite
threshold). With the rotations fixed, the rest of the problem is nearly convex, so a few SOCPs
finish the job, exactly and cheaply.

**The problem** (paper Section IV-B). Parts k = 1..n with centres :math:`c_k = (x_k, y_k)`,
fixed angles :math:`\theta_k`, footprints :math:`w_k \times h_k`. Kit fitness (Eq. 11 with the
erratum's sign, docs/errata.md) is :math:`f = -(D_{same} - D_{diff} + W_6 Z)` with

.. math::

    D_{diff} = \sum_{k<j,\ Q_k \ne Q_j} \|c_k - c_j\|    \quad (8)  \qquad
    D_{same} = \sum_{k<j,\ Q_k = Q_j} \|c_k - c_j\|      \quad (9)

and Z the overlap area (Eq. 10). Here Z = 0 is a hard constraint, so we minimise
:math:`g(c) = D_{same}(c) - D_{diff}(c)` over non-overlapping layouts inside the tray.

**Fixed rectangles, linear constraints.** With :math:`a_k = (\cos\theta_k, \sin\theta_k)` and
:math:`b_k = (-\sin\theta_k, \cos\theta_k)`, the half-width of part k along a unit vector n is
its support :math:`s_k(n) = \tfrac{w_k}{2}|n \cdot a_k| + \tfrac{h_k}{2}|n \cdot b_k|`, a
constant once :math:`\theta_k` is fixed. For each pair (k, j) an axis :math:`n_{kj}` is fixed
from the current layout: among the four edge normals :math:`a_k, b_k, a_j, b_j` (the axes of the
separating-axis theorem), the one along which the projections are furthest apart, oriented from
k to j. Then

.. math:: n_{kj} \cdot (c_j - c_k) \ge s_k(n_{kj}) + s_j(n_{kj})            \quad (\text{sep})

is linear in c and *sufficient* for non-overlap (the projections on :math:`n_{kj}` are
disjoint), and the current layout satisfies it: a valid layout has a separating edge normal
(SAT), and touching parts satisfy it with equality. Tray containment (the constraint of
Eq. 11) is linear too: :math:`e^x_k \le x_k \le W - e^x_k`, :math:`e^y_k \le y_k \le H - e^y_k`
with the exact half-extents :math:`e^x_k = (w_k|\cos\theta_k| + h_k|\sin\theta_k|)/2`,
:math:`e^y_k = (w_k|\sin\theta_k| + h_k|\cos\theta_k|)/2` of the rotated rectangle.

**Convex-concave procedure.** :math:`D_{same}` is a sum of Euclidean norms (convex, second-order
cones); :math:`-D_{diff}` is concave. At the current point :math:`c^t`, with
:math:`u_{kj} = (c^t_j - c^t_k) / \|c^t_j - c^t_k\|`, Cauchy-Schwarz gives the linear minorant
:math:`\|c_j - c_k\| \ge u_{kj} \cdot (c_j - c_k)` (equal at :math:`c^t`, the first-order
Taylor expansion). Replacing :math:`D_{diff}` by it gives the convex majorant

.. math:: \hat g_t(c) = \sum_{Q_k = Q_j} \|c_j - c_k\| - \sum_{Q_k \ne Q_j} u_{kj}\cdot(c_j - c_k)
          \;\ge\; g(c), \qquad \hat g_t(c^t) = g(c^t),

minimised subject to (sep) and containment: an SOCP, solved with cvxpy and Clarabel. So
:math:`g(c^{t+1}) \le \hat g_t(c^{t+1}) \le \hat g_t(c^t) = g(c^t)`: the true objective never
increases. Axes and u are re-chosen from each new layout, and rounds repeat until the relative
improvement falls below ``tol`` or ``max_rounds`` is reached.

**Exactness guard.** Solvers are accurate to about 1e-8, not exactly, so every round's answer
is re-checked before it is accepted: the exact fitness (:func:`bilevel_kit.fitness
.layout_fitness`, exact Z) must not decrease, and the checker's geometry
(:mod:`bilevel_kit.geometry`, separating-axis test and corner containment, tolerance
``geometry.TOL``) must find no overlap and every part inside the tray. Otherwise polishing stops
and returns the previous layout. Constraints are tightened by ``MARGIN`` (1e-7 mm) where the
current layout allows it (never beyond the current layout, which stays feasible), so solver
noise does not reach the tolerance.

**Assumptions and limits.** Angles are fixed (rotations make the footprints non-convex in the
variables) and so is each pair's separating axis within a round: parts cannot pass each other or
swap places, only slide. The result is a *local* improvement of the given layout, never a global
optimum. An invalid input layout is refused (:class:`~bilevel_kit.errors.UsageError`).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from .. import geometry
from ..errors import UsageError
from ..fitness import layout_fitness, layout_terms
from ..instance import Instance, Tray
from ..plan import Kit, Placement, Plan

if TYPE_CHECKING:
    from .cross_entropy import Arrangement

#: Tightening (mm) of the separation and containment constraints where the current layout allows
#: it; keeps the solver's ~1e-8 feasibility error far from ``geometry.TOL``.
MARGIN = 1e-7

#: Clarabel's tolerances (defaults 1e-8): the defaults left separations violated by up to 5e-7
#: mm per round on the 28-part table kit (absolute errors scale with the ~300 mm coordinates),
#: which accumulated past ``geometry.TOL`` within 3 rounds; with these the margin held.
CLARABEL_OPTS: dict[str, float] = {"tol_feas": 1e-11, "tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10}

#: Statuses of :class:`PolishResult`.
STATUSES = ("converged", "max_rounds", "rejected", "solver_failed", "trivial")


@dataclass(frozen=True)
class PolishResult:
    """Outcome of :func:`polish`.

    ``status``: ``converged`` (the last round improved by less than ``tol``), ``max_rounds``,
    ``rejected`` (a round's answer failed the exact check and was rolled back), ``solver_failed``
    (the solver gave no optimal answer; rolled back) or ``trivial`` (fewer than 2 parts).
    ``rounds`` counts the SOCPs solved; ``trace`` holds the exact fitness of every accepted
    layout, starting with the input's, so it is non-decreasing.
    """

    layout: tuple[Placement, ...]
    fitness_before: float
    fitness_after: float
    rounds: int
    status: str
    wall_time_s: float
    trace: tuple[float, ...] = ()

    @property
    def gain(self) -> float:
        """Fitness gained (>= 0)."""
        return self.fitness_after - self.fitness_before


# ---------------------------------------------------------------------------------------------
# Geometry of the fixed rectangles
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Parts:
    """Constants of one layout: axes, half-sizes, extents and the pair index arrays."""

    a: np.ndarray  # (n, 2) unit vector along the width
    b: np.ndarray  # (n, 2) unit vector along the height
    hw: np.ndarray  # (n,) half widths
    hh: np.ndarray  # (n,) half heights
    ex: np.ndarray  # (n,) half-extents of the rotated boxes along x
    ey: np.ndarray  # (n,) ... along y
    i: np.ndarray  # (P,) first index of each pair
    j: np.ndarray  # (P,) second index
    same: np.ndarray  # (P,) equal types

    @classmethod
    def build(cls, layout: Sequence[Placement]) -> _Parts:
        t = np.radians(np.array([p.theta for p in layout], dtype=np.float64))
        c, s = np.cos(t), np.sin(t)
        w = np.array([p.w for p in layout], dtype=np.float64)
        h = np.array([p.h for p in layout], dtype=np.float64)
        types = [p.type for p in layout]
        i, j = np.triu_indices(len(layout), 1)
        same = np.array([types[a] == types[b] for a, b in zip(i, j, strict=True)], dtype=bool)
        return cls(
            a=np.stack([c, s], axis=1),
            b=np.stack([-s, c], axis=1),
            hw=w / 2.0,
            hh=h / 2.0,
            ex=(w * np.abs(c) + h * np.abs(s)) / 2.0,
            ey=(w * np.abs(s) + h * np.abs(c)) / 2.0,
            i=i,
            j=j,
            same=same.reshape(-1),
        )

    def support(self, k: np.ndarray, n: np.ndarray) -> np.ndarray:
        """Half-width s_k(n) of parts ``k`` along unit vectors ``n`` (rows), broadcast."""
        along_w = np.abs(np.einsum("...d,...d->...", n, self.a[k]))
        along_h = np.abs(np.einsum("...d,...d->...", n, self.b[k]))
        return self.hw[k] * along_w + self.hh[k] * along_h


def _separating_axes(parts: _Parts, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pair: the fixed axis n (oriented from i to j), the support sum s_i(n) + s_j(n),
    and the current projected distance n . (c_j - c_i).

    The axis is the SAT edge normal with the largest projection gap (the first one on ties)."""
    i, j = parts.i, parts.j
    cand = np.stack([parts.a[i], parts.b[i], parts.a[j], parts.b[j]], axis=1)  # (P, 4, 2)
    d = xy[j] - xy[i]  # (P, 2)
    proj = np.einsum("pcd,pd->pc", cand, d)
    sup = parts.support(i[:, None], cand) + parts.support(j[:, None], cand)
    best = np.argmax(np.abs(proj) - sup, axis=1)
    rows = np.arange(len(i))
    sign = np.where(proj[rows, best] >= 0.0, 1.0, -1.0)
    n = cand[rows, best] * sign[:, None]
    return n, sup[rows, best], np.abs(proj[rows, best])


# ---------------------------------------------------------------------------------------------
# One SOCP round
# ---------------------------------------------------------------------------------------------


class _RoundProblem:
    """The SOCP of one round, built once per :func:`polish` call and re-solved each round.

    Everything that changes between rounds (the axes, the right-hand sides, the tray bounds
    and the linearisation directions u) is a cvxpy ``Parameter`` entering the problem
    affinely (DPP), so cvxpy canonicalises the problem once; later rounds only refill the
    parameters (about 3x cheaper per round than rebuilding the problem).
    """

    def __init__(self, parts: _Parts, width: float, height: float, solver: str) -> None:
        from .._native import ortools_first

        ortools_first()  # before cvxpy loads highspy: the two libhighs builds clash
        import cvxpy as cp

        self.cp = cp
        self.parts = parts
        self.width, self.height = width, height
        self.solver = solver
        n = parts.hw.size
        npairs = parts.i.size
        rows = np.arange(npairs)
        # Pair differences c_j - c_i as a sparse (P, n) operator.
        diff = sp.csr_matrix(
            (
                np.concatenate([np.ones(npairs), -np.ones(npairs)]),
                (np.concatenate([rows, rows]), np.concatenate([parts.j, parts.i])),
            ),
            shape=(npairs, n),
        )
        self.x = cp.Variable(n)
        self.y = cp.Variable(n)
        self.nx = cp.Parameter(npairs)
        self.ny = cp.Parameter(npairs)
        self.rhs = cp.Parameter(npairs)
        self.lo = cp.Parameter((2, n))
        self.hi = cp.Parameter((2, n))
        x, y = self.x, self.y
        cons = [
            cp.multiply(self.nx, diff @ x) + cp.multiply(self.ny, diff @ y) >= self.rhs,
            x >= self.lo[0],
            x <= self.hi[0],
            y >= self.lo[1],
            y <= self.hi[1],
        ]
        objective = cp.Constant(0.0)
        same = np.flatnonzero(parts.same)
        if same.size:
            ds = diff[same]
            objective = cp.sum(cp.norm(cp.vstack([ds @ x, ds @ y]), 2, axis=0))
        self.other = np.flatnonzero(~parts.same)
        self.ux = cp.Parameter(self.other.size)
        self.uy = cp.Parameter(self.other.size)
        if self.other.size:
            dd = diff[self.other]
            objective = objective - (self.ux @ (dd @ x) + self.uy @ (dd @ y))
        self.problem = cp.Problem(cp.Minimize(objective), cons)

    def solve(self, xy: np.ndarray) -> tuple[np.ndarray | None, str]:
        """Minimise the convex majorant at ``xy`` (module docstring): new centres, or None and
        the solver's status."""
        cp, parts = self.cp, self.parts
        axis, sup, gap = _separating_axes(parts, xy)
        self.nx.value = axis[:, 0]
        self.ny.value = axis[:, 1]
        self.rhs.value = np.minimum(sup + MARGIN, gap)  # the current layout stays feasible
        ext = np.stack([parts.ex, parts.ey])
        size = np.array([[self.width], [self.height]])
        self.lo.value = np.minimum(ext + MARGIN, xy.T)
        self.hi.value = np.maximum(size - ext - MARGIN, xy.T)
        if self.other.size:
            d0 = xy[parts.j[self.other]] - xy[parts.i[self.other]]
            length = np.linalg.norm(d0, axis=1)[:, None]
            u = np.divide(d0, length, out=np.zeros_like(d0), where=length > 0)
            self.ux.value = u[:, 0]
            self.uy.value = u[:, 1]
        opts = CLARABEL_OPTS if self.solver == "CLARABEL" else {}
        try:
            with warnings.catch_warnings():  # "may be inaccurate": the exact check decides
                warnings.simplefilter("ignore", UserWarning)
                self.problem.solve(solver=self.solver, **opts)
        except cp.SolverError as exc:
            return None, f"solver error: {exc}"
        x, y = self.x.value, self.y.value
        # An inaccurate answer is still a candidate: the exact check decides.
        if self.problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or x is None:
            return None, str(self.problem.status)
        return np.stack([np.asarray(x), np.asarray(y)], axis=1), str(self.problem.status)


# ---------------------------------------------------------------------------------------------
# Exact acceptance test
# ---------------------------------------------------------------------------------------------


def _moved(layout: Sequence[Placement], xy: np.ndarray) -> tuple[Placement, ...]:
    return tuple(replace(p, x=float(c[0]), y=float(c[1])) for p, c in zip(layout, xy, strict=True))


def exactly_valid(layout: Sequence[Placement], width: float, height: float) -> bool:
    """True when the checker's geometry accepts the layout (every part inside the tray, no pair
    penetrating by more than ``geometry.TOL``): :func:`bilevel_kit.geometry.exactly_valid`."""
    return geometry.exactly_valid(layout, width, height)


def _tray_size(instance_or_tray: Instance | Tray | tuple[float, float]) -> tuple[float, float]:
    if isinstance(instance_or_tray, Instance):
        return instance_or_tray.tray.width, instance_or_tray.tray.height
    if isinstance(instance_or_tray, Tray):
        return instance_or_tray.width, instance_or_tray.height
    width, height = instance_or_tray
    return float(width), float(height)


# ---------------------------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------------------------


def polish(
    instance_or_tray: Instance | Tray | tuple[float, float],
    layout: Sequence[Placement],
    *,
    w6: float | None = None,
    max_rounds: int = 20,
    tol: float = 1e-6,
    solver: str = "CLARABEL",
) -> PolishResult:
    """Locally improve ``layout`` (rotations fixed) by the convex-concave procedure above.

    The returned layout keeps every part's id, type, footprint and angle, passes the checker's
    geometry, and has an exact fitness at least the input's. ``w6`` defaults to the instance's
    W6 (required with a bare tray). Stops when a round gains less than ``tol`` relative to
    ``max(1, |fitness|)`` or after ``max_rounds`` SOCPs; deterministic.
    """
    start = time.perf_counter()
    if w6 is None:
        if not isinstance(instance_or_tray, Instance):
            raise UsageError("polish: w6 is required when no instance is given")
        w6 = instance_or_tray.weights["W6"]
    if max_rounds < 0 or tol < 0:
        raise UsageError("polish: max_rounds and tol must be >= 0")
    width, height = _tray_size(instance_or_tray)
    current = tuple(layout)
    if not exactly_valid(current, width, height):
        raise UsageError("polish: the input layout overlaps or leaves the tray")
    f_cur = layout_fitness(current, w6)
    trace = [f_cur]
    if len(current) < 2:
        return PolishResult(current, f_cur, f_cur, 0, "trivial", _since(start), tuple(trace))
    parts = _Parts.build(current)
    xy = np.array([[p.x, p.y] for p in current], dtype=np.float64)
    problem = _RoundProblem(parts, width, height, solver)
    status = "max_rounds"
    rounds = 0
    while rounds < max_rounds:
        rounds += 1
        new_xy, _ = problem.solve(xy)
        if new_xy is None:
            status = "solver_failed"
            break
        cand = _moved(current, new_xy)
        if not exactly_valid(cand, width, height):
            status = "rejected"
            break
        f_new = layout_fitness(cand, w6)
        if not f_new >= f_cur:  # also catches NaN
            status = "converged"
            break
        gain = f_new - f_cur
        current, xy, f_cur = cand, new_xy, f_new
        trace.append(f_cur)
        if gain < tol * max(1.0, abs(f_cur)):
            status = "converged"
            break
    return PolishResult(current, trace[0], f_cur, rounds, status, _since(start), tuple(trace))


def _since(start: float) -> float:
    return time.perf_counter() - start


def polish_plan(
    instance: Instance,
    plan: Plan,
    w6: float | None = None,
    *,
    max_rounds: int = 20,
    tol: float = 1e-6,
    solver: str = "CLARABEL",
) -> tuple[Plan, dict[str, Any]]:
    """Polish every kit's layout of ``plan``; tasks and kit order are unchanged.

    Returns the new plan and statistics: per kit the fitness before/after, rounds, status and
    time, and the totals. Identical layouts are polished once. ``w6`` defaults to the
    instance's W6; the other options go to :func:`polish`.
    """
    start = time.perf_counter()
    w6 = float(instance.weights["W6"] if w6 is None else w6)
    done: dict[tuple[Placement, ...], PolishResult] = {}
    kits: list[Kit] = []
    per_kit: list[dict[str, Any]] = []
    for kit in plan.kits:
        key = tuple(kit.layout)
        res = done.get(key)
        if res is None:
            res = polish(instance, key, w6=w6, max_rounds=max_rounds, tol=tol, solver=solver)
            done[key] = res
        kits.append(Kit(kit.tasks, res.layout))
        per_kit.append(
            {
                "fitness_before": res.fitness_before,
                "fitness_after": res.fitness_after,
                "rounds": res.rounds,
                "status": res.status,
                "wall_time_s": res.wall_time_s,
            }
        )
    stats: dict[str, Any] = {
        "kits": per_kit,
        "fitness_before": sum(k["fitness_before"] for k in per_kit),
        "fitness_after": sum(k["fitness_after"] for k in per_kit),
        "distinct_layouts": len(done),
        "wall_time_s": _since(start),
    }
    return Plan(tuple(kits)), stats


def polish_arrangement(instance: Instance, arrangement: Arrangement, w6: float) -> Arrangement:
    """The CE arrangement with its layout polished, terms and fitness recomputed exactly and
    ``source`` tagged ``+polish`` (for ``greedy-ce --polish``). Arrangements without a valid
    layout (``fits`` false) or with fewer than two parts are returned unchanged."""
    if not arrangement.fits or len(arrangement.layout) < 2:
        return arrangement
    res = polish(instance, arrangement.layout, w6=w6)
    d_same, d_diff, z_bbox, z_exact = layout_terms(res.layout)
    fitness = -(d_same - d_diff + w6 * z_exact)
    if not math.isfinite(fitness):  # pragma: no cover - defensive
        return arrangement
    return replace(
        arrangement,
        layout=res.layout,
        d_same=d_same,
        d_diff=d_diff,
        z=z_exact,
        z_bbox=z_bbox,
        fitness=fitness,
        source=arrangement.source + "+polish",
    )
