"""``bilevel-kit methods [NAME]``: the registered methods, or one method's (or simulation
policy's) options."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from .common import EXIT_OK

HELP = "list the registered methods"
DESCRIPTION = (
    "Without NAME: one line per registered method (in brackets: left out of compare's "
    "default set, [stations] when it plans for several assembly stations, the objectives it "
    "minimises besides the makespan), then a line on what J (bilevel-milp's "
    "objective) is. With NAME: that method's options "
    "(solve --param KEY=VALUE) with type, default and meaning; NAME may also be a simulation "
    "policy that is not a method (optimized, cpsat-rolling: simulate --param KEY=VALUE)."
)

if TYPE_CHECKING:
    from ..methods import MethodSpec
    from ..options import Registered


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "name", nargs="?", metavar="NAME", help="a method or policy whose options to list"
    )


def run(args: argparse.Namespace) -> int:
    from ..methods import REGISTRY

    if args.name is None:
        from ..objectives import J_MEANING

        for s in REGISTRY.values():
            print(f"{s.name:<16} {s.summary}{_notes(s)}")
        if any(" J " in s.summary for s in REGISTRY.values()):
            print(f"\n{J_MEANING}.")
    else:
        print(describe_method(find(args.name)))
    return EXIT_OK


def _notes(spec: MethodSpec) -> str:
    """What a method's spec declares beyond its summary, in brackets: left out of
    ``compare``'s default set, plans for several stations, objectives besides the makespan."""
    notes = [] if spec.in_default else ["not in compare's default set: name it"]
    if spec.supports_stations:
        notes.append("stations")
    if (names := spec.objective_names()) != ("makespan",):
        notes.append(f"objectives: {', '.join(names)}")
    return f" [{'; '.join(notes)}]" if notes else ""


def find(name: str) -> Registered:
    """The method ``name``, else the simulation policy ``name`` (methods win: the baselines
    are both, and their policies take no options either)."""
    from ..methods import REGISTRY, get_method
    from ..sim.registry import POLICIES

    if name not in REGISTRY and name in POLICIES:
        return POLICIES.spec(name)
    if name not in REGISTRY:
        from ..errors import UsageError

        policies = [p for p in POLICIES if p not in REGISTRY]
        raise UsageError(
            f"unknown method or policy {name!r}; methods: {', '.join(REGISTRY)}; "
            f"simulation policies: {', '.join(policies)}"
        )
    return get_method(name)


def describe_method(spec: Registered) -> str:
    """The name and summary of a method or policy, then one line per option: name, type,
    default, help."""
    policy = spec.kind == "policy"
    lines = [f"{spec.name}: {spec.summary}" + (" (simulation policy)" if policy else "")]
    infos = spec.describe_options()
    if not infos:
        lines.append("takes no options")
        return "\n".join(lines)
    rows = [(i.name, i.type, _show(i.default), i.help) for i in infos]
    widths = [max(len(r[c]) for r in rows) for c in range(3)]
    lines.append(f"options ({'simulate' if policy else 'solve'} --param KEY=VALUE):")
    for name, tp, default, text in rows:
        lines.append(
            f"  {name:<{widths[0]}}  {tp:<{widths[1]}}  default {default:<{widths[2]}}  {text}"
        )
    return "\n".join(line.rstrip() for line in lines)


def _show(value: Any) -> str:
    """A default as it would be written on the command line."""
    if value is None:
        return "none"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)
