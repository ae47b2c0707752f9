"""Tampered solution files: whatever one changes (numbers, keys, kits, layouts), the checker
either rejects the file (a SolutionError, exit 2, or violations, exit 1) or every number the
file states is what the evaluator computes for the plan it holds, and that plan is valid.

The property is checked against the document itself, not against what the loader kept, so a
claim the loader dropped on the floor would be caught.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bilevel_kit import load, solve
from bilevel_kit.errors import SolutionError
from bilevel_kit.plan import evaluate
from bilevel_kit.solution import from_dict, result_to_dict

ROOT = Path(__file__).resolve().parents[2]
TIMES = ("robot_start", "robot_end", "arrive", "human_start", "human_end")

INSTANCES = {name: load(ROOT / "instances" / f"{name}.json") for name in ("tiny", "stool")}
DOCS = {
    (name, method): json.loads(json.dumps(result_to_dict(solve(inst, method))))
    for name, inst in INSTANCES.items()
    for method in ("single-task", "whole-assembly")
}

_values = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-3, 30),
    st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False),
    st.text(max_size=3),
    st.lists(st.integers(0, 3), max_size=2),
    st.builds(dict),
)


def _containers(doc: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Paths of every dict and list in the document."""
    out = []
    if isinstance(doc, dict):
        out.append(path)
        for k, v in doc.items():
            out += _containers(v, (*path, k))
    elif isinstance(doc, list):
        out.append(path)
        for i, v in enumerate(doc):
            out += _containers(v, (*path, i))
    return out


def _at(doc: Any, path: tuple[Any, ...]) -> Any:
    for k in path:
        doc = doc[k]
    return doc


@st.composite
def tampered(draw: st.DrawFn) -> tuple[str, dict[str, Any]]:
    """A valid solution document with 1-3 random edits."""
    key = draw(st.sampled_from(sorted(DOCS)))
    doc = copy.deepcopy(DOCS[key])
    for _ in range(draw(st.integers(1, 3))):
        where = _at(doc, draw(st.sampled_from(_containers(doc))))
        if isinstance(where, dict):
            keys = sorted(where)
            action = draw(st.sampled_from(["nudge", "set", "delete", "add"] if keys else ["add"]))
            if action == "add":
                where[draw(st.sampled_from(["x", "tasks", "bound", "gap", "zz"]))] = draw(_values)
                continue
            k = draw(st.sampled_from(keys))
            value = where[k]
            if action == "delete":
                del where[k]
            elif (
                action == "nudge" and isinstance(value, int | float) and not isinstance(value, bool)
            ):
                where[k] = value + draw(st.sampled_from([-1, -1e-3, 1e-9, 1e-3, 0.5, 7]))
            else:
                where[k] = draw(_values)
        elif where:
            i = draw(st.integers(0, len(where) - 1))
            action = draw(st.sampled_from(["drop", "duplicate", "swap", "set"]))
            if action == "drop":
                where.pop(i)
            elif action == "duplicate":
                where.insert(i, copy.deepcopy(where[i]))
            elif action == "swap":
                j = draw(st.integers(0, len(where) - 1))
                where[i], where[j] = where[j], where[i]
            else:
                where[i] = draw(_values)
    return key[0], doc


def _agrees(claimed: Any, actual: float) -> bool:
    return math.isclose(float(claimed), actual, abs_tol=1e-6, rel_tol=1e-9)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tampered())
def test_check_rejects_or_every_claim_holds(case: tuple[str, dict[str, Any]]) -> None:
    name, doc = case
    instance = INSTANCES[name]
    try:
        sol = from_dict(copy.deepcopy(doc))
    except SolutionError:
        return  # rejected: exit 2
    violations = sol.check(instance)
    if violations:
        return  # rejected: exit 1
    # accepted: the plan is the one the file describes, and every stated number is its own
    tl = evaluate(instance, sol.plan)
    assert [list(k.tasks) for k in sol.plan.kits] == [kd["tasks"] for kd in doc["kits"]]
    for kd, times in zip(doc["kits"], tl.kits, strict=True):
        for key in TIMES:
            if key in kd:
                assert _agrees(kd[key], getattr(times, key))
    for key, value in (doc.get("metrics") or {}).items():
        assert _agrees(value, tl.metrics()[key])
    # the makespan's numbers: its block's, the objective block's first when it names the
    # makespan (the two are one claim then, and a number stated in both agrees)
    own = doc.get("objective") or {"name": "makespan"}
    keys = ("value", "bound", "gap")
    claim = dict(doc.get("makespan") or {})
    if own["name"] == "makespan":
        for k in (k for k in keys if k in own):
            assert k not in claim or claim[k] == own[k]
            claim[k] = own[k]
    if claim.get("value") is not None:
        assert _agrees(claim["value"], tl.makespan)
    bound = claim.get("bound")
    if bound is not None:
        assert bound <= tl.makespan + 1e-6
    if claim.get("gap") is not None:
        assert bound is not None and abs(claim["gap"] - max(0.0, 1 - bound / tl.makespan)) < 1e-9
    if doc["status"] == "optimal" and own["name"] == "makespan":
        assert bound is not None and _agrees(bound, tl.makespan)
    assert doc["status"] != "infeasible"


@st.composite
def tampered_instance(draw: st.DrawFn) -> dict[str, Any]:
    """The stool or tiny instance document with 1-3 random edits (same edits as above)."""
    name = draw(st.sampled_from(sorted(INSTANCES)))
    doc = INSTANCES[name].to_dict()
    for _ in range(draw(st.integers(1, 3))):
        where = _at(doc, draw(st.sampled_from(_containers(doc))))
        if isinstance(where, dict) and where:
            k = draw(st.sampled_from(sorted(where)))
            if draw(st.booleans()):
                del where[k]
            else:
                where[k] = draw(_values)
        elif isinstance(where, list) and where:
            where[draw(st.integers(0, len(where) - 1))] = draw(_values)
    return doc


@settings(max_examples=300, deadline=None)
@given(
    st.one_of(
        tampered().map(lambda c: ("solution", c[1])),
        tampered_instance().map(lambda d: ("instance", d)),
    )
)
def test_fast_schema_path_agrees_with_jsonschema(case: tuple[str, dict[str, Any]]) -> None:
    """The compiled fast path accepts exactly what jsonschema accepts."""
    import jsonschema

    from bilevel_kit import instance, solution
    from bilevel_kit.jsonio import _compiled

    kind, doc = case
    schema = (solution if kind == "solution" else instance).schema()
    fast = _compiled(json.dumps(schema, sort_keys=True))
    assert fast is not None, "the fast path must cover the toolkit's own schemas"
    assert fast(doc) == jsonschema.Draft202012Validator(schema).is_valid(doc)
