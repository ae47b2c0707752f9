r"""Precedence bounds: one machine with heads or tails (docs/formulations.md, "Stronger lower
bounds").

The closed forms (a) and (b) of :mod:`bilevel_kit.bounds` charge the human's wait for the first
kit and the robot's work after it with the cheapest source and sink. Precedence makes both
larger. With :math:`m(S) = \max(1, \lceil \mathrm{area}(S) / (W H) \rceil)` kits at least
for a set S of tasks, :math:`a_0 = o_R + d` and w the one-tray wait
(:func:`bilevel_kit.bounds.tray_wait`):

* **head** :math:`\rho_i = r(A_i) + a_0\, m(A_i) + w\,(m(A_i) - 1)` with
  :math:`A_i = \mathrm{anc}^*(i)` (i and its ancestors, all in the kit of i or earlier): the kit of
  i cannot arrive before :math:`\rho_i`. For the tasks :math:`S_j = \{i: \rho_i \ge \rho_j\}`
  the human does all of their work and the overheads of their (at least :math:`m(S_j)`) kits
  after :math:`\rho_j`: :math:`C \ge \rho_j + h(S_j) + o_H\, m(S_j)`.
* **tail** :math:`q_i = h(\mathrm{desc}^*(i)) + o_H\, m(\mathrm{desc}^*(i))`: once the kit of i
  has arrived the human still does i, its descendants and the overheads of their kits. For
  :math:`S_j = \{i: q_i \ge q_j\}` the last of their kits arrives after the robot picked all of
  them: :math:`C \ge r(S_j) + a_0\, m(S_j) + w\,(m(S_j) - 1) + q_j`.

(a) and (b) are the cases :math:`S = V` of these. Trays only delay (every bound holds for every
T), the one-tray wait is added only with one tray. Both cost O(n log n) after the ancestor
sets.
"""

from __future__ import annotations

import math

import numpy as np

from ...bounds import tray_wait
from ...instance import Instance

#: Slack when rounding an area ratio up (as :data:`bilevel_kit.bounds._AREA_EPS`).
_AREA_EPS = 1e-9


def head_tail_bounds(instance: Instance) -> dict[str, float]:
    """The head and tail bounds of the module docstring (seconds), keyed ``head``, ``tail``."""
    ids = [t.id for t in instance.tasks]
    idx = instance.index
    n = len(ids)
    r = np.array([instance.robot_time(i) for i in ids])
    h = np.array([instance.human_time(i) for i in ids])
    area = np.array(
        [sum(instance.part_types[p].area * c for p, c in t.parts) for t in instance.tasks]
    )
    tray = instance.tray.area
    one = instance.params_of()  # one station's bound
    a0 = instance.kit_overhead_robot + one.delivery_time
    b0 = one.kit_overhead_human
    w = tray_wait(instance)
    anc = [np.array([idx[a] for a in instance.ancestors[i]], dtype=np.int64) for i in ids]
    desc_lists: list[list[int]] = [[] for _ in range(n)]
    for j, a in enumerate(anc):
        for i in a.tolist():
            desc_lists[i].append(j)
    desc = [np.array(d, dtype=np.int64) for d in desc_lists]

    def kits(a: float) -> int:
        return max(1, math.ceil(a / tray - _AREA_EPS))

    rho = np.empty(n)
    q = np.empty(n)
    for i in range(n):
        m_a = kits(area[i] + area[anc[i]].sum())
        rho[i] = r[i] + r[anc[i]].sum() + a0 * m_a + w * (m_a - 1)
        m_d = kits(area[i] + area[desc[i]].sum())
        q[i] = h[i] + h[desc[i]].sum() + b0 * m_d
    head = tail = 0.0
    h_sum = a_sum = 0.0
    for j in np.argsort(-rho, kind="stable").tolist():
        h_sum += h[j]
        a_sum += area[j]
        head = max(head, rho[j] + h_sum + b0 * kits(a_sum))
    r_sum = a_sum = 0.0
    for j in np.argsort(-q, kind="stable").tolist():
        r_sum += r[j]
        a_sum += area[j]
        m_s = kits(a_sum)
        tail = max(tail, r_sum + a0 * m_s + w * (m_s - 1) + q[j])
    return {"head": float(head), "tail": float(tail)}
