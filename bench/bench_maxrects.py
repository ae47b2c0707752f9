"""The maximal-rectangles packer's cost on kits it does not lay out, against the parts of the
kit (docs/formulations.md, "CP-SAT packing"): random kits filling 97 % of a 392 x 262 tray
(seed 0), the attempts :func:`bilevel_kit.models.maxrects.attempts` allows, and with
``--all`` every one of the 48.

    python bench/bench_maxrects.py [--all] [--repeat 3]

Prints one row per kit size: parts, attempts, whether a layout was found, and the least wall
time of ``--repeat`` calls (s).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bilevel_kit.models import maxrects as mr

SIZES = (25, 50, 100, 200, 400)
TRAY = (392, 262)


def kit(parts: int, rng: np.random.Generator) -> list[tuple[int, int, bool]]:
    """``parts`` rotatable rectangles of aspect 1:3 to 3:1, 97 % of the tray's area in all."""
    s = rng.uniform(0.5, 1.5, size=(parts, 2))
    s *= np.sqrt(0.97 * TRAY[0] * TRAY[1] / (s[:, 0] * s[:, 1]).sum())
    return [(max(1, int(a)), max(1, int(b)), True) for a, b in s]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--all", action="store_true", help="every attempt (no cap by size)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print("parts  attempts  found  seconds")
    for parts in SIZES:
        sizes = kit(parts, rng)
        tries = mr.ALL_ATTEMPTS if args.all else mr.attempts(parts)
        best = float("inf")
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            out = mr.maxrects_pack(sizes, *TRAY, max_attempts=tries)
            best = min(best, time.perf_counter() - t0)
        print(f"{parts:5d}  {tries:8d}  {out is not None!s:5s}  {best:7.3f}")


if __name__ == "__main__":
    main()
