"""Figure 6 of the paper: Optimized vs Single Task / Whole Assembly over a MAT x MTTF grid.

    python paper_repro/fig6.py --out out/repro [--quick] [--reps 30] [--jobs 2]
        [--delivery-time 2] [--policies single-task,whole-assembly,optimized]

Resumable: cells are saved under ``<out>/fig6/cells/`` as they finish; rerun the same command
after an interruption and only the missing cells are computed.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from paper_repro.common import base_parser, ensure_importable, print_files


def main(argv: list[str] | None = None) -> int:
    p = base_parser(__doc__.splitlines()[0], "out/repro")
    p.add_argument("--reps", type=int, default=None, help="replications (default 30, quick 3)")
    p.add_argument(
        "--delivery-time",
        type=float,
        default=None,
        help="delivery time d in s (default: the instance's)",
    )
    p.add_argument(
        "--policies", default=None, help="comma-separated policies (default the paper's three)"
    )
    p.add_argument(
        "--buffer",
        default="0",
        help="kits that may wait at the human: 0 (one tray, default) or 'none'",
    )
    args = p.parse_args(argv)
    ensure_importable()
    from bilevel_kit.repro import CONDITIONS, run_fig6

    policies = tuple(args.policies.split(",")) if args.policies else CONDITIONS
    buffer = None if args.buffer.lower() == "none" else int(args.buffer)
    res = run_fig6(
        Path(args.out) / "fig6",
        quick=args.quick,
        reps=args.reps,
        jobs=args.jobs,
        delivery_time=args.delivery_time,
        seed=args.seed,
        policies=policies,
        buffer=buffer,
    )
    print(Path(res["files"]["markdown"]).read_text())
    print(
        f"{res['cells']} cells ({res['computed']} computed, {res['reused']} reused), "
        f"wall time {res['wall_s']:.1f} s"
    )
    print_files(res)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
