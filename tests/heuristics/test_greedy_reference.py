"""greedy-ce's decisions are those recorded before the sparse-graph speed-ups (issue 27,
item 3, docs/scaling.md): on sparse, in-tree, series-parallel, wide, table and mixed
instances, with capped searches, the signed form and a time limit that is not reached, the
same kits in the same order with the same layouts, the same makespan and the same scores
(tests/greedy_reference.py recorded them).

What the decisions fix is compared exactly: kits, their order, part identities, the makespan.
Layout coordinates leave the cross-entropy kernel as float32, whose last bit depends on the
CPU's SIMD path (numpy's and numba's float32 trigonometry round differently with and without
AVX2/AVX-512): one unit in the last place is 7.6e-6 mm at 64-128 mm and 6.1e-5 mm on a
1,024 mm tray, so geometry is held to ``GEOMETRY_ABS`` (a few units in the last place of the
largest tray coordinate) and the scores, computed from those coordinates in float64, to a
relative ``SCORE_REL`` (docs/scaling.md#portability)."""

from __future__ import annotations

import json
import math

import pytest
from greedy_reference import CASES, REFERENCE, snapshot

RECORDED = json.loads(REFERENCE.read_text())

#: mm (x, y) and degrees (theta): float32 ulps at the tray's scale, not a tuning knob.
GEOMETRY_ABS = 2e-4
#: the kit scores inherit the coordinates' float32 rounding (~1e-7 relative).
SCORE_REL = 1e-5


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
            assert p[2:] == pytest.approx(q[2:], rel=0, abs=GEOMETRY_ABS)
    assert len(now["scores"]) == len(ref["scores"])
    for s, t in zip(now["scores"], ref["scores"], strict=True):
        assert s == t or (
            s is not None and t is not None and math.isclose(s, t, rel_tol=SCORE_REL, abs_tol=1e-9)
        )
