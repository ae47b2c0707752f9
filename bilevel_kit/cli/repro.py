"""``bilevel-kit repro``: the paper's user study (Fig. 5), Figure 6, or the adaptive-pace study
beyond the paper (see paper_repro/)."""

from __future__ import annotations

import argparse

from .common import (
    EXIT_OK,
    Subparsers,
    add_delivery_time,
    add_output,
    add_seed,
    add_sweep_options,
    nonneg,
    positive_int,
    sweep_exit,
    sweep_session,
)


def add_parser(subparsers: Subparsers) -> None:
    p = subparsers.add_parser(
        "repro",
        help="reproduce the paper's user study (Fig. 5) or Figure 6",
        description="user-study: within-subject participants x {Whole Assembly, Single Task, "
        "Optimized}, fitted on a calibration cohort to 3 of the paper's numbers, then 200 fresh "
        "studies of 18 give every other paper number a median and 95%% prediction interval. "
        "fig6: MAT x MTTF grid of the shop-floor simulation (10 tables per run), percent "
        "improvement heatmaps with ANOVA + Tukey marks; saved per cell (resumable). "
        "--jobs/--scheduler run the cells (fig6 grid points, user-study studies) in parallel "
        "(docs/cluster.md); exit 5 when a cell failed. adaptive: optimized, optimized-adaptive "
        "(learns the human's pace) and optimized-oracle over fast, median, slow and sampled "
        "participants, without and with supply delays (docs/simulation.md). See "
        "paper_repro/README.md.",
    )
    p.add_argument("experiment", choices=("user-study", "fig6", "adaptive"))
    p.add_argument(
        "--quick",
        action="store_true",
        help="a smaller run of the same experiment (fewer studies, cells, replications); "
        "its outputs say so",
    )
    add_output(
        p, "--out", folder=True, metavar="DIR", help="output folder (default out/repro/EXPERIMENT)"
    )
    add_seed(p)
    p.add_argument(
        "--reps",
        type=positive_int,
        metavar="R",
        help="fig6: replications per cell (default 30; 3 with --quick); adaptive: runs per "
        "participant group (default 10; 2 with --quick), 3R sampled participants",
    )
    p.add_argument(
        "--mats",
        type=numbers,
        metavar="30,60",
        help="fig6: the MAT values of the grid (default 30,60,90,120; 30,120 with --quick)",
    )
    p.add_argument(
        "--mttfs",
        type=numbers,
        metavar="60,90",
        help="fig6: the MTTF values of the grid (default 30,60,90,120; 60 with --quick)",
    )
    add_delivery_time(p, "fig6: delivery time (default: the instance's)")
    p.add_argument(
        "--with-cpsat",
        action="store_true",
        help="fig6: add the cpsat-rolling policy and compare it with Optimized",
    )
    p.add_argument(
        "--cpsat-time-limit",
        type=nonneg,
        default=1.0,
        metavar="S",
        help="fig6 --with-cpsat: CP-SAT time limit per decision (default 1 s)",
    )
    add_sweep_options(p)


def numbers(text: str) -> tuple[float, ...]:
    """``30,60``: one or more finite numbers > 0."""
    values = []
    for item in filter(None, (s.strip() for s in text.split(","))):
        try:
            v = float(item)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected numbers, got {item!r}") from None
        if not 0 < v < float("inf"):
            raise argparse.ArgumentTypeError(f"expected numbers > 0, got {item!r}")
        values.append(v)
    if not values:
        raise argparse.ArgumentTypeError("expected at least one number")
    return tuple(values)


def run(args: argparse.Namespace) -> int:
    with sweep_session(args) as session:
        return sweep_exit(session, _run(args))


def _run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .. import repro
    from ..paths import check_outputs

    default = "out/repro/" + args.experiment.replace("-", "_")
    check_outputs({}, {"--out": args.out or default})  # the default folder too, before any work
    if args.experiment == "adaptive":
        from ..repro.adaptive import run_adaptive

        res = run_adaptive(
            args.out or default, quick=args.quick, reps=args.reps, jobs=args.jobs, seed=args.seed
        )
    elif args.experiment == "user-study":
        out = args.out or default
        res = repro.run_user_study(out, quick=args.quick, seed=args.seed, jobs=args.jobs)
    else:
        out = args.out or default
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
            mats=args.mats,
            mttfs=args.mttfs,
        )
    md = res.get("files", {}).get("markdown")
    if md and Path(md).exists():
        print(Path(md).read_text().rstrip())
    for name, path in sorted(res.get("files", {}).items()):
        print(f"wrote {name}: {path}")
    return EXIT_OK
