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
