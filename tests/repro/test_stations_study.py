"""``bilevel-kit repro stations`` on a tiny configuration (docs/stations.md)."""

from __future__ import annotations

import json

import pytest

from bilevel_kit import check
from bilevel_kit.errors import UsageError
from bilevel_kit.methods import solve
from bilevel_kit.repro.stations import (
    LINES,
    line_instance,
    run_stations,
    served,
    station_idle,
)
from bilevel_kit.sim import SimParams, TimingModel, simulate


@pytest.mark.parametrize("line", sorted(LINES))
def test_line_instances_give_each_station_its_product(line) -> None:
    inst = line_instance(line, 4, 2)
    assert [s.id for s in inst.stations] == ["S1", "S2", "S3", "S4"]
    products = {t.station: t.product.rstrip("1234") for t in inst.tasks}
    assert [products[f"S{k}"] for k in range(1, 5)] == [
        LINES[line][k % len(LINES[line])] for k in range(4)
    ]
    res = solve(inst, "single-task", check=True)
    assert res.extra["violations"] == []


def test_station_idle_leaves_out_the_wait_for_the_first_kit() -> None:
    inst = line_instance("mix", 2, 1)
    res = simulate(inst, "single-task", params=SimParams(timing=TimingModel.deterministic()))
    assert check(inst, res.plan) == []
    idle = station_idle(res.timeline)
    per = res.timeline.station_metrics()
    assert len(idle) == 2 and all(0.0 <= x < 1.0 for x in idle)
    # S2's human waits for its first kit while S1's is built: that wait is not counted
    assert idle[1] < per["S2"]["human_idle"] / per["S2"]["completion"]


def test_served_counts_stations_up_to_the_first_above_the_threshold() -> None:
    def rec(seed, s, idle):
        cell = {"line": "mix", "delay": "none", "policy": "p", "seed": seed, "stations": s}
        return {"cell": cell, "idle": idle}

    records = [rec(0, 1, 0.05), rec(0, 2, 0.08), rec(0, 3, 0.2), rec(1, 1, 0.12), rec(1, 2, 0.0)]
    (row,) = served(records)
    assert row["per_rep"] == [2, 0] and row["s_max"] == 1.0
    # the t-interval of [2, 0] is 1 +- 12.7; no replication can serve fewer than 0 stations
    # or more than the 3 studied, so it is cut to [0, 3]
    assert (row["s_max_low"], row["s_max_high"]) == (0.0, 3.0)


def test_tiny_study_writes_table_figure_and_resumes(tmp_path) -> None:
    opts = dict(
        reps=2,
        lines=("mix",),
        stations=(1, 2),
        units=1,
        policies=("single-task", "whole-assembly"),
    )
    res = run_stations(tmp_path, **opts)
    assert res["failed"] == [] and res["computed"] == res["cells"] == 2 * 2 * 2 * 2
    assert {r["policy"] for r in res["rows"]} == {"single-task", "whole-assembly"}
    for r in res["rows"]:
        assert r["throughput_low"] <= r["throughput"] <= r["throughput_high"]
        assert 0 <= r["robot_utilisation"] <= 100 and r["reps"] == 2
    assert len(res["served"]) == 2 * 2
    md = (tmp_path / "stations.md").read_text()
    assert "S_max" in md and "units/h" in md
    assert (tmp_path / "stations_mix.png").stat().st_size > 0
    assert json.loads((tmp_path / "stations.json").read_text())["cells"] == 16
    again = run_stations(tmp_path, **opts)
    assert again["computed"] == 0 and again["rows"] == res["rows"]


def test_bad_options_and_unknown_policies() -> None:
    with pytest.raises(UsageError, match="optimized-adaptive"):
        run_stations("unused", policies=("optimized-adaptive",))
    with pytest.raises(UsageError, match="lines from"):
        run_stations("unused", lines=("sofa",))


def test_cli_quick_subset(tmp_path, capsys) -> None:
    from bilevel_kit.cli import main

    out = tmp_path / "st"
    code = main(
        [
            "repro",
            "stations",
            "--quick",
            "--lines",
            "stool",
            "--stations",
            "1,2",
            "--reps",
            "2",
            "--supply",
            "feeders",
            "--out",
            str(out),
            "-q",
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "S_max" in text and "cpsat-rolling" in text
    assert (out / "stations_stool.png").exists()


@pytest.mark.slow
def test_lines_sharing_an_instance_give_identical_rows(tmp_path) -> None:
    """The table and mix lines at S = 1 are the same instance (docs/stations.md), so every
    policy's row must be the same, though the mix cells run after the table's in the same
    process (docs/simulation.md#determinism: a process-wide HiGHS object once made later cells
    differ)."""
    res = run_stations(
        tmp_path, reps=2, units=2, lines=["table", "mix"], stations=[1], delays=["none"]
    )
    assert res["failed"] == []

    def same(rows: list[dict], drop: tuple[str, ...]) -> dict[str, list[dict]]:
        out: dict[str, list[dict]] = {}
        for r in rows:
            kept = {k: v for k, v in r.items() if k not in drop}
            out.setdefault(r["line"], []).append(kept)
        return out

    rows = same(res["rows"], ("line", "wall_s"))
    assert rows["table"] == rows["mix"] and len(rows["table"]) == 4
    served_rows = same(res["served"], ("line",))
    assert served_rows["table"] == served_rows["mix"]
    cpsat = next(r for r in rows["table"] if r["policy"] == "cpsat-rolling")
    assert (cpsat["throughput"], cpsat["idle"]) == (9.52, 6.25)  # seeds 0 and 1: 792.2, 723.2 s
