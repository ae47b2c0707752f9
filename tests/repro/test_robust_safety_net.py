"""The robust study's wall-clock safety net (docs/robust.md#the-study): a solve it cuts is
recorded (``saa_safety_net``, the CSV's ``safety_net_fired``), and a cut cell is computed once
more instead of being kept as if it were a pure function of its configuration and seed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bilevel_kit.repro import robust
from bilevel_kit.stochastic import OPTIMISE, sample

pytest.importorskip("ortools")


def _scenarios(name: str, trays: int | None) -> tuple[Any, Any]:
    inst = robust.study_instance(name, trays)
    return inst, sample(inst, 10, 0, cv=0.3, stream=OPTIMISE)


def test_a_solve_cut_by_the_clock_says_so_and_one_cut_by_its_deterministic_time_does_not():
    from bilevel_kit.models.cpsat.saa import solve_saa

    inst, sc = _scenarios("sp12", 2)
    # 5.0 of deterministic time take several seconds: a one-second net stops CP-SAT first
    cut = solve_saa(inst, sc, time_limit=1.0, deterministic_time=5.0, workers=1)
    assert cut.info["saa_safety_net"] is True
    assert cut.info["saa_deterministic_time"] < 5.0 and not cut.proven
    # 0.3 of deterministic time, far within the net: stopped by it (it reaches the limit)
    ok = solve_saa(inst, sc, time_limit=300.0, deterministic_time=0.3, workers=1)
    assert ok.info["saa_safety_net"] is False
    assert ok.info["saa_deterministic_time"] >= 0.3 - 1e-9
    # a clock-limited solve (lns, cpsat) keeps its keys: the net is a reproducible run's notion
    plain = solve_saa(inst, sc[:2], time_limit=2.0, workers=1)
    assert "saa_safety_net" not in plain.info


@pytest.fixture
def flaky_net(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """Every hinted solve (SAA, wait-and-see) of a cell's first ``cut_passes`` computations
    gets a 0.05 s safety net (the net fires before CP-SAT starts: the hint is returned), the
    others the study's; smaller deterministic limits keep the cell quick."""
    from bilevel_kit.models.cpsat import saa

    real = saa.solve_saa
    state: dict[str, Any] = {"cut_passes": 1, "passes": 0}

    def solve(inst: Any, scenarios: Any, *, time_limit: float, start: Any = None, **kw: Any):
        if start is None:  # the mean-value solve opens a computation of the cell
            state["passes"] += 1
        elif state["passes"] <= state["cut_passes"]:
            time_limit = 0.05
        return real(inst, scenarios, time_limit=time_limit, start=start, **kw)

    monkeypatch.setattr(saa, "solve_saa", solve)
    monkeypatch.setattr(robust, "DET_SAA", 0.5)
    monkeypatch.setattr(robust, "DET_WS", 0.1)
    return state


ONE_CELL = dict(instances=("sp12",), cvs=(0.3,), trays=(None,), jobs=1, progress=False)


@pytest.mark.slow
def test_a_cell_cut_once_is_computed_again_and_comes_out_clean(
    flaky_net: dict[str, Any], tmp_path: Path
) -> None:
    res = robust.run_robust(tmp_path, **ONE_CELL)
    (row,) = res["rows"]
    assert flaky_net["passes"] == 2 and res["computed"] == 2
    assert len(res["retried"]) == 1 and res["cut"] == [] and row["safety_net_fired"] == 0
    assert res["slowest_solve_wall_s"] > 0
    # the clean record is kept: a rerun reads it back
    again = robust.run_robust(tmp_path, **ONE_CELL)
    assert again["computed"] == 0 and again["retried"] == [] and again["rows"] == res["rows"]


@pytest.mark.slow
def test_a_cell_cut_every_time_keeps_its_count_in_the_csv(
    flaky_net: dict[str, Any], tmp_path: Path
) -> None:
    flaky_net["cut_passes"] = 99
    res = robust.run_robust(tmp_path, **ONE_CELL)
    (row,) = res["rows"]
    # the SAA solve and the 5 wait-and-see solves were cut; the mean-value solve was not
    assert row["safety_net_fired"] == 1 + robust.WAIT_AND_SEE_N == 6
    assert res["cut"] == res["retried"] and len(res["cut"]) == 1 and res["computed"] == 2
    # cut before CP-SAT started, the SAA solve returned its hint: the mean-value plan
    assert row["same_plan"] is True and row["vss"] == 0.0
    head, line = (tmp_path / "robust.csv").read_text().splitlines()
    assert line.split(",")[head.split(",").index("safety_net_fired")] == "6"
    # a saved cut cell is never reused as it stands: the next run computes it again
    again = robust.run_robust(tmp_path, **ONE_CELL)
    assert again["computed"] == 1 and again["cut"] == res["cut"]
