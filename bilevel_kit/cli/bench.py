"""``bilevel-kit bench run | verify | update``: the KitBench library (docs/kitbench.md)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from .common import (
    EXIT_INVALID,
    EXIT_OK,
    Parser,
    add_method_param_option,
    add_output,
    add_seed,
    add_sweep_options,
    add_time_limit,
    method_params,
    say,
    sweep_exit,
    sweep_session,
)

HELP = "the KitBench library: run methods against it, verify its records, merge improvements"
DESCRIPTION = (
    "run: every (instance, method) of the library as a resumable cell (--jobs/--scheduler, "
    "docs/cluster.md); writes results.csv, results.md (each method's gap to the best-known "
    "and to the best bound), profile.png (performance profile) and gap_size.png into --out. "
    "verify: every record's plan passes the checker, its makespan is the evaluator's, every "
    "bound is at most its plan, statuses agree (exit 1 otherwise). update DIR: merge a run's "
    "better plans and higher proven bounds into the records; anything wrong refuses the whole "
    "merge (exit 2, nothing written). See docs/kitbench.md."
)
DEFAULT_LIBRARY = "instances/kitbench"
PARAM_USAGE = "-p METHOD:KEY=VALUE"

FILTER_HELP = (
    "which instances: comma-separated terms that must all hold, KEY OP VALUE with OP one of "
    "= != < <= > >= (e.g. family=intree|sparse,tasks<=130,trays=1; keys: instance, family, "
    "tray, status, tasks, trays, delivery_time, best_known, best_bound, gap)"
)


def _library_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--library",
        default=DEFAULT_LIBRARY,
        metavar="DIR",
        help=f"the library folder (default {DEFAULT_LIBRARY}, from the repository root)",
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="action", metavar="ACTION", parser_class=Parser)
    sub.required = True
    run = sub.add_parser("run", help="run methods against the library")
    _library_option(run)
    run.add_argument(
        "--methods",
        default="all",
        metavar="M1,M2",
        help="method names, 'all' (the default: every method) or 'default' (as in compare)",
    )
    add_time_limit(run, "time limit per solve (s); default: each method's own")
    add_seed(run, "random seed of every cell (default 0)")
    add_method_param_option(run)
    run.add_argument("--filter", metavar="EXPR", help=FILTER_HELP)
    add_output(run, "--out", folder=True, required=True, metavar="DIR", help="output folder")
    add_sweep_options(run, "solves")
    verify = sub.add_parser("verify", help="check every record of the library")
    _library_option(verify)
    verify.add_argument("--filter", metavar="EXPR", help=FILTER_HELP)
    update = sub.add_parser("update", help="merge a run's improvements into the records")
    _library_option(update)
    update.add_argument("runs", nargs="+", metavar="DIR", help="output folder(s) of bench run")
    update.add_argument(
        "--dry-run", action="store_true", help="check and list the changes, write nothing"
    )


def run(args: argparse.Namespace) -> int:
    return {"run": _run, "verify": _verify, "update": _update}[args.action](args)


def _run(args: argparse.Namespace) -> int:
    from ..experiments.kitbench import Library, parse_filter, run_bench, select
    from .compare import parse_methods

    library = Library.at(args.library)
    terms = parse_filter(args.filter)  # a bad filter costs nothing
    methods = parse_methods(args.methods)  # 'all' as in compare
    params = method_params(args.param, methods)
    records = select(library.read(), terms)
    if not records:
        from ..errors import UsageError

        raise UsageError(f"--filter {args.filter!r}: no instance of {args.library} matches")
    manifest = {"filter": args.filter, "command": "bilevel-kit " + " ".join(sys.argv[1:])}
    with sweep_session(args) as session:
        result = run_bench(
            library,
            records,
            methods,
            args.out,
            time_limit=args.time_limit,
            seed=args.seed,
            params=params,
            manifest=manifest,
        )
        for row in result.rows:
            if row["status"] == "error" and not result.all_failed:  # else one line says so
                say(f"{row['instance']} / {row['method']}: {row['error']}")
        print(f"{Path(args.out) / 'results.md'}:")
        print("\n".join(_summary_lines(result.summary)))
        code = EXIT_OK
        if any(r["valid"] is False for r in result.rows):
            say("INVALID plans found (see the 'valid' column)")
            code = EXIT_INVALID
        return sweep_exit(session, code, result.failed, result.all_failed)


def _summary_lines(summary: list[dict[str, Any]]) -> list[str]:
    """The per-method summary as a short text table (results.md has the whole one)."""
    from ..experiments import text_lines

    def pct(value: float | None, digits: int) -> str:
        return "-" if value is None else f"{100 * value:.{digits}f}"

    header = ["method", "plans", "within 1 % (%)", "within 5 % (%)", "median cert. gap (%)"]
    rows = [
        [
            str(t["method"]),
            f"{t['plans']}/{t['cells']}",
            pct(t["within_1%"], 0),
            pct(t["within_5%"], 0),
            pct(t["median_certified_gap"], 2),
        ]
        for t in summary
    ]
    return text_lines(header, rows)


def _verify(args: argparse.Namespace) -> int:
    from ..experiments.kitbench import Library, parse_filter, verify

    library = Library.at(args.library)
    terms = parse_filter(args.filter)
    t0 = time.perf_counter()
    records, problems = verify(library, terms)
    wall = time.perf_counter() - t0
    for p in problems:
        say(p.line())
    optimal = sum(r.status == "optimal" for r in records)
    verdict = f"{len(problems)} problem(s)" if problems else "all hold"
    print(
        f"{library.folder}: {len(records)} records ({optimal} optimal, "
        f"{len(records) - optimal} open): {verdict} ({wall:.1f} s)"
    )
    return EXIT_INVALID if problems else EXIT_OK


def _update(args: argparse.Namespace) -> int:
    from ..experiments.kitbench import Library, update

    library = Library.at(args.library)
    merge = update(library, args.runs, dry_run=args.dry_run)
    for change in merge.changes:
        print(change.line())
    plans = sum(c.what == "plan" for c in merge.changes)
    verb = "would change" if args.dry_run else "changed"
    print(
        f"{library.index_path}: {verb} {plans} plan(s) and {len(merge.changes) - plans} "
        f"bound(s) from {merge.cells} cell(s) ({merge.skipped} without a plan or bound)"
    )
    return EXIT_OK
