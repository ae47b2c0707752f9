"""The gap-versus-size figures of the committed KitBench passes (docs/kitbench.md#performance-
profiles): redrawn from the passes' rows by ``python bench/kitbench_docs.py --gap-size``, each
solve's own plan and bound kept, the gap graded against the best bound known now."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

from bilevel_kit.experiments.kitbench import Library

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def docs_script():
    spec = importlib.util.spec_from_file_location(
        "kitbench_docs", ROOT / "bench" / "kitbench_docs.py"
    )
    module = importlib.util.module_from_spec(spec)
    argv, sys.argv = sys.argv, ["kitbench_docs.py"]
    try:
        spec.loader.exec_module(module)
    finally:
        sys.argv = argv
    return module


@pytest.fixture(scope="module")
def records():
    return Library.at(ROOT / "instances" / "kitbench").read()


@pytest.mark.parametrize(
    ("label", "lowered", "zeros"),
    [
        ("60s", 144, {"cpsat": 22, "milp": 23, "lns": 31}),
        ("10s", 201, {"cpsat": 14, "milp": 18, "lns": 0}),
    ],
)
def test_a_pass_regraded_keeps_its_plans_and_only_lowers_gaps(
    docs_script, records, label, lowered, zeros
) -> None:
    """Every solve's plan, bound and validity are the committed row's; a record proven or
    raised since the pass can only lower a certified gap (``lowered`` rows did), never raise
    one; ``zeros``: each exact method's gaps of 0, the figure's legend counts."""
    old = docs_script.read_rows(docs_script.RESULTS / f"kitbench_{label}.csv")
    new = docs_script.result_rows(records, docs_script.cells_of(old))
    assert len(new) == len(old)
    for o, n in zip(old, new, strict=True):
        assert (n["instance"], n["method"], n["makespan"], n["valid"]) == (
            o["instance"],
            o["method"],
            o["makespan"],
            o["valid"],
        )
        assert n["bound"] == (float(o["bound"]) if o["bound"] else None)
    drops = [
        float(o["certified_gap"]) - n["certified_gap"]
        for o, n in zip(old, new, strict=True)
        if n["certified_gap"] is not None
    ]
    assert min(drops) >= -1e-12
    assert sum(d > 1e-12 for d in drops) == lowered
    for method, count in zeros.items():
        mine = [n for n in new if n["method"] == method and n["certified_gap"] is not None]
        assert sum(n["certified_gap"] <= 1e-11 for n in mine) == count
