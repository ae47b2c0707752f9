"""Reference plans of greedy-ce, recorded before the sparse-graph speed-ups (issue 27, item 3)
so that tests/heuristics/test_greedy_reference.py can hold the faster code to the same
decisions: the same kits in the same order, the same layouts, the same makespan and scores.

Regenerate (only after an *intended* change of decisions, and review the diff) with
``python tests/greedy_reference.py`` from the repository root.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from bilevel_kit import check, load, solve
from bilevel_kit.generate import generate
from bilevel_kit.instance import Instance, from_dict

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "tests" / "data" / "greedy_reference.json"

#: (case name, instance file or generated family, greedy-ce options, time limit in s)
CASES: tuple[tuple[str, str, dict[str, Any], float | None], ...] = (
    ("sparse100", "instances/kitbench/sparse_n100_s1_tu_tight_d30.json", {}, None),
    ("sparse100_one_tray", "instances/kitbench/sparse_n100_s2_t1_tight_d0.json", {}, None),
    ("sparse250", "instances/kitbench/sparse_n250_s1_tu_loose_d10.json", {}, None),
    (
        "sparse100_capped",
        "instances/kitbench/sparse_n100_s1_tu_tight_d30.json",
        {"max_rest_nodes": 40, "beam_width": 16},
        None,
    ),
    (
        "sparse100_signed",
        "instances/kitbench/sparse_n100_s1_tu_tight_d30.json",
        {"signed": True},
        None,
    ),
    ("sparse_gen150", "sparse:150:7", {}, None),
    ("intree100", "instances/kitbench/intree_n100_s1_t1_tight_d30.json", {}, None),
    ("sp_gen60", "series-parallel:60:2", {}, None),
    ("wide_gen120", "wide:120:3", {}, None),
    ("table", "instances/hrc_table.json", {}, None),
    ("table_limit", "instances/hrc_table.json", {}, 600.0),
    ("table_u2", "instances/generated/table_u2.json", {}, None),
    ("mixed_u1", "instances/generated/mixed_u1.json", {}, None),
)


def instance_of(source: str) -> Instance:
    """A case's instance: a file, or ``family:size:seed`` of the generator."""
    if source.endswith(".json"):
        return load(ROOT / source)
    family, size, seed = source.split(":")
    return from_dict(generate(family, int(size), int(seed)))


def snapshot(source: str, options: dict[str, Any], time_limit: float | None) -> dict[str, Any]:
    """What the decisions fix: kits (tasks, layout), the makespan and the chosen scores."""
    inst = instance_of(source)
    res = solve(inst, "greedy-ce", seed=0, time_limit=time_limit, **options)
    assert res.plan is not None
    return {
        "violations": [v.kind for v in check(inst, res.plan)],
        "makespan": res.objective,
        "kits": [
            {
                "tasks": list(kit.tasks),
                "layout": [[p.part, p.type, p.x, p.y, p.theta] for p in kit.layout],
            }
            for kit in res.plan.kits
        ],
        "scores": [t["score"] for t in res.extra["kit_terms"]],
    }


if __name__ == "__main__":
    out = {name: snapshot(src, opts, tl) for name, src, opts, tl in CASES}
    REFERENCE.parent.mkdir(parents=True, exist_ok=True)
    REFERENCE.write_text(json.dumps(out, indent=0) + "\n")
    print({name: (v["makespan"], len(v["kits"])) for name, v in out.items()})
