"""A format-2 solution document rewritten as format 1 (``bilevel-kit-solution/1``), which
the reader still takes (docs/formats.md#solutions): the claims tables of the edge tests are
written for its keys, and a converted file must check exactly like the original."""

from __future__ import annotations

import copy
from typing import Any

from bilevel_kit.objectives import OBJECTIVES
from bilevel_kit.solution import FORMAT_1


def to_format_1(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with its ``objective`` and ``makespan`` blocks as format 1 states them: the
    makespan's ``objective``, ``bound``, ``gap``, the ``status_objective``, and the numbers of
    another objective in ``extra`` under the registry's first keys."""
    out = copy.deepcopy(doc)
    own, makespan = out.pop("objective"), out.pop("makespan")
    obj = OBJECTIVES.get(own["name"])
    head = {k: out[k] for k in ("instance", "method", "status") if k in out}
    rest = {k: v for k, v in out.items() if k not in head and k != "format"}
    extra = dict(rest.get("extra") or {})
    if obj is not None and not obj.top_level:
        extra.update(
            {
                obj.value_keys[0]: own.get("value"),
                obj.bound_keys[0]: own.get("bound"),
                obj.gap_keys[0]: own.get("gap"),
            }
        )
    timeline = {"timeline_params": rest.pop("timeline_params")} if "timeline_params" in rest else {}
    return {
        "format": FORMAT_1,
        **head,
        "status_objective": own["name"],
        **timeline,
        "objective": makespan["value"],
        "bound": makespan["bound"],
        "gap": makespan["gap"],
        **{k: v for k, v in rest.items() if k != "extra"},
        **({"extra": extra} if "extra" in rest else {}),
    }
