"""The sane ranges of an instance's numbers and the checks the JSON Schema cannot make.

Both the parser and :meth:`~bilevel_kit.instance.Instance.with_overrides` (the CLI's
``--trays``) use them, and the pack-file reader shares :func:`check_lengths`, so they live
apart from either.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ..errors import InstanceError
from ..jsonio import ErrorType

#: Sane ranges of an instance's numbers (docs/formats.md#ranges): lengths in
#: [MIN_LENGTH, MAX_LENGTH] mm, times in [0, MAX_TIME] s, weights in [0, MAX_WEIGHT]. Outside
#: them the geometry's 1e-6 mm tolerance and the checker's time tolerance lose their meaning.
MIN_LENGTH = 0.01
MAX_LENGTH = 1e5
MAX_TIME = 1e7
MAX_WEIGHT = 1e6
#: The most tasks an instance may have once its units are built one after another: the
#: checker is measured up to 80,000 tasks (bench/bench_check.py, the 180,000-task file of
#: issue 14 checks in seconds); beyond this an input number (``units: 1e9``) would only ask
#: for memory no machine has.
MAX_TASKS = 200_000
#: The most parts one task may ask for (the checker is measured on a 30,000-part kit).
MAX_PARTS = 100_000
#: The most parts a pack file may ask for in all: pack compares the parts pairwise (3,000
#: parts: 2 s and 0.5 GB at a 5 s limit; 10,000 took 45 s and 5.2 GB; 10^7 asked for 2.4 GB
#: before any layout).
MAX_PACK_PARTS = 3_000
#: The pattern of every id (part types, tasks, pack items). ``$`` alone would let a trailing
#: newline through in Python's regular expressions; the lookahead says "the end" in both
#: Python's and JSON Schema's (ECMA-262) dialects.
ID_PATTERN = r"^[A-Za-z0-9_.:-]+$(?!\n)"
#: The pattern of a station's ``serves`` entry: a product (any name without ``@`` or a line
#: break, as a task's ``product`` may be the instance's name) or ``product@unit`` with the unit
#: a positive integer in plain digits: ``prod@``, ``prod@01`` (a second spelling of unit 1)
#: and ``prod@１`` do not name a unit (docs/formats.md#ranges).
SERVES_PATTERN = r"^[^@\n]+(@[1-9][0-9]*)?$(?!\n)"


def check_size(n_tasks: int, units: int, source: str) -> None:
    """At most :data:`MAX_TASKS` tasks over all units (an :class:`InstanceError` naming
    ``$.units`` when the units make the instance too large, else ``$.tasks``)."""
    if n_tasks * units > MAX_TASKS:
        where = "$.units" if units > 1 else "$.tasks"
        raise InstanceError(
            source,
            where,
            f"{n_tasks} task(s) x {units} unit(s) = {n_tasks * units:,} tasks, above the "
            f"limit of {MAX_TASKS:,} (docs/formats.md#ranges)",
        )


#: The most cells a reach map may have: each cell holds a joint configuration and a few numbers
#: (about 75 bytes) and costs an inverse-kinematics solve, so a million cells is ~75 MB and
#: already hours of work; a 600 x 400 mm tray at the default 10 mm is 2,400 cells.
MAX_REACH_CELLS = 1_000_000


def reach_cells(width: float, height: float, resolution: float) -> int:
    """The number of cells of a reach map (as the Sawyer's reach map builds them)."""
    nx = max(1, math.ceil(width / resolution - 1e-9))
    ny = max(1, math.ceil(height / resolution - 1e-9))
    return nx * ny


def reach_cells_problem(width: float, height: float, resolution: float) -> str | None:
    """Why a reach map of this tray at this cell size is not built (None: it is)."""
    cells = reach_cells(width, height, resolution)
    if cells <= MAX_REACH_CELLS:
        return None
    return (
        f"a reach map of {width:g} x {height:g} mm at {resolution:g} mm has {cells:,} cells, "
        f"above the limit of {MAX_REACH_CELLS:,} (use a coarser resolution)"
    )


def check_reach_cells(width: float, height: float, resolution: float, source: str) -> None:
    """An :class:`InstanceError` at ``$.reach_resolution`` when the map would be too large."""
    why = reach_cells_problem(width, height, resolution)
    if why is not None:
        raise InstanceError(source, "$.reach_resolution", why)


def check_lengths(
    obj: Mapping[str, Any],
    where: str,
    source: str,
    keys: tuple[str, ...] = ("width", "height"),
    error: ErrorType = InstanceError,
) -> None:
    """The lengths ``keys`` of ``obj`` at least :data:`MIN_LENGTH` mm: far below it, a part is
    smaller than the geometry's tolerance and overlaps are measured in rounding noise."""
    for key in keys:
        if key in obj and obj[key] < MIN_LENGTH:
            raise error(
                source,
                f"{where}.{key}",
                f"{obj[key]:g} mm is below the smallest length {MIN_LENGTH:g} mm (docs/formats.md)",
            )


def parse_trays(value: Any, source: str = "<memory>") -> int | None:
    """A tray count: an integer >= 1, or ``None``/``"unlimited"``/``"none"`` for no limit."""
    if value is None or (isinstance(value, str) and value.lower() in ("unlimited", "none")):
        return None
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise InstanceError(
                source, "$.trays", f"must be an integer >= 1 or unlimited, got {value!r}"
            ) from None
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not math.isfinite(value)
        or value != int(value)
        or value < 1
    ):
        raise InstanceError(
            source, "$.trays", f"must be an integer >= 1 or unlimited, got {value!r}"
        )
    return int(value)
