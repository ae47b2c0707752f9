r"""The upper-level objective F of the paper (Section IV-A, Eqs. 3-7, and the W7 term of V-B).

For a partial sequence :math:`K = (K_1, \dots, K_L)` of the remaining tasks and a split
:math:`i \in 1..L` (the next kit is the prefix :math:`K_{1:i}`, the rest :math:`K_{i+1:L}` is
what the robot would kit after it):

.. math::

    F(K, i) = W_1 \sum_{j=1}^{L} \bigl(1 - \mathrm{allowed}(K_j)\bigr)          \quad (3)
            - W_2\, i                                                          \quad (4)
            + W_3 \bigl| d + R(K_{1:i}) - H_{rem} \bigr|                       \quad (5)
            + W_4 \bigl| d + R(K_{i+1:L}) - H(K_{1:i}) \bigr|                  \quad (6)
            - W_5\, f\bigl(P(K_{1:i})\bigr)                                    \quad (7)
            + W_7 \sum_{p \in P(K_{1:i})} U(p)                                 \quad (\text{V-B})

with :math:`R(S) = o_R + \sum_{j \in S} r_j` and :math:`H(S) = o_H + \sum_{j \in S} h_j` the
robot and human times of a kit (per-kit overheads included, as in the timeline of
docs/timeline.md), :math:`R(\emptyset) = 0` (Eq. 6 with :math:`i = L`: the sum is empty, d
stays), :math:`H_{rem}` the human's remaining work on the kit in hand when the robot starts the
next one, :math:`f` the kit fitness of the lower level (Eq. 11) and :math:`U(p)` the parts of
the kit the robot does not have yet.

Errata and choices (docs/errata.md):

* Terms (5) and (6) are absolute differences by default; ``signed=True`` keeps the printed
  signed form, which rewards idling.
* Precedence is hard by default: only precedence-feasible K are scored and term (3) is 0 (pass
  no ``violations``). In the penalty form every K is scored and term (3) counts, per task, a
  predecessor that is neither done nor earlier in K (:func:`precedence_violations`).

The functions are vectorised over candidates: greedy-ce
(:mod:`bilevel_kit.heuristics.greedy_ce`) scores all (K, i) of an epoch in one call, and a plan's
kits (the pairs (kit k, kit k+1), :math:`H_{rem}` from the timeline) are scored the same way.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

#: Arrays of seconds, scores or counts (float64).
FloatArray = np.ndarray


def balance_terms(
    prefix_robot: FloatArray,
    prefix_human: FloatArray,
    rest_robot: FloatArray,
    has_rest: np.ndarray,
    *,
    delivery: float,
    human_remaining: float | FloatArray,
    overhead_robot: float = 0.0,
    overhead_human: float = 0.0,
    signed: bool = False,
) -> tuple[FloatArray, FloatArray]:
    """The differences inside terms (5) and (6), for broadcastable arrays of candidates.

    ``prefix_robot``/``prefix_human``: task times summed over the next kit; ``rest_robot``:
    over the rest, used only where ``has_rest`` is true (elsewhere R of the rest is 0);
    ``human_remaining``: :math:`H_{rem}`, seconds. The per-kit overheads are added here; pass
    0 (the default) when the sums already include them. Returns ``(diff5, diff6)``, seconds,
    as absolute values unless ``signed``.
    """
    diff5 = delivery + overhead_robot + prefix_robot - human_remaining
    diff6 = (
        delivery
        + np.where(has_rest, overhead_robot + rest_robot, 0.0)
        - (overhead_human + prefix_human)
    )
    if not signed:
        diff5, diff6 = np.abs(diff5), np.abs(diff6)
    return diff5, diff6


def window_balance(
    robot: FloatArray,
    human: FloatArray,
    *,
    delivery: float,
    human_remaining: float,
    overhead_robot: float = 0.0,
    overhead_human: float = 0.0,
    signed: bool = False,
) -> tuple[FloatArray, FloatArray]:
    """Terms (5) and (6) of every split of every candidate sequence.

    ``robot``/``human``: shape (S, L), the task times of S sequences of length L. Returns
    ``(diff5, diff6)`` of shape (S, L); column ``i - 1`` is the split after ``i`` tasks.
    """
    r_cum = np.cumsum(robot, axis=1)  # R of the prefix K_{1:i} without overhead
    h_cum = np.cumsum(human, axis=1)
    r_rest = r_cum[:, -1:] - r_cum  # R of K_{i+1:L} without overhead
    length = robot.shape[1]
    has_rest = np.arange(1, length + 1) < length
    return balance_terms(
        r_cum,
        h_cum,
        r_rest,
        has_rest,
        delivery=delivery,
        human_remaining=human_remaining,
        overhead_robot=overhead_robot,
        overhead_human=overhead_human,
        signed=signed,
    )


def plan_balance(
    kit_robot: FloatArray,
    kit_human: FloatArray,
    human_remaining: FloatArray,
    *,
    delivery: float,
    signed: bool = False,
) -> tuple[FloatArray, FloatArray]:
    """Terms (5) and (6) of the consecutive kits of a plan: for kit k the rest
    :math:`K_{i+1:L}` is the plan's kit k+1 (nothing after the last kit).

    ``kit_robot``/``kit_human``: :math:`R_k`, :math:`H_k` with the overheads included, shape
    (m,); ``human_remaining[k]``: :math:`H_{rem}` when the robot starts kit k (0 for the first),
    from the timeline. Returns ``(diff5, diff6)``, shape (m,).
    """
    kit_robot = np.asarray(kit_robot, dtype=np.float64)
    m = len(kit_robot)
    return balance_terms(
        kit_robot,
        np.asarray(kit_human, dtype=np.float64),
        np.append(kit_robot[1:], 0.0),
        np.arange(m) < m - 1,
        delivery=delivery,
        human_remaining=np.asarray(human_remaining, dtype=np.float64),
        signed=signed,
    )


def objective(
    weights: Mapping[str, float],
    *,
    n_tasks: float | FloatArray,
    diff5: FloatArray,
    diff6: FloatArray,
    fitness: FloatArray,
    violations: FloatArray | None = None,
    unavailable: FloatArray | None = None,
) -> FloatArray:
    """F of Eqs. 3-7 and the W7 term (smaller is better), for broadcastable candidate arrays.

    ``n_tasks``: i, the tasks in the next kit; ``diff5``/``diff6`` from :func:`balance_terms`;
    ``fitness``: f of the next kit's layout (bigger is better); ``violations``: term (3)'s
    count (None: the hard form, term 0); ``unavailable``: the next kit's parts the robot does
    not have (None: every part is available, term 0). Weights are read by name ``W1``..``W7``.
    """
    if violations is None:
        score = -weights["W2"] * n_tasks
    else:
        score = weights["W1"] * violations - weights["W2"] * n_tasks
    score = score + weights["W3"] * diff5 + weights["W4"] * diff6 - weights["W5"] * fitness
    if unavailable is not None:
        score = score + weights["W7"] * unavailable
    return np.asarray(score, dtype=np.float64)


def precedence_violations(
    sequences: np.ndarray, done: set[int], predecessors: Sequence[frozenset[int]]
) -> FloatArray:
    """Term (3)'s count per sequence: tasks whose predecessors are not all done or earlier in
    the sequence (``sequences``: shape (S, L) of task indices)."""
    out = np.zeros(len(sequences))
    for s, seq in enumerate(sequences.tolist()):
        seen = set(done)
        for j in seq:
            out[s] += not predecessors[j] <= seen
            seen.add(j)
    return out


def unavailable_parts(counts: np.ndarray, available: np.ndarray) -> FloatArray:
    """The W7 count per kit: parts beyond what the robot has (``counts``: shape (K, T) over
    part types, ``available``: shape (T,))."""
    return np.maximum(counts - available, 0).sum(axis=1).astype(np.float64)
