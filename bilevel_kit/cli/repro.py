"""``bilevel-kit repro STUDY``: the paper's user study (Fig. 5) and Figure 6, and the studies
beyond the paper (see paper_repro/); each study is a subcommand with its own options only."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .common import (
    EXIT_OK,
    add_delivery_time,
    add_derived_outputs,
    add_output,
    add_seed,
    add_sweep_options,
    add_time_limit,
    listed,
    positive,
    positive_int,
    sweep_exit,
    sweep_session,
)

if TYPE_CHECKING:
    from ..paths import Output

HELP = (
    "reproduce the paper's user study (Fig. 5) or Figure 6; the horizon, adaptive, "
    "stations and robust studies"
)
DESCRIPTION = (
    "One study per subcommand; `bilevel-kit repro STUDY --help` lists that study's options "
    "only. See paper_repro/README.md."
)

#: Each study's ``--help`` line and description, in the order ``repro --help`` lists them.
STUDIES: dict[str, tuple[str, str]] = {
    "calibrate": (
        "fit the robot and human parameters to 3 of the paper's numbers",
        "Fit the robot's speed, the human's pickup time and the participant x condition SD to "
        "3 of the paper's numbers on a calibration cohort, with a parametric bootstrap; its "
        "CSVs (committed in paper_repro/results/) are the one calibration every other "
        "experiment reads (their --calibration DIR: another one).",
    ),
    "user-study": (
        "the paper's within-subject user study (Fig. 5), as prediction intervals",
        "Within-subject participants x {Whole Assembly, Single Task, Optimized}; 200 fresh "
        "studies of 18 give every paper number a median and 95% prediction interval, with and "
        "without the calibration's uncertainty. --jobs/--scheduler run the studies in parallel "
        "(docs/cluster.md); exit 5 when a cell failed.",
    ),
    "fig6": (
        "the paper's Figure 6: the shop-floor simulation over MAT x MTTF",
        "MAT x MTTF grid of the shop-floor simulation (10 tables per run), percent improvement "
        "heatmaps with ANOVA + Tukey marks; saved per cell (resumable). --jobs/--scheduler run "
        "the grid points in parallel (docs/cluster.md); exit 5 when a cell failed.",
    ),
    "horizon": (
        "greedy-ce's horizon N and cpsat-rolling's window (beyond the paper)",
        "greedy-ce at horizon N = 1..12 against the exact cpsat optimum (or its bound) on the "
        "table, 2 and 5 table units and instances/generated, and cpsat-rolling's window against "
        "Optimized in the Figure 6 simulation (no delay, MAT 60 and 90 s at MTTF 60 s).",
    ),
    "adaptive": (
        "policies that learn the human's pace (beyond the paper)",
        "optimized, optimized-adaptive (learns the human's pace) and optimized-oracle over "
        "fast, median, slow and sampled participants, without and with supply delays "
        "(docs/simulation.md).",
    ),
    "stations": (
        "how many assembly stations one robot keeps busy (beyond the paper)",
        "Throughput, human idle per station and robot utilisation against S = 1..6 stations "
        "of the table, stool, chair and mixed lines, per policy, without and with feeders "
        "(docs/stations.md).",
    ),
    "robust": (
        "plans for the mean human times against plans for their spread (beyond the paper)",
        "Plans for the mean human times against sample-average plans for their spread, VSS and "
        "EVPI per cv and tray count (docs/robust.md).",
    ),
    "robust-kitbench": (
        "the robust study on KitBench records of up to 60 tasks (beyond the paper)",
        "The robust study's cell (mean-value and SAA plans, VSS and EVPI) on every "
        "KitBench record of at most 60 tasks, each with its own tray count, at cv 0.5 "
        "(docs/robust.md#kitbench-up-to-60-tasks).",
    ),
    "robust-sim": (
        "the robust study's plans in the shop-floor simulation, online policies beside them",
        "The robust study's mean-value and SAA plans (recomputed, checked against robust.csv) "
        "run as fixed plans in the shop-floor simulation with the simulator's human model at "
        "the cell's cv, cpsat-rolling and optimized-adaptive beside them on the same seeds "
        "(docs/robust.md).",
    ),
}

#: ``--reps``' meaning in each study that has it.
_REPS = {
    "fig6": "replications per cell (default 30; 3 with --quick)",
    "horizon": "replications per simulation cell (default 3; 1 with --quick)",
    "adaptive": "runs per participant group (default 10; 2 with --quick), 3R sampled participants",
    "stations": "replications (default 5; 2 with --quick)",
    "robust-sim": "replications per cell and human-time law (default 30; 5 with --quick)",
}


def add_arguments(p: argparse.ArgumentParser) -> None:
    """One subparser per study, each with the common options and its own only."""
    from .common import Parser

    sub = p.add_subparsers(dest="experiment", metavar="STUDY", parser_class=Parser)
    sub.required = True
    for name, (line, description) in STUDIES.items():
        s = sub.add_parser(name, help=line, description=description)
        _add_common(s)
        if name in _REPS:
            s.add_argument("--reps", type=positive_int, metavar="R", help=_REPS[name])
        if name in ("user-study", "fig6", "horizon", "adaptive", "stations"):
            s.add_argument(
                "--calibration",
                metavar="DIR",
                help="the folder of the calibration's CSVs (default: the committed one, "
                "paper_repro/results/)",
            )
        {
            "calibrate": _add_calibrate,
            "fig6": _add_fig6,
            "horizon": _add_horizon,
            "stations": _add_stations,
            "robust-sim": _add_robust_sim,
        }.get(name, lambda _: None)(s)
        add_sweep_options(s)


def _add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--quick",
        action="store_true",
        help="a smaller run of the same experiment (fewer studies, cells, replications); "
        "its outputs say so",
    )
    add_output(
        p, "--out", folder=True, metavar="DIR", help="output folder (default out/repro/STUDY)"
    )
    add_derived_outputs(p, _default_out)
    add_seed(p)


def _add_calibrate(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--draws",
        type=positive_int,
        metavar="B",
        help="parametric bootstrap draws (default 50; 3 with --quick)",
    )


def _add_grid(p: argparse.ArgumentParser, mats: str, mttfs: str) -> None:
    p.add_argument("--mats", type=numbers, metavar="30,60", help=mats)
    p.add_argument("--mttfs", type=numbers, metavar="60,90", help=mttfs)


def _add_fig6(p: argparse.ArgumentParser) -> None:
    _add_grid(
        p,
        "the MAT values of the grid (default 30,60,90,120; 30,120 with --quick)",
        "the MTTF values of the grid (default 30,60,90,120; 60 with --quick)",
    )
    add_delivery_time(p, "delivery time (default: the instance's)")
    p.add_argument(
        "--with-cpsat",
        action="store_true",
        help="add the cpsat-rolling policy and compare it with Optimized",
    )
    add_time_limit(
        p,
        "with --with-cpsat: CP-SAT time limit per decision (default 1 s)",
        default=1.0,
        flag="--cpsat-time-limit",
    )


def _add_horizon(p: argparse.ArgumentParser) -> None:
    _add_grid(
        p,
        "the MAT values of the delay cells (default 60,90; 60 with --quick)",
        "the MTTF values of the delay cells (default 60)",
    )
    p.add_argument(
        "--horizons",
        type=integers,
        metavar="1,2,5",
        help="greedy horizons N (default 1..12; 1,2,4,5,6,8,12 with --quick)",
    )
    p.add_argument(
        "--windows",
        type=integers,
        metavar="4,12",
        help="cpsat-rolling windows, tasks (default 4,8,...,24; 4,12,24 with --quick)",
    )
    p.add_argument(
        "--instances",
        nargs="+",
        metavar="FILE",
        help="planning instances (default: the table, 2 and 5 table units, "
        "instances/generated; the table and 2 units with --quick)",
    )
    p.add_argument(
        "--reference-time-limit",
        type=positive,
        metavar="S",
        help="CP-SAT time limit of the exact reference per instance (default 60 s; 20 s with "
        "--quick)",
    )
    p.add_argument(
        "--no-simulation", action="store_true", help="planning only (skip the window study)"
    )


def _add_stations(p: argparse.ArgumentParser) -> None:
    _add_list(p, "--lines", str, "table,mix", "lines: table, stool, chair, mix (default all)")
    p.add_argument(
        "--stations",
        type=integers,
        metavar="1,2,3",
        help="stations per robot S (default 1..6; 1,2,4 with --quick)",
    )
    p.add_argument(
        "--units",
        type=positive_int,
        metavar="U",
        help="units each station builds (default 2)",
    )
    _add_list(
        p,
        "--supply",
        str,
        "none,feeders",
        "supply settings: none (all in stock), feeders (default both)",
    )


def _add_robust_sim(p: argparse.ArgumentParser) -> None:
    """The cells: every (instance, trays, cv) of the lists given (docs/robust.md)."""
    _add_list(
        p,
        "--instances",
        str,
        "table,sp12",
        "instances of the robust study: table, sp12 (default: both, when --trays or "
        "--cvs is given; none of the three: the default cells, docs/robust.md)",
    )
    _add_list(
        p,
        "--trays",
        _trays,
        "1,2,unlimited",
        "tray counts (default 1, 2 and unlimited, when a selection is given)",
    )
    _add_list(
        p,
        "--cvs",
        positive,
        "0.1,0.3",
        "coefficients of variation (default 0.1, 0.2, 0.3, 0.5, when a selection is given)",
    )


def _add_list(
    p: argparse.ArgumentParser, flag: str, item: Callable[[str], Any], metavar: str, text: str
) -> None:
    """An option taking comma-separated values, each parsed by ``item`` (:func:`listed`)."""
    p.add_argument(flag, type=lambda t: listed(t, item), metavar=metavar, help=text)


def _trays(text: str) -> int | None:
    """A tray count: an integer >= 1 or ``unlimited``."""
    if text.lower() == "unlimited":
        return None
    try:
        return positive_int(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(
            f"expected an integer >= 1 or 'unlimited', got {text!r}"
        ) from None


def integers(text: str) -> tuple[int, ...]:
    """``1,2,5``: one or more integers >= 1."""
    return listed(text, positive_int)


def numbers(text: str) -> tuple[float, ...]:
    """``30,60``: one or more finite numbers > 0."""
    return listed(text, positive)


def run(args: argparse.Namespace) -> int:
    with sweep_session(args) as session:
        if session.progress is None:  # a long run shows its bar even when stderr is a file
            session.progress = True
        return sweep_exit(session, _run(args))


def _default(args: argparse.Namespace) -> str:
    """The output folder without ``--out``."""
    return f"out/repro/{args.experiment.replace('-', '_')}"


def _default_out(args: argparse.Namespace) -> list[Output]:
    """The default folder, checked up front like ``--out`` (docs/cli.md#output-paths)."""
    from ..paths import Output

    return (
        []
        if args.out
        else [Output(f"--out {_default(args)} (the default)", _default(args), "folder")]
    )


def _run(args: argparse.Namespace) -> int:
    from .. import repro

    out = args.out or _default(args)
    run: dict[str, Any] = {"quick": args.quick, "jobs": args.jobs, "seed": args.seed}
    # the Figure 6 delay cells (fig6 and horizon only)
    grid: dict[str, Any] = {
        "mats": getattr(args, "mats", None),
        "mttfs": getattr(args, "mttfs", None),
    }
    if args.experiment == "calibrate":
        res = repro.run_calibration(out, draws=args.draws, **run)
        return _report(res)
    if args.experiment == "robust":
        from ..repro.robust import run_robust

        return _report(run_robust(out, **run))
    if args.experiment == "robust-kitbench":
        from ..repro.robust_kitbench import run_robust_kitbench

        return _report(run_robust_kitbench(out, **run))
    if args.experiment == "robust-sim":
        from ..repro.robust_sim import run_robust_sim, select_cells

        chosen = (args.instances, args.trays, args.cvs)
        cells = select_cells(*chosen) if any(c is not None for c in chosen) else None
        return _report(run_robust_sim(out, reps=args.reps, cells=cells, **run))
    run["calibration"] = args.calibration
    if args.experiment == "stations":
        from ..repro.stations import run_stations

        res = run_stations(
            out,
            reps=args.reps,
            lines=args.lines,
            stations=args.stations,
            delays=args.supply,
            units=args.units,
            **run,
        )
    elif args.experiment == "adaptive":
        from ..repro.adaptive import run_adaptive

        res = run_adaptive(out, reps=args.reps, **run)
    elif args.experiment == "user-study":
        res = repro.run_user_study(out, **run)
    elif args.experiment == "horizon":
        res = repro.run_horizon(
            out,
            horizons=args.horizons,
            instances=args.instances,
            reference_time_limit=args.reference_time_limit,
            windows=args.windows,
            reps=args.reps,
            simulation=not args.no_simulation,
            **grid,
            **run,
        )
    else:
        policies = tuple(repro.CONDITIONS)
        options = None
        if args.with_cpsat:
            policies += ("cpsat-rolling",)
            options = {"time_limit": args.cpsat_time_limit}
        res = repro.run_fig6(
            out,
            reps=args.reps,
            delivery_time=args.delivery_time,
            policies=policies,
            policy_options=options,
            **grid,
            **run,
        )
    return _report(res)


def _report(res: dict[str, Any]) -> int:
    """Print the run's Markdown summary and the files it wrote."""
    from pathlib import Path

    md = res.get("files", {}).get("markdown")
    if md and Path(md).exists():
        print(Path(md).read_text().rstrip())
    for name, path in sorted(res.get("files", {}).items()):
        print(f"wrote {name}: {path}")
    return EXIT_OK
