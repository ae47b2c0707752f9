"""The robot's reach map seen from the packing grid (docs/formulations.md#cp-sat-packing):
which half-grid centres lie in a reachable cell, as CP-SAT constraints for the packing model
(:mod:`.packing`) and the embedded tray of :mod:`.cpsat.tray`, and as a check of given corners.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..reachability import ReachGrid


@dataclass(frozen=True)
class ReachTables:
    """The instance's reach map seen from the half grid: a part centred at ``k * res / 2`` mm
    (k integer) lies in cell column ``cols[k]`` (row ``rows[k]`` for y); ``cells`` are the
    reachable (column, row) pairs. Same arithmetic as :meth:`ReachGrid.lookup`, and layouts
    put centres exactly at ``k * res / 2``, so the model and the checker agree bit for bit."""

    cols: tuple[int, ...]
    rows: tuple[int, ...]
    cells: tuple[tuple[int, int], ...]
    n_cols: int
    n_rows: int
    #: when a cell is exactly ``step`` half-grid units wide (``cols[k] == k // step`` for every
    #: centre k < 2W), the column is linear in k: cheaper than an element constraint
    step_x: int | None = None
    step_y: int | None = None
    #: per row, the reachable columns as one span (lo, hi) (lo > hi: none), when every row's
    #: reachable cells are contiguous: two small element constraints replace the cell table
    row_spans: tuple[tuple[int, int], ...] | None = None


def reach_tables(reach: ReachGrid, W: int, H: int, resolution: float) -> ReachTables:
    """Tables of a :class:`bilevel_kit.reachability.ReachGrid` for a W x H grid tray."""
    import numpy as np

    ny, nx = reach.reachable.shape
    cw, ch = reach.cell_size
    xs = np.arange(2 * W + 1) * resolution / 2.0
    ys = np.arange(2 * H + 1) * resolution / 2.0
    cols = np.clip((xs // cw).astype(np.int64), 0, nx - 1)
    rows = np.clip((ys // ch).astype(np.int64), 0, ny - 1)
    cells = tuple((int(c), int(r)) for r, c in zip(*np.nonzero(reach.reachable), strict=True))

    def step(index: np.ndarray, size: float) -> int | None:
        q = round(2 * size / resolution)
        k = np.arange(len(index) - 1)
        return q if q >= 1 and bool((index[:-1] == k // q).all()) else None

    rows_spans: list[tuple[int, int]] = []
    spans: list[tuple[int, int]] | None = rows_spans
    for r in range(ny):
        cs = np.nonzero(reach.reachable[r])[0]
        if len(cs) == 0:
            rows_spans.append((nx, -1))
        elif cs[-1] - cs[0] + 1 == len(cs):
            rows_spans.append((int(cs[0]), int(cs[-1])))
        else:
            spans = None  # a row with a hole: no span encoding
            break
    return ReachTables(
        tuple(map(int, cols)),
        tuple(map(int, rows)),
        cells,
        nx,
        ny,
        step(cols, cw),
        step(rows, ch),
        None if spans is None else tuple(spans),
    )


def add_reach(
    model: Any,
    tables: ReachTables,
    cx2: Any,
    cy2: Any,
    W: int,
    H: int,
    present: Any = None,
    absent_at: tuple[int, int] = (0, 0),
) -> None:
    """Centre (cx2 / 2, cy2 / 2 grid units) in a reachable cell. With ``present``: only when
    present; an absent part sits at the fixed doubled centre ``absent_at``."""
    kx = model.new_int_var(0, 2 * W, "")
    ky = model.new_int_var(0, 2 * H, "")
    model.add(kx == cx2)
    model.add(ky == cy2)
    col = model.new_int_var(0, tables.n_cols - 1, "")
    row = model.new_int_var(0, tables.n_rows - 1, "")
    for k, index, cell, q in (
        (kx, tables.cols, col, tables.step_x),
        (ky, tables.rows, row, tables.step_y),
    ):
        if q is None:
            model.add_element(k, index, cell)
        else:  # centres never reach k = 2W (parts have a positive size)
            model.add(k <= 2 * (W if k is kx else H) - 1)
            model.add(q * cell <= k)
            model.add(k <= q * cell + q - 1)
    if tables.row_spans is not None:
        lo = model.new_int_var(0, tables.n_cols, "")
        hi = model.new_int_var(-1, tables.n_cols - 1, "")
        model.add_element(row, [a for a, _ in tables.row_spans], lo)
        model.add_element(row, [b for _, b in tables.row_spans], hi)
        enforce = [] if present is None else [present]
        model.add(lo <= col).only_enforce_if(enforce)
        model.add(col <= hi).only_enforce_if(enforce)
    elif present is None:
        model.add_allowed_assignments([col, row], tables.cells)
    else:
        parked = (0, tables.cols[absent_at[0]], tables.rows[absent_at[1]])
        model.add_allowed_assignments(
            [present, col, row], [(1, *cell) for cell in tables.cells] + [parked]
        )


def corners_reachable(
    tables: ReachTables | None,
    corners_: Sequence[tuple[int, int, bool]],
    sizes: Sequence[tuple[int, int, bool]],
) -> bool:
    """Are the centres of these grid corners (x, y, rotated) of parts of these grid ``sizes``
    all in reachable cells (always, without ``tables``)?"""
    if tables is None:
        return True
    ok = set(tables.cells)
    for (x, y, rot), (w, h, _) in zip(corners_, sizes, strict=True):
        ww, hh = (h, w) if rot else (w, h)
        if (tables.cols[2 * x + ww], tables.rows[2 * y + hh]) not in ok:
            return False
    return True
