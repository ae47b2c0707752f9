"""``bilevel-kit compare``: instances x methods in one table (resumable cell by cell)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from .common import (
    EXIT_INVALID,
    EXIT_OK,
    EXIT_UNKNOWN,
    add_derived_outputs,
    add_instance_overrides,
    add_method_param_option,
    add_output,
    add_seed,
    add_sweep_options,
    add_time_limit,
    instance_overrides,
    method_params,
    say,
    sweep_exit,
    sweep_session,
)

if TYPE_CHECKING:
    from ..experiments import CompareCell
    from ..paths import Output

HELP = "solve instances with several methods and tabulate"
DESCRIPTION = (
    "One row per instance x method: makespan, human idle, kits, status, the best lower bound of "
    "the compared methods and the percentage above it ((makespan - best bound) / best bound, "
    "the optimum's when a method proved it), the method's own bound and own gap, checker "
    "verdict, wall time. Each cell is saved on its own under --cells, so an "
    "interrupted run resumes where it stopped; --jobs/--scheduler run the cells in parallel "
    "(docs/cluster.md). Exit 5 when a cell failed (its row says why), 1 when a plan is invalid."
)


#: How ``-p`` is spelled here; the help lists every method's keys after it.
PARAM_USAGE = "-p METHOD:KEY=VALUE"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("instances", nargs="+", metavar="INSTANCE")
    p.add_argument(
        "--methods",
        default="default",
        metavar="M1,M2",
        help="comma-separated method names, 'all' (every method) or 'default' (the default: "
        "every method but bilevel-milp, which minimises the paper's J and needs minutes for a "
        "proof, so that two runs print the same table)",
    )
    add_seed(p, "random seed of every cell (default 0)")
    add_time_limit(p, "time limit per solve for methods that take one")
    add_method_param_option(p)
    add_output(p, "--csv", metavar="FILE", help="write all record fields as CSV")
    add_output(p, "--md", metavar="FILE", help="write the table as Markdown")
    add_output(
        p,
        "--figures",
        folder=True,
        metavar="DIR",
        help="write a comparison chart, and one Gantt chart and one page of tray layouts per "
        "method, here",
    )
    add_output(p, "--cells", folder=True, metavar="DIR", help="save/resume per-cell results in DIR")
    add_derived_outputs(p, _outputs)
    add_instance_overrides(p)
    add_sweep_options(p, "solves")


def parse_methods(text: str) -> list[str]:
    """``--methods``: registered names, at least one, each once; ``all`` stands for every
    method and ``default`` for every method not registered with ``in_default=False``
    (bilevel-milp), and either may be combined with names (``default,bilevel-milp``)."""
    from ..errors import UsageError
    from ..methods import default_method_names, get_method, method_names

    methods: list[str] = []
    for m in (m.strip() for m in text.split(",")):
        if not m:
            continue
        groups = {"all": method_names, "default": default_method_names}
        named = groups[m]() if m in groups else [get_method(m).name]
        for name in named:
            if name in methods:
                raise UsageError(f"--methods {text!r}: {name!r} is named twice")
            methods.append(name)
    if not methods:
        raise UsageError(f"--methods {text!r}: name at least one method, 'default' or 'all'")
    return methods


def run(args: argparse.Namespace) -> int:
    from ..experiments import CompareCell, add_best_bound_gap, compare_cell, run_cells
    from ..experiments.cells import all_failed_line
    from ..experiments.compare import instance_fields
    from ..instance import load
    from ..methods import get_method

    methods = parse_methods(args.methods)
    params = method_params(args.param, methods)
    for m in methods:  # every method's options before any cell runs (a bad one is exit 2)
        get_method(m).parse(params[m])
    overrides = instance_overrides(args)
    for path in args.instances:  # validate every input before any solve or write
        load(path).with_overrides(**overrides)
    cells = [  # each carries its file's text, read once per file (docs/cluster.md)
        CompareCell(str(path), m, args.seed, args.time_limit, params[m], overrides, *fields)
        for path, fields in ((p, instance_fields(p)) for p in args.instances)
        for m in methods
    ]
    from .solve import prepare

    prepare(methods)
    with sweep_session(args) as session:
        raw = run_cells(cells, compare_cell, cell_dir=args.cells, desc="compare")
        records = add_best_bound_gap(_named(c, r) for c, r in zip(cells, raw, strict=True))
        everything = all_failed_line("compare", records)  # one line, not one per cell
        code = _report(args, records, quiet_errors=everything is not None)
        failed = sum(r["status"] == "error" for r in records)
        return sweep_exit(session, code, failed, everything)


def _named(cell: CompareCell, record: dict[str, Any]) -> dict[str, Any]:
    """A row for every cell: the error record of a cell that raised (rather than reporting
    an error) gets the cell's instance and method."""
    from pathlib import Path

    if "method" in record:
        return record
    return {
        "instance": Path(cell.instance).stem,
        "instance_file": cell.instance,
        "method": cell.method,
        "seed": cell.seed,
        **record,
    }


