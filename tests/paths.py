"""The repository's folders that tests read, defined once (not a ``parents[2]`` per module)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
INSTANCES = ROOT / "instances"
#: The committed benchmark passes (CSVs and run metadata) that the pages render.
RESULTS = ROOT / "bench" / "results"
