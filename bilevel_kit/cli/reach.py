"""``bilevel-kit reach``: the Sawyer reachability map of the tray, optionally with a kit on it."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import EXIT_INVALID, EXIT_OK, add_output, add_resolution, positive_int

HELP = "Sawyer reachability map of the tray (Pinocchio)"
DESCRIPTION = (
    "Discretise the tray, solve a top-down grasp (and its approach pose) per cell with the "
    "project's own Sawyer model, and print/draw the map: reachable cells coloured by "
    "manipulability. The instance's 'work_cell' section (the work cell's geometry) places the "
    "tray (the default work cell otherwise). With --solution, kit K's layout is drawn on top "
    "and its unreachable parts are listed."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("instance")
    add_resolution(p, "cell size in mm (default: the instance's reach_resolution, 10)")
    add_output(p, "--png", figure=True, metavar="FILE", help="draw the map here")
    p.add_argument("--solution", metavar="FILE", help="solution whose kit to draw on the map")
    p.add_argument("--kit", type=positive_int, help="kit of --solution (default 1)")


def run(args: argparse.Namespace) -> int:
    from ..errors import UsageError
    from ..instance import load

    if args.kit is not None and not args.solution:
        raise UsageError("--kit needs --solution (the solution whose kit to draw)")
    args.kit = args.kit or 1
    instance = load(args.instance)
    resolution = instance.reach_resolution if args.resolution is None else args.resolution
    from ..instance.ranges import reach_cells_problem

    why = reach_cells_problem(instance.tray.width, instance.tray.height, resolution)
    if why is not None:
        where = (
            f"--resolution {resolution:g}"
            if args.resolution
            else f"{args.instance}: $.reach_resolution"
        )
        raise UsageError(f"{where}: {why}")
    layout = None
    if args.solution:
        from .. import solution

        sol = solution.read(args.solution)
        if args.kit > len(sol.plan.kits):
            raise UsageError(f"--kit {args.kit}: the solution has {len(sol.plan.kits)} kits")
        layout = sol.plan.kits[args.kit - 1].layout
    from ..sawyer import DEFAULT_WORK_CELL, build_reach_map, ensure_placeable

    work_cell = instance.work_cell or DEFAULT_WORK_CELL
    m = build_reach_map(work_cell, instance.tray.width, instance.tray.height, resolution)
    ny, nx = m.shape
    print(
        f"{instance.name}: tray {instance.tray.width:g} x {instance.tray.height:g} mm at "
        f"({work_cell.tray_x:g}, {work_cell.tray_y:g}, {work_cell.tray_z:g}) mm, yaw "
        f"{work_cell.tray_yaw:g} deg; {nx} x {ny} cells of {m.cell_size[0]:.1f} x "
        f"{m.cell_size[1]:.1f} mm; reachable {100 * m.fraction:.1f}%; built in "
        f"{m.build_time:.3f} s"
    )
    if not m.is_empty:
        manip = m.manipulability[m.reachable]
        print(
            f"manipulability of reachable cells: min {manip.min():.4f}  mean "
            f"{manip.mean():.4f}  max {manip.max():.4f}"
        )
    bad: list[str] = []
    if layout is not None:
        ensure_placeable(m, f"kit {args.kit} of {args.solution}")
        bad = [p.part for p in layout if not m.reachable_at(p.x, p.y)]
        print(
            f"kit {args.kit}: {len(layout)} parts, {len(bad)} unreachable"
            + (f": {', '.join(bad)}" if bad else "")
        )
    if args.png:
        from ..plots import save_figure
        from ..sawyer import plot_reach_map

        title = (
            f"{instance.name}: Sawyer reachability, {100 * m.fraction:.0f}% of {nx} x {ny} cells"
        )
        if layout is not None:
            title += (
                f"\nkit {args.kit} of {Path(args.solution).name}: {len(layout)} parts, "
                f"{len(bad)} unreachable" + (" (red)" if bad else "")
            )
        ax = plot_reach_map(m, layout, title=title)
        save_figure(ax.figure, args.png)
    return EXIT_INVALID if bad else EXIT_OK
