"""``bilevel-kit solve``: one instance, one method; a summary, the solution JSON, figures."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable
from typing import IO, TYPE_CHECKING

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


def run(args: argparse.Namespace) -> int:
    from ..methods import get_method, solve
    from ..progress import LiveLine

    get_method(args.method)  # fail fast on an unknown method, before loading anything heavy
    instance = load_instance(args)
    if not args.quiet:
        compile_notice([args.method])
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
    _write_outputs(args, instance, result)
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


def _write_outputs(args: argparse.Namespace, instance: Instance, result: Result) -> None:
    """The figures and the solution file; every figure is drawn before any file is written."""
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

        write(args.out, result, instance_overrides(args))
    if figures:
        from ..plots import save_figure

        for fig, path in figures:
            save_figure(fig, path)


def _fmt(v: float | None, unit: str = "") -> str:
    return "-" if v is None else f"{v:.2f}{unit}"


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.2f}%"


def summary(instance: Instance, result: Result, quiet: bool) -> str:
    """The summary line and, unless ``quiet``, one line per kit. When the status is about
    another objective than the makespan (``-p objective=sum_completion``, bilevel-milp's J),
    the first line states no status and calls its bound and gap the makespan's; the status
    follows on a line of its own with that objective's numbers (docs/cli.md#shared-options),
    so "optimal" never stands beside a gap it is not about."""
    m = result.metrics or {}
    own = result.status_objective == "makespan"
    head = f"{result.method} {result.status}" if own else f"{result.method}"
    which = "" if own else "makespan "
    lines = [
        f"{instance.name}: {head}"
        f"  makespan {_fmt(m.get('makespan'))} s"
        f"  human idle {_fmt(m.get('human_idle'))} s  robot idle {_fmt(m.get('robot_idle'))} s"
        f"  kits {m.get('n_kits', '-')}  {which}bound {_fmt(result.bound)} s"
        f"  {which}gap {_pct(result.gap)}  time {result.wall_time_s:.3f} s"
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
    """``  OBJECTIVE: STATUS`` and that objective's value, bound and gap (when known)."""
    x = result.extra
    if result.status_objective == "J":
        numbers = ""
        if x.get("plan_objective_J") is not None:
            j_bound = x.get("plan_objective_J_bound")
            numbers = (
                f"  J {_fmt(x['plan_objective_J'])}  J bound {_fmt(j_bound)}"
                f"  J gap {_pct(x.get('plan_objective_J_gap'))}"
            )
        return f"  J (the paper's F summed over the kits): {result.status}{numbers}"
    numbers = ""
    if x.get("objective_value") is not None:
        numbers = (
            f"  {_fmt(x['objective_value'])} s  bound {_fmt(x.get('objective_bound'))} s"
            f"  gap {_pct(x.get('objective_gap'))}"
        )
    return f"  {result.status_objective}: {result.status}{numbers}"


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


#: The one note of a first run: numba compiles the cross-entropy kernels once per install.
COMPILE_NOTE = (
    "note: compiling the cross-entropy kernels (first run after an install: about 15 s, "
    "once; numba caches them)"
)


def compile_notice(needed: Iterable[str], stream: IO[str] | None = None) -> None:
    """Say on a terminal that a slow first compile is coming, rather than stay silent for
    ~15 s; ``needed``: the methods or policies about to run (the paper's cross-entropy lower
    level compiles: greedy-ce and the optimized policies)."""
    from ..progress import is_terminal

    stream = sys.stderr if stream is None else stream
    uses_ce = any(n == "greedy-ce" or n.startswith("optimized") for n in needed)
    if not uses_ce or not is_terminal(stream):
        return
    from ..heuristics._kernels import cache_missing

    if cache_missing():
        print(COMPILE_NOTE, file=stream, flush=True)
