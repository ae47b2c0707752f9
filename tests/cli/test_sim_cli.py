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
