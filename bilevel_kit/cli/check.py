"""``bilevel-kit check``: the independent checker on a solution file (exit 1 when invalid);
it believes nothing the file states (docs/formats.md). The instance overrides a solution
records (``--units``, ``--trays``, ...) are applied again, so a plan is checked against the
instance it was solved for."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from .common import (
    EXIT_INVALID,
    EXIT_OK,
    add_instance_overrides,
    instance_overrides,
    print_violations,
    say,
)

HELP = "check a solution file against an instance"
DESCRIPTION = (
    "Run the independent checker on the plan and on every number the file states (kit times, "
    "metrics, objective, bound, gap, status), all recomputed from the instance; exit 1 and list "
    "the violations when anything is wrong, 2 when the file is malformed. The overrides the "
    "solution was solved with (units, trays, ...) are applied again; an override option that "
    "contradicts the recorded one is refused (exit 2)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("instance")
    p.add_argument("solution")
    add_instance_overrides(p)


def _fmt(overrides: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in sorted(overrides.items()))


def run(args: argparse.Namespace) -> int:
    from .. import solution
    from ..errors import InstanceError, SolutionError, UsageError
    from ..instance import load

    sol = solution.read(args.solution)
    recorded = sol.overrides
    given = instance_overrides(args)
    clash = {k for k in given.keys() & recorded.keys() if given[k] != recorded[k]}
    if clash:
        k = sorted(clash)[0]
        raise UsageError(
            f"{args.solution}: $.overrides.{k}: the plan was solved with {k}="
            f"{recorded[k]}, but --{k.replace('_', '-')} {given[k]} was given"
        )
    instance = load(args.instance)
    try:  # the solution's own overrides: an error in one is the solution file's
        instance = instance.with_overrides(**recorded)
    except InstanceError as exc:
        raise SolutionError(args.solution, f"$.overrides{exc.path[1:]}", exc.detail) from None
    instance = instance.with_overrides(**given)
    if recorded:
        say(f"applying the solution's overrides: {_fmt(recorded)}")
    violations = sol.check(instance)
    if violations:
        print_violations([str(v) for v in violations], sys.stdout)
        if not recorded and any(v.kind == "unknown_task" for v in violations):
            say(
                "hint: the plan names tasks this instance lacks, and the file records no "
                "overrides: was it solved with --units U (task ids 'task@u')? give the same "
                "override to check"
            )
        return EXIT_INVALID
    print(f"valid: {len(sol.plan.kits)} kits, {sum(len(k.tasks) for k in sol.plan.kits)} tasks")
    return EXIT_OK
