"""A plugin adds an objective (docs/extending.md#adding-an-objective, issue 36): the example
plugin's ``kit_handling`` (the makespan plus 2 x the human's kit handling ``sum_s o_H,s m_s``)
is taken by ``cpsat`` and ``milp`` as they are, checked by ``check``, listed by ``bilevel-kit
methods`` and held by ``compare``; its optimum equals a brute force over every plan, timed by
the reference timeline (tests/reference_timeline.py, not the package's evaluator)."""

from __future__ import annotations

import csv
import math

import pytest
from brute import assert_objective_optimal, fits, segmentations
from reference_timeline import close, timeline, times_of
from strategies import random_doc, stations_doc

from bilevel_kit import UsageError, solve
from bilevel_kit.bounds import best_bound
from bilevel_kit.cli import main
from bilevel_kit.instance import from_dict
from bilevel_kit.objectives import OBJECTIVES, model_objectives
from bilevel_kit.plan import Kit, Plan, evaluate
from bilevel_kit.validate import Claims, check

pytest.importorskip("ortools")
pytest.importorskip("pyomo")

#: On the paper's table (o_H = 4 s): the makespan optimum (435.085 s) has 5 kits, so
#: 435.085 + 2 x 5 x 4 = 475.085; kit_handling's optimum trades 13.695 s of makespan for two
#: kits fewer: 448.78 + 2 x 3 x 4 = 472.78 (both proven by cpsat and milp).
TABLE_OPTIMUM = 472.78
TABLE_MAKESPAN = 448.78


def brute_kit_handling(inst, weight: int) -> float:
    """The least ``makespan + weight * sum_k o_H,s(k)`` over every valid plan (every order cut
    into kits of one station's tasks, each kit with parts and fitting the tray), timed by the
    reference timeline; the package's evaluation of the plugin objective is held to it on
    every plan."""
    times = times_of(inst)
    needs = {t.id for t in inst.tasks if inst.needs_kit(t.id)}
    best = math.inf
    for kits in segmentations(inst):
        if any(needs.isdisjoint(k) for k in kits) or not all(fits(inst, k) for k in kits):
            continue
        ref = timeline(times, kits)
        handling = sum(times.stations[k.station].overhead_human for k in ref.kits)
        value = ref.makespan + weight * handling
        tl = evaluate(inst, Plan(tuple(Kit(k) for k in kits)))
        assert close(OBJECTIVES["kit_handling"].value(tl), value), kits
        best = min(best, value)
    return best


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_the_exact_methods_minimise_the_plugin_objective(pairs, table, method):
    """On the table both prove the same optimum; the result checks, states the registry's
    evaluation of its timeline, and beats the makespan-optimal plan on the objective."""
    from bk_example_plugin import kit_handling

    res = solve(table, method, objective="kit_handling", check=True, time_limit=120)
    assert res.extra["violations"] == []
    assert res.status == "optimal" and res.status_objective == "kit_handling"
    assert res.status_text == "optimal (for kit_handling)"
    value = OBJECTIVES["kit_handling"].value(res.timeline)
    assert value == pytest.approx(kit_handling(res.timeline))
    assert res.objective_name == "kit_handling"
    assert res.objective == pytest.approx(value, abs=1e-9)
    assert res.bound == pytest.approx(value, abs=1e-6)
    assert res.gap == pytest.approx(0.0, abs=1e-9)
    assert value == pytest.approx(TABLE_OPTIMUM, abs=1e-6)
    assert res.makespan == pytest.approx(TABLE_MAKESPAN, abs=1e-6)
    assert len(res.plan.kits) == 3
    # the makespan is a metric with its own bound: at least the closed form's and at most the
    # makespan optimum, 435.085 s
    assert best_bound(table) <= res.makespan_bound <= 435.085 + 1e-9


@pytest.mark.parametrize(
    ("label", "doc", "optimum"),
    [  # the makespan-optimal plans score 100.5 and 82.5: a makespan model would fail here
        ("one station", random_doc(3, 6), 97.0),
        ("two stations", stations_doc(8, 2, n=5), 80.0),
    ],
)
@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_its_optimum_is_the_brute_force(pairs, method, label, doc, optimum):
    """The optimum each exact method proves (for every plan, or for 0/90-degree plans, which
    the brute force's exact 1 mm grid holds too) is the brute force's."""
    from bk_example_plugin import HANDLING_WEIGHT

    inst = from_dict(doc)
    opt = brute_kit_handling(inst, HANDLING_WEIGHT)
    assert opt == pytest.approx(optimum)
    res = solve(inst, method, objective="kit_handling", check=True, time_limit=60)
    assert res.extra["violations"] == [], res.extra["violations"]
    assert_objective_optimal(res, opt)
    assert OBJECTIVES["kit_handling"].value(res.timeline) == pytest.approx(opt, abs=1e-5)


