"""Command-line interface: ``bilevel-kit solve | check | schema | methods``.

Exit codes: 0 ok, 1 the solution is invalid, 2 bad input or usage (a one-line message on
stderr, no traceback), 3 a definite answer could not be reached within the time limit.
Heavy back-ends are imported inside the commands, so ``bilevel-kit --help`` stays fast.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

EXIT_OK, EXIT_INVALID, EXIT_USAGE, EXIT_UNKNOWN = 0, 1, 2, 3


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit 2) instead of the usage dump."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see --help)\n")


def _key_values(text: str) -> dict[str, str]:
    out: dict[str, str] = {}
    for item in filter(None, (s.strip() for s in text.split(","))):
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def _weights(text: str) -> dict[str, float]:
    out = {}
    for k, v in _key_values(text).items():
        key = k.upper()
        try:
            out[key] = float(v)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{k} must be a number, got {v!r}") from None
    return out


def _scalar(value: str) -> Any:
    low = value.lower()
    if low in ("true", "yes", "on"):
        return True
    if low in ("false", "no", "off"):
        return False
    for cast in (int, float):
        try:
            return cast(value)
        except ValueError:
            pass
    return value


def _param(text: str) -> tuple[str, Any]:
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"--param: expected KEY=VALUE, got {text!r}")
    return key.replace("-", "_"), _scalar(value)


def _float_map(text: str) -> dict[str, float]:
    out = {}
    for k, v in _key_values(text).items():
        try:
            out[k] = float(v)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{k} must be a number, got {v!r}") from None
        if not out[k] > 0 or out[k] == float("inf"):
            raise argparse.ArgumentTypeError(f"{k} must be a finite number > 0")
    return out


def _nonneg(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v >= 0 or v == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return v


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return v


def _add_param_option(p: argparse.ArgumentParser, text: str) -> None:
    p.add_argument(
        "--param", "-p", type=_param, action="append", default=[], metavar="KEY=VALUE", help=text
    )


def _add_instance_overrides(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("instance overrides")
    g.add_argument(
        "--d",
        "--delivery-time",
        dest="delivery_time",
        type=_nonneg,
        metavar="S",
        help="delivery time d in seconds (overrides the instance)",
    )
    g.add_argument(
        "--weights",
        type=_weights,
        metavar="W3=1,W4=1",
        help="override some of the paper's weights W1..W7",
    )
    g.add_argument(
        "--horizon",
        type=_positive_int,
        metavar="N",
        help="look-ahead N of the greedy upper level (default: the instance's, 5)",
    )
    g.add_argument(
        "--units",
        type=_positive_int,
        metavar="U",
        help="number of product units built one after another",
    )


def build_parser() -> argparse.ArgumentParser:
    from .methods import REGISTRY

    methods = "\n".join(f"  {s.name:<16} {s.summary}" for s in REGISTRY.values())
    parser = _Parser(
        prog="bilevel-kit",
        description="Just-in-time robotic kitting: solve, compare and check kitting plans.",
        epilog="exit codes: 0 ok, 1 invalid solution, 2 bad input or usage, 3 unknown "
        "within the time limit\n\nmethods:\n" + methods,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    p = sub.add_parser(
        "solve",
        help="solve an instance with one method",
        description="Solve an instance file with a registered method and print "
        "a summary; optionally write the solution JSON and figures.",
    )
    p.add_argument("instance", help="instance JSON file (format bilevel-kit/1)")
    p.add_argument(
        "--method",
        "-m",
        required=True,
        metavar="NAME",
        help="registered method: " + ", ".join(REGISTRY),
    )
    p.add_argument("--out", "-o", metavar="FILE", help="write the solution JSON here")
    p.add_argument("--gantt", metavar="PNG", help="draw the robot/human Gantt chart")
    p.add_argument("--tray", metavar="PNG", help="draw every kit's tray layout")
    p.add_argument(
        "--check",
        action="store_true",
        help="run the independent checker on the plan (exit 1 when invalid)",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--convergence", metavar="PNG", help="plot the cross-entropy trace of one kit (greedy-ce)"
    )
    p.add_argument(
        "--convergence-kit",
        type=_positive_int,
        metavar="K",
        help="kit for --convergence (default: the kit with the most parts)",
    )
    p.add_argument(
        "--time-limit",
        type=_nonneg,
        metavar="S",
        help="time limit in seconds for methods that take one",
    )
    _add_param_option(p, "method-specific option (repeatable)")
    p.add_argument("--quiet", "-q", action="store_true", help="print only the summary line")
    _add_instance_overrides(p)

    p = sub.add_parser(
        "compare",
        help="solve instances with several methods and tabulate",
        description="One row per instance x method: makespan, human idle, "
        "kits, status, best lower bound, gap to it, checker verdict, wall time. "
        "Each cell is saved on its own under --cells, so an interrupted run "
        "resumes where it stopped.",
    )
    p.add_argument("instances", nargs="+", metavar="INSTANCE")
    p.add_argument(
        "--methods",
        default="all",
        metavar="M1,M2",
        help="comma-separated method names, or 'all' (default)",
    )
    p.add_argument("--seed", type=int, default=0, help="random seed of every cell (default 0)")
    p.add_argument(
        "--time-limit",
        type=_nonneg,
        metavar="S",
        help="time limit per solve for methods that take one",
    )
    p.add_argument(
        "--param",
        "-p",
        action="append",
        default=[],
        metavar="METHOD:KEY=VALUE",
        help="option for one method, e.g. greedy-ce:polish=true (repeatable)",
    )
    p.add_argument("--csv", metavar="FILE", help="write all record fields as CSV")
    p.add_argument("--md", metavar="FILE", help="write the table as Markdown")
    p.add_argument(
        "--figures",
        metavar="DIR",
        help="write a comparison chart and one Gantt chart per method here",
    )
    p.add_argument("--cells", metavar="DIR", help="save/resume per-cell results in DIR")
    _add_instance_overrides(p)

    p = sub.add_parser(
        "simulate",
        help="shop-floor simulation (SimPy) of a kitting policy",
        description="Replications of the paper's shop-floor simulation (Section V-B): feeders "
        "with Poisson arrivals (mean inter-arrival MAT) and exponential failures (MTTF, fixed "
        "repair), the robot asking its policy for the next kit at each epoch, the human "
        "assembling with sampled participant times. Replication r uses seed SEED + r.",
    )
    p.add_argument("instance")
    p.add_argument(
        "--policy",
        default="optimized",
        metavar="NAME",
        help="single-task | whole-assembly | optimized | cpsat-rolling (default optimized)",
    )
    p.add_argument(
        "--mat",
        type=_float_map,
        default={},
        metavar="leg=60,foot=60",
        help="mean inter-arrival time (s) per part type; other types always there",
    )
    p.add_argument("--mttf", type=_nonneg, metavar="S", help="mean time to failure of feeders")
    p.add_argument("--repair", type=_nonneg, metavar="S", help="repair time (default 30 s)")
    p.add_argument(
        "--buffer",
        type=int,
        metavar="K",
        help="kits allowed to wait at the human before the robot stops "
        "(default unlimited, the evaluator's semantics; 0 = the user study)",
    )
    p.add_argument("--reps", type=_positive_int, default=30, help="replications (default 30)")
    p.add_argument("--seed", type=int, default=0, help="seed of the first replication")
    p.add_argument("--csv", metavar="FILE", help="one row per replication")
    _add_instance_overrides(p)
    _add_param_option(p, "policy option, e.g. cpsat-rolling: window=12, time_limit=1 (repeatable)")

    p = sub.add_parser(
        "repro",
        help="reproduce the paper's user study (Fig. 5) or Figure 6",
        description="user-study: 18 simulated participants x {Whole Assembly, Single Task, "
        "Optimized}, calibrated on two of the paper's numbers, ANOVA + Tukey HSD side by side "
        "with the paper. fig6: MAT x MTTF grid of the shop-floor simulation, percent "
        "improvement heatmaps with significance marks; saved per cell (resumable). See "
        "paper_repro/README.md.",
    )
    p.add_argument("experiment", choices=("user-study", "fig6"))
    p.add_argument("--quick", action="store_true", help="a reduced run (seconds)")
    p.add_argument("--out", metavar="DIR", help="output folder (default out/repro/EXPERIMENT)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--reps",
        type=_positive_int,
        metavar="R",
        help="fig6: replications per cell (default 30; 3 with --quick)",
    )
    p.add_argument("--jobs", type=_positive_int, default=1, help="fig6: parallel cells")
    p.add_argument(
        "--d",
        "--delivery-time",
        dest="delivery_time",
        type=_nonneg,
        metavar="S",
        help="fig6: delivery time (default: the instance's)",
    )
    p.add_argument(
        "--with-cpsat",
        action="store_true",
        help="fig6: add the cpsat-rolling policy and compare it with Optimized",
    )
    p.add_argument(
        "--cpsat-time-limit",
        type=_nonneg,
        default=1.0,
        metavar="S",
        help="fig6 --with-cpsat: CP-SAT time limit per decision (default 1 s)",
    )

    p = sub.add_parser(
        "pack",
        help="place parts on the tray with CP-SAT (fits? best layout?)",
        description="FILE is an instance (with --tasks a,b,c: the parts of those tasks) or a "
        'stand-alone pack file {"tray": {"width", "height"}, "items": [{"id", "width", '
        '"height", "count", "rotatable"}]}. Integer grid at --resolution mm, rotation 0/90 '
        "degrees for rotatable parts, no-overlap-2D. Exit 0 for a definite answer (feasible, "
        "optimal or infeasible), 3 for unknown within the time limit.",
    )
    p.add_argument("file", metavar="FILE")
    p.add_argument("--tasks", metavar="A,B,C", help="tasks whose parts to pack (instances)")
    p.add_argument(
        "--objective",
        choices=("feasible", "fitness"),
        default="feasible",
        help="feasible: decide whether they fit; fitness: maximise the L1 "
        "surrogate of the paper's kit fitness (default feasible)",
    )
    p.add_argument(
        "--resolution",
        type=float,
        default=1.0,
        metavar="MM",
        help="grid resolution in mm (default 1)",
    )
    p.add_argument(
        "--time-limit",
        type=_nonneg,
        default=10.0,
        metavar="S",
        help="time limit in seconds (default 10)",
    )
    p.add_argument("--workers", type=_positive_int, default=2, help="CP-SAT workers (2)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", "-o", metavar="FILE", help="write the layout as JSON")
    p.add_argument("--png", metavar="FILE", help="draw the layout")

    p = sub.add_parser(
        "reach",
        help="Sawyer reachability map of the tray (Pinocchio)",
        description="Discretise the tray, solve a top-down grasp (and its approach pose) per "
        "cell with the project's own Sawyer model, and print/draw the map: reachable cells "
        "coloured by manipulability. The instance's 'station' section places the tray "
        "(default station otherwise). With --solution, kit K's layout is drawn on top and "
        "its unreachable parts are listed.",
    )
    p.add_argument("instance")
    p.add_argument(
        "--resolution",
        type=float,
        metavar="MM",
        help="cell size in mm (default: the instance's reach_resolution, 10)",
    )
    p.add_argument("--png", metavar="FILE", help="draw the map here")
    p.add_argument("--solution", metavar="FILE", help="solution whose kit to draw on the map")
    p.add_argument("--kit", type=_positive_int, default=1, help="kit of --solution (default 1)")

    p = sub.add_parser(
        "generate",
        help="write a generated instance",
        description="Families: table (units of the paper's table), mixed (table + stool + "
        "chair per unit), intree and series-parallel (random task graphs of SIZE tasks; "
        "--tightness = total part area / tray area).",
    )
    p.add_argument("family", help="table | mixed | intree | series-parallel")
    p.add_argument("--size", type=_positive_int, required=True, help="units or tasks")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--tightness", type=float, default=0.6, help="part area / tray area (0.6)")
    p.add_argument(
        "--d",
        "--delivery-time",
        dest="delivery_time",
        type=_nonneg,
        metavar="S",
        help="delivery time d (default: the family's)",
    )
    p.add_argument("--out", "-o", metavar="FILE", help="write here instead of stdout")

    p = sub.add_parser(
        "check",
        help="check a solution file against an instance",
        description="Run the independent checker; exit 1 and list the "
        "violations when the solution is invalid.",
    )
    p.add_argument("instance")
    p.add_argument("solution")
    _add_instance_overrides(p)

    p = sub.add_parser("schema", help="print the JSON Schema of instance or solution files")
    p.add_argument("--solution", action="store_true", help="the solution schema instead")
    p.add_argument("--out", "-o", metavar="FILE", help="write it to FILE instead of stdout")

    sub.add_parser("methods", help="list the registered methods")
    return parser


def _load_instance(args: argparse.Namespace):
    from .instance import load

    inst = load(args.instance)
    return inst.with_overrides(
        delivery_time=args.delivery_time,
        weights=args.weights,
        horizon=args.horizon,
        units=args.units,
    )


def _fmt(v: float | None, unit: str = "") -> str:
    return "-" if v is None else f"{v:.2f}{unit}"


def _summary(instance, result, quiet: bool) -> str:
    lines = []
    m = result.metrics or {}
    gap = "-" if result.gap is None else f"{100 * result.gap:.2f}%"
    lines.append(
        f"{instance.name}: {result.method} {result.status}  makespan {_fmt(m.get('makespan'))} s"
        f"  human idle {_fmt(m.get('human_idle'))} s  robot idle {_fmt(m.get('robot_idle'))} s"
        f"  kits {m.get('n_kits', '-')}  bound {_fmt(result.bound)} s  gap {gap}"
        f"  time {result.wall_time_s:.3f} s"
    )
    if quiet or result.plan is None:
        return "\n".join(lines)
    lines.append(f"{'kit':>3}  {'robot':>15}  {'arrive':>8}  {'human':>15}  tasks")
    for k, (kit, t) in enumerate(zip(result.plan.kits, result.timeline.kits, strict=True), 1):
        lines.append(
            f"{k:>3}  {t.robot_start:7.1f}-{t.robot_end:<7.1f}  {t.arrive:8.1f}  "
            f"{t.human_start:7.1f}-{t.human_end:<7.1f}  {','.join(kit.tasks)}"
        )
    return "\n".join(lines)


def _print_violations(lines: list[str], stream, limit: int = 20) -> None:
    print(f"INVALID: {len(lines)} violation(s)", file=stream)
    for line in lines[:limit]:
        print(f"  {line}", file=stream)
    if len(lines) > limit:
        print(f"  ... and {len(lines) - limit} more", file=stream)


def _convergence_figure(result, kit: int | None):
    from . import plots
    from .errors import UsageError

    terms = result.extra.get("kit_terms")
    if not terms:
        raise UsageError(f"--convergence: method {result.method!r} records no CE trace")
    if kit is None:
        kit = 1 + max(range(len(terms)), key=lambda k: (terms[k]["n_parts"], -k))
    if kit > len(terms):
        raise UsageError(f"--convergence-kit {kit}: the plan has {len(terms)} kits")
    t = terms[kit - 1]
    ax = plots.plot_convergence(t["trace"], label=f"kit {kit} ({t['n_parts']} parts)")
    ax.set_title(
        f"cross-entropy, kit {kit}: {t['ce_iterations']} iterations, layout from "
        f"{t['layout_source']}"
    )
    ax.legend()
    return ax.figure


def cmd_solve(args: argparse.Namespace) -> int:
    from .methods import get_method, solve

    get_method(args.method)  # fail fast on an unknown method, before loading anything heavy
    instance = _load_instance(args)
    params = dict(args.param)
    result = solve(
        instance,
        args.method,
        seed=args.seed,
        time_limit=args.time_limit,
        check=args.check,
        **params,
    )
    figures = []
    if args.convergence:
        figures.append((_convergence_figure(result, args.convergence_kit), args.convergence))
    if result.plan is not None and (args.gantt or args.tray):
        from . import plots

        if args.gantt:
            ax = plots.plot_gantt(instance, result.plan, result.timeline)
            figures.append((ax.figure, args.gantt))
        if args.tray:
            figures.append((plots.plot_trays(instance, result.plan), args.tray))
    if args.out:
        from .solution import write

        write(args.out, result)
    if figures:
        from .plots import save_figure

        for fig, path in figures:
            save_figure(fig, path)
    print(_summary(instance, result, args.quiet))
    violations = result.extra.get("violations")
    if violations:
        _print_violations([f"[{v['kind']}] {v['message']}" for v in violations], sys.stderr)
        return EXIT_INVALID
    if args.check and result.plan is not None:
        print("check: valid")
    if result.plan is None:
        return EXIT_UNKNOWN if result.status == "unknown" else EXIT_OK
    return EXIT_OK


def _method_params(items: list[str], methods: list[str]) -> dict[str, dict[str, Any]]:
    from .errors import UsageError

    out: dict[str, dict[str, Any]] = {m: {} for m in methods}
    for item in items:
        method, sep, kv = item.partition(":")
        if not sep or method not in out:
            raise UsageError(
                f"--param {item!r}: expected METHOD:KEY=VALUE with METHOD one of "
                f"{', '.join(methods)}"
            )
        try:
            key, value = _param(kv)
        except argparse.ArgumentTypeError as exc:
            raise UsageError(f"--param {item!r}: {exc}") from None
        out[method][key] = value
    return out


def cmd_compare(args: argparse.Namespace) -> int:
    from .experiments import (
        CompareCell,
        add_best_bound_gap,
        compare_cell,
        format_markdown,
        format_table,
        run_cells,
        write_csv,
    )
    from .instance import load
    from .methods import get_method, method_names

    methods = (
        method_names()
        if args.methods == "all"
        else [m.strip() for m in args.methods.split(",") if m.strip()]
    )
    for m in methods:
        get_method(m)
    params = _method_params(args.param, methods)
    overrides = {
        k: v
        for k, v in (
            ("delivery_time", args.delivery_time),
            ("weights", args.weights),
            ("horizon", args.horizon),
            ("units", args.units),
        )
        if v is not None
    }
    for path in args.instances:  # validate every input before any solve or write
        load(path).with_overrides(**overrides)
    cells = [
        CompareCell(str(path), m, args.seed, args.time_limit, params[m], overrides)
        for path in args.instances
        for m in methods
    ]
    records = add_best_bound_gap(
        run_cells(cells, compare_cell, cell_dir=args.cells, desc="compare")
    )
    print(format_table(records))
    errors = [r for r in records if r["status"] == "error"]
    for r in errors:
        print(f"{r['instance']} / {r['method']}: {r['error']}", file=sys.stderr)
    if args.figures:
        _compare_figures(records, args.figures)
    if args.csv:
        write_csv(args.csv, records)
    if args.md:
        from .atomic import write_text

        write_text(args.md, format_markdown(records))
    if any(
        r.get("valid") is False and r["status"] != "error" and r["makespan"] is not None
        for r in records
    ):
        print("INVALID plans found (see the 'valid' column)", file=sys.stderr)
        return EXIT_INVALID
    return EXIT_OK


def _compare_figures(records: list[dict[str, Any]], folder: str) -> None:
    from pathlib import Path

    from . import plots, solution
    from .instance import load

    out = Path(folder)
    by_instance: dict[str, list[dict[str, Any]]] = {}
    for r in records:
        by_instance.setdefault(r["instance_file"], []).append(r)
    for path, rows in by_instance.items():
        inst = load(path)
        ok = [r for r in rows if r.get("makespan") is not None]
        if not ok:
            continue
        ax = plots.plot_comparison(ok)
        plots.save_figure(ax.figure, out / f"{inst.name}_compare.png")
        for r in ok:
            sol = solution.from_dict(r["solution"], f"{path} ({r['method']})")
            ax = plots.plot_gantt(inst, sol.plan)
            ax.set_title(f"{inst.name} / {r['method']}: " + ax.get_title())
            plots.save_figure(ax.figure, out / f"{inst.name}_{r['method']}_gantt.png")


SIM_COLUMNS = (
    "makespan",
    "human_idle",
    "robot_idle",
    "n_kits",
    "robot_wait",
    "n_waits",
    "robot_blocked",
)


def cmd_simulate(args: argparse.Namespace) -> int:
    import statistics

    from .errors import UsageError
    from .instance import load
    from .sim import POLICIES, SimParams, replicate

    if args.policy not in POLICIES:
        raise UsageError(f"unknown policy {args.policy!r}; choose from {', '.join(POLICIES)}")
    instance = load(args.instance)
    unknown = sorted(set(args.mat) - set(instance.part_types))
    if unknown:
        raise UsageError(f"--mat: unknown part type(s) {', '.join(unknown)}")
    if args.mttf is not None and not args.mat and not instance.supply:
        raise UsageError("--mttf needs feeders: give --mat or an instance 'supply' section")
    if args.buffer is not None and args.buffer < 0:
        raise UsageError("--buffer must be >= 0")
    params = SimParams(
        units=args.units,
        delivery_time=args.delivery_time,
        mat=args.mat,
        mttf=args.mttf,
        repair_time=args.repair,
        buffer=args.buffer,
        horizon=args.horizon,
        weights=args.weights,
        policy_options=dict(args.param),
    )
    records = replicate(
        instance,
        args.policy,
        params,
        seeds=range(args.seed, args.seed + args.reps),
        progress=sys.stderr.isatty(),
    )
    units = records[0]["units"]
    print(f"{instance.name}: policy {args.policy}, {units} unit(s), {args.reps} replication(s)")
    for col in SIM_COLUMNS:
        vals = [float(r[col]) for r in records]
        sd = statistics.stdev(vals) if len(vals) > 1 else 0.0
        print(
            f"  {col:<14} mean {statistics.fmean(vals):10.2f}   sd {sd:9.2f}   "
            f"min {min(vals):10.2f}   max {max(vals):10.2f}"
        )
    if args.csv:
        from .experiments import write_csv

        rows = [
            {
                "instance": instance.name,
                "policy": args.policy,
                **{
                    k: r[k]
                    for k in (
                        "seed",
                        "units",
                        *SIM_COLUMNS,
                        "human_work",
                        "robot_work",
                        "max_queue",
                    )
                },
            }
            for r in records
        ]
        write_csv(args.csv, rows)
    return EXIT_OK


def cmd_repro(args: argparse.Namespace) -> int:
    from . import repro

    if args.experiment == "user-study":
        out = args.out or "out/repro/user_study"
        res = repro.run_user_study(out, quick=args.quick, seed=args.seed, jobs=args.jobs)
    else:
        out = args.out or "out/repro/fig6"
        policies = tuple(repro.CONDITIONS)
        options = None
        if args.with_cpsat:
            policies += ("cpsat-rolling",)
            options = {"time_limit": args.cpsat_time_limit}
        res = repro.run_fig6(
            out,
            quick=args.quick,
            reps=args.reps,
            jobs=args.jobs,
            delivery_time=args.delivery_time,
            seed=args.seed,
            policies=policies,
            policy_options=options,
        )
    from pathlib import Path

    md = res.get("files", {}).get("markdown")
    if md and Path(md).exists():
        print(Path(md).read_text().rstrip())
    for name, path in sorted(res.get("files", {}).items()):
        print(f"wrote {name}: {path}")
    return EXIT_OK


def cmd_pack(args: argparse.Namespace) -> int:
    import json

    from . import packfile
    from .errors import InstanceError, UsageError
    from .instance import load, read_json
    from .plan import Kit

    if not args.resolution > 0:
        raise UsageError("--resolution must be > 0")
    doc = read_json(args.file, InstanceError)
    if packfile.is_pack_file(doc):
        if args.tasks:
            raise UsageError("--tasks applies to instance files, not to pack files")
        instance, counts = packfile.load(args.file)
        tasks: list[str] = []
    else:
        instance = load(args.file)
        if not args.tasks:
            raise UsageError("an instance needs --tasks a,b,c (the tasks whose parts to pack)")
        tasks = [t.strip() for t in args.tasks.split(",") if t.strip()]
        unknown = [t for t in tasks if t not in instance.task_by_id]
        if unknown:
            raise UsageError(f"--tasks: unknown task(s) {', '.join(unknown)}")
        counts = dict(instance.kit_parts(tasks))
    from .layout.cpsat_packing import pack
    from .layout.shelf import kit_items
    from .reachability import reach_grid

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
    n = sum(counts.values())
    line = (
        f"{instance.name}: {n} parts on {instance.tray.width:g} x "
        f"{instance.tray.height:g} mm: {res.status} in {res.wall_time_s:.3f} s"
    )
    if res.layout is not None and args.objective == "fitness":
        line += (
            f"; L1 surrogate {res.surrogate_objective:.1f} (bound {res.bound:.1f}), "
            f"true Euclidean fitness {res.true_fitness:.1f}"
        )
    print(line)
    if args.out:
        from .atomic import write_text

        out = {
            "format": "bilevel-kit-layout/1",
            "file": args.file,
            "tasks": tasks,
            "status": res.status,
            "objective": args.objective,
            "resolution": args.resolution,
            "wall_time_s": res.wall_time_s,
            "surrogate_objective": res.surrogate_objective,
            "bound": res.bound,
            "true_fitness": res.true_fitness,
            "tray": {"width": instance.tray.width, "height": instance.tray.height},
            "layout": [p.to_dict() for p in res.layout or ()],
        }
        write_text(args.out, json.dumps(out, indent=2) + "\n")
    if args.png and res.layout is not None:
        from .plots import plot_tray, save_figure

        ax = plot_tray(
            instance, Kit(tuple(tasks), res.layout), title=f"{instance.name}: {res.status}"
        )
        save_figure(ax.figure, args.png)
    return EXIT_UNKNOWN if res.status == "unknown" else EXIT_OK


def cmd_reach(args: argparse.Namespace) -> int:
    from .errors import UsageError
    from .instance import load

    instance = load(args.instance)
    resolution = instance.reach_resolution if args.resolution is None else args.resolution
    if not resolution > 0:
        raise UsageError("--resolution must be > 0")
    layout = None
    if args.solution:
        from . import solution

        sol = solution.read(args.solution)
        if args.kit > len(sol.plan.kits):
            raise UsageError(f"--kit {args.kit}: the solution has {len(sol.plan.kits)} kits")
        layout = sol.plan.kits[args.kit - 1].layout
    from .sawyer import DEFAULT_STATION, build_reach_map, ensure_placeable

    station = instance.station or DEFAULT_STATION
    m = build_reach_map(station, instance.tray.width, instance.tray.height, resolution)
    ny, nx = m.shape
    print(
        f"{instance.name}: tray {instance.tray.width:g} x {instance.tray.height:g} mm at "
        f"({station.tray_x:g}, {station.tray_y:g}, {station.tray_z:g}) mm, yaw "
        f"{station.tray_yaw:g} deg; {nx} x {ny} cells of {m.cell_size[0]:.1f} x "
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
        from .plots import save_figure
        from .sawyer import plot_reach_map

        ax = plot_reach_map(m, layout)
        save_figure(ax.figure, args.png)
    return EXIT_INVALID if bad else EXIT_OK


def cmd_generate(args: argparse.Namespace) -> int:
    import json

    from .generate import generate
    from .instance import from_dict

    doc = generate(args.family, args.size, args.seed, args.tightness, args.delivery_time)
    from_dict(doc, f"<generated {args.family}>")  # never write an instance that doesn't load
    text = json.dumps(doc, indent=2) + "\n"
    if args.out:
        from .atomic import write_text

        write_text(args.out, text)
        print(
            f"wrote {args.out}: {doc['name']}, {len(doc['tasks'])} tasks x "
            f"{doc.get('units', 1)} unit(s)"
        )
    else:
        sys.stdout.write(text)
    return EXIT_OK


def cmd_check(args: argparse.Namespace) -> int:
    from . import solution
    from .validate import check

    instance = _load_instance(args)
    sol = solution.read(args.solution)
    violations = check(
        instance, sol.plan, reported_kits=sol.reported_kits, reported_metrics=sol.reported_metrics
    )
    if violations:
        _print_violations([str(v) for v in violations], sys.stdout)
        return EXIT_INVALID
    print(f"valid: {len(sol.plan.kits)} kits, {sum(len(k.tasks) for k in sol.plan.kits)} tasks")
    return EXIT_OK


def cmd_schema(args: argparse.Namespace) -> int:
    import json

    if args.solution:
        from .solution import schema
    else:
        from .instance import schema
    text = json.dumps(schema(), indent=2) + "\n"
    if args.out:
        from .atomic import write_text

        write_text(args.out, text)
    else:
        sys.stdout.write(text)
    return EXIT_OK


def cmd_methods(args: argparse.Namespace) -> int:
    from .methods import REGISTRY

    for s in REGISTRY.values():
        print(f"{s.name:<16} {s.summary}")
    return EXIT_OK


COMMANDS = {
    "solve": cmd_solve,
    "compare": cmd_compare,
    "generate": cmd_generate,
    "reach": cmd_reach,
    "pack": cmd_pack,
    "repro": cmd_repro,
    "simulate": cmd_simulate,
    "check": cmd_check,
    "schema": cmd_schema,
    "methods": cmd_methods,
}


def main(argv: Sequence[str] | None = None) -> int:
    from .errors import BilevelKitError

    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, or a usage error already printed on one line
        return int(exc.code or 0)
    try:
        return COMMANDS[args.command](args)
    except BilevelKitError as exc:
        print(f"bilevel-kit {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("bilevel-kit: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