def _report(
    args: argparse.Namespace, records: list[dict[str, Any]], quiet_errors: bool = False
) -> int:
    """The table on stdout, errors on stderr (not with ``quiet_errors``: every cell failed,
    one line says so), the requested files; exit 1 on an invalid plan or a false claim, else
    3 when a method gave no plan."""
    from ..experiments import format_markdown, format_table, write_csv
    from ..experiments.compare import inconsistencies

    print(format_table(records))
    if any("(for J)" in str(r.get("status")) for r in records):
        from ..objectives import J_MEANING

        print(f"(for J): the status is about J, not the makespan. {J_MEANING}.")
    for r in records:
        if r["status"] == "error" and not quiet_errors:
            say(f"{r['instance']} / {r['method']}: {r['error']}")
    if args.figures:
        _figures(records, args.figures, instance_overrides(args))
    if args.csv:
        write_csv(args.csv, records)
    if args.md:
        from ..atomic import write_text

        write_text(args.md, format_markdown(records))
    code = EXIT_OK
    if any(
        r.get("valid") is False and r["status"] != "error" and r["makespan"] is not None
        for r in records
    ):
        say("INVALID plans found (see the 'valid' column)")
        code = EXIT_INVALID
    for line in inconsistencies(records):  # false claims: never printed as normal
        say(f"INCONSISTENT: {line}")
        code = EXIT_INVALID
    missing = [r for r in records if r["status"] != "error" and r.get("makespan") is None]
    for r in missing:  # a time limit without a plan is not success either
        say(f"NO PLAN: {r['instance']} / {r['method']} ({r['status']})")
    if missing and code == EXIT_OK:
        code = EXIT_UNKNOWN
    return code


def _figures(records: list[dict[str, Any]], folder: str, overrides: dict[str, Any]) -> None:
    """A comparison chart per instance (methods without a plan marked "no plan"), and per
    instance x method with a plan a Gantt chart and its tray layouts (of the instance as
    solved, with the command's overrides such as ``--trays``)."""
    from pathlib import Path

    from .. import plots, solution
    from ..instance import load
    from ..paths import safe_name

    out = Path(folder)
    by_instance: dict[str, list[dict[str, Any]]] = {}
    for r in records:
        by_instance.setdefault(r["instance_file"], []).append(r)
    names = _figure_names(list(by_instance), overrides)
    planned = [sum(r.get("makespan") is not None for r in rows) for rows in by_instance.values()]
    total = sum(1 + 2 * n for n in planned if n)
    # the table is printed already; drawing takes a while (trays of many kits): say so, and
    # say each file as it is written, on stderr so the table stays alone on stdout
    say(f"drawing {total} figure(s) into {out}")
    done = 0

    def save(fig: Any, path: Path) -> None:
        nonlocal done
        plots.save_figure(fig, path)
        done += 1
        say(f"figure {done}/{total}: {path}")

    for path, rows in by_instance.items():
        inst = load(path).with_overrides(**overrides)
        name = names[path]
        ok = [r for r in rows if r.get("makespan") is not None]
        if not ok:
            continue
        save(plots.plot_comparison(rows).figure, out / f"{name}_compare.png")
        for r in ok:
            sol = solution.from_dict(r["solution"], f"{path} ({r['method']})")
            method = str(r["method"])
            stem = f"{name}_{safe_name(method)}"
            save(plots.plot_gantt(inst, sol.plan, method=method).figure, out / f"{stem}_gantt.png")
            save(plots.plot_trays(inst, sol.plan, method=method), out / f"{stem}_trays.png")


def _figure_names(paths: list[str], overrides: dict[str, Any]) -> dict[str, str]:
    """Each instance file's figure name: its instance's name as a file name, told apart by
    the file's name when two instances share one."""
    from pathlib import Path

    from ..instance import load
    from ..paths import safe_name

    names: dict[str, str] = {}
    for path in paths:
        name = safe_name(load(path).with_overrides(**overrides).name)  # data, never a path
        if name in names.values():  # another file has this name: tell them apart by file
            base, i = f"{name}_{safe_name(Path(path).stem)}", 2
            name = base
            while name in names.values():
                name, i = f"{base}_{i}", i + 1
        names[path] = name
    return names


def _outputs(args: argparse.Namespace) -> list[Output]:
    """The figures ``--figures DIR`` will hold (for every method: a method may give a plan),
    declared with the output options: ``--csv``/``--md`` can be none of them."""
    from pathlib import Path

    from ..paths import Output, safe_name

    if not args.figures:
        return []
    paths = list(dict.fromkeys(str(p) for p in args.instances))
    methods = parse_methods(args.methods)
    out = []
    for name in _figure_names(paths, instance_overrides(args)).values():
        files = [f"{name}_compare.png"] + [
            f"{name}_{safe_name(m)}_{kind}.png" for m in methods for kind in ("gantt", "trays")
        ]
        out += [
            Output(f"--figures {args.figures} (its figure {f})", Path(args.figures) / f, "figure")
            for f in files
        ]
    return out
