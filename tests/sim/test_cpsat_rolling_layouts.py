"""cpsat-rolling's committed layouts: shelf packer, else the model's or the packing oracle's,
else a split kit (docs/simulation.md#layouts-of-committed-kits)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bilevel_kit import Kit, Plan, check, load
from bilevel_kit.errors import KitDoesNotFit
from bilevel_kit.heuristics.baselines import packed_kit
from bilevel_kit.instance import topological_order
from bilevel_kit.sim import SimParams, make_policy, simulate
from bilevel_kit.sim.cpsat_rolling import MODEL, ORACLE, SPLIT, CPSATRollingPolicy

SP12 = Path(__file__).resolve().parents[2] / "instances/kitbench/sp_n12_s1_t1_tight_d10.json"
#: the kits every replication commits (the first two windows plan around the human token)
SP12_KITS = [("t0",), ("t1",), ("t2", "t3"), ("t4", "t5", "t6"), ("t7", "t8", "t9", "t10", "t11")]


@pytest.fixture(scope="module")
def sp12():
    return load(SP12)


def _valid_with(instance, kit: Kit) -> list:
    """The checker's violations of a plan of ``kit`` and single-task kits for the rest."""
    kits, placed = [], False
    for t in topological_order(instance):
        if t in kit.tasks:
            if not placed:
                kits.append(kit)
                placed = True
        else:
            kits.append(packed_kit(instance, [t], t))
    return check(instance, Plan(tuple(kits)))


def test_sp12_runs_and_the_shelf_packer_could_not_lay_out_its_kits(sp12):
    # the regression: t4-t6 is kept by the model but has no shelf layout (KitDoesNotFit before)
    with pytest.raises(KitDoesNotFit):
        packed_kit(sp12, ["t4", "t5", "t6"], "t4-t6")
    params = SimParams(policy_options={"time_limit": 5.0, "deterministic_time": 0.05})
    for seed in (0, 1):
        pol = make_policy("cpsat-rolling", sp12, seed=seed, params=params)
        res = simulate(sp12, pol, params=params, seed=seed)
        assert check(res.instance, res.plan) == []
        assert [k.tasks for k in res.plan.kits] == SP12_KITS
        # the last two kits have no shelf layout: the model's own layouts are committed
        assert pol.oracle_layouts == 2 and pol.layout_fallbacks == 0
        assert res.layout_fallbacks == 0 and "layout_fallbacks" not in res.record()
        assert res.makespan == pytest.approx(res.timeline.makespan)
        assert 200.0 < res.makespan < 600.0  # 12 tasks: 356 s with the mean times (bound)


def test_layout_sources_and_the_split_fallback(sp12):
    pol = CPSATRollingPolicy(sp12)
    window = [t.id for t in sp12.tasks]
    sub = pol._sub_instance(window, {t: sp12.robot_time(t) for t in window}, 0.0)
    # no model layout: the packing oracle's (deterministic limit)
    kit, rest, source = pol._commit(sub, [("t4", "t5", "t6"), ("t7",)], {})
    assert source == ORACLE and rest == (("t7",),) and len(kit.layout) == 8
    assert _valid_with(sp12, kit) == []
    # the model's layout, when the plan has one, comes first (slots handed out by type)
    typed: dict[str, list[tuple[float, float, float]]] = {}
    for p in kit.layout:
        typed.setdefault(p.type, []).append((p.x, p.y, p.theta))
    model = {frozenset(kit.tasks): {t: v[::-1] for t, v in typed.items()}}
    again, _, source = pol._commit(sub, [("t4", "t5", "t6")], model)
    assert source == MODEL and _valid_with(sp12, again) == []
    assert {(p.x, p.y) for p in again.layout} == {(p.x, p.y) for p in kit.layout}
    # 8 parts p1 (34944 mm^2) exceed the tray (32708 mm^2): split greedily, in order
    kit, rest, source = pol._commit(sub, [("t4", "t5", "t6", "t7", "t9"), ("t8",)], {})
    assert source == SPLIT
    assert kit.tasks == ("t4", "t5", "t6") and rest == (("t7", "t9"), ("t8",))
    assert _valid_with(sp12, kit) == []


def test_a_run_without_any_oracle_layout_splits_and_completes(sp12, monkeypatch):
    # neither the model nor the oracle lays out t4-t6: the policy splits it, the run completes
    laid_out = CPSATRollingPolicy._laid_out

    def shelf_only(self, sub, tasks, model):
        got = laid_out(self, sub, tasks, model)
        return None if got is None or got[1] == ORACLE else got

    monkeypatch.setattr("bilevel_kit.sim.cpsat_rolling._model_layouts", lambda plan, back: {})
    monkeypatch.setattr(CPSATRollingPolicy, "_laid_out", shelf_only)
    pol = make_policy("cpsat-rolling", sp12, seed=0, params=SimParams())
    res = simulate(sp12, pol, seed=0)
    assert check(res.instance, res.plan) == []
    # t4-t6 split into t4-t5 (committed) and t6 (the next hint); the next window re-plans
    assert [k.tasks for k in res.plan.kits] == [
        *SP12_KITS[:3],
        ("t4", "t5"),
        ("t6", "t7"),
        ("t8", "t9", "t10", "t11"),
    ]
    assert pol.oracle_layouts == 0 and res.layout_fallbacks == pol.layout_fallbacks == 1
    assert res.record()["layout_fallbacks"] == res.layout_fallbacks
