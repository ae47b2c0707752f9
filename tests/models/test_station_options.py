"""Every option of ``cpsat`` and ``milp`` is honoured with several assembly stations or refused
with one line (exit 2 at the CLI), never ignored (issue 36; docs/formulations.md, "Options with
several stations"): the declarations of ``STATION_OPTIONS``, the refusals through ``solve`` and
the CLI, and the honoured options' effect."""

from __future__ import annotations

import dataclasses
import json

import pytest
from stations_example import first_tray_doc

from bilevel_kit import solve
from bilevel_kit.cli import main
from bilevel_kit.errors import UsageError
from bilevel_kit.instance import from_dict
from bilevel_kit.models.cpsat.method import STATION_OPTIONS as CPSAT_RULES
from bilevel_kit.models.cpsat.method import CpsatOptions, ScheduleOptions
from bilevel_kit.models.exact.station_options import Honoured, Refused, declare, refusal
from bilevel_kit.models.milp.method import STATION_OPTIONS as MILP_RULES
from bilevel_kit.models.milp.method import MilpOptions

pytest.importorskip("ortools")
# imported here, not first inside a test's captured output: Pyomo's log handlers keep the
# stream they were made with, which a test's capture closes
pytest.importorskip("pyomo.environ")
pytest.importorskip("pyomo.contrib.appsi.solvers")

RULES = {"cpsat": (CpsatOptions, CPSAT_RULES), "milp": (MilpOptions, MILP_RULES)}
#: A value of each refused option that its station model would ignore.
REFUSED = {
    ("cpsat", "tray"): "embedded",
    ("cpsat", "time_resolution"): 0.5,
    ("cpsat", "refine_times"): False,
    ("cpsat", "pack_resolution"): 2.0,
    ("cpsat", "fallback"): "none",
    ("cpsat", "hint"): "none",
    ("milp", "hint"): "lns",
}
#: The table of the CHANGELOG and docs/formulations.md: the honoured options.
HONOURED = {
    "cpsat": {"workers", "objective", "log"},
    "milp": {"solver", "objective", "tray", "log", "fallback"},
}


@pytest.fixture(scope="module")
def station_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("stations") / "first_tray.json"
    path.write_text(json.dumps(first_tray_doc()))
    return path


@pytest.fixture(scope="module")
def inst(station_file):
    return from_dict(first_tray_doc(), str(station_file))


@pytest.mark.parametrize("method", sorted(RULES))
def test_every_option_is_declared_one_way_or_the_other(method):
    """A new option of cpsat or milp fails here (and at import, :func:`declare`) until it is
    declared honoured or refused with stations, and every refusal has a value tested here."""
    cls, rules = RULES[method]
    assert set(rules) == {f.name for f in dataclasses.fields(cls)}
    assert {n for n, r in rules.items() if isinstance(r, Honoured)} == HONOURED[method]
    refused = {n for n, r in rules.items() if isinstance(r, Refused)}
    assert refused == {name for m, name in REFUSED if m == method}


def test_declare_refuses_a_missing_or_unknown_option():
    @dataclasses.dataclass(frozen=True)
    class Opts:
        a: int = 1
        b: int = 2

    with pytest.raises(TypeError, match=r"not declared for several stations: \['b'\]"):
        declare(Opts, {"a": Honoured()})
    with pytest.raises(TypeError, match=r"declared but not options: \['c'\]"):
        declare(Opts, {"a": Honoured(), "b": Honoured(), "c": Honoured()})


def _expected(inst, method, name, value):
    return (
        f"{inst.source}: {method} does not use option '{name}={value}' with several "
        "assembly stations ("
    )


@pytest.mark.parametrize(("method", "name"), sorted(REFUSED))
def test_refused_option_through_solve(inst, method, name):
    value = REFUSED[method, name]
    with pytest.raises(UsageError) as exc:
        solve(inst, method, time_limit=5, **{name: value})
    text = str(exc.value)
    assert text.startswith(_expected(inst, method, name, value)) and "\n" not in text
    assert "drop it or use" in text and "docs/timeline.md#several-stations" in text


