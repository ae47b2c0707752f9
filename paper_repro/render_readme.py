"""Render paper_repro/README.md, docs/reproduction.md and the reproduction section of README.md
from their templates (paper_repro/templates/) and the committed CSVs in paper_repro/results/.

python paper_repro/render_readme.py [--check]

--check writes nothing and exits 1 with a diff when a document disagrees with its template and
the CSVs (what tests/repro/test_paper_repro_readme.py checks).
"""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # a plain checkout works too

from bilevel_kit.repro.template import check, write_all  # noqa: E402

if __name__ == "__main__":
    if "--check" in sys.argv[1:]:
        diffs = check(ROOT)
        if diffs:
            raise SystemExit("\n\n".join(diffs))
    else:
        for path in write_all(ROOT):
            print(f"rendered {path.relative_to(ROOT)}")
