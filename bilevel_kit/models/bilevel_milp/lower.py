"""The lower level: the best known fitness and layout of a kit's part multiset (package
docstring, "The lower level"), memoised."""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ...errors import UsageError
from ...fitness import layout_fitness as layout_fitness_value
from ...instance import Instance
from ...plan import Kit, Placement
from .. import packing, packing_oracle

LOWER_MODES = ("ce", "best")

Multiset = tuple[tuple[str, int], ...]


@dataclass(frozen=True)
class KitValue:
    """The lower level's answer for one part multiset: ``fits`` (some valid layout is known),
    the best ``fitness`` (``-inf`` if none), its ``layout`` (part ids ``type-j``) and where it
    came from (``ce``, ``cpsat`` or ``oracle``); without a layout, ``proof`` is the scope of
    the oracle's proof that none exists (:mod:`..packing_oracle`), None when it is not proven.
    """

    fits: bool
    fitness: float
    layout: tuple[Placement, ...]
    source: str
    proof: str | None = None


class LowerLevel:
    """Kit values f(multiset), each computed once (package docstring, "The lower level").

    ``lower="ce"``: CE and the oracle's layout; ``"best"``: also the CP-SAT packing fitness
    objective with ``pack_time_limit`` seconds per multiset. Call it on a :class:`Kit` to use
    it as ``fitness_of``.
    """

    def __init__(
        self,
        instance: Instance,
        *,
        seed: int = 0,
        lower: str = "best",
        pack_time_limit: float = 0.5,
        ce_params: Any = None,
    ) -> None:
        from ...heuristics.greedy_ce import GreedyCEPolicy, GreedyParams
        from ...reachability import reach_grid

        if lower not in LOWER_MODES:
            raise UsageError(f"lower must be one of {', '.join(LOWER_MODES)}, not {lower!r}")
        self.instance = instance
        self.lower = lower
        self.pack_time_limit = float(pack_time_limit)
        params = GreedyParams() if ce_params is None else GreedyParams(ce=ce_params)
        self._policy = GreedyCEPolicy(instance, params, seed)
        self._reach = reach_grid(instance)
        self._values: dict[Multiset, KitValue] = {}
        self.time_s = 0.0
        #: values computed with a packing limit cut by :attr:`deadline` (machine-speed dependent)
        self.n_cut = 0
        #: perf_counter time after which packing calls get only what is left (None: no end);
        #: a value computed with a cut packing limit is not memoised
        self.deadline: float | None = None

    def _limit(self, limit: float) -> tuple[float, bool]:
        """``limit`` cut to the time left before :attr:`deadline`; and whether it was cut."""
        if self.deadline is None:
            return limit, False
        left = max(0.02, self.deadline - time.perf_counter())
        return min(limit, left), left < limit

    @staticmethod
    def key(counts: Mapping[str, int]) -> Multiset:
        return tuple(sorted((t, int(n)) for t, n in counts.items() if n))

    def value(self, counts: Mapping[str, int]) -> KitValue:
        key = self.key(counts)
        hit = self._values.get(key)
        if hit is not None:
            return hit
        t0 = time.perf_counter()
        inst = self.instance
        w6 = inst.weights["W6"]
        cands: list[tuple[float, tuple[Placement, ...], str]] = []
        arr = self._policy.arrangement(dict(key))
        if arr.fits:
            cands.append((arr.fitness, arr.layout, "ce"))
        fit_tl, cut = self._limit(2.0)
        verdict = packing_oracle.fit_verdict(
            inst.tray, inst.part_types, dict(key), time_limit=fit_tl, reach=self._reach
        )
        typed = verdict.layout
        if verdict.fits and typed is not None:
            layout = tuple(
                Placement(
                    f"{t}-{j + 1}", t, x, y, th, inst.part_types[t].width, inst.part_types[t].height
                )
                for t, slots in sorted(typed.items())
                for j, (x, y, th) in enumerate(slots)
            )
            cands.append((layout_fitness_value(layout, w6), layout, "oracle"))
            if self.lower == "best" and len(layout) > 1:
                items = [(p.part, inst.part_types[p.type]) for p in layout]
                pack_tl, cut_pack = self._limit(self.pack_time_limit)
                cut = cut or cut_pack
                res = packing.pack(
                    inst.tray,
                    items,
                    objective="fitness",
                    time_limit=pack_tl,
                    workers=1,
                    w6=w6,
                    reach=self._reach,
                )
                if res.layout is not None and res.true_fitness is not None:
                    cands.append((res.true_fitness, res.layout, "cpsat"))
        if cands:
            fit, layout, src = max(cands, key=lambda c: c[0])
            val = KitValue(True, float(fit), layout, src)
        else:
            val = KitValue(False, float("-inf"), (), "none", verdict.scope)
        if not cut:
            self._values[key] = val
        else:
            self.n_cut += 1
        self.time_s += time.perf_counter() - t0
        return val

    def __call__(self, kit: Kit) -> float:
        return self.value(self.instance.kit_parts(kit.tasks)).fitness

    @property
    def n_values(self) -> int:
        return len(self._values)
