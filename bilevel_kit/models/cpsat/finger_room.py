"""``cpsat``'s option ``finger_room``: the trays packed with room for the station gripper's open
fingers, as greedy-ce's option of the same name (docs/execution.md#finger-room).

The whole run (warm start, model, packing oracle, embedded tray) sees every part type as its
**grasp footprint** (:func:`bilevel_kit.sawyer.gripper.grasp_footprint`), so each packed
rectangle holds the part and its open fingers; the plan then keeps the centres and angles
with the parts' true sizes. Footprints that lie within the tray and do not overlap keep every
pad within the tray and off every other part, so the plan passes ``execute --grasp-check
strict`` by construction. The status and bound are those of the problem with the footprints
(the one asked for); the part sizes do not enter the schedule's times.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ...instance import Instance
    from ...methods import MethodOutput


def with_room(
    method: Callable[..., MethodOutput], instance: Instance, options: Any, **kw: Any
) -> MethodOutput:
    """``method(instance, options, **kw)`` run on the instance's grasp footprints (with
    ``options.finger_room`` off), its plan given back the parts' true sizes; ``extra``
    records the footprints packed (``finger_room``: part type -> [w, h] mm)."""
    from ...sawyer.gripper import true_sizes, with_finger_room

    grown = with_finger_room(instance)  # exit 2 naming a part type whose room exceeds the tray
    out = method(grown, replace(options, finger_room=False), **kw)
    plan = None if out.plan is None else true_sizes(out.plan, instance)
    footprints = {name: [pt.width, pt.height] for name, pt in grown.part_types.items()}
    return replace(out, plan=plan, extra={**out.extra, "finger_room": footprints})
