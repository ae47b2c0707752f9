"""``bilevel-kit repro``: the paper's user study (Fig. 5) or Figure 6 (see paper_repro/)."""

from __future__ import annotations

import argparse

from .common import (
    EXIT_OK,
    Subparsers,
    add_delivery_time,
    add_output,
    add_seed,
    nonneg,
    positive_int,
)


def add_parser(subparsers: Subparsers) -> None:
    p = subparsers.add_parser(
        "repro",
        help="reproduce the paper's user study (Fig. 5) or Figure 6",
        description="user-study: within-subject participants x {Whole Assembly, Single Task, "
        "Optimized}, fitted on a calibration cohort to 3 of the paper's numbers, then 200 fresh "
        "studies of 18 give every other paper number a median and 95%% prediction interval. "
        "fig6: MAT x MTTF grid of the shop-floor simulation (10 tables per run), percent "
        "improvement heatmaps with ANOVA + Tukey marks; saved per cell (resumable). See "
        "paper_repro/README.md.",
    )
    p.add_argument("experiment", choices=("user-study", "fig6"))
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
        help="fig6: replications per cell (default 30; 3 with --quick)",
    )
    p.add_argument("--jobs", type=positive_int, default=1, help="fig6: parallel cells")
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


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .. import repro
    from ..paths import check_outputs

    default = "out/repro/user_study" if args.experiment == "user-study" else "out/repro/fig6"
    check_outputs({}, {"--out": args.out or default})  # the default folder too, before any work
    if args.experiment == "user-study":
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
        )
    md = res.get("files", {}).get("markdown")
    if md and Path(md).exists():
        print(Path(md).read_text().rstrip())
    for name, path in sorted(res.get("files", {}).items()):
        print(f"wrote {name}: {path}")
    return EXIT_OK
