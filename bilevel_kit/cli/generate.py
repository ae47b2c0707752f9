"""``bilevel-kit generate``: write a generated instance (see :mod:`bilevel_kit.generate`)."""

from __future__ import annotations

import argparse
import json
import sys

from .common import EXIT_OK, add_delivery_time, add_output, add_seed, positive, positive_int

HELP = "write a generated instance"
DESCRIPTION = (
    "Families: table (units of the paper's table), mixed (table + stool + chair per unit), "
    "intree and series-parallel (random task graphs of SIZE tasks; --tightness = total part "
    "area / tray area)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("family", help="table | mixed | intree | series-parallel")
    p.add_argument("--size", type=positive_int, required=True, help="units or tasks")
    add_seed(p, "random seed (random families; default 0)", default=None)
    p.add_argument(
        "--tightness",
        type=positive,
        metavar="T",
        help="part area / tray area (random families; default 0.6)",
    )
    add_delivery_time(p, "delivery time d (default: the family's)")
    add_output(p, "--out", "-o", metavar="FILE", help="write here instead of stdout")


def run(args: argparse.Namespace) -> int:
    from ..errors import UsageError
    from ..generate import generate
    from ..instance import from_dict

    if args.family in ("table", "mixed"):  # deterministic families: nothing to seed or size
        for option, value in (("--tightness", args.tightness), ("--seed", args.seed)):
            if value is not None:
                raise UsageError(
                    f"{option} applies to the random families (intree, series-parallel), "
                    f"not to {args.family!r}"
                )
    doc = generate(
        args.family,
        args.size,
        0 if args.seed is None else args.seed,
        0.6 if args.tightness is None else args.tightness,
        args.delivery_time,
    )
    from_dict(doc, f"<generated {args.family}>")  # never write an instance that doesn't load
    text = json.dumps(doc, indent=2, allow_nan=False) + "\n"
    if args.out:
        from ..atomic import write_text

        write_text(args.out, text)
        print(
            f"wrote {args.out}: {doc['name']}, {len(doc['tasks'])} tasks x "
            f"{doc.get('units', 1)} unit(s)"
        )
    else:
        sys.stdout.write(text)
    return EXIT_OK
