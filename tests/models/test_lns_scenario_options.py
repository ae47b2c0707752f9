"""Options only the scenario objectives read (docs/robust.md#options-of-the-scenario-objectives):
set with another objective they are a one-line usage error, never silently ignored."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from bilevel_kit.errors import UsageError
from bilevel_kit.methods import get_method, solve
from bilevel_kit.models.lns.method import LnsOptions
from bilevel_kit.options import keyword_options, parse_options

SCENARIO_MSG = (
    "method 'lns': option {name!r} is read only with objective 'expected_makespan' or "
    "'cvar_makespan', and objective is 'makespan': set objective=expected_makespan or leave "
    "{name!r} out"
)
ALPHA_MSG = (
    "method 'lns': option 'alpha' is read only with objective 'cvar_makespan', and objective "
    "is {objective!r}: set objective=cvar_makespan or leave 'alpha' out"
)


@pytest.mark.parametrize(
    ("param", "name"),
    [("scenarios=5", "scenarios"), ("scenario_seed=0", "scenario_seed"), ("cv=0.3", "cv")],
)
def test_a_scenario_option_without_a_scenario_objective_is_exit_2(
    param, name, capsys, tmp_path, root
):
    """The default value given explicitly (scenario_seed=0) is refused too: it was set."""
    from bilevel_kit.cli import main

    out = tmp_path / "out.json"
    argv = ["solve", str(root / "instances/hrc_table.json"), "-m", "lns", "-p", param]
    code = main([*argv, "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert err == f"bilevel-kit solve: error: {SCENARIO_MSG.format(name=name)}\n"
    assert "compiling" not in err  # refused before greedy-ce's kernels are compiled


@pytest.mark.parametrize("objective", ["makespan", "expected_makespan"])
def test_alpha_is_refused_unless_the_objective_is_the_cvar(objective, capsys, tmp_path, root):
    from bilevel_kit.cli import main

    argv = ["solve", str(root / "instances/hrc_table.json"), "-m", "lns"]
    argv += ["-p", f"objective={objective}", "-p", "alpha=0.5", "-o", str(tmp_path / "o.json")]
    assert main(argv) == 2
    assert capsys.readouterr().err.endswith(f"{ALPHA_MSG.format(objective=objective)}\n")


def test_python_solve_raises_the_usage_error(root):
    from bilevel_kit.instance import load

    inst = load(root / "instances/hrc_table.json")
    with pytest.raises(UsageError) as exc:
        solve(inst, "lns", time_limit=1, scenarios=20)  # 20 is the default: still set
    assert str(exc.value) == SCENARIO_MSG.format(name="scenarios")
    with pytest.raises(UsageError, match="option 'alpha' is read only"):
        solve(inst, "lns", time_limit=1, objective="expected_makespan", alpha=0.9)


def test_the_scenario_objectives_accept_them():
    spec = get_method("lns")
    given = {"scenarios": "7", "scenario_seed": "3", "cv": "0.2"}
    mean = spec.parse({"objective": "expected_makespan", **given})
    assert (mean.scenarios, mean.scenario_seed, mean.cv, mean.alpha) == (7, 3, 0.2, 0.9)
    tail = spec.parse({"objective": "cvar_makespan", "alpha": "0.75", **given})
    assert (tail.objective, tail.alpha, tail.scenarios) == ("cvar_makespan", 0.75, 7)
    assert spec.parse({}) == LnsOptions()  # nothing set: nothing refused


def test_an_options_object_is_held_to_its_values_other_than_the_defaults():
    """A dataclass built in Python cannot say which defaults were passed: a value other than
    the default counts as set."""
    spec = get_method("lns")
    assert spec.parse(LnsOptions(scenarios=20)) == LnsOptions()
    with pytest.raises(UsageError, match="option 'scenarios' is read only"):
        spec.parse(LnsOptions(scenarios=5))
    with pytest.raises(UsageError, match="option 'alpha' is read only"):
        spec.parse(LnsOptions(objective="expected_makespan", alpha=0.5))


def test_the_help_says_when_an_option_is_refused():
    help_of = {i.name: i.help for i in get_method("lns").describe_options()}
    for name in ("scenarios", "scenario_seed", "cv"):
        assert help_of[name].endswith(
            "(only with objective 'expected_makespan' or 'cvar_makespan': refused with "
            "another objective)"
        )
    assert help_of["alpha"].endswith(
        "(only with objective 'cvar_makespan': refused with another objective)"
    )
    assert "refused" not in help_of["window"]


@dataclass(frozen=True)
class _Toy:
    mode: str = "a"
    depth: int = field(default=1, metadata={"needs": {"mode": lambda: ("b", "c")}})


def test_needs_is_generic_and_keywords_count_values_other_than_the_default():
    assert parse_options(_Toy, {"mode": "b", "depth": 4}, "toy").depth == 4
    with pytest.raises(UsageError) as exc:
        parse_options(_Toy, {"depth": 1}, "toy")  # the default, given: set
    assert str(exc.value).startswith("toy: option 'depth' is read only with mode 'b' or 'c',")
    # a Python entry's keywords hold every option: only a value other than the default is set
    assert keyword_options(_Toy, {"mode": "a", "depth": 1}, "toy") == _Toy()
    with pytest.raises(UsageError, match="option 'depth'"):
        keyword_options(_Toy, {"mode": "a", "depth": 2}, "toy")
