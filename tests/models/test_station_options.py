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
#: Every option is honoured with stations (cpsat: one station is the S = 1 case of its model;
#: milp: its one model too). These tests also drive the refusal path with a refusal declared
#: here (:func:`refusing`), through ``solve`` and the CLI.
REFUSED = {("cpsat", "tray"): "embedded", ("milp", "tray"): "benders"}
#: The table of docs/formulations.md: the refused options (none since ``search`` runs the ideal
#: search on the stations' space, tests/models/test_search_first_stations.py) and the honoured
#: ones (every one, one station being the S = 1 case of cpsat's model).
REFUSED_NOW: set[str] = set()
HONOURED = {
    "cpsat": {f.name for f in dataclasses.fields(CpsatOptions)} - REFUSED_NOW,
    "milp": {f.name for f in dataclasses.fields(MilpOptions)} - REFUSED_NOW,
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
    assert {n for n, r in rules.items() if isinstance(r, Refused)} == REFUSED_NOW


@pytest.fixture
def refusing(monkeypatch):
    """The methods' rules with the options of :data:`REFUSED` declared refused."""
    import bilevel_kit.models.cpsat.method as cpsat_method
    import bilevel_kit.models.milp.method as milp_method

    for module, method in ((cpsat_method, "cpsat"), (milp_method, "milp")):
        rules = dict(module.STATION_OPTIONS)
        for m, name in REFUSED:
            if m == method:
                rules[name] = Refused("a refusal declared by the test")
        monkeypatch.setattr(module, "STATION_OPTIONS", rules)
    return {"cpsat": cpsat_method.STATION_OPTIONS, "milp": milp_method.STATION_OPTIONS}


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
def test_refused_option_through_solve(inst, refusing, method, name):
    value = REFUSED[method, name]
    with pytest.raises(UsageError) as exc:
        solve(inst, method, time_limit=5, **{name: value})
    text = str(exc.value)
    assert text.startswith(_expected(inst, method, name, value)) and "\n" not in text
    assert "drop it or use" in text and "docs/timeline.md#several-stations" in text


@pytest.mark.parametrize(("method", "name"), sorted(REFUSED))
def test_refused_option_through_the_cli(
    station_file, inst, refusing, tmp_path, capsys, method, name
):
    value = REFUSED[method, name]
    out = tmp_path / "sol.json"
    args = ["solve", str(station_file), "-m", method, "-p", f"{name}={value}"]
    assert main([*args, "--time-limit", "5", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert _expected(inst, method, name, value) in err
    assert not out.exists()


@pytest.mark.parametrize(("method", "name"), sorted(REFUSED))
def test_refused_options_hold_with_one_station(table, inst, refusing, method, name):
    """The same values are fine without stations (the refusal is about them alone)."""
    cls = RULES[method][0]
    options = cls(**{name: REFUSED[method, name]})
    assert refusal(table, method, options, refusing[method]) is None
    assert refusal(inst, method, options, refusing[method]) is not None


def test_default_and_accepted_values_are_not_refused(inst):
    assert refusal(inst, "cpsat", CpsatOptions(tray="benders"), CPSAT_RULES) is None
    assert refusal(inst, "cpsat", CpsatOptions(time_resolution=0.5), CPSAT_RULES) is None
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
    """``solver`` solves the model with its station variables; ``tray`` and ``fallback`` are
    accepted (``auto`` and ``lns`` act as ``benders`` and ``none`` there: the option help)."""
    from bilevel_kit.models.milp import benders

    used = []

    def recording(model, opt, solver, **kw):
        used.append((model.name, solver))
        return run_solver(model, opt, solver, **kw)

    run_solver = benders.run_solver
    monkeypatch.setattr(benders, "run_solver", recording)
    res = solve(inst, "milp", time_limit=20, solver="appsi_highs", tray="benders", fallback="none")
    assert res.status == "optimal" and res.objective == 31.0
    assert res.extra["solver"] == "appsi_highs" and res.extra["tray_mode"] == "benders"
    assert used and set(used) == {("milp_schedule", "appsi_highs")}


#: cpsat's options formerly refused with stations, each with a value and what the result
#: reports of it (``extra`` key -> value; None: nothing to read, the run must just be optimal).
CPSAT_HONOURED = [
    ({"tray": "embedded"}, {"tray_mode": "embedded"}),
    ({"tray": "benders"}, {"tray_mode": "benders"}),
    ({"time_resolution": 0.5, "refine_times": False}, {"time_resolution": 0.5}),
    ({"time_resolution": 0.25}, {"time_resolution": 0.25, "times_exact": True}),
    ({"pack_resolution": 2.0}, {}),
    ({"fallback": "none"}, {}),
    ({"hint": "none"}, {"hint_method": None, "hint_used": False}),
    ({"hint": "greedy-ce"}, {"hint_method": "greedy-ce", "hint_used": True}),
]


@pytest.mark.parametrize(("params", "reported"), CPSAT_HONOURED)
def test_cpsat_options_are_honoured_with_stations(inst, params, reported):
    """The values the old station model refused now reach the one model (first_tray: 31 s
    optimal, tests/stations_example.py)."""
    res = solve(inst, "cpsat", time_limit=20, workers=1, **params)
    assert res.status == "optimal" and res.objective == 31.0
    for key, value in reported.items():
        assert res.extra[key] == value


def test_cpsat_time_grid_off_the_times_is_honest_with_stations(inst):
    """No divisor of 0.3 s is exact for first_tray's half seconds: times are rounded down, the
    plan is still the optimum (31 s) but only feasible, its bound below (30.3 s measured)."""
    res = solve(inst, "cpsat", time_limit=20, workers=1, time_resolution=0.3)
    assert res.extra["time_resolution"] == 0.3 and res.extra["times_exact"] is False
    assert res.status == "feasible" and res.objective == 31.0
    assert 30.0 <= res.bound < 31.0


def test_cpsat_hint_method_without_stations_is_one_line(inst):
    """A hint method that does not plan for several stations: one line, exit 2."""
    with pytest.raises(UsageError, match="method 'bilevel-milp' does not model several"):
        solve(inst, "cpsat", time_limit=5, hint="bilevel-milp")


def test_cpsat_keyword_entry_solves_stations(inst):
    """``bilevel_kit.models.cpsat.solve``/``run`` build the one model, stations included (it
    used to ignore them and claim 35.5 s optimal with bound 48.5 s; 31 s is optimal); release
    times, which it models for one station only, are refused."""
    from bilevel_kit.models.cpsat import method

    out = method.solve(inst, time_limit=20, workers=1)
    assert out.status == "optimal" and out.extra["makespan"] == 31.0 and out.bound == 31.0
    out = method.run(inst, ScheduleOptions(workers=1), time_limit=20)
    assert out.status == "optimal" and out.extra["makespan"] == 31.0
    with pytest.raises(UsageError, match="release times with one assembly station only"):
        method.solve(inst, time_limit=5, releases={inst.tasks[0].id: 3.0})
