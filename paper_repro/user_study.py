"""The simulated user study (paper Section V-A, Fig. 5 top): ``bilevel-kit repro user-study``.

python paper_repro/user_study.py [--quick] [--seed 0] [--out out/repro/user_study]
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # a plain checkout works too

from bilevel_kit.cli import main

if __name__ == "__main__":
    raise SystemExit(main(["repro", "user-study", *sys.argv[1:]]))
