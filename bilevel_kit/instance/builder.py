"""Build an instance in Python: part types, tasks, precedence and stations, without JSON.

:class:`InstanceBuilder` collects the same fields as the instance format (docs/formats.md)
and hands the document it wrote to the parser, so a mistake gets the very message the JSON
file would get, naming the field by its JSON path (``$.tasks[2].parts[0].type``), and the
document round-trips: :meth:`InstanceBuilder.document` is a ``bilevel-kit/1`` document,
:meth:`InstanceBuilder.save` writes it, and :func:`bilevel_kit.instance.load` reads the file
back into an equal instance (docs/formats.md#building-an-instance-in-python).

>>> from bilevel_kit.instance import InstanceBuilder
>>> b = InstanceBuilder("stool", tray=(300, 200), delivery_time=2, kit_overhead=(3, 1))
>>> b = b.part_type("leg", 200, 30, pick_time=4).part_type("seat", 180, 180, pick_time=6)
>>> b = b.task("legs", {"leg": 3}, human_time=30).task("seat", {"seat": 1}, human_time=20)
>>> inst = b.precede("legs", "seat").build()
>>> inst.n_tasks, inst.precedence
(2, (('legs', 'seat'),))
"""

from __future__ import annotations

import copy
import itertools
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .model import FORMAT, Instance
from .parser import from_dict


class InstanceBuilder:
    """An instance document built by calls (docs/formats.md for every field's meaning).

    ``tray``: (width, height) in mm; ``delivery_time`` and ``kit_overhead`` (robot, human) in
    s; ``trays``: trays in circulation (None: unlimited); ``fields``: any other top-level
    field of the format (``units``, ``weights``, ``horizon``, ``description`` ...). Each
    method returns the builder, so calls chain; nothing is checked until :meth:`build`.
    """

    def __init__(
        self,
        name: str,
        *,
        tray: tuple[float, float],
        delivery_time: float = 0.0,
        kit_overhead: tuple[float, float] = (0.0, 0.0),
        trays: int | None = None,
        **fields: Any,
    ) -> None:
        self._doc: dict[str, Any] = {
            "format": FORMAT,
            "name": name,
            "tray": {"width": tray[0], "height": tray[1]},
            "delivery_time": delivery_time,
            "kit_overhead": {"robot": kit_overhead[0], "human": kit_overhead[1]},
            "part_types": [],
            "tasks": [],
            "precedence": [],
            **({"trays": trays} if trays is not None else {}),
            **fields,
        }

    def part_type(
        self,
        id: str,
        width: float,
        height: float,
        *,
        pick_time: float,
        rotatable: bool = True,
        name: str | None = None,
    ) -> InstanceBuilder:
        """A part type: footprint ``width`` x ``height`` (mm) at 0°, ``pick_time`` (s)."""
        entry: dict[str, Any] = {"id": id, "width": width, "height": height}
        entry.update(pick_time=pick_time, rotatable=rotatable)
        self._doc["part_types"].append({**entry, **({"name": name} if name else {})})
        return self

    def task(
        self,
        id: str,
        parts: Mapping[str, int] | None = None,
        *,
        human_time: float,
        human_sd: float | None = None,
        robot_time: float | None = None,
        name: str | None = None,
        station: str | None = None,
        product: str | None = None,
    ) -> InstanceBuilder:
        """A task needing ``parts`` (part type -> count; none: a part-less task,
        docs/timeline.md#part-less-tasks) and ``human_time`` (s, its mean)."""
        entry: dict[str, Any] = {"id": id}
        optional = {"name": name, "product": product, "station": station}
        entry.update({k: v for k, v in optional.items() if v is not None})
        entry["parts"] = [{"type": t, "count": n} for t, n in (parts or {}).items()]
        entry["human_time"] = {"mean": human_time, **({"sd": human_sd} if human_sd else {})}
        if robot_time is not None:
            entry["robot_time"] = robot_time
        self._doc["tasks"].append(entry)
        return self

    def precede(self, *chain: str) -> InstanceBuilder:
        """Precedence along ``chain``: ``precede("a", "b", "c")`` adds a -> b and b -> c."""
        self._doc["precedence"] += [[a, b] for a, b in itertools.pairwise(chain)]
        return self

    def station(
        self,
        id: str,
        *,
        serves: tuple[str, ...] = (),
        delivery_time: float | None = None,
        trays: int | None = None,
        kit_overhead_human: float | None = None,
    ) -> InstanceBuilder:
        """An assembly station served by the robot (docs/timeline.md#several-stations)."""
        optional = {
            "delivery_time": delivery_time,
            "trays": trays,
            "kit_overhead_human": kit_overhead_human,
        }
        entry = {"id": id, **{k: v for k, v in optional.items() if v is not None}}
        if serves:
            entry["serves"] = list(serves)
        self._doc.setdefault("stations", []).append(entry)
        return self

    def work_cell(self, **keys: Any) -> InstanceBuilder:
        """The Sawyer work cell's geometry, the ``work_cell`` section (docs/formats.md): the
        keys given (``tray_pose``, ``bins``, ``gripper`` ...) over those set before. Not an
        assembly station: that is :meth:`station`."""
        self._doc["work_cell"] = {**self._doc.get("work_cell", {}), **keys}
        return self

    def document(self) -> dict[str, Any]:
        """The ``bilevel-kit/1`` document built so far (a copy)."""
        return copy.deepcopy(self._doc)

    def build(self, source: str | None = None) -> Instance:
        """The instance, validated by the parser: a mistake raises
        :class:`~bilevel_kit.errors.InstanceError` naming ``source`` (default
        ``<builder NAME>``) and the field's JSON path, as a file with it would."""
        return from_dict(self.document(), source or f"<builder {self._doc['name']}>")

    def save(self, path: str | Path) -> Instance:
        """Validate, then write the document as JSON to ``path``; the instance it holds."""
        from ..atomic import write_text

        inst = self.build(str(path))
        write_text(path, json.dumps(self.document(), indent=2, allow_nan=False) + "\n")
        return inst
