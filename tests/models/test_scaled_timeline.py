"""The timelines outside the one evaluator, held to it (issue 36, item 4): CP-SAT's timeline on
integer times (``scaled_timeline``, ``scaled_makespan``), its makespan with release times
(``released_makespan``) and the large-neighbourhood search's suffix response
(``tail_response``) and window edge (``window_edge``). They stay separate for speed (integer
times, empty kit positions, symbolic max-plus forms); these properties say they are the
timeline of docs/timeline.md all the same, on random plans with trays 1, 2 and unlimited."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reference_timeline import close, reference
from strategies import timeline_cases

from bilevel_kit.instance import from_dict
from bilevel_kit.models.cpsat.scaling import (
    released_makespan,
    scale_times,
    scaled_makespan,
    scaled_objective,
    scaled_timeline,
)
from bilevel_kit.models.lns.state import kit_times, tail_response, window_edge
from bilevel_kit.plan import Kit, Plan, evaluate
from bilevel_kit.stations import objective_of

MANY = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _case(case):
    """The instance, its plan as task ids and as task indices, and the evaluator's timeline."""
    doc, kits = case
    inst = from_dict(doc)
    idx = inst.index
    tl = evaluate(inst, Plan(tuple(Kit(tuple(k)) for k in kits)))
    return inst, kits, [[idx[t] for t in k] for k in kits], tl


@MANY
@given(timeline_cases(max_stations=0, grid=True), st.integers(0, 3))
def test_scaled_timeline_is_the_evaluator_on_an_exact_grid(case, empty):
    """Times on 1/8 s: the grid is exact and every kit's robot start, arrival and human end
    are the evaluator's; trailing empty kit positions (the model's unused kits) change
    nothing."""
    inst, _, kits, tl = _case(case)
    sc = scale_times(inst, 0.1)
    assert sc.exact
    rows = scaled_timeline(sc, kits + [[]] * empty)
    for (start, arrive, end), kt in zip(rows, tl.kits, strict=False):
        assert close(start * sc.res, kt.robot_start)
        assert close(arrive * sc.res, kt.arrive)
        assert close(end * sc.res, kt.human_end)
    assert close(scaled_makespan(sc, kits + [[]] * empty) * sc.res, tl.makespan)


@MANY
@given(timeline_cases(max_stations=3, grid=True), st.integers(0, 3))
def test_scaled_timeline_with_stations_is_the_reference(case, empty):
    """One to three stations (declared or not) on an exact grid: every kit's robot start,
    arrival and human end are those of the independent reference timeline
    (tests/reference_timeline.py), and the makespan, the sum of completions and the human
    idle (the model's expression plus its dropped constant) the evaluator's."""
    inst, ids, kits, tl = _case(case)
    sc = scale_times(inst, 0.1)
    assert sc.exact
    ref = reference(inst, ids)
    rows = scaled_timeline(sc, kits + [[]] * empty)
    for (start, arrive, end), kt in zip(rows, ref.kits, strict=False):
        assert close(start * sc.res, kt.robot_start)
        assert close(arrive * sc.res, kt.arrive)
        assert close(end * sc.res, kt.human_end)
    assert close(scaled_makespan(sc, kits) * sc.res, tl.makespan)
    done = objective_of(tl, "sum_completion")  # (one station: the makespan)
    assert close(scaled_objective(sc, kits, "sum_completion") * sc.res, done)
    idle = (scaled_objective(sc, kits, "human_idle") - sum(sc.h)) * sc.res
    assert close(idle, tl.human_idle, 1e-7)


@MANY
@given(timeline_cases(max_stations=0))
def test_scaled_makespan_is_a_lower_bound_off_the_grid(case):
    """Any times: rounded down when off the grid, so the scaled makespan never exceeds the
    evaluator's (docs/formulations.md: the model's bound stays valid), and is the evaluator's
    when the grid is exact."""
    inst, _, kits, tl = _case(case)
    sc = scale_times(inst, 0.1)
    value = scaled_makespan(sc, kits) * sc.res
    assert value <= tl.makespan * (1 + 1e-9) + 1e-9
    if sc.exact:
        assert close(value, tl.makespan)


@MANY
@given(timeline_cases(max_stations=0, grid=True), st.data())
def test_released_makespan_is_the_reference_with_releases(case, data):
    """Release times in half seconds on some tasks, precedence along the plan's order: the
    makespan is the reference timeline's with the same releases (raised to the ancestors',
    each kit picked in order of release); no releases (or all 0): the evaluator's."""
    doc, kits = case
    order = [t for k in kits for t in k]
    pairs = [(a, b) for i, a in enumerate(order) for b in order[i + 1 :]]
    doc["precedence"] = [list(e) for e in pairs if data.draw(st.booleans())]
    inst, kits, _, tl = _case((doc, kits))
    plan = Plan(tuple(Kit(tuple(k)) for k in kits))
    rel = {t: data.draw(st.integers(0, 120)) / 2 for t in order if data.draw(st.booleans())}
    assert close(released_makespan(inst, plan, {t: 0.0 for t in order}), tl.makespan)
    ref = reference(inst, kits, releases=rel)
    assert close(released_makespan(inst, plan, rel), ref.makespan)
    assert ref.makespan >= tl.makespan - 1e-9  # releases only delay


@MANY
@given(timeline_cases(max_tasks=9, max_stations=0, grid=True))
def test_tail_response_and_window_edge_are_the_evaluator(case):
    """At every cut ``k1``: the window edge (arrival, human end, the human starts of the
    last T kits) is the evaluator's, and the suffix's max-plus response to the end state of
    kits ``[0, k1)`` gives the evaluator's makespan."""
    inst, _, kits, tl = _case(case)
    sc = scale_times(inst, 0.1)
    for k1 in range(1, len(kits) + 1):
        edge = window_edge(sc, kits, k1)
        last = tl.kits[k1 - 1]
        assert close(edge.arrive * sc.res, last.arrive)
        assert close(edge.end * sc.res, last.human_end)
        starts = [kt.human_start for kt in tl.kits[:k1]]
        kept = starts[-sc.trays :] if sc.trays is not None else []
        assert len(edge.starts) == len(kept)
        assert all(close(a * sc.res, b) for a, b in zip(edge.starts, kept, strict=True))
        prefix = scaled_timeline(sc, kits[:k1])
        state = {"A": prefix[-1][1], "E": prefix[-1][2]}
        for j, (row, kit) in enumerate(
            zip(reversed(prefix), reversed(kits[:k1]), strict=True), start=1
        ):
            state[f"HS{j}"] = row[2] - kit_times(sc, kit)[1]
        form = tail_response(sc, kits[k1:], k1)
        assert close(max(state[v] + c for v, c in form.items()) * sc.res, tl.makespan)
