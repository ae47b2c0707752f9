"""``bilevel-kit methods [NAME]``: the registered methods, or one method's options."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from .common import EXIT_OK, Subparsers

if TYPE_CHECKING:
    from ..methods import MethodSpec


def add_parser(subparsers: Subparsers) -> None:
    p = subparsers.add_parser(
        "methods",
        help="list the registered methods",
        description="Without NAME: one line per registered method. With NAME: that method's "
        "options (solve --param KEY=VALUE) with type, default and meaning.",
    )
    p.add_argument("name", nargs="?", metavar="NAME", help="a method whose options to list")


def run(args: argparse.Namespace) -> int:
    from ..methods import REGISTRY, get_method

    if args.name is None:
        for s in REGISTRY.values():
            print(f"{s.name:<16} {s.summary}")
    else:
        print(describe_method(get_method(args.name)))
    return EXIT_OK


def describe_method(spec: MethodSpec) -> str:
    """The name and summary of a method, then one line per option: name, type, default, help."""
    lines = [f"{spec.name}: {spec.summary}"]
    infos = spec.describe_options()
    if not infos:
        lines.append("takes no options")
        return "\n".join(lines)
    rows = [(i.name, i.type, _show(i.default), i.help) for i in infos]
    widths = [max(len(r[c]) for r in rows) for c in range(3)]
    lines.append("options (solve --param KEY=VALUE):")
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
