r"""Exact optimum of the paper's own objective on small instances (registered ``bilevel-milp``).

The greedy of :mod:`bilevel_kit.heuristics.greedy_ce` scores one kit at a time with the paper's
F (Eqs. 3-7) over a rolling window. This module turns F into a **whole-plan objective** and
minimises it exactly over all plans, by enumerating the kits (columns) and solving one
set-partitioning + sequencing MILP, so that the greedy's gap on its own objective (not only on
makespan) can be measured.

**The paper's objective of a plan** (:func:`paper_objective`). For kits k = 1..m in delivery
order with the section-2 timeline (R_k, H_k include the per-kit overheads):

.. math::

    J = \sum_{k=1}^{m} \Bigl[ -W_2 |S_k|
        + W_3 \bigl| d + R_k - B_{k-1} \bigr|
        + W_4 \bigl| d + R_{k+1} - H_k \bigr|
        - W_5 f(S_k) \Bigr]

* term (4) ``-W2 |S_k|``: the number of tasks in the kit (it sums to the constant -W2 n);
* term (5): :math:`B_{k-1}` = the human's remaining work on kit k-1 when the robot starts kit k,
  :math:`B_{k-1} = \mathrm{human\_end}_{k-1} - \mathrm{arrive}_{k-1}` (:math:`B_0 = 0`), the
  greedy's ``H_rem``;
* term (6): the greedy's window remainder :math:`K_{i+1:L}` is replaced by the plan's own next
  kit, :math:`R_{m+1} = 0` (as the greedy does when its window ends, d stays);
* term (7): :math:`f(S_k)` = the kit's fitness, given by ``fitness_of`` (a function of the kit);
* term (3) is 0 (precedence is hard) and the W7 term is 0 (offline: every part is available).

Absolute values as in docs/errata.md (``signed=True``: the printed signed form). Every plan,
in particular greedy-ce's, has a well-defined J, and :func:`paper_objective` is the one function
that computes it. (The greedy's own objective in its ``extra``, the sum of its per-epoch window
scores, differs in term 6, which there looks at a hypothetical window, not at the kit that
really came next.)

**The lower level** (:class:`LowerLevel`). f is a function of the kit's part multiset:
the best (largest) true Euclidean fitness among the valid layouts found by (i) the
cross-entropy arrangement exactly as greedy-ce computes it (same CE parameters, same seed
derived from the run's seed and the multiset), (ii) the CP-SAT packing ``fitness`` objective
(L1 surrogate, its layout's Euclidean fitness; ``lower="best"``) and (iii) the packing
oracle's feasibility layout. So for any kit, f >= the fitness greedy-ce's own layout has, and
with the same seed and CE parameters the optimum J* below is <= J of greedy-ce's plan under both
f and greedy's own layouts. The lower level itself is a non-convex continuous problem: "exact"
here means exact for the upper level given these kit values.

**Columns.** A kit must be *convex* in the precedence order (if a, c are in the kit and
a -> b -> c then b is too: b's kit lies between theirs), and must fit the tray. Convex sets are
enumerated by growth from singletons (every convex set arises from a smaller one by adding a
maximal element), pruned by the exact area bound (total part area <= tray area, necessary for
any layout); a kit is a column when its multiset fits (oracle "fits" or a valid CE layout).
A candidate left out without a proof that holds at any angle (the oracle's proof may hold for
0/90-degree layouts only, or be missing: docs/formulations.md#what-optimal-means) could be a
column of a plan at other angles, so the status is then at most "feasible".

**MILP.** Positions k = 0..K-1 (K = n), ``z[c,k]`` = column c is kit k, only where possible
(:math:`k \ge 1` if c has ancestors outside it; :math:`k \le n - |c| - |\mathrm{desc}(c)
\setminus c|`). With :math:`X_{ik} = \sum_{c \ni i} z_{ck}`, :math:`u_k = \sum_c z_{ck}`:

* partition :math:`\sum_k X_{ik} = 1`; :math:`u_k \le 1`, :math:`u_{k+1} \le u_k`;
* precedence (transitive reduction) :math:`\sum_{q \le k} X_{bq} \le \sum_{q \le k} X_{aq}`;
* interchangeable chains in lexicographic order (as in :mod:`bilevel_kit.models.milp`);
* :math:`R_k = \sum_c R_c z_{ck}`, :math:`H_k = \sum_c H_c z_{ck}`; term 5 exactly, with its
  positive and negative parts :math:`g_k = p_k - q_k = d u_k + R_k - B_{k-1}` (relaxed by
  :math:`M(1-u_k)` on unused positions, :math:`p_k + q_k \le M u_k`), complementarity by one
  binary :math:`s_k` (:math:`p_k \le M s_k`, :math:`q_k \le M(1-s_k)`), and the recursion
  :math:`B_k = q_k + H_k` (= :math:`\max(0, B_{k-1} - R_k - d) + H_k`, the timeline);
* term 6 likewise: :math:`p'_k - q'_k = d u_k + R_{k+1} - H_k` (0 on unused positions);
* minimise :math:`\sum_{c,k} (-W_2 |c| - W_5 f_c) z_{ck} + \sum_k W_3 (p_k + q_k)
  + W_4 (p'_k + q'_k)`.

**Trays.** With T trays the robot starts kit k at :math:`A_{k-1} + w_k` with the tray wait
:math:`w_k = \max(0, \mathrm{hs}_{k-T} + o_H - A_{k-1})` (docs/timeline.md), so
:math:`B_{k-1} = q_{k-1} + H_{k-1} - w_k` (the same backlog :func:`paper_terms` reads off the
evaluator's timeline). With one tray the human has started kit k - 1 when it arrived, so
:math:`w_k = q_{k-1} + o_H` and :math:`B_{k-1} = H_{k-1} - o_H`: linear, no new variable.
With T >= 2, :math:`y_k = q_{k-T} + o_H - \sum_{k-T < j < k} (w_j + R_j + d)` (the human start
of kit k - T is its arrival plus its wait :math:`q`) and :math:`w_k - v_k = y_k` with
complementarity by one binary, the big-M being the no-overlap horizon
:math:`\sum_i (r_i + h_i) + n (o_R + o_H + d)` that bounds every time of the timeline.

The big-M :math:`M = d + o_R + \sum r + n\,o_H + \sum h` bounds every |g| and B (derived from
the data). The exact complementarity makes J exact for any sign of the weights. A MIP start
is greedy-ce's plan (same seed and CE parameters) improved by :func:`local_search`.

**Size limit.** At most :data:`MAX_TASKS` tasks and :data:`MAX_COLUMNS` candidate kits
(convex and within the tray area, before the fit test); beyond either the method raises a
UsageError (both are parameters). The 12-task table has 2,400 convex kits (7^4 - 1: per leg
chain an interval or nothing), all of which fit its tray, 104 distinct multisets and about
9,800 binaries; HiGHS proves its optimum in about 100-250 s on a busy 2-core machine (the LP
relaxation is weak: root bound about 132 against J* = 195.6, so branching does the work).
Random instances of up to 6 tasks solve in well under a second.

**Result.** ``status`` refers to J: optimal (proven over every kit that fits, each left-out
candidate proven not to fit at any angle) / feasible / infeasible (a task whose own kit
provably fits at no angle) / unknown.
``bound`` is the closed-form *makespan* bound (the method does not minimise makespan).
``extra`` keys:

* ``objective_value`` (J of the plan, by :func:`paper_objective`), ``objective_bound`` (the
  MILP's bound on J*), ``objective_gap`` (``|J - bound| / max(1, |J|)``): the result's
  ``objective``, ``bound`` and ``gap`` (:func:`bilevel_kit.methods.solve`); and
  ``plan_objective_J_milp`` (J as the MILP computed it), ``makespan`` (of the plan),
  ``optimal_over_columns`` (the MILP proved J optimal over its columns);
* ``excluded_axis_aligned``, ``excluded_unproven``: candidates left out on a proof for
  0/90-degree layouts only, or without a proof; ``status_reason`` when they cost the status;
* ``solver``, ``lower``, ``candidates`` (convex kits within the tray area), ``columns`` (those
  that fit), ``multisets`` (kit values computed), ``binaries``, ``termination``;
* ``start_objective`` and ``local_search_objective``: J of the warm-start plan before and
  after :func:`local_search`, ``local_search_converged``: whether it reached a local optimum
  within its share of the time (only with a warm start; if not, the start and so the MILP's
  choice among plans of equal J depend on the machine's speed);
* ``incumbent``: ``milp`` (the MILP's solution) or ``warm start`` (the solver stopped without
  returning one, e.g. killed past the time limit: the local-search plan it was started from);
* ``lower_level_cut``: kit values computed with a packing limit cut short by the deadline
  (their layouts depend on the machine's speed; not memoised);
* ``lower_level_s``, ``milp_s``, ``wall_time_s``: seconds spent;
* ``reason`` when the run ends without a plan for a known reason.

**Time.** ``time_limit`` (default 60 s) covers the kit values, the local search (a tenth of
what is left) and the MILP, with 0.2 s kept back for the final plan. The kit values' packing
calls get at most :data:`LOWER_SHARE` of the time: past it the remaining values are computed
with cut packing limits (``lower_level_cut`` counts them), so the MILP always has time to load
its warm start (on the paper's table the full lower level takes about 55 s of a 60 s limit).

**Modules.** :mod:`.objective` (J), :mod:`.lower` (the kit values), :mod:`.columns` (the
enumeration), :mod:`.warm_start` (the MIP start), :mod:`.model` (the MILP) and :mod:`.method`
(the registered method); this package re-exports their public names.
"""

from __future__ import annotations

from .columns import LOWER_SHARE, MAX_COLUMNS, Column, build_columns, enumerate_kits
from .lower import LOWER_MODES, KitValue, LowerLevel, Multiset
from .method import MARGIN, MAX_TASKS, BilevelMilpOptions, bilevel_milp, run, solve
from .objective import FitnessOf, layout_fitness, paper_objective, paper_terms
from .warm_start import local_search

__all__ = [
    "LOWER_MODES",
    "LOWER_SHARE",
    "MARGIN",
    "MAX_COLUMNS",
    "MAX_TASKS",
    "BilevelMilpOptions",
    "Column",
    "FitnessOf",
    "KitValue",
    "LowerLevel",
    "Multiset",
    "bilevel_milp",
    "build_columns",
    "enumerate_kits",
    "layout_fitness",
    "local_search",
    "paper_objective",
    "paper_terms",
    "run",
    "solve",
]
