"""The warm-up compiles every kernel greedy-ce calls (docs/scaling.md#first-run): after it,
the paper's table, the stool and generated graphs, with the options that change the kernels'
argument types (precision) and the paths that reach other kernels (penalty precedence,
polish, capped searches, snap), compile nothing more, so no time limit pays for a compile."""

from __future__ import annotations

import pytest

from bilevel_kit import load, solve
from bilevel_kit.generate import generate
from bilevel_kit.heuristics import _beam_kernel, _dfs_kernel, _kernels, _rest_kernel, warmup
from bilevel_kit.instance import from_dict

pytestmark = pytest.mark.skipif(_kernels.njit() is None, reason="numba disabled or missing")


def signatures() -> dict[str, tuple[str, ...]]:
    """Every compiled entry's signatures, by module and name."""
    out = {}
    for mod in (_kernels, _dfs_kernel, _beam_kernel, _rest_kernel):
        for name, f in vars(mod).items():
            if hasattr(f, "signatures") and hasattr(f, "py_func"):
                out[f"{mod.__name__}.{name}"] = tuple(map(str, f.signatures))
    return out


CASES = [
    ("instances/hrc_table.json", {}),
    ("instances/hrc_table.json", {"precision": "float64"}),
    ("instances/hrc_table.json", {"signed": True, "precedence": "penalty"}),
    ("instances/stool.json", {"polish": True, "snap": True}),
    ("intree:40:1", {}),
    ("sparse:40:2", {"max_rest_nodes": 40, "beam_width": 16}),
]


def test_after_the_warm_up_no_solve_compiles(root):
    assert warmup.compile_kernels() is not None
    assert warmup.ready()
    before = signatures()
    entries = ["_ce_block", "_push_apart_loop", "_score_samples"]
    for name in entries:  # the entries reached from Python, in both precisions where typed
        assert before[f"bilevel_kit.heuristics._kernels.{name}"], name
    assert len(before["bilevel_kit.heuristics._kernels._ce_block"]) == 2  # float32, float64
    for mod in (_dfs_kernel, _beam_kernel):
        assert before[f"{mod.__name__}._JITTED"], mod.__name__
    assert before["bilevel_kit.heuristics._rest_kernel._JITTED_REST"]
    for source, options in CASES:
        if source.endswith(".json"):
            inst = load(root / source)
        else:
            family, size, seed = source.split(":")
            inst = from_dict(generate(family, int(size), int(seed)))
        res = solve(inst, "greedy-ce", **options)
        assert res.plan is not None
        assert res.extra["prepare_s"] == 0.0  # compiled once per process
        assert signatures() == before, (source, options)
