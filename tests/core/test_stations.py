"""Several assembly stations (docs/timeline.md#several-stations): the format, the evaluator
on the page's worked example, the checker's station rules, and one station changing nothing."""

from __future__ import annotations

import json

import pytest
from stations_example import worked_example_doc

from bilevel_kit import Kit, Plan, check, evaluate
from bilevel_kit.errors import InstanceError
from bilevel_kit.instance import document, from_dict, load
from bilevel_kit.plan import KitTimes


def _doc(**fields):
    """The worked example of docs/timeline.md#several-stations."""
    return worked_example_doc(**fields)


def _plan(*kits):
    return Plan(tuple(Kit(tuple(k)) for k in kits))


def test_worked_example_by_hand():
    inst = from_dict(_doc())
    tl = evaluate(inst, _plan(["a1"], ["a2"], ["b1"]))
    got = [(k.robot_start, k.robot_end, k.arrive, k.human_start, k.human_end) for k in tl.kits]
    assert got == [(0, 3, 4, 4, 14.5), (4.5, 10.5, 11.5, 14.5, 19), (11.5, 15.5, 17.5, 17.5, 23.5)]
    assert tl.makespan == 23.5
    assert tl.human_idle == pytest.approx(4 + 17.5)
    assert tl.robot_idle == pytest.approx(23.5 - (4 + 7 + 6))
    assert tl.station_metrics() == {
        "A": {"completion": 19, "human_idle": pytest.approx(4), "n_kits": 2},
        "B": {"completion": 23.5, "human_idle": pytest.approx(17.5), "n_kits": 1},
    }
    assert tl.task_start["a2"] == 15 and tl.task_start["b1"] == 17.5
    assert check(inst, _plan(["a1"], ["a2"], ["b1"])) == []
    # one station: no per-station block (the four metrics say it), as documented
    parts = [{"id": "p", "width": 10, "height": 10, "pick_time": 1}]
    tasks = [{"id": "a", "parts": [], "human_time": {"mean": 3}, "robot_time": 2}]
    one = from_dict(document("one", parts, tasks, delivery_time=1, overhead=(1, 0.5)))
    assert evaluate(one, _plan(["a"])).station_metrics() == {}


def test_interleaving_and_station_humans_work_in_parallel():
    inst = from_dict(_doc())
    tl = evaluate(inst, _plan(["a1"], ["b1"], ["a2"]))
    # b1 is built while A's human works; a2 waits for the robot, not for B's human
    assert [k.human_start for k in tl.kits] == [4, 10, 17]
    assert tl.makespan == 21.5


def test_one_station_changes_no_number(tiny):
    """A declared station serving everything, with nothing of its own, is today's rule."""
    doc = tiny.to_dict()
    doc["stations"] = [{"id": "S", "serves": [tiny.tasks[0].product]}]
    one = from_dict(doc)
    for kits in (
        [["t1"], ["t2", "t3"]],
        [["t1"], ["t2"], ["t3"]],
        [["t2", "t1", "t3"]],
    ):
        for trays in (None, 1, 2):
            a = evaluate(tiny.with_overrides(trays=trays or "unlimited"), _plan(*kits))
            b = evaluate(one.with_overrides(trays=trays or "unlimited"), _plan(*kits))
            assert a.kits == b.kits and a.metrics() == b.metrics()


