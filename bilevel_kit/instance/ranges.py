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
