"""``bilevel-kit solve``: one instance, one method; a summary, the solution JSON, figures."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable
from typing import IO, TYPE_CHECKING, Any

from ..objectives import is_top_level
from .common import (
    EXIT_INVALID,
    EXIT_OK,
    EXIT_UNKNOWN,
    add_instance_overrides,
    add_output,
    add_param_option,
    add_seed,
    add_time_limit,
    instance_overrides,
    load_instance,
    positive_int,
    print_violations,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure, SubFigure

    from ..instance import Instance
    from ..methods import Result


HELP = "solve an instance with one method"
DESCRIPTION = (
    "Solve an instance file with a registered method and print a summary; optionally write the "
    "solution JSON and figures. Exact methods show a live line (incumbent, bound, gap, elapsed) "
    "on a terminal; -q hides it."
)


#: How ``-p`` is spelled here; the help lists every method's keys after it.
PARAM_USAGE = "-p KEY=VALUE"


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..methods import REGISTRY

    p.add_argument("instance", help="instance JSON file (format bilevel-kit/1)")
    p.add_argument(
        "--method",
        "-m",
        required=True,
        metavar="NAME",
        help="registered method: " + ", ".join(REGISTRY),
    )
    add_output(p, "--out", "-o", metavar="FILE", help="write the solution JSON here")
    add_output(p, "--gantt", figure=True, metavar="PNG", help="draw the robot/human Gantt chart")
    add_output(p, "--tray", figure=True, metavar="PNG", help="draw every kit's tray layout")
    p.add_argument(
        "--check",
        action="store_true",
        help="run the independent checker on the plan (exit 1 when invalid)",
    )
    add_seed(p)
    add_output(
        p,
        "--convergence",
        figure=True,
        metavar="PNG",
        help="plot the cross-entropy trace of one kit (greedy-ce)",
    )
    p.add_argument(
        "--convergence-kit",
        type=positive_int,
        metavar="K",
        help="kit for --convergence (default: the kit with the most parts)",
    )
    add_time_limit(p, "time limit in seconds for methods that take one")
    add_param_option(p, "method-specific option (repeatable)")
    p.add_argument(
        "--quiet",
        "-q",
        action="store_true",
        help="print only the summary line (and no live progress line on the terminal)",
    )
    add_instance_overrides(p)
    p.add_argument(
        "--work-cell",
        metavar="FILE",
        help="work-cell JSON whose geometry, gripper and grasp widths replace the instance's "
        "(docs/execution.md#the-work-cell), e.g. for greedy-ce's -p finger_room=true",
    )


def run(args: argparse.Namespace) -> int:
    from ..methods import get_method, solve
    from ..progress import LiveLine

    spec = get_method(args.method)  # fail fast on an unknown method, before anything heavy
    spec.parse(dict(args.param))  # and on its options, before a compile (prepare below)
    record = None
    if args.work_cell is None:
        instance = load_instance(args)
    else:  # the cell first: the command-line overrides apply to the instance in its cell
        from ..instance import load
        from ..sawyer.workcell import apply_work_cell, cell_record, load_work_cell

        cell = load_work_cell(args.work_cell)
        base = apply_work_cell(load(args.instance), cell)
        record = cell_record(cell)  # the solution file records it, for execute
        instance = base.with_overrides(**instance_overrides(args))
    prepare([args.method])  # a compile is announced, and never charged to --time-limit
    with LiveLine(sys.stderr, quiet=args.quiet) as line:  # exact methods: a live line
        result = solve(
            instance,
            args.method,
            seed=args.seed,
            time_limit=args.time_limit,
            check=args.check,
            progress=line if line.enabled else None,
            **dict(args.param),
        )
    _write_outputs(args, instance, result, record)
    note = no_model_note(result)
    if note is not None:  # one line: the plan is a heuristic's, not the model's
        print(note, file=sys.stderr)
    print(summary(instance, result, args.quiet))
    violations = result.extra.get("violations")
    if violations:
        print_violations([f"[{v['kind']}] {v['message']}" for v in violations], sys.stderr)
        return EXIT_INVALID
    if args.check and result.plan is not None:
        print("check: valid")
    if result.plan is None:
        return EXIT_UNKNOWN if result.status == "unknown" else EXIT_OK
    return EXIT_OK


def _write_outputs(
    args: argparse.Namespace,
    instance: Instance,
    result: Result,
    work_cell: dict[str, Any] | None = None,
) -> None:
    """The figures and the solution file (with the work cell's record, if any); every figure
    is drawn before any file is written."""
    figures = []
    if args.convergence:
        figures.append((_convergence_figure(result, args.convergence_kit), args.convergence))
    if result.plan is not None and (args.gantt or args.tray):
        from .. import plots

        if args.gantt:
            ax = plots.plot_gantt(instance, result.plan, result.timeline, method=result.method)
            figures.append((ax.figure, args.gantt))
        if args.tray:
            figures.append(
                (plots.plot_trays(instance, result.plan, method=result.method), args.tray)
            )
    if args.out:
        from ..solution import write

        write(args.out, result, instance_overrides(args), work_cell)
    if figures:
        from ..plots import save_figure

        for fig, path in figures:
            save_figure(fig, path)


#: The ``solver_status`` of an exact method that built no model (docs/formulations.md, "Model
#: too large"), in words.
NO_MODEL = {"too_large": "too large", "not_built": "too slow to build"}


def no_model_note(result: Result) -> str | None:
    """``METHOD: no model built (WHY): REASON`` when an exact method built no model (over the
    memory limit or too slow to build, with its estimated size), and whose plan it returns;
    else None."""
    from ..models.exact import keys

    x = result.extra
    why = NO_MODEL.get(str(keys.read(x, keys.SOLVER_STATUS)))  # (old records: old names)
    if why is None:
        return None
    who = x.get("improved_by") or x.get("hint_method")  # the LNS's hand-off, else the start
    plan = f" (the plan is {who}'s)" if who else ""
    reason = str(x.get("reason")).removeprefix(f"{result.method}: ")
    return f"{result.method}: no model built ({why}): {reason}{plan}"


def _fmt(v: float | None, unit: str = "") -> str:
    return "-" if v is None else f"{v:.2f}{unit}"


def limit_note(result: Result) -> str:
    """`` (time limit reached)`` when the run stopped at its time limit (docs/cli.md)."""
    return " (time limit reached)" if result.extra.get("time_limit_hit") else ""


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.2f}%"


def summary(instance: Instance, result: Result, quiet: bool) -> str:
    """The summary line and, unless ``quiet``, one line per kit. When the status is about
    another objective than the makespan (``-p objective=sum_completion``, bilevel-milp's J),
    the first line states no status and calls its bound and gap the makespan's; the status
    follows on a line of its own with that objective's numbers (docs/cli.md#shared-options),
    so "optimal" never stands beside a gap it is not about."""
    m = result.metrics or {}
    own = is_top_level(result.objective_name)
    head = f"{result.method} {result.status}" if own else f"{result.method}"
    which = "" if own else "makespan "
    lines = [
        f"{instance.name}: {head}{limit_note(result)}"
        f"  makespan {_fmt(m.get('makespan'))} s"
        f"  human idle {_fmt(m.get('human_idle'))} s  robot idle {_fmt(m.get('robot_idle'))} s"
        f"  kits {m.get('n_kits', '-')}  {which}bound {_fmt(result.makespan_bound)} s"
        f"  {which}gap {_pct(result.makespan_gap)}  time {result.wall_time_s:.3f} s"
    ]
    for station, sm in result.extra.get("station_metrics", {}).items():
        lines.append(
            f"  station {station}: completion {_fmt(sm['completion'])} s"
            f"  human idle {_fmt(sm['human_idle'])} s  kits {sm['n_kits']}"
        )
    if not own:
        lines.append(_status_line(result))
    if quiet or result.plan is None or result.timeline is None:
        return "\n".join(lines)
    lines.append(f"{'kit':>3}  {'robot':>15}  {'arrive':>8}  {'human':>15}  tasks")
    where = result.timeline.kit_stations
    for k, (kit, t) in enumerate(zip(result.plan.kits, result.timeline.kits, strict=True), 1):
        at = f"  (station {where[k - 1]})" if where else ""
        lines.append(
            f"{k:>3}  {t.robot_start:7.1f}-{t.robot_end:<7.1f}  {t.arrive:8.1f}  "
            f"{t.human_start:7.1f}-{t.human_end:<7.1f}  {','.join(kit.tasks)}{at}"
        )
    return "\n".join(lines)


def _status_line(result: Result) -> str:
    """``  OBJECTIVE: STATUS`` and the value, bound and gap of the objective minimised (when
    known); J's meaning on a line of its own."""
    from ..objectives import OBJECTIVES

    obj = OBJECTIVES.get(result.objective_name)
    value, bound, gap = result.objective, result.bound, result.gap
    if obj is not None and obj.meaning is not None:  # J: no unit, its meaning below
        numbers = ""
        if value is not None:
            numbers = (
                f"  {obj.name} {_fmt(value)}  {obj.name} bound {_fmt(bound)}"
                f"  {obj.name} gap {_pct(gap)}"
            )
        return f"  {obj.name}: {result.status}{numbers}\n  ({obj.meaning})"
    numbers = ""
    if value is not None:
        numbers = f"  {_fmt(value)} s  bound {_fmt(bound)} s  gap {_pct(gap)}"
    return f"  {result.objective_name}: {result.status}{numbers}"


def _convergence_figure(result: Result, kit: int | None) -> Figure | SubFigure:
    """The cross-entropy trace of one kit (``--convergence``)."""
    from .. import plots
    from ..errors import UsageError
    from ..style import plural

    terms = result.extra.get("kit_terms")
    if not terms:
        raise UsageError(f"--convergence: method {result.method!r} records no CE trace")
    if kit is None:
        kit = 1 + max(range(len(terms)), key=lambda k: (terms[k]["n_parts"], -k))
    if kit > len(terms):
        raise UsageError(f"--convergence-kit {kit}: the plan has {len(terms)} kits")
    t = terms[kit - 1]
    ax = plots.plot_convergence(
        t["trace"],
        label=f"kit {kit} ({plural(t['n_parts'], 'part')})",
        converged=t.get("ce_converged"),
        title=f"cross-entropy, kit {kit}: {t['ce_iterations']} iterations, layout from "
        f"{t['layout_source']}",
    )
    return ax.figure


def prepare(needed: Iterable[str], stream: IO[str] | None = None) -> None:
    """Run the ``prepare`` step of every method or policy about to run (numba's compile of the
    cross-entropy kernels: greedy-ce, the exact methods whose warm start runs it, the
    optimized policies) before any clock starts, so that it is charged to no time limit; a
    compile without numba's cache (the first run after an install) is announced on ``stream``
    (stderr by default, terminal or not), before and with its measured time after."""
    from ..methods import COMPILE_KERNELS, REGISTRY
    from ..options import import_target

    stream = sys.stderr if stream is None else stream

    def notify(text: str) -> None:
        print(text, file=stream, flush=True)

    steps: list[str] = []
    for name in needed:
        step = REGISTRY[name].prepare if name in REGISTRY else None
        if name.startswith("optimized") or name == "fixed-plan":  # greedy-ce in the simulation
            step = COMPILE_KERNELS
        if step is not None and step not in steps:
            steps.append(step)
    for step in steps:
        import_target(step)(notify)
