r"""A plan as the large-neighbourhood search holds it, and what a window of it sees.

Kits are lists of task indices (file order of the instance) in the human's order; times are the
integer times of :mod:`bilevel_kit.models.cpsat.scaling`. A *window* is a run of consecutive
kits ``[k0, k1)``; the kits before it are its prefix and fix the state it starts from (when
the robot is free, when the human is free, the human starts of the last T kits), the kits after
it its suffix.

**The suffix as a function of the window's end** (:func:`tail_response`). The timeline of
docs/timeline.md is max-plus linear in its start: every time of a suffix kit is a maximum of
(a variable of the window's end state + a constant). The end state is the window's last arrival
``A``, its human end ``E`` and, with T trays, the human starts ``HS_1 .. HS_T`` of its last T
kits (``HS_1`` the last). Propagating the suffix's kits symbolically (max and + on those
forms) gives the makespan as :math:`C = \max_v (v + c_v)`, exact, in O(suffix x T). It and
:func:`window_edge` are held to :func:`bilevel_kit.plan.evaluate` by property tests
(docs/timeline.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..cpsat.scaling import Scaled, clock_after

#: A max-plus linear form: state variable -> constant (the form is max_v (v + c_v)).
Form = dict[str, int]


def _shift(form: Form, c: int) -> Form:
    return {k: v + c for k, v in form.items()}


def _max(a: Form, b: Form) -> Form:
    out = dict(a)
    for k, v in b.items():
        out[k] = max(out.get(k, v), v)
    return out


def kit_times(sc: Scaled, kit: Sequence[int]) -> tuple[int, int]:
    """The scaled robot and human times of a used kit (overheads included)."""
    return sc.o_r + sum(sc.r[i] for i in kit), sc.o_h + sum(sc.h[i] for i in kit)


def tail_response(sc: Scaled, suffix: Sequence[Sequence[int]], first: int) -> Form:
    """The makespan as a max-plus form of the window's end state (module docstring): keys
    ``A``, ``E`` and ``HS1`` .. ``HST`` (``HS1`` the last window kit's human start);
    ``first`` is the position of the suffix's first kit in the plan (the tray rule binds from
    position T on)."""
    if not suffix:
        return {"E": 0}
    trays = sc.trays
    arrive: Form = {"A": 0}
    end: Form = {"E": 0}
    starts: list[Form] = [] if trays is None else [{f"HS{j}": 0} for j in range(trays, 0, -1)]
    for k, kit in enumerate(suffix, start=first):
        r, h = kit_times(sc, kit)
        start = arrive
        if trays is not None and k >= trays:
            start = _max(start, _shift(starts[-trays], sc.o_h))
        arrive = _shift(start, r + sc.d)
        hs = _max(arrive, end)
        end = _shift(hs, h)
        starts.append(hs)
    return end


@dataclass(frozen=True)
class Edge:
    """The state a window starts from: the previous arrival ``arrive`` and human end ``end``
    (0 before the first kit) and the human starts of the kits before it (oldest first)."""

    arrive: int
    end: int
    starts: tuple[int, ...]


def window_edge(sc: Scaled, kits: Sequence[Sequence[int]], k0: int) -> Edge:
    """The :class:`Edge` of a window starting at kit ``k0`` of ``kits`` (one station): the
    :class:`~..cpsat.scaling.Clock` after the kits before it."""
    clock = clock_after(sc, kits[:k0])
    starts = tuple(clock.starts[0]) if sc.trays is not None else ()
    return Edge(clock.arrive, clock.done[0], starts)
