"""Does a kit fit the tray, fast: the large-neighbourhood search asks this for many kits.

The shelf packer (:func:`bilevel_kit.heuristics.shelf.shelf_pack`) is tried first: a layout it
finds is valid (the checker accepts it), so the kit fits. Only when it finds none is the exact
packing oracle asked (:class:`..common.Packer`: its pre-search tests, then CP-SAT); an answer
it does not reach within its limit counts as "does not fit" (the windows ask with a
deterministic limit, :mod:`.window`, so their verdicts do not depend on the machine load).
With a reach map the shelf packer does not apply (it ignores reachability) and the oracle
decides. Answers and layouts are memoised by part multiset.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from ...instance import Instance
from ...plan import Placement
from .. import packing, packing_oracle
from ..common import Packer


class FastFit:
    """The memoised fit test and layouts of one run (module docstring)."""

    def __init__(self, instance: Instance, packer: Packer) -> None:
        self.instance = instance
        self.packer = packer
        self._fits: dict[frozenset[tuple[str, int]], bool | None] = {}
        self._area = {p.id: p.area for p in instance.part_types.values()}

    def counts(
        self,
        counts: Mapping[str, int],
        limit: float | None = None,
        oracle: bool = True,
        deterministic: bool | None = None,
    ) -> bool | None:
        """Whether the part multiset fits (None: not decided: the oracle did not decide in
        ``limit`` s, or was not asked, ``oracle`` False, after the shelf packer failed);
        ``deterministic``: the oracle's limit is deterministic (:class:`..common.Packer`)."""
        counts = {t: c for t, c in counts.items() if c}
        key = frozenset(counts.items())
        if key in self._fits:
            return self._fits[key]
        inst = self.instance
        verdict: bool | None
        if sum(self._area[t] * c for t, c in counts.items()) > inst.tray.area * (1 + 1e-12):
            verdict = False
        elif self.packer.reach is None and self._shelf(counts) is not None:
            verdict = True
        elif not oracle:
            return None
        else:
            verdict = self.packer.counts(counts, limit, deterministic)[0]
        if verdict is not None:
            self._fits[key] = verdict
        return verdict

    def fits(self, tasks: Sequence[str], limit: float | None = None, oracle: bool = True) -> bool:
        return self.counts(self.instance.kit_parts(tasks), limit, oracle) is True

    def _shelf(self, counts: Mapping[str, int]) -> tuple[Placement, ...] | None:
        """The shelf packer on the packing grid (sizes rounded up, the tray down), as the
        oracle runs it first: a layout there is one the oracle accepts too."""
        from ...heuristics.shelf import kit_items, shelf_pack
        from ...instance import PartType, Tray

        res = self.packer.res
        tray = self.instance.tray
        items = [
            (
                pid,
                PartType(
                    id=pid,
                    width=float(packing.grid_up(pt.width, res)),
                    height=float(packing.grid_up(pt.height, res)),
                    pick_time=0.0,
                    rotatable=pt.rotatable,
                ),
            )
            for pid, pt in kit_items(self.instance.part_types, counts)
        ]
        grid = Tray(
            float(packing.grid_down(tray.width, res)), float(packing.grid_down(tray.height, res))
        )
        return shelf_pack(grid, items)

    def layout(self, tasks: Sequence[str]) -> tuple[Placement, ...] | None:
        """A valid layout of the kit: the shelf packer's, else the oracle's (None if neither
        has one)."""
        from ...heuristics.shelf import shelf_pack

        inst = self.instance
        if self.packer.reach is None:
            items = [
                (f"{t}:{p}:{j}", inst.part_types[p])
                for t in tasks
                for p, n in inst.task_by_id[t].parts
                for j in range(1, n + 1)
            ]
            placed = shelf_pack(inst.tray, items)
            if placed is not None:
                return placed
        ok, typed = self.packer.counts(inst.kit_parts(tasks))
        if ok and typed is not None:
            return packing_oracle.typed_to_placements(inst, tasks, typed)
        return None