def test_serves_product_unit_and_unit_chains():
    doc = _doc(units=2)
    for t in doc["tasks"]:
        del t["station"]
        t["product"] = "table"
    doc["precedence"] = [["a1", "a2"]]
    doc["stations"] = [{"id": "A", "serves": ["table@1"]}, {"id": "B", "serves": ["table"]}]
    inst = from_dict(doc)
    assert {t.id: t.station for t in inst.tasks} == {
        "a1@1": "A",
        "b1@1": "A",
        "a2@1": "A",
        "a1@2": "B",
        "b1@2": "B",
        "a2@2": "B",
    }
    # units on different stations are independent: no edge joins unit 1 and unit 2
    assert sorted(inst.precedence) == [("a1@1", "a2@1"), ("a1@2", "a2@2")]
    three = from_dict(
        {
            **doc,
            "units": 3,
            "stations": [
                {"id": "A", "serves": ["table@1", "table@3"]},
                {"id": "B", "serves": ["table@2"]},
            ],
        }
    )
    # units 1 and 3 share station A: unit 1's sinks precede unit 3's sources
    assert ("a2@1", "a1@3") in three.precedence and ("b1@1", "b1@3") in three.precedence
    assert not any(a.endswith("@1") and b.endswith("@2") for a, b in three.precedence)
    assert json.loads(json.dumps(inst.to_dict())) == inst.to_dict()
    assert from_dict(inst.to_dict()).tasks == inst.tasks


@pytest.mark.parametrize(
    ("change", "path", "words"),
    [
        (lambda d: d["tasks"][1].update(station="C"), "$.tasks[1].station", "unknown station"),
        (lambda d: d["tasks"][1].pop("station"), "$.tasks[1].station", "belongs to no station"),
        (lambda d: d["stations"][1].update(delivery_time=-1), "$.stations[1].delivery_time", ""),
        (lambda d: d["stations"][0].update(trays=0), "$.stations[0].trays", ""),
        (lambda d: d["stations"][1].update(id="A"), "$.stations[1].id", "duplicate station"),
        (
            lambda d: d["stations"][1].update(serves=["chair"]),
            "$.stations[1].serves[0]",
            "no product",
        ),
        (
            lambda d: d["stations"][1].update(serves=["two@2"]),
            "$.stations[1].serves[0]",
            "unit in 1..1",
        ),
        (
            lambda d: d.update(precedence=[["a1", "b1"]]),
            "$.precedence[0]",
            "stations are independent",
        ),
        (lambda d: d.pop("stations"), "$.tasks[0].station", "declares no stations"),
    ],
)
def test_bad_stations_name_file_and_field(change, path, words):
    doc = _doc()
    change(doc)
    with pytest.raises(InstanceError) as err:
        from_dict(doc, "s.json")
    assert str(err.value).startswith(f"s.json: {path}"), str(err.value)
    assert words in str(err.value)


def test_checker_wrong_station_and_station_trays():
    inst = from_dict(_doc())
    kinds = {v.kind for v in check(inst, _plan(["a1", "b1"], ["a2"]))}
    assert kinds == {"wrong_station"}
    from bilevel_kit.validate import Claims

    empty = Plan((Kit(()), *_plan(["a1"], ["a2"], ["b1"]).kits))
    kinds = {v.kind for v in check(inst, empty, claims=Claims(objective=1.0))}
    assert "empty_kit" in kinds
    plan = _plan(["a1"], ["a2"], ["b1"])
    tl = evaluate(inst, plan)
    early = list(tl.kits)
    k = early[1]
    # kit 2 (station A, one tray) may not start before kit 1's tray is back at 4.5
    early[1] = KitTimes(4.0, k.robot_end, k.arrive, k.human_start, k.human_end)
    found = check(inst, plan, reported_kits=early)
    assert "tray_not_returned" in {v.kind for v in found}
    assert all(v.kit == 2 for v in found if v.kind == "tray_not_returned")
    # station B's kit follows A's kits but has its own trays: nothing to wait for
    assert check(inst, plan, reported_kits=tl.kits) == []


def test_methods_without_stations_refuse(tiny):
    from bilevel_kit.errors import UsageError
    from bilevel_kit.methods import solve

    inst = from_dict(_doc())
    with pytest.raises(UsageError, match="does not model several assembly stations"):
        solve(inst, "bilevel-milp")
    from bilevel_kit.sim import simulate

    with pytest.raises(UsageError, match="does not model several assembly stations"):
        simulate(inst, "greedy-ce")
    res = solve(inst, "single-task", check=True)
    assert res.extra["violations"] == []
    assert res.bound is not None and res.bound <= res.objective


