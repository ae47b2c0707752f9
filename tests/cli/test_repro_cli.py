"""`bilevel-kit repro fig6 --quick` end to end through the CLI, with cpsat-rolling."""

from __future__ import annotations

import json

from bilevel_kit.cli import main


def test_repro_fig6_quick_with_cpsat(tmp_path, capsys):
    out = tmp_path / "fig6"
    args = ["fig6", "--quick", "--reps", "2", "--with-cpsat", "--cpsat-time-limit", "0.05"]
    code = main(["repro", *args, "--out", str(out)])
    captured = capsys.readouterr()
    text = captured.out
    assert code == 0
    # never silent: how many cells must be computed, then the bar, then the summary
    assert "fig6: 3 cells (R = 2, 4 policies), 3 to compute" in captured.err
    assert "fig6 cells: 3 done, 0 skipped" in captured.err
    assert "total task time, Optimized over Single Task (%)" in text
    assert "cpsat-rolling over Optimized" in text
    for name in (
        "fig6.png",
        "fig6_cpsat-rolling_over_optimized.png",
        "fig6_cells.csv",
        "fig6.md",
        "fig6.json",
    ):
        assert (out / name).stat().st_size > 0, name
    summary = json.loads((out / "fig6.json").read_text())
    assert "cpsat-rolling" in json.dumps(summary)
    assert main(["repro", *args, "--out", str(out)]) == 0
    assert "fig6: 3 cells (R = 2, 4 policies), all saved" in capsys.readouterr().err


def test_repro_rejects_unknown_experiment(capsys):
    assert main(["repro", "fig7"]) == 2
    assert "invalid choice: 'fig7'" in capsys.readouterr().err


def _help(capsys, study: str) -> str:
    assert main(["repro", study, "--help"]) == 0
    return capsys.readouterr().out


def test_each_study_lists_its_own_options_only(capsys):
    """`repro STUDY --help` shows that study's options, not every study's (docs/cli.md)."""
    own = {
        "calibrate": {"--draws"},
        "user-study": {"--calibration"},
        "fig6": {"--mats", "--with-cpsat", "--cpsat-time-limit", "--reps", "--calibration"},
        "horizon": {
            "--horizons",
            "--windows",
            "--reference-time-limit",
            "--no-simulation",
            "--instances",
        },
        "adaptive": {"--reps", "--calibration"},
        "stations": {"--lines", "--stations", "--units", "--supply", "--reps"},
        "robust": set(),
        "robust-kitbench": set(),
        "robust-sim": {"--reps", "--instances", "--trays", "--cvs"},
    }
    every = set().union(*own.values())
    for study, flags in own.items():
        text = _help(capsys, study)
        for flag in ("--quick", "--out", "--seed", "--jobs", *flags):
            assert f"{flag} " in text or f"{flag}," in text, (study, flag)
        for flag in every - flags - {"--reps", "--calibration", "--mats"}:
            assert f"{flag} " not in text, (study, flag)
    assert "--draws" not in _help(capsys, "fig6")
    assert "--reps" not in _help(capsys, "robust")


def test_repro_rejects_another_study_option(capsys):
    assert main(["repro", "fig6", "--horizons", "1,2"]) == 2
    assert "unrecognized arguments: --horizons 1,2" in capsys.readouterr().err


def test_quick_horizon_includes_the_default_horizon():
    """Its "at N = 5" columns need N = 5 (the table's own horizon) in the quick run too."""
    from bilevel_kit.instance import load
    from bilevel_kit.repro.horizon import QUICK_HORIZONS

    assert load("instances/hrc_table.json").horizon == 5 in QUICK_HORIZONS
