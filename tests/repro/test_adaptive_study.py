"""The adaptive-pace study (``bilevel-kit repro adaptive``): shares, groups, resumable cells."""

from __future__ import annotations

import csv
import json

import pytest

from bilevel_kit.cli import main
from bilevel_kit.repro.adaptive import ADAPTIVE, FIXED, ORACLE, factor_quantile, summarize


def test_factor_quantiles_of_the_paper_cv():
    assert factor_quantile(0.5) == pytest.approx(0.98695, abs=1e-5)  # exp(-s2 / 2)
    assert factor_quantile(0.1) == pytest.approx(0.80185, abs=1e-5)
    assert factor_quantile(0.9) == pytest.approx(1.21478, abs=1e-5)


def _record(fixed, adaptive, oracle):
    runs = {
        p: {"idle": v, "idle_sim": v, "makespan": v, "n_kits": [5] * len(v)}
        for p, v in ((FIXED, fixed), (ADAPTIVE, adaptive), (ORACLE, oracle))
    }
    cell = {"mat": None, "mttf": None, "group": "fast", "factors": [0.8] * len(fixed)}
    return {"cell": cell, "runs": runs}


def test_share_of_the_gap():
    rows = summarize(_record([100.0, 110.0, 120.0], [80.0, 92.0, 96.0], [70.0, 80.0, 90.0]))
    idle = rows[0]
    assert idle["gap_fixed_minus_oracle"] == 30.0
    assert idle["fixed_minus_adaptive"] == pytest.approx(62 / 3, abs=0.01)
    assert idle["share_closed"] == pytest.approx((62 / 3) / 30, abs=1e-3)
    assert idle["delay"] == "none" and idle["runs"] == 3
    # no significant gap (oracle no better than fixed): no share
    rows = summarize(_record([100.0, 110.0, 120.0], [99.0, 111.0, 118.0], [101.0, 108.0, 121.0]))
    assert rows[0]["share_closed"] is None


def test_cli_quick_run_and_resume(tmp_path, capsys):
    out = tmp_path / "adaptive"
    assert main(["repro", "adaptive", "--quick", "--out", str(out), "-q"]) == 0
    text = capsys.readouterr().out
    assert "| fast (0.8019) |" in text and "wrote csv" in text
    with open(out / "adaptive.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 * 4 * 3  # supply settings x groups x metrics
    assert {r["group"] for r in rows} == {"fast", "median", "slow", "population"}
    summary = json.loads((out / "adaptive.json").read_text())
    assert summary["computed"] == 8 and summary["units"] == 2
    # the fast participant: the oracle and the adaptive policy both beat the fixed one
    fast = next(r for r in rows if r["group"] == "fast" and r["metric"] == "makespan")
    assert float(fast[f"mean_{ORACLE}"]) < float(fast[f"mean_{FIXED}"])
    assert float(fast[f"mean_{ADAPTIVE}"]) < float(fast[f"mean_{FIXED}"])
    assert main(["repro", "adaptive", "--quick", "--out", str(out), "-q"]) == 0
    assert json.loads((out / "adaptive.json").read_text())["computed"] == 0