@pytest.mark.parametrize(("method", "name"), sorted(REFUSED))
def test_refused_option_through_the_cli(station_file, inst, tmp_path, capsys, method, name):
    value = REFUSED[method, name]
    out = tmp_path / "sol.json"
    args = ["solve", str(station_file), "-m", method, "-p", f"{name}={value}"]
    assert main([*args, "--time-limit", "5", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert _expected(inst, method, name, value) in err
    assert not out.exists()


@pytest.mark.parametrize(("method", "name"), sorted(REFUSED))
def test_refused_options_hold_with_one_station(table, method, name):
    """The same values are fine without stations (the refusal is about them alone)."""
    cls, rules = RULES[method]
    options = cls(**{name: REFUSED[method, name]})
    assert refusal(table, method, options, rules) is None


def test_default_and_accepted_values_are_not_refused(inst):
    assert refusal(inst, "cpsat", CpsatOptions(tray="benders"), CPSAT_RULES) is None
    assert refusal(inst, "cpsat", CpsatOptions(time_resolution=0.1), CPSAT_RULES) is None
    assert refusal(inst, "milp", MilpOptions(tray="auto", fallback="none"), MILP_RULES) is None


@pytest.mark.parametrize("method", sorted(RULES))
def test_honoured_objective_and_log(inst, capfd, method):
    """``objective`` is the one the station model minimises; ``log`` prints its solver's log."""
    params = {"workers": 1} if method == "cpsat" else {}
    quiet = solve(inst, method, time_limit=20, objective="human_idle", **params)
    assert quiet.status_objective == "human_idle" and quiet.extra["objective"] == "human_idle"
    assert quiet.objective == quiet.timeline.human_idle
    silent = capfd.readouterr().out
    solve(inst, method, time_limit=20, log=True, **params)
    logged = capfd.readouterr().out
    assert len(logged) > len(silent) + 200


def test_cpsat_workers_and_tray_benders_are_honoured(inst, monkeypatch):
    """The station model's CP-SAT runs with ``workers`` threads, by Benders cuts."""
    from bilevel_kit.models import stoppable

    workers = []

    def recording(solver, model, *args, **kw):
        workers.append(solver.parameters.num_workers)
        return solve_cp(solver, model, *args, **kw)

    solve_cp = stoppable.solve
    monkeypatch.setattr(stoppable, "solve", recording)
    res = solve(inst, "cpsat", time_limit=20, workers=3, tray="benders")
    assert res.status == "optimal" and res.objective == 31.0
    assert res.extra["tray_mode"] == "benders"
    assert workers and set(workers) == {3}


def test_milp_solver_tray_and_fallback_are_honoured(inst, monkeypatch):
    """``solver`` solves the station master; ``tray`` and ``fallback`` are accepted (``auto``
    and ``lns`` act as ``benders`` and ``none`` there: the option help)."""
    from bilevel_kit.models.milp import method

    used = []

    def recording(model, opt, solver, **kw):
        used.append((model.name, solver))
        return run_solver(model, opt, solver, **kw)

    run_solver = method.run_solver
    monkeypatch.setattr(method, "run_solver", recording)
    res = solve(inst, "milp", time_limit=20, solver="appsi_highs", tray="benders", fallback="none")
    assert res.status == "optimal" and res.objective == 31.0
    assert res.extra["solver"] == "appsi_highs" and res.extra["tray_mode"] == "benders"
    assert used and set(used) == {("milp_stations", "appsi_highs")}


def test_cpsat_keyword_entry_refuses_stations(inst):
    """``bilevel_kit.models.cpsat.solve``/``run`` build the one-station model: with stations
    they ignored them and claimed a false optimum (35.5 s, bound 48.5 s; 31 s is optimal)."""
    from bilevel_kit.models.cpsat import method

    with pytest.raises(UsageError, match="solve/run entry models one assembly station"):
        method.solve(inst, time_limit=5)
    with pytest.raises(UsageError, match="solve/run entry models one assembly station"):
        method.run(inst, ScheduleOptions(), time_limit=5)
