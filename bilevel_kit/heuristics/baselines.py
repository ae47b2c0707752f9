"""The paper's two baselines (Section V-A): Single Task and Whole Assembly.

* Single Task: one kit per task ("one kit per vertex" of the task graph), tasks in the
  deterministic topological order of :func:`bilevel_kit.instance.topological_order` (Kahn's
  algorithm, ties broken by the order of the tasks in the file).
* Whole Assembly: one kit per product unit holding all of that unit's tasks, in the same order.

With several assembly stations (docs/timeline.md#several-stations) each station gets these
kits of its own tasks (Whole Assembly: one kit per product unit and station), and the stations'
kit sequences are interleaved by earliest need: the next kit is the next one of the station
whose human runs out of work first (the earliest end of its last kit so far, ties to the
station listed first), by the one timeline evaluator.

Layouts come from the shelf packer (when the instance enforces Sawyer reachability and the
packer's layout puts a part out of reach, from cross-entropy with seed 0 instead); a kit that
cannot be laid out raises
:class:`~bilevel_kit.errors.KitDoesNotFit` instead of returning an overlapping layout.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from ..errors import KitDoesNotFit
from ..instance import Instance, topological_order
from ..methods import MethodOutput, Status
from ..options import NO_OPTIONS, NoOptions
from ..plan import Kit, Plan, TimelineBuilder
from ..reachability import unreachable
from .shelf import kit_items, shelf_pack


def packed_kit(instance: Instance, tasks: Sequence[str], label: str) -> Kit:
    """A kit of ``tasks`` laid out by the shelf packer, or :class:`KitDoesNotFit`."""
    counts = instance.kit_parts(tasks)
    layout = shelf_pack(instance.tray, kit_items(instance.part_types, counts))
    if layout is not None and instance.reachability and unreachable(instance, layout):
        # the shelf packer knows nothing of the arm: let CE (seed 0) respect the reach map
        from .cross_entropy import arrange

        arr = arrange(instance, counts, rng=0)
        layout = arr.layout if arr.fits else None
    if layout is None:
        area = sum(instance.part_types[p].area * n for p, n in counts.items())
        how = "with the shelf packer"
        if instance.reachability:
            from ..reachability import reach_grid

            grid = reach_grid(instance)
            assert grid is not None  # reachability is on
            share = grid.reachable.mean()
            how = (
                f"with every centre in the robot's reach ({100 * share:.0f}% of the tray) by the "
                "shelf packer or cross-entropy"
            )
        raise KitDoesNotFit(
            f"{instance.source}: {label}: its {sum(counts.values())} parts "
            f"({area:.0f} mm^2) do not fit the {instance.tray.width:g} x "
            f"{instance.tray.height:g} mm tray ({instance.tray.area:.0f} mm^2) {how}"
        )
    return Kit(tuple(tasks), layout)


def single_task(
    instance: Instance,
    options: NoOptions = NO_OPTIONS,
    *,
    seed: int = 0,
    time_limit: float | None = None,
) -> MethodOutput:
    """One kit per task, in topological order."""
    if instance.stations:
        order = topological_order(instance)
        queues = {
            s: [[t] for t in order if instance.station_of(t) == s] for s in instance.station_ids
        }
        return _interleaved(instance, queues, "kit for task")
    kits = tuple(
        packed_kit(instance, [t], f"kit for task {t!r}") for t in topological_order(instance)
    )
    return MethodOutput(Plan(kits), Status.FEASIBLE)


def whole_assembly(
    instance: Instance,
    options: NoOptions = NO_OPTIONS,
    *,
    seed: int = 0,
    time_limit: float | None = None,
) -> MethodOutput:
    """One kit per product unit, its tasks in topological order."""
    order = topological_order(instance)
    unit = {t.id: t.unit for t in instance.tasks}
    if instance.stations:
        queues = {
            s: [
                kit
                for u in range(1, instance.units + 1)
                if (kit := [t for t in order if unit[t] == u and instance.station_of(t) == s])
            ]
            for s in instance.station_ids
        }
        return _interleaved(instance, queues, "whole-assembly kit of")
    kits = tuple(
        packed_kit(instance, [t for t in order if unit[t] == u], f"whole-assembly kit of unit {u}")
        for u in range(1, instance.units + 1)
    )
    return MethodOutput(Plan(kits), Status.FEASIBLE)


def _interleaved(
    instance: Instance, queues: dict[str, list[list[str]]], label: str
) -> MethodOutput:
    """Each station's kits in its own order, interleaved by earliest need (the module
    docstring), each laid out by the shelf packer."""
    plan = interleave(
        instance, queues, lambda tasks: packed_kit(instance, tasks, f"{label} {', '.join(tasks)}")
    )
    return MethodOutput(plan, Status.FEASIBLE)


def interleave(
    instance: Instance,
    queues: dict[str, list[list[str]]],
    make: Callable[[list[str]], Kit] = lambda tasks: Kit(tuple(tasks)),
    head: Sequence[Kit] = (),
) -> Plan:
    """``head``, then each station's kits of ``queues`` in its own order, interleaved by
    earliest need (the module docstring): the station whose human is free first gets the next
    kit (ties to the station listed first); ``make`` builds a kit from its tasks (no layout by
    default)."""
    timeline = TimelineBuilder(instance)
    kits = list(head)
    for kit in kits:
        timeline.append(kit)
    heads = dict.fromkeys(queues, 0)
    while True:
        ready = [s for s in queues if heads[s] < len(queues[s])]
        if not ready:
            break
        station = min(ready, key=timeline.station_free)  # stable: file order
        kit = make(queues[station][heads[station]])
        heads[station] += 1
        timeline.append(kit)
        kits.append(kit)
    return Plan(tuple(kits))
