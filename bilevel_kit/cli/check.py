"""``bilevel-kit check``: the independent checker on a solution file (exit 1 when invalid);
it believes nothing the file states (docs/formats.md)."""

from __future__ import annotations

import argparse
import sys

from .common import EXIT_INVALID, EXIT_OK, add_instance_overrides, load_instance, print_violations

HELP = "check a solution file against an instance"
DESCRIPTION = (
    "Run the independent checker on the plan and on every number the file states (kit times, "
    "metrics, objective, bound, gap, status), all recomputed from the instance; exit 1 and list "
    "the violations when anything is wrong, 2 when the file is malformed."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("instance")
    p.add_argument("solution")
    add_instance_overrides(p)


def run(args: argparse.Namespace) -> int:
    from .. import solution

    instance = load_instance(args)
    sol = solution.read(args.solution)
    violations = sol.check(instance)
    if violations:
        print_violations([str(v) for v in violations], sys.stdout)
        return EXIT_INVALID
    print(f"valid: {len(sol.plan.kits)} kits, {sum(len(k.tasks) for k in sol.plan.kits)} tasks")
    return EXIT_OK
