"""Simulated user study (paper Section V-A, Fig. 5 top), side by side with the paper.

    python paper_repro/user_study.py --out out/repro [--quick] [--seed 0] [--studies 20]

Writes ``<out>/user_study/``: runs CSV, summary CSV, Markdown table, JSON and fig5_top.png.
"""

from __future__ import annotations

import sys
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from paper_repro.common import base_parser, ensure_importable, print_files


def main(argv: list[str] | None = None) -> int:
    p = base_parser(__doc__.splitlines()[0], "out/repro")
    p.add_argument(
        "--studies",
        type=int,
        default=None,
        help="repeated studies for the sampling spread (default 20, quick 2)",
    )
    p.add_argument(
        "--buffer",
        default="0",
        help="kits that may wait at the human: 0 (the study's protocol) or 'none'",
    )
    args = p.parse_args(argv)
    ensure_importable()
    from bilevel_kit.repro import run_user_study

    buffer = None if args.buffer.lower() == "none" else int(args.buffer)
    res = run_user_study(
        Path(args.out) / "user_study",
        quick=args.quick,
        seed=args.seed,
        jobs=args.jobs,
        n_studies=args.studies,
        buffer=buffer,
    )
    print(Path(res["files"]["markdown"]).read_text())
    print(f"wall time {res['wall_s']:.1f} s")
    print_files(res)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
