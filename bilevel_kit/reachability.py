"""Reachability of tray points by the Sawyer, as every packer and the checker see it.

Definition (one for the whole toolkit): a part placement is *reachable* when the cell of the
instance's reach map that contains its footprint centre is reachable, i.e. the Sawyer has a
top-down grasp there and the approach pose above it (:mod:`bilevel_kit.sawyer.reach`). The map
is built once per (work cell, tray, resolution) and cached; Pinocchio is imported only when an
instance enables reachability.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .instance import Instance
    from .plan import Placement
    from .sawyer import ReachMap, WorkCell


@dataclass(frozen=True, eq=False)
class ReachGrid:
    """Boolean cell grid ``reachable[row, col]`` over the tray, with vectorised lookup."""

    reachable: np.ndarray
    width: float
    height: float
    map: ReachMap

    @property
    def cell_size(self) -> tuple[float, float]:
        ny, nx = self.reachable.shape
        return self.width / nx, self.height / ny

    def lookup(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Reachability of points (any shape); points outside the tray are unreachable."""
        ny, nx = self.reachable.shape
        cw, ch = self.cell_size
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        inside = (x >= 0) & (x <= self.width) & (y >= 0) & (y <= self.height)
        col = np.clip((x // cw).astype(np.int64), 0, nx - 1)
        row = np.clip((y // ch).astype(np.int64), 0, ny - 1)
        return inside & self.reachable[row, col]


@lru_cache(maxsize=16)
def _grid(work_cell: WorkCell, width: float, height: float, resolution: float) -> ReachGrid:
    from .sawyer import build_reach_map

    m = build_reach_map(work_cell, width, height, resolution)
    return ReachGrid(m.reachable.copy(), width, height, m)


def reach_grid(instance: Instance) -> ReachGrid | None:
    """The instance's reach grid, or None when the instance does not enforce reachability."""
    if not instance.reachability:
        return None
    from .sawyer import DEFAULT_WORK_CELL

    work_cell = instance.work_cell or DEFAULT_WORK_CELL
    return _grid(work_cell, instance.tray.width, instance.tray.height, instance.reach_resolution)


def ensure_kit_placeable(instance: Instance, what: str = "a kit") -> None:
    """Raise a clear error when reachability is enforced and no tray cell is reachable."""
    grid = reach_grid(instance)
    if grid is not None:
        from .sawyer import ensure_placeable

        ensure_placeable(grid.map, what)


def unreachable(instance: Instance, layout: Sequence[Placement]) -> list[str]:
    """Ids of the placements whose centre lies in an unreachable cell."""
    grid = reach_grid(instance)
    if grid is None or not layout:
        return []
    ok = grid.lookup(np.array([p.x for p in layout]), np.array([p.y for p in layout]))
    return [p.part for p, good in zip(layout, ok, strict=True) if not good]
