"""The ``fixed-plan`` policy and ``simulate --plan`` (docs/simulation.md#a-fixed-plan): a
solved plan runs in the simulator as it is, checked against the simulated instance first."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from bilevel_kit.cli import main
from bilevel_kit.errors import UsageError
from bilevel_kit.plan import evaluate
from bilevel_kit.sim import SimParams, TimingModel, effective_instance, simulate
from bilevel_kit.sim.fixed import FixedPlanPolicy, load_plan

#: greedy-ce's plan of the table with seed 0 (``solve -m greedy-ce --seed 0``), evaluated
GREEDY_TABLE = 463.78


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory: pytest.TempPathFactory, root: Path) -> Path:
    out = tmp_path_factory.mktemp("fixed") / "plan.json"
    table = str(root / "instances/hrc_table.json")
    assert main(["solve", table, "-m", "greedy-ce", "--seed", "0", "-o", str(out)]) == 0
    return out


def _simulate(root: Path, *args: str) -> int:
    return main(["simulate", str(root / "instances/hrc_table.json"), *args])


def test_mean_times_reproduce_the_plans_makespan(plan_file, root, tmp_path, capsys) -> None:
    doc = json.loads(plan_file.read_text())
    assert doc["metrics"]["makespan"] == pytest.approx(GREEDY_TABLE, abs=0.005)
    out = tmp_path / "sim.csv"
    args = ("--plan", str(plan_file), "--mean-times", "--reps", "2", "--csv", str(out))
    assert _simulate(root, *args) == 0
    assert "policy fixed-plan, 1 unit(s), 2 replication(s)" in capsys.readouterr().out
    rows = list(csv.DictReader(out.open()))
    assert [r["policy"] for r in rows] == ["fixed-plan"] * 2
    for r in rows:
        assert float(r["makespan"]) == pytest.approx(doc["metrics"]["makespan"], abs=1e-6)
        assert float(r["human_idle"]) == pytest.approx(doc["metrics"]["human_idle"], abs=1e-6)
        assert int(r["n_kits"]) == len(doc["kits"]) == 8


def test_sampled_times_are_seeded(plan_file, root, tmp_path) -> None:
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    for out in (a, b):
        assert _simulate(root, "--plan", str(plan_file), "--reps", "3", "--csv", str(out)) == 0
    assert a.read_text() == b.read_text()
    spans = [float(r["makespan"]) for r in csv.DictReader(a.open())]
    assert len(set(spans)) == 3 and all(int(r["n_kits"]) == 8 for r in csv.DictReader(a.open()))


def test_a_run_is_the_plans_timeline_under_its_sampled_times(plan_file, table) -> None:
    """Exact relation: the executed kits are the plan's, and the makespan is the evaluator's
    on the run's sampled human times (no feeders, deterministic picks)."""
    params = SimParams(timing=TimingModel(task_cv=0.3))
    eff = effective_instance(table, params)
    plan = load_plan(str(plan_file), eff)
    for seed in (0, 1):
        res = simulate(
            table, FixedPlanPolicy(eff, params=params, plan=plan), params=params, seed=seed
        )
        assert [k.tasks for k in res.plan.kits] == [k.tasks for k in plan.kits]
        want = evaluate(eff, plan, human_times=res.times.human).makespan
        assert res.makespan == pytest.approx(want, abs=1e-9)
        assert res.makespan != pytest.approx(GREEDY_TABLE, abs=0.01)


def test_default_plan_is_greedy_ce_offline(table) -> None:
    det = SimParams(timing=TimingModel.deterministic())
    res = simulate(table, "fixed-plan", params=det, seed=3)
    assert res.makespan == pytest.approx(GREEDY_TABLE, abs=0.005) and res.n_kits == 8


def test_feeder_delays_make_the_plan_wait_not_replan(plan_file, table) -> None:
    params = SimParams(mat={"leg": 60.0, "foot": 60.0}, mttf=90.0)
    eff = effective_instance(table, params)
    plan = load_plan(str(plan_file), eff)
    res = simulate(table, "fixed-plan", params=SimParams(
        mat={"leg": 60.0, "foot": 60.0}, mttf=90.0, policy_options={"plan": str(plan_file)}
    ), seed=2)  # fmt: skip
    assert res.robot_wait > 0 and res.n_waits > 0
    assert [k.tasks for k in res.plan.kits] == [k.tasks for k in plan.kits]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--trays", "2"), "computed with trays = 1, the instance has 2"),
        (("--units", "2"), "unknown task"),
        (("--delivery-time", "5"), "computed with delivery_time = 2.0"),
        (("--policy", "optimized"), "--plan runs the fixed-plan policy, not 'optimized'"),
        (("-p", "plan=x.json"), "give the plan once"),
    ],
)
def test_a_plan_that_does_not_fit_is_refused(plan_file, root, tmp_path, capsys, args, message):
    out = tmp_path / "sim.csv"
    code = _simulate(root, "--plan", str(plan_file), *args, "--csv", str(out))
    err = capsys.readouterr().err.strip()
    assert code == 2 and message in err and len(err.splitlines()) == 1
    assert "Traceback" not in err and not out.exists()
    if "policy" not in message and "once" not in message:
        assert err.startswith(f"bilevel-kit simulate: error: {plan_file}: the plan does not fit")


def test_another_instance_or_a_bad_file_is_refused(plan_file, root, tmp_path, capsys) -> None:
    stool = str(root / "instances/stool.json")
    assert main(["simulate", stool, "--plan", str(plan_file)]) == 2
    assert f"{plan_file}: the plan does not fit" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "bilevel-kit-solution/2"}')
    assert _simulate(root, "--plan", str(bad)) == 2
    err = capsys.readouterr().err
    assert f"{bad}: $: missing required field" in err and len(err.strip().splitlines()) == 1


def test_the_policy_object_checks_its_plan(plan_file, table) -> None:
    plan = load_plan(str(plan_file), table)
    with pytest.raises(UsageError, match="the plan does not fit the simulated instance"):
        FixedPlanPolicy(table.with_overrides(units=2), plan=plan)
