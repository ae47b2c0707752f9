"""``bilevel-kit methods [NAME]``: the registered methods, or one method's options."""

from __future__ import annotations

import argparse
from typing import Any

from .common import EXIT_OK

HELP = "list the registered methods"
DESCRIPTION = (
    "Without NAME: one line per registered method. With NAME: that method's options "
    "(solve --param KEY=VALUE) with type, default and meaning."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("name", nargs="?", metavar="NAME", help="a method whose options to list")


def run(args: argparse.Namespace) -> int:
    from ..methods import REGISTRY

    if args.name is None:
        for s in REGISTRY.values():
            print(f"{s.name:<16} {s.summary}")
    else:
        print(describe_method(args.name))
    return EXIT_OK


def describe_method(name: str) -> str:
    """The name and summary of method NAME, then one line per option: name, type, default, help
    (an unknown NAME raises the registry's usage error)."""
    from ..methods import get_method

    spec = get_method(name)
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
