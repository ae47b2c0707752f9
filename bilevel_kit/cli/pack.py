"""``bilevel-kit pack``: CP-SAT tray packing of an instance's kit or of a pack file."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from .common import (
    EXIT_NO_GRID_LAYOUT,
    EXIT_OK,
    EXIT_UNKNOWN,
    add_output,
    add_resolution,
    add_seed,
    add_time_limit,
    positive_int,
)

#: The layout file's status when CP-SAT finds no layout on a grid that is not exact.
NO_GRID_LAYOUT = "no_grid_layout"

if TYPE_CHECKING:
    from ..instance import Instance, Tray
    from ..models.packing import PackResult
    from ..plan import Kit

HELP = "place parts on the tray with CP-SAT (fits? best layout?)"
DESCRIPTION = (
    "FILE is an instance (with --tasks a,b,c: the parts of those tasks) or a stand-alone pack "
    'file {"tray": {"width", "height"}, "items": [{"id", "width", "height", "count", '
    '"rotatable"}]}. Integer grid at --resolution mm, rotation 0/90 degrees for rotatable '
    "parts, no-overlap-2D. Exit 0 for a definite answer (feasible, optimal or infeasible), 3 "
    "for unknown within the time limit, 4 for no layout on this grid when the grid is not exact "
    "(some size is not a multiple of --resolution): that is not a proof that the parts do not "
    "fit; try a finer --resolution."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE")
    p.add_argument("--tasks", metavar="A,B,C", help="tasks whose parts to pack (instances)")
    p.add_argument(
        "--objective",
        choices=("feasible", "fitness"),
        default="feasible",
        help="feasible: decide whether they fit; fitness: maximise the L1 "
        "surrogate of the paper's kit fitness (default feasible)",
    )
    add_resolution(p, "grid resolution in mm (default 1)", default=1.0)
    add_time_limit(p, "time limit in seconds (default 10)", default=10.0)
    p.add_argument("--workers", type=positive_int, default=2, help="CP-SAT workers (2)")
    add_seed(p)
    add_output(p, "--out", "-o", metavar="FILE", help="write the layout as JSON")
    add_output(p, "--png", metavar="FILE", help="draw the layout")


def _read_target(args: argparse.Namespace) -> tuple[Instance, dict[str, int], list[str]]:
    """The tray and part types, the part counts to pack and the tasks they come from."""
    from .. import packfile
    from ..errors import InstanceError, UsageError
    from ..instance import load, read_json

    doc = read_json(args.file, InstanceError)
    if packfile.is_pack_file(doc):
        if args.tasks:
            raise UsageError("--tasks applies to instance files, not to pack files")
        instance, counts = packfile.load(args.file)
        return instance, counts, []
    instance = load(args.file)
    if not args.tasks:
        raise UsageError("an instance needs --tasks a,b,c (the tasks whose parts to pack)")
    tasks = [t.strip() for t in args.tasks.split(",") if t.strip()]
    if not tasks:
        raise UsageError(f"--tasks {args.tasks!r}: no task given")
    repeated = sorted({t for t in tasks if tasks.count(t) > 1})
    if repeated:
        raise UsageError(f"--tasks: task(s) given twice: {', '.join(repeated)}")
    unknown = [t for t in tasks if t not in instance.task_by_id]
    if unknown:
        raise UsageError(f"--tasks: unknown task(s) {', '.join(unknown)}")
    return instance, dict(instance.kit_parts(tasks)), tasks


def run(args: argparse.Namespace) -> int:
    instance, counts, tasks = _read_target(args)
    from ..heuristics.shelf import kit_items
    from ..models.packing import pack
    from ..progress import is_terminal
    from ..reachability import reach_grid

    if is_terminal(sys.stderr):  # CP-SAT may take the whole limit: say what runs meanwhile
        limit = "" if args.time_limit is None else f", up to {args.time_limit:g} s"
        print(
            f"packing {sum(counts.values())} parts with CP-SAT ({args.objective}{limit}) ...",
            file=sys.stderr,
            flush=True,
        )
    res = pack(
        instance.tray,
        kit_items(instance.part_types, counts),
        objective=args.objective,
        resolution=args.resolution,
        time_limit=args.time_limit,
        workers=args.workers,
        seed=args.seed,
        w6=instance.weights["W6"],
        reach=reach_grid(instance),
    )
    status = res.status
    if status == "infeasible" and not res.extra.get("proof", True):
        status = NO_GRID_LAYOUT
    shown = (
        f"no layout on the {args.resolution:g} mm grid (not a proof; try a finer --resolution)"
        if status == NO_GRID_LAYOUT
        else status
    )
    line = (
        f"{instance.name}: {sum(counts.values())} parts on {instance.tray.width:g} x "
        f"{instance.tray.height:g} mm: {shown} in {res.wall_time_s:.3f} s"
    )
    if res.layout is not None and args.objective == "fitness":
        line += (
            f"; L1 surrogate {res.surrogate_objective:.1f} (bound {res.bound:.1f}), "
            f"true Euclidean fitness {res.true_fitness:.1f}"
        )
    print(line)
    if args.out:
        import json

        from ..atomic import write_text

        doc = layout_document(
            res,
            file=args.file,
            tasks=tasks,
            objective=args.objective,
            resolution=args.resolution,
            tray=instance.tray,
        )
        doc["status"] = status
        write_text(args.out, json.dumps(doc, indent=2) + "\n")
    if args.png and res.layout is not None:
        from ..plan import Kit
        from ..plots import plot_tray, save_figure

        kit = Kit(tuple(tasks), res.layout)
        ax = plot_tray(instance, kit, title=_png_title(instance, kit, args, res.status))
        save_figure(ax.figure, args.png)
    if status == NO_GRID_LAYOUT:
        return EXIT_NO_GRID_LAYOUT
    return EXIT_UNKNOWN if status == "unknown" else EXIT_OK


def _png_title(instance: Instance, kit: Kit, args: argparse.Namespace, status: str) -> str:
    """The layout figure's title: what was packed (instance and tasks, or the pack file), the
    parts and the kit fitness, then how (CP-SAT's answer, objective, grid)."""
    from ..plots import kit_fitness
    from ..style import plural

    head = instance.name + (f", tasks {', '.join(kit.tasks)}" if kit.tasks else "")
    fitness = kit_fitness(instance, kit)
    what = plural(len(kit.layout), "part") + (
        f", kit fitness {round(fitness):,} mm" if fitness is not None else ""
    )
    return (
        f"{head}: {what}\nCP-SAT {status}, objective {args.objective}, {args.resolution:g} mm grid"
    )


def layout_document(
    result: PackResult,
    *,
    file: str,
    tasks: Sequence[str],
    objective: str,
    resolution: float,
    tray: Tray,
) -> dict[str, Any]:
    """The layout file of one packing: what was packed (``file``, ``tasks``), how (objective,
    grid resolution), the answer (status, L1 surrogate, bound, true fitness, wall time) and
    the placements; JSON-serialisable."""
    from ..packfile import LAYOUT_FORMAT

    return {
        "format": LAYOUT_FORMAT,
        "file": file,
        "tasks": list(tasks),
        "status": result.status,
        "objective": objective,
        "resolution": resolution,
        "wall_time_s": result.wall_time_s,
        "surrogate_objective": result.surrogate_objective,
        "bound": result.bound,
        "true_fitness": result.true_fitness,
        "tray": {"width": tray.width, "height": tray.height},
        "layout": [p.to_dict() for p in result.layout or ()],
    }
