"""`bilevel-kit simulate`: summary, CSV, seeds, bad input."""

from __future__ import annotations

import csv

from bilevel_kit.cli import main


def test_simulate_writes_one_row_per_replication(capsys, tmp_path, root):
    out = tmp_path / "sim.csv"
    code = main(
        [
            "simulate",
            str(root / "instances/hrc_table.json"),
            "--policy",
            "single-task",
            "--units",
            "2",
            "--mat",
            "leg=60,foot=60",
            "--mttf",
            "90",
            "--reps",
            "4",
            "--seed",
            "7",
            "--csv",
            str(out),
        ]
    )
    text = capsys.readouterr().out
    assert code == 0 and "policy single-task, 2 unit(s), 4 replication(s)" in text
    rows = list(csv.DictReader(out.open()))
    assert [int(r["seed"]) for r in rows] == [7, 8, 9, 10]
    assert all(int(r["n_kits"]) == 24 for r in rows)
    assert len({r["makespan"] for r in rows}) == 4  # sampled participants and arrivals differ
    assert any(float(r["robot_wait"]) > 0 for r in rows)


def test_simulate_is_deterministic(capsys, tmp_path, root):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    for out in (a, b):
        assert (
            main(
                [
                    "simulate",
                    str(root / "instances/stool.json"),
                    "--policy",
                    "whole-assembly",
                    "--reps",
                    "3",
                    "--csv",
                    str(out),
                ]
            )
            == 0
        )
    assert a.read_text() == b.read_text()


def test_simulate_bad_input(capsys, root):
    inst = str(root / "instances/hrc_table.json")
    for argv, msg in (
        (["--policy", "magic"], "unknown policy 'magic'"),
        (["--mat", "gear=3"], "unknown part type(s) gear"),
        (["--mttf", "90"], "--mttf needs feeders"),
        (["--mat", "leg=-1"], "must be a finite number > 0"),
        (["--trays", "0"], "--trays"),
        (["--trays", "1.5"], "--trays"),
        (["--trays", "two"], "--trays"),
        (["--buffer", "0"], "use --trays (trays = buffer + 1)"),
    ):
        code = main(["simulate", inst, *argv])
        err = capsys.readouterr().err
        assert code == 2 and msg in err and err.count("\n") == 1, argv


def test_simulate_trays_override(capsys, tmp_path, root):
    """``--trays`` overrides the instance's (the table has one tray): 1 is the file's value,
    unlimited lets the robot stack kits at the human (``max_queue`` > 1)."""
    inst = str(root / "instances/hrc_table.json")
    rows = {}
    for trays in (None, "1", "unlimited"):
        out = tmp_path / f"{trays}.csv"
        extra = [] if trays is None else ["--trays", trays]
        argv = ["simulate", inst, "--policy", "single-task", "--reps", "2", "--csv", str(out)]
        assert main([*argv, *extra]) == 0
        capsys.readouterr()
        rows[trays] = list(csv.DictReader(out.open()))
    assert rows[None] == rows["1"]
    assert all(int(r["max_queue"]) == 1 for r in rows["1"])
    assert all(float(r["robot_blocked"]) > 0 for r in rows["1"])
    assert any(int(r["max_queue"]) > 1 for r in rows["unlimited"])
    assert all(float(r["robot_blocked"]) == 0 for r in rows["unlimited"])


def test_simulate_with_stations_shows_and_writes_each_station(capsys, tmp_path, root):
    """The summed idle of several humans is said to be a sum (it may exceed the makespan),
    and the summary and the CSV show each station's completion, idle and kits (issue 40)."""
    out = tmp_path / "sim.csv"
    inst = str(root / "instances/stations/table_u1_s2.json")
    argv = ["simulate", inst, "--policy", "single-task", "--reps", "2", "--csv", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "the 2 humans waiting for a kit, summed over the stations" in text
    assert "S1_completion (s)" in text and "S2_n_kits  " in text and "n_waits (s)" not in text
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 2 and list(rows[0])[-6:] == [
        "S1_completion", "S1_human_idle", "S1_n_kits", "S2_completion", "S2_human_idle",
        "S2_n_kits",
    ]  # fmt: skip
    for r in rows:
        idle = float(r["S1_human_idle"]) + float(r["S2_human_idle"])
        assert abs(idle - float(r["human_idle"])) < 1e-6  # the sum the summary names
        ends = max(float(r["S1_completion"]), float(r["S2_completion"]))
        assert abs(ends - float(r["makespan"])) < 1e-6
        assert int(r["S1_n_kits"]) + int(r["S2_n_kits"]) == int(r["n_kits"]) == 24


def test_simulate_says_why_a_replication_beats_the_mean_time_bound(capsys, tmp_path, root):
    """Issue: a replication below the proven optimum confused users; the output says why and
    counts the replications below the closed-form mean-time bound (415.78 s on the table)."""
    out = tmp_path / "sim.csv"
    table = str(root / "instances/hrc_table.json")
    assert main(["simulate", table, "--reps", "3", "--seed", "0", "--csv", str(out)]) == 0
    text = capsys.readouterr().out
    assert "human times are sampled per replication" in text
    makespans = [float(r["makespan"]) for r in csv.DictReader(out.open())]
    below = sum(m < 415.78 for m in makespans)
    assert below == 1  # seeds 0-2: one participant faster than the means
    assert f"{below} of 3 replication(s) ended below the mean-time lower bound 415.78 s" in text
    assert main(["simulate", table, "--reps", "2", "--seed", "0", "--units", "2"]) == 0
    text = capsys.readouterr().out
    assert "human times are sampled" in text and "below the mean-time lower bound" not in text