def test_schema_round_trip_of_committed_files_unchanged():
    inst = load("instances/tiny.json")
    assert "stations" not in inst.to_dict() and inst.station_ids == ("",)


def test_solution_file_round_trip_checks(tmp_path):
    from bilevel_kit import solution
    from bilevel_kit.methods import solve

    inst = from_dict(_doc())
    res = solve(inst, "whole-assembly")
    assert set(res.extra["station_metrics"]) == {"A", "B"}
    path = tmp_path / "s.json"
    solution.write(path, res)
    loaded = solution.read(path)
    assert check(inst, loaded.plan, reported_kits=loaded.reported_kits, claims=loaded.claims) == []
    other = from_dict(_doc(stations=[{"id": "A"}, {"id": "B"}]))
    kinds = {v.kind for v in check(other, loaded.plan, claims=loaded.claims)}
    assert "instance_mismatch" in kinds


def test_generate_stations_splits_units_by_station():
    from bilevel_kit.generate import generate

    doc = generate("stool", 2, stations=3)
    inst = from_dict(doc)
    assert inst.units == 6 and inst.station_ids == ("S1", "S2", "S3")
    assert {t.id: t.station for t in inst.tasks if t.base_id == "a1"} == {
        "a1@1": "S1",
        "a1@2": "S1",
        "a1@3": "S2",
        "a1@4": "S2",
        "a1@5": "S3",
        "a1@6": "S3",
    }
    assert "--stations 3" in doc["description"]
    one = from_dict(generate("stool", 2, stations=1))
    plain = from_dict(generate("stool", 2))
    plan = _plan(*([t.id] for t in plain.tasks))
    assert evaluate(one, plan).metrics() == evaluate(plain, plan).metrics()


@pytest.mark.parametrize("name", ["table_u1_s2", "stool_u1_s3", "table_stool_s2"])
def test_committed_station_instances(root, name):
    from bilevel_kit.generate import generate
    from bilevel_kit.methods import solve

    path = root / "instances" / "stations" / f"{name}.json"
    inst = load(path)
    assert len(inst.station_ids) >= 2
    doc = json.loads(path.read_text())
    if "generated_by" in doc:  # made by a command: the command makes it again
        words = doc.pop("generated_by").split()
        opts = dict(zip(words[3::2], words[4::2], strict=True))
        n = int(opts["--stations"])
        again = generate(words[2], int(opts["--size"]), stations=n)
        # committed before stations got their own token (docs/formats.md#names-of-generated-
        # instances): the same instance, named _sK then, _stK now
        assert (doc.pop("name"), again.pop("name")) == (name, name.replace(f"_s{n}", f"_st{n}"))
        assert again == doc
    for method in ("single-task", "whole-assembly"):
        res = solve(inst, method, check=True)
        assert res.extra["violations"] == []
        assert res.bound <= res.objective


def test_overrides_with_stations():
    inst = from_dict(_doc())
    assert inst.with_overrides(delivery_time=3).station_params["A"].delivery_time == 3
    assert inst.with_overrides(delivery_time=3).station_params["B"].delivery_time == 2
    doc = _doc()
    for t in doc["tasks"]:
        del t["station"]
    doc["stations"] = [{"id": "A", "serves": ["two@1"]}]
    with pytest.raises(InstanceError, match="on no station"):
        from_dict(doc, "s.json").with_overrides(units=2)


