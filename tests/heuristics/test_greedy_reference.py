"""greedy-ce's decisions are those recorded before the sparse-graph speed-ups (issue 27,
item 3, docs/scaling.md): on sparse, in-tree, series-parallel, wide, table and mixed
instances, with capped searches, the signed form and a time limit that is not reached, the
same kits in the same order with the same layouts, the same makespan and the same scores
(tests/greedy_reference.py recorded them)."""

from __future__ import annotations

import json
import math

import pytest
from greedy_reference import CASES, REFERENCE, snapshot

RECORDED = json.loads(REFERENCE.read_text())


@pytest.mark.parametrize(
    ("name", "source", "options", "time_limit"), CASES, ids=[c[0] for c in CASES]
)
def test_plan_is_the_recorded_one(name, source, options, time_limit):
    ref, now = RECORDED[name], snapshot(source, options, time_limit)
    assert now["makespan"] == ref["makespan"]
    assert [k["tasks"] for k in now["kits"]] == [k["tasks"] for k in ref["kits"]]
    for a, b in zip(now["kits"], ref["kits"], strict=True):
        assert [p[:2] for p in a["layout"]] == [p[:2] for p in b["layout"]]
        for p, q in zip(a["layout"], b["layout"], strict=True):
            assert p[2:] == pytest.approx(q[2:], rel=1e-9, abs=1e-9)
    assert len(now["scores"]) == len(ref["scores"])
    for s, t in zip(now["scores"], ref["scores"], strict=True):
        assert s == t or (s is not None and t is not None and math.isclose(s, t, abs_tol=1e-12))