def test_check_holds_a_stated_plugin_objective(pairs, tiny):
    """``check`` holds the plugin objective's stated numbers like a built-in's."""
    from bilevel_kit.heuristics.baselines import single_task

    plan = single_task(tiny).plan  # one kit per task, laid out
    value = OBJECTIVES["kit_handling"].value(evaluate(tiny, plan))
    assert value == pytest.approx(evaluate(tiny, plan).makespan + 2 * 0.5 * 3)

    def kinds(status: str, **extra: float) -> list[str]:
        stated = {"objective_value": value, "objective_bound": value, "objective_gap": 0.0}
        stated.update(extra)  # a format-2 file's objective block: value, bound, gap
        numbers = (stated["objective_value"], stated["objective_bound"], stated["objective_gap"])
        claims = Claims(
            status=status,
            status_objective="kit_handling",
            objective_claims=(*numbers, True),
        )
        return sorted(v.kind for v in check(tiny, plan, claims=claims))

    assert kinds("optimal") == []
    assert kinds("feasible", objective_value=value - 1) == ["objective_mismatch"]
    assert kinds("feasible", objective_bound=value + 1) == ["bound_above_objective"]
    assert kinds("feasible", objective_gap=0.5) == ["gap_mismatch"]


def test_the_option_takes_it_only_while_registered(pairs, tiny, root, capsys):
    """``-p objective=`` is checked against the registry when parsed: the plugin's objective
    is a choice of cpsat and milp (and listed), a misspelt one a one-line exit 2."""
    assert model_objectives()[-1] == "kit_handling"
    with pytest.raises(UsageError, match=r"^method 'cpsat': option 'objective': must be one of"):
        solve(tiny, "cpsat", objective="kit_handlin")
    tiny_file = str(root / "instances" / "tiny.json")
    assert main(["solve", tiny_file, "-m", "milp", "-p", "objective=speed"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "'kit_handling', got 'speed'" in err
    assert "method 'milp': option 'objective'" in err
    assert main(["methods"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("cpsat "))
    assert line.endswith("objectives: makespan, sum_completion, human_idle, kit_handling]")
    assert main(["methods", "milp"]) == 0
    assert "'human_idle' | 'kit_handling'" in capsys.readouterr().out
    OBJECTIVES.remove("kit_handling")  # (the fixture's teardown removes it again: a no-op)
    with pytest.raises(UsageError, match="must be one of 'makespan', 'sum_completion', "):
        solve(tiny, "cpsat", objective="kit_handling")


def test_compare_holds_it(pairs, root, tmp_path):
    """``compare`` runs cpsat on the plugin objective; its row is valid."""
    out = tmp_path / "compare.csv"
    table = str(root / "instances" / "hrc_table.json")
    args = ["compare", table, "--methods", "cpsat", "-p", "cpsat:objective=kit_handling"]
    assert main([*args, "--csv", str(out), "-q", "--time-limit", "60"]) == 0
    row = next(csv.DictReader(out.open()))
    assert row["valid"] == "True" and float(row["makespan"]) == pytest.approx(TABLE_MAKESPAN)


def test_registering_a_bad_objective_is_refused():
    """Only an :class:`~bilevel_kit.objectives.Objective`; a modelled one defines its bound,
    horizon and expression; a name is lower-case and registered once."""
    from dataclasses import replace

    from bilevel_kit.objectives import Objective, register

    with pytest.raises(UsageError, match=r"is not a bilevel_kit\.objectives\.Objective"):
        register("kit_handling")  # type: ignore[arg-type]
    bare = Objective("bare", "a bare one", lambda tl: tl.makespan, ("v",), ("b",), ("g",))
    with pytest.raises(UsageError, match="'bare' is modelled but does not define bound, horizon"):
        register(bare)
    with pytest.raises(UsageError, match="objective 'makespan' is already registered"):
        register(replace(OBJECTIVES["makespan"]))
    with pytest.raises(UsageError, match="objective name 'Idle' is not valid"):
        register(replace(OBJECTIVES["human_idle"], name="Idle"))
    assert "bare" not in OBJECTIVES and "Idle" not in OBJECTIVES
