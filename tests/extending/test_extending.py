"""The extension guide's worked example (docs/extending.md), so the guide cannot drift: a method
written outside the package is registered by a test, held to the method contract, listed, run
by ``solve`` and ``compare``; and the same package installed as a plugin appears in the CLI
without any registration in code."""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from contract import INSTANCES, assert_contract

from bilevel_kit import UsageError, load, solve
from bilevel_kit.cli import main
from bilevel_kit.methods import REGISTRY
from bilevel_kit.registry import PLUGIN_GROUP, load_plugins, reset_plugins
from bilevel_kit.sim import SimParams, run

PLUGIN = Path(__file__).parent / "example_plugin"


@pytest.mark.parametrize("name", INSTANCES)
def test_the_example_keeps_the_method_contract(pairs, name, root):
    assert_contract(load(root / "instances" / name), pairs, {})


def test_the_example_gives_the_guides_numbers(pairs, table):
    """docs/extending.md quotes these: two tasks per kit beats greedy-ce's 463.78 s on the table."""
    got = {size: solve(table, pairs, size=size).objective for size in (1, 2, 3)}
    assert got == pytest.approx({1: 466.695, 2: 450.78, 3: 452.78}, abs=1e-6)
    assert solve(table, "single-task").objective == pytest.approx(got[1])


def test_its_options_are_checked_before_it_runs(pairs, tiny):
    with pytest.raises(UsageError, match=r"method 'pairs': option 'size': must be >= 1"):
        solve(tiny, pairs, size=0)
    with pytest.raises(UsageError, match=r"method 'pairs': unknown option 'colour'"):
        solve(tiny, pairs, colour=1)


def test_a_name_is_registered_once(pairs):
    import bk_example_plugin

    with pytest.raises(UsageError, match="objective 'kit_handling' is already registered"):
        bk_example_plugin.register_plugin()  # its objective comes first
    with pytest.raises(UsageError, match="method 'pairs' is already registered"):
        REGISTRY.add(REGISTRY[pairs])


def test_it_appears_in_methods_solve_and_compare(pairs, root, tmp_path, capsys):
    assert main(["methods", "pairs"]) == 0
    assert "size" in capsys.readouterr().out
    table = str(root / "instances" / "hrc_table.json")
    assert main(["solve", table, "--method", pairs, "--check", "-q"]) == 0
    out = tmp_path / "compare.csv"
    code = main(["compare", table, "--methods", f"{pairs},single-task", "--csv", str(out), "-q"])
    assert code == 0
    rows = {r["method"]: r for r in csv.DictReader(out.open())}
    assert float(rows["pairs"]["makespan"]) == pytest.approx(450.78)
    assert rows["pairs"]["valid"] == "True"


def test_it_declares_stations_and_its_objective(pairs, root, capsys):
    """docs/extending.md: the spec's ``supports_stations`` lets ``solve`` take an instance
    with stations (the example's kits never mix two, so the checker accepts them), and
    ``bilevel-kit methods`` shows the declaration; without it ``solve`` refuses (exit 2)."""
    from dataclasses import replace

    from bilevel_kit.methods import station_methods

    spec = REGISTRY[pairs]
    assert spec.supports_stations and spec.objectives == ("makespan",)
    assert pairs in station_methods()
    stations = load(root / "instances/stations/table_stool_s2.json")
    res = solve(stations, pairs, check=True)
    assert res.extra["violations"] == [] and len(res.extra["station_metrics"]) == 2
    assert main(["methods"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("pairs "))
    assert line.endswith("[stations]")
    REGISTRY[pairs] = replace(spec, supports_stations=False)
    with pytest.raises(UsageError, match="'pairs' does not model several assembly stations"):
        solve(stations, pairs)
    assert pairs not in station_methods()


def test_an_objective_option_is_held_to_the_declared_objectives(pairs, tiny):
    """A method's ``objective`` option must name one of the objectives its spec declares,
    and a spec may declare only registered objectives."""
    import sys
    import types
    from dataclasses import dataclass

    from bilevel_kit.methods import register

    @dataclass(frozen=True)
    class ObjectiveOptions:
        objective: str = "makespan"

    module = types.ModuleType("bk_objective_options")
    module.ObjectiveOptions = ObjectiveOptions
    sys.modules[module.__name__] = module
    try:
        register(
            "pairs-idle",
            "bilevel_kit.heuristics.baselines:single_task",
            "a test's method with an objective option",
            "bk_objective_options:ObjectiveOptions",
            objectives=("makespan", "human_idle"),
        )
        assert solve(tiny, "pairs-idle", objective="human_idle").plan is not None
        with pytest.raises(UsageError, match="option 'objective': must be one of 'makespan', "):
            solve(tiny, "pairs-idle", objective="J")
        with pytest.raises(UsageError, match="objectives must name registered ones"):
            register("pairs-bad", "x:y", "unknown objective", "x:Y", objectives=("speed",))
        assert "pairs-bad" not in REGISTRY
    finally:
        REGISTRY.remove("pairs-idle")
        del sys.modules[module.__name__]


def _install(tmp_path: Path) -> Path:
    """pip-install the example package into a folder of its own (as a user would, but not into
    the test environment), from a copy so the source tree stays clean."""
    src = tmp_path / "src"
    shutil.copytree(PLUGIN, src, ignore=shutil.ignore_patterns("__pycache__"))
    target = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(target), src],
        check=True,
        capture_output=True,
    )
    return target


