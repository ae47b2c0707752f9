"""Rewrite the result tables of paper_repro/README.md from the CSVs in paper_repro/results/.

python paper_repro/render_readme.py [--check]
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # a plain checkout works too

from bilevel_kit.repro.report import render_readme

if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    readme = here / "README.md"
    text = readme.read_text()
    new = render_readme(text, here / "results")
    if "--check" in sys.argv[1:]:
        raise SystemExit(0 if new == text else "README.md disagrees with results/")
    readme.write_text(new)
