"""``bilevel-kit schema``: the JSON Schema of instance or solution files."""

from __future__ import annotations

import argparse
import json
import sys

from .common import EXIT_OK, add_output

HELP = "print the JSON Schema of instance or solution files"
DESCRIPTION = None


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--solution", action="store_true", help="the solution schema instead")
    add_output(p, "--out", "-o", metavar="FILE", help="write it to FILE instead of stdout")


def run(args: argparse.Namespace) -> int:
    if args.solution:
        from .. import solution

        doc = solution.schema()
    else:
        from ..instance import schema

        doc = schema()
    text = json.dumps(doc, indent=2) + "\n"
    if args.out:
        from ..atomic import write_text

        write_text(args.out, text)
    else:
        sys.stdout.write(text)
    return EXIT_OK