@pytest.mark.slow
def test_an_installed_plugin_appears_in_the_cli(tmp_path, root):
    site = _install(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(site)}
    cli = [sys.executable, "-m", "bilevel_kit.cli"]
    listing = subprocess.run([*cli, "methods"], env=env, capture_output=True, text=True)
    assert listing.returncode == 0 and "pairs" in listing.stdout, listing.stderr
    run = subprocess.run(
        [*cli, "solve", str(root / "instances/hrc_table.json"), "--method", "pairs",
         "-p", "size=3", "--check"],
        env=env, capture_output=True, text=True,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert "check: valid" in run.stdout and "452.78" in run.stdout
    # its objective, with no registration in code: cpsat minimises it as it is
    table = str(root / "instances/hrc_table.json")
    obj = ["-m", "cpsat", "-p", "objective=kit_handling", "--check"]
    run = subprocess.run([*cli, "solve", table, *obj], env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "kit_handling: optimal  472.78 s  bound 472.78 s  gap 0.00%" in run.stdout
    assert "check: valid" in run.stdout
    # without the plugin on the path the name is unknown: a clear exit 2
    bare = subprocess.run(
        [*cli, "solve", str(root / "instances/hrc_table.json"), "--method", "pairs"],
        capture_output=True, text=True,
    )  # fmt: skip
    assert bare.returncode == 2 and "unknown method 'pairs'" in bare.stderr


def test_a_broken_plugin_is_reported_and_skipped(tmp_path, monkeypatch, capsys):
    """One line on stderr naming the plugin; the built-in methods stay usable."""
    dist = tmp_path / "broken_plugin-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: broken-plugin\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(f"[{PLUGIN_GROUP}]\nbroken = no_such_module:register\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    reset_plugins()
    try:
        assert load_plugins() == []
    finally:
        reset_plugins()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "plugin 'broken' (no_such_module:register) was not loaded" in err[0]
    assert "cpsat" in REGISTRY


def test_the_example_policy_runs_in_the_simulation(pairs, table):
    """The plugin's policy, registered by the same function: without supply delays it kits what
    the method plans (the same kits in the same order), and ``size=1`` is Single Task's run."""
    record = run(table, "pairs", params=SimParams(), seed=4)
    kits = solve(table, pairs).plan.kits
    assert [tuple(k) for k in record["kits"]] == [k.tasks for k in kits]
    one = run(table, "pairs", params=SimParams(policy_options={"size": 1}), seed=4)
    single = run(table, "single-task", params=SimParams(), seed=4)
    assert one["makespan"] == pytest.approx(single["makespan"])


def test_the_policy_options_are_checked(pairs, table):
    with pytest.raises(UsageError, match=r"policy 'pairs': option 'size': must be >= 1"):
        run(table, "pairs", params=SimParams(policy_options={"size": 0}), seed=0)
