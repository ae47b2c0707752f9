"""Draw docs/figures/execution-view.png: the 3-D execution view of greedy-ce's plan of the
paper's table (docs/execution.md#the-animated-3-d-view), a 1000 x 625 screenshot of the page
in headless Chromium (Debian's ``chromium``), paused during kit 2 at t = 81.4 s, the arm
carrying ``leg-2``.

python docs/figures/execution_view.py [--out docs/figures/execution-view.png]

The browser is driven by the test suite's DevTools client (tests/chromium.py); without a
Chromium the script says so and exits 1.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]  # a plain checkout works too

from chromium import Chromium, find_chromium  # noqa: E402

from bilevel_kit import atomic  # noqa: E402
from bilevel_kit.cli import main as cli  # noqa: E402

TABLE = ROOT / "instances" / "hrc_table.json"
#: The moment shown: during kit 2, the arm carrying leg-2 (s of plan time).
PAUSE_AT = 81.4
WIDTH, HEIGHT = 1000, 625
_FRAMES = "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(1))))"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures" / "execution-view.png")
    args = ap.parse_args(argv)
    binary = find_chromium()
    if binary is None:
        print("execution_view: no Chromium on this machine (Debian: apt install chromium)")
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        sol, page = Path(tmp) / "gce.json", Path(tmp) / "kitting.html"
        solve = ["solve", str(TABLE), "--method", "greedy-ce", "--out", str(sol), "-q"]
        if cli(solve) != 0 or cli(["execute", str(TABLE), str(sol), "--html", str(page)]) != 0:
            return 1
        browser = Chromium(binary, width=WIDTH, height=HEIGHT)
        try:
            browser.open(page)
            browser.evaluate(_FRAMES)
            browser.evaluate(f"bilevelKit.viewer.animator.pause(); bilevelKit.seek({PAUSE_AT}); 1")
            browser.evaluate(_FRAMES)
            png = browser.screenshot()
        finally:
            browser.close()
    with atomic.atomic_path(args.out) as tmp:
        tmp.write_bytes(png)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
