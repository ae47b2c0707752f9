"""Golden-file comparison of CSV outputs: every number to a relative 1e-9.

The golden CSVs under ``tests/data/golden/`` were produced by the commands the golden tests
rerun; a refactor that changes any number fails them. After an *intended* change of results,
regenerate them with ``UPDATE_GOLDEN=1 pytest tests/sim tests/repro -k golden`` and review the
diff.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
from pathlib import Path
from typing import Any

GOLDEN = Path(__file__).resolve().parent / "data" / "golden"
REL = 1e-9


def _close(a: Any, b: Any, where: str) -> None:
    if isinstance(a, list) or isinstance(b, list):
        assert isinstance(a, list) and isinstance(b, list), where
        assert len(a) == len(b), f"{where}: length {len(a)} != {len(b)}"
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, f"{where}[{i}]")
    elif isinstance(a, dict) or isinstance(b, dict):
        assert isinstance(a, dict) and isinstance(b, dict), where
        assert list(a) == list(b), f"{where}: keys {list(a)} != {list(b)}"
        for k in a:
            _close(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, int | float) and not isinstance(a, bool):
        assert isinstance(b, int | float) and not isinstance(b, bool), f"{where}: {a!r} {b!r}"
        if math.isnan(a) or math.isnan(b):
            assert math.isnan(a) and math.isnan(b), f"{where}: {a!r} != {b!r}"
        else:
            assert math.isclose(a, b, rel_tol=REL, abs_tol=1e-12), f"{where}: {a!r} != {b!r}"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def _value(text: str) -> Any:
    """A CSV cell as a number, a JSON list/dict, or the text itself."""
    if text[:1] in ("[", "{"):
        return json.loads(text)
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def _read(path: Path) -> tuple[list[str], list[list[Any]]]:
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    return rows[0], [[_value(c) for c in r] for r in rows[1:]]


def assert_matches_golden(produced: str | Path, name: str) -> None:
    """Compare a produced CSV with ``tests/data/golden/<name>`` cell by cell (numbers to a
    relative 1e-9, JSON lists element-wise, text exactly); ``UPDATE_GOLDEN=1`` rewrites it."""
    golden = GOLDEN / name
    if os.environ.get("UPDATE_GOLDEN"):
        golden.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(produced, golden)
        return
    head_g, rows_g = _read(golden)
    head_p, rows_p = _read(Path(produced))
    assert head_p == head_g, f"{name}: columns changed"
    assert len(rows_p) == len(rows_g), f"{name}: {len(rows_p)} rows, golden {len(rows_g)}"
    for i, (rp, rg) in enumerate(zip(rows_p, rows_g, strict=True)):
        assert len(rp) == len(rg), f"{name} row {i + 1}: cell count"
        for col, a, b in zip(head_g, rp, rg, strict=True):
            _close(a, b, f"{name} row {i + 1} column {col!r}")


def assert_names_match_golden(names: list[str], name: str) -> None:
    """Compare a list of names (e.g. cell files) with ``tests/data/golden/<name>``."""
    golden = GOLDEN / name
    text = "".join(f"{n}\n" for n in sorted(names))
    if os.environ.get("UPDATE_GOLDEN"):
        golden.write_text(text)
        return
    assert text == golden.read_text(), f"{name}: names changed"