def _reference(inst, plan):
    """The rule of docs/timeline.md#several-stations, written out again: (robot_start,
    arrive, human_start, human_end) per kit, and the makespan."""
    prm = inst.station_params
    free, out, past = 0.0, [], {}
    for kit in plan.kits:
        s = inst.station_of(kit.tasks[0])
        p = prm[s]
        mine = past.setdefault(s, [])
        start = free
        if p.tray_limit is not None and len(mine) >= p.tray_limit:
            start = max(start, mine[-p.tray_limit][0] + p.kit_overhead_human)
        r = inst.kit_overhead_robot + sum(inst.robot_time(t) for t in kit.tasks)
        h = p.kit_overhead_human + sum(inst.human_time(t) for t in kit.tasks)
        arrive = start + r + p.delivery_time
        hs = max(arrive, mine[-1][1] if mine else 0.0)
        mine.append((hs, hs + h))
        out.append((start, arrive, hs, hs + h))
        free = arrive
    return out, max(e for _, _, _, e in out)


@pytest.mark.parametrize("seed", range(30))
def test_evaluator_matches_the_rule_written_out(seed):
    import random

    import strategies

    inst = from_dict(strategies.stations_doc(seed, 2 + seed % 2, n=6))
    rng = random.Random(seed)
    order = _topological(inst)
    kits, cur = [], [order[0]]
    for t in order[1:]:
        if inst.station_of(t) == inst.station_of(cur[0]) and rng.random() < 0.5:
            cur.append(t)
        else:
            kits.append(cur)
            cur = [t]
    kits.append(cur)
    plan = _plan(*kits)
    tl = evaluate(inst, plan)
    want, makespan = _reference(inst, plan)
    got = [(k.robot_start, k.arrive, k.human_start, k.human_end) for k in tl.kits]
    flat = [v for row in got for v in row]
    assert flat == pytest.approx([v for row in want for v in row])
    assert tl.makespan == pytest.approx(makespan)
    per = tl.station_metrics()
    assert sum(m["human_idle"] for m in per.values()) == pytest.approx(tl.human_idle)


def _topological(inst):
    from bilevel_kit.instance import topological_order

    return topological_order(inst)


def test_one_declared_station_changes_no_committed_number(root):
    """Every committed instance, declared as one station serving all its products: the same
    times, bit for bit, for the baselines' plans."""
    from bilevel_kit.errors import KitDoesNotFit
    from bilevel_kit.methods import solve

    paths = sorted((root / "instances").glob("*.json"))
    paths += sorted((root / "instances" / "generated").glob("*.json"))
    assert len(paths) >= 8
    for path in paths:
        plain = load(path)
        doc = plain.to_dict()
        doc["stations"] = [{"id": "S", "serves": sorted({t.product for t in plain.base_tasks})}]
        one = from_dict(doc)
        for method in ("single-task", "whole-assembly"):
            try:
                plan = solve(plain, method).plan
            except KitDoesNotFit:  # a whole-assembly kit larger than the tray
                continue
            a, b = evaluate(plain, plan), evaluate(one, plan)
            assert a.kits == b.kits and a.metrics() == b.metrics(), (path.name, method)


def test_solution_file_states_each_station_and_the_checker_recomputes_it(tmp_path):
    import json

    from bilevel_kit import solution
    from bilevel_kit.methods import solve

    inst = from_dict(_doc())
    res = solve(inst, "single-task")
    path = tmp_path / "s.json"
    solution.write(path, res)
    doc = json.loads(path.read_text())
    per = res.timeline.station_metrics()
    assert doc["station_metrics"] == {s: per[s] for s in ("A", "B")}
    assert "station_metrics" not in doc["extra"]  # one copy, the checked one
    assert [k["station"] for k in doc["kits"]] == list(res.timeline.kit_stations)
    assert solution.read(path).check(inst) == []
    # a wrong completion and a kit stated for the other station are both caught
    doc["station_metrics"]["B"]["completion"] += 5.0
    first_b = next(i for i, k in enumerate(doc["kits"]) if k["station"] == "B")
    doc["kits"][first_b]["station"] = "A"
    found = solution.from_dict(doc).check(inst)
    assert sorted(v.kind for v in found) == ["times_inconsistent", "wrong_station"]
    assert any("station B: reported completion" in v.message for v in found)
    assert next(v for v in found if v.kind == "wrong_station").kit == first_b + 1
