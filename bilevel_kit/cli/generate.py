"""``bilevel-kit generate``: write a generated instance (see :mod:`bilevel_kit.generate`)."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from .common import (
    EXIT_OK,
    add_delivery_time,
    add_output,
    add_seed,
    length,
    positive,
    positive_int,
    trays,
)

HELP = "write a generated instance"
DESCRIPTION = (
    "Families: table (units of the paper's table), mixed (table + stool + chair per unit), "
    "stool (units of the stool of Fig. 2), intree, series-parallel, wide (many short chains) "
    "and sparse (each task has a one-in-five chance of an arc to one of the next 40 tasks; 6 "
    "part types): random task graphs of SIZE tasks (--tightness = total part area / tray "
    "area). The file records the command that made it (its generated_by field)."
)


def tray_size(text: str) -> tuple[float, float]:
    """``--tray 160x120``: width x height in mm, each a length in the instances' range."""
    w, sep, h = text.lower().partition("x")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in mm, e.g. 160x120, got {text!r}")
    return length(w.strip()), length(h.strip())


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..generate import FAMILIES

    p.add_argument("family", help=" | ".join(FAMILIES))
    p.add_argument("--size", type=positive_int, required=True, help="units or tasks")
    add_seed(p, "random seed (random families; default 0)", default=None)
    p.add_argument(
        "--tightness",
        type=positive,
        metavar="T",
        help="part area / tray area (random families; default 0.6)",
    )
    add_delivery_time(p, "delivery time d (default: the family's)")
    p.add_argument(
        "--trays",
        type=trays,
        metavar="T",
        help="kit trays in circulation, an integer >= 1 or 'unlimited' (default: the "
        "family's: 1 for the table, unlimited for the others)",
    )
    p.add_argument(
        "--tray",
        type=tray_size,
        metavar="WxH",
        help="the tray's width x height in mm, replacing the family's (not with --tightness)",
    )
    p.add_argument("--name", metavar="NAME", help="the instance's name (default: the family's)")
    p.add_argument(
        "--stations",
        type=positive_int,
        metavar="S",
        help="S assembly stations served by one robot, each building --size units of the "
        "family's products (docs/timeline.md#several-stations)",
    )
    add_output(p, "--out", "-o", metavar="FILE", help="write here instead of stdout")


def run(args: argparse.Namespace) -> int:
    from ..errors import UsageError
    from ..generate import PRODUCTS, command_line, generate
    from ..instance import from_dict

    if args.family in PRODUCTS:  # deterministic families: nothing to seed or size
        for option, value in (("--tightness", args.tightness), ("--seed", args.seed)):
            if value is not None:
                raise UsageError(
                    f"{option} applies to the random families (intree, series-parallel, wide, "
                    f"sparse), not to {args.family!r}"
                )
    seed = 0 if args.seed is None else args.seed
    options = {"trays": args.trays, "tray": args.tray, "name": args.name, "stations": args.stations}
    doc = generate(args.family, args.size, seed, args.tightness, args.delivery_time, **options)
    cmd = command_line(args.family, args.size, seed, args.tightness, args.delivery_time, **options)
    doc = _with_command(doc, cmd)
    from_dict(doc, f"<generated {args.family}>")  # never write an instance that doesn't load
    text = json.dumps(doc, indent=2, allow_nan=False) + "\n"
    if args.out:
        from ..atomic import write_text

        write_text(args.out, text)
        print(
            f"wrote {args.out}: {doc['name']}, {len(doc['tasks'])} tasks x "
            f"{doc.get('units', 1)} unit(s)"
            + (f" on {len(doc['stations'])} station(s)" if "stations" in doc else "")
        )
    else:
        sys.stdout.write(text)
    return EXIT_OK


def _with_command(doc: dict[str, Any], command: str) -> dict[str, Any]:
    """``doc`` with ``generated_by`` right after its description (where a reader looks)."""
    out: dict[str, Any] = {}
    for key, value in doc.items():
        out[key] = value
        if key == "description":
            out["generated_by"] = command
    out.setdefault("generated_by", command)
    return out
