"""Figure 6 of the paper (Section V-B): ``bilevel-kit repro fig6``.

python paper_repro/fig6.py [--quick] [--reps 30] [--jobs 2] [--d 2] [--with-cpsat]
    [--out out/repro/fig6]
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # a plain checkout works too

from bilevel_kit.cli import main

if __name__ == "__main__":
    raise SystemExit(main(["repro", "fig6", *sys.argv[1:]]))
