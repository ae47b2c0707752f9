"""The reproduction's claims and their tests: the one calibration and its bootstrap, the three
kinds of paper number and the read-off, Figure 6 by direction, trends and power, the adaptive
shares' intervals and the window study's paired intervals."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from scipy.stats import studentized_range

from bilevel_kit.errors import UsageError
from bilevel_kit.repro import calibrated, fig6_stats, horizon, predictions
from bilevel_kit.repro.adaptive import share_interval
from bilevel_kit.repro.common import (
    DEFAULT_INSTANCE,
    DEFAULT_TARGETS,
    F_TARGET,
    PAPER_CI,
    PAPER_F,
    READOFF,
)
from bilevel_kit.repro.fig6 import calibrated_timing
from bilevel_kit.repro.stats import paper_half_width, tukey_pairs, tukey_rm

# -- the one calibration -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def quick_calibration(tmp_path_factory):
    out = tmp_path_factory.mktemp("calibration")
    return out, calibrated.run_calibration(out, quick=True, progress=False)


def test_calibration_fits_its_targets_and_bootstraps(quick_calibration):
    out, res = quick_calibration
    for name in calibrated.FILES.values():
        assert (out / name).is_file(), name
    means = [t for t in res["targets"] if t["condition"]]
    assert len(means) == 2 and all(abs(t["residual"]) < 0.5 for t in means)
    assert all(t["readoff"] == pytest.approx(READOFF) for t in means)
    assert len(res["draws"]) == calibrated.QUICK_DRAWS
    bound = next(r["value"] for r in res["parameters"] if r["name"] == "within_cv_bound")
    for d in res["draws"]:
        assert d["robot_scale"] > 0 and d["kit_overhead_human"] >= 0
        assert 0 < d["within_cv"] <= bound + 1e-12
    cal = calibrated.load_calibration(out)
    assert cal.quick and len(cal.draws) == calibrated.QUICK_DRAWS
    assert cal.timing().robot_scale == res["parameters"][0]["value"]
    assert cal.design(cal.draws[0]).within_cv == cal.draws[0].within_cv


def test_calibration_refuses_another_version_of_the_instance(quick_calibration, tmp_path):
    out, _ = quick_calibration
    other = tmp_path / "hrc_table.json"
    doc = json.loads(DEFAULT_INSTANCE.read_text())
    doc["name"] = "hrc_table_edited"
    other.write_text(json.dumps(doc))
    with pytest.raises(UsageError, match="another version"):
        calibrated.load_calibration(out, other)


def test_committed_calibration_is_the_full_one_and_current():
    cal = calibrated.load_calibration()  # checks the instance's digest
    assert not cal.quick and len(cal.draws) == calibrated.DRAWS
    assert cal.robot_scale > 0 and 0 < cal.within_cv < cal.total_cv


def test_a_missing_calibration_is_a_usage_error(tmp_path):
    with pytest.raises(UsageError, match="repro calibrate"):
        calibrated.load_calibration(tmp_path)


# -- fitted, implied, predicted ------------------------------------------------------------------


def test_readoff_is_the_largest_gap_to_the_tukey_centres():
    # Fig. 5 read-offs 98 and 270 against the exact OPT-WA idle centre -173.0805
    assert pytest.approx(1.0805) == READOFF


def test_paper_numbers_are_counted_by_kind():
    nums = {n["quantity"]: n for n in predictions.paper_numbers(DEFAULT_TARGETS, F_TARGET)}
    kinds = [n["kind"] for n in nums.values()]
    assert (kinds.count("fitted"), kinds.count("implied"), kinds.count("predicted")) == (3, 4, 7)
    wa = nums["mean total task time, Whole Assembly (s)"]
    assert wa["kind"] == "implied" and wa["implied"] == pytest.approx(270 + 374.78)
    st_wa = nums["Tukey 95% CI ST-WA centre, total task time (s)"]
    assert st_wa["implied"] == pytest.approx(99 - 270)
    assert st_wa["paper"] == pytest.approx((-188.211 - 103.851) / 2)
    opt = nums["mean total task time, Optimized (s)"]
    assert opt["kind"] == "predicted" and "Optimized" in opt["follows"]
    half = nums["Tukey 95% CI half-width (every pair), human idle time (s)"]
    assert half["paper"] == pytest.approx((-160.141 + 186.020) / 2) and not half["follows"]
    # two independent predictions: Optimized's idle mean and the idle residual (the idle
    # half-width); F(idle) follows both, the total half-width Optimized's idle mean
    independent = [q for q, n in nums.items() if n["kind"] == "predicted" and not n["follows"]]
    assert sorted(independent) == sorted(
        [
            "mean human idle time, Optimized (s)",
            "Tukey 95% CI half-width (every pair), human idle time (s)",
        ]
    )
    f_idle = nums["repeated-measures F(2, 34), human idle time"]["follows"]
    assert "Optimized" in f_idle and "half-width" in f_idle
    half_total = nums["Tukey 95% CI half-width (every pair), total task time (s)"]["follows"]
    assert half_total == "mean human idle time, Optimized"


def test_paper_half_widths_follow_from_its_f_and_centres():
    # the within-subject Tukey: q(3, 34) sqrt(MS_conditions / (F 18)), the paper's numbers
    for metric, half in (("total", 42.181), ("idle", 12.9394)):
        centres = [(lo + hi) / 2 for lo, hi in PAPER_CI[metric].values()]
        assert paper_half_width(centres, PAPER_F[metric], 18) == pytest.approx(half, abs=5e-4)
        # the published ends have three decimals: their half-widths agree to rounding
        ends = [(hi - lo) / 2 for lo, hi in PAPER_CI[metric].values()]
        assert all(e == pytest.approx(half, abs=2e-3) for e in ends)


def test_within_subject_tukey_uses_the_repeated_measures_error_term():
    rng = np.random.default_rng(3)
    speed = rng.normal(0, 30, 18)  # a participant's own speed: cancels within subject
    rows = [
        {"participant": p, "condition": c, "y": 100 + 20 * j + speed[p] + rng.normal(0, 5)}
        for p in range(18)
        for j, c in enumerate(("a", "b", "c"))
    ]
    within = tukey_rm(rows, "y")
    groups = tukey_pairs([r["y"] for r in rows], [r["condition"] for r in rows])
    y = np.array([[r["y"] for r in rows if r["participant"] == p] for p in range(18)])
    resid = y - y.mean(1, keepdims=True) - y.mean(0, keepdims=True) + y.mean()
    ms_error = float((resid**2).sum()) / 34  # df (3 - 1)(18 - 1)
    half = studentized_range.ppf(0.95, 3, 34) * np.sqrt(ms_error / 18)
    w = within[("b", "a")]
    assert (w["hi"] - w["lo"]) / 2 == pytest.approx(half)
    assert w["diff"] == pytest.approx(groups[("b", "a")]["diff"])
    g = groups[("b", "a")]
    assert (w["hi"] - w["lo"]) < (g["hi"] - g["lo"]) / 3  # the participants' spread is removed


def _summary(opt_idle: float) -> dict:
    conds = {
        c: {"total_mean": 400.0 + v, "idle_mean": v}
        for c, v in (("optimized", opt_idle), ("single-task", 99.0), ("whole-assembly", 270.0))
    }
    tukey = {"lo": -180.0, "hi": -160.0, "p": 0.0}
    return {
        "conditions": conds,
        "anova": {"total": {"F": 50.0}, "idle": {"F": 700.0}},
        "tukey": {m: {"ST-WA": tukey, "OPT-WA": tukey} for m in ("total", "idle")},
    }


def test_inside_counts_the_paper_mean_within_its_readoff():
    studies = [_summary(v) for v in np.linspace(98.9, 100.0, 41)]
    table = predictions.prediction_table(studies, DEFAULT_TARGETS, F_TARGET, studies)
    (opt,) = [r for r in table if r["quantity"] == "mean human idle time, Optimized (s)"]
    assert opt["cal_low"] > 98.0 and opt["cal_low"] - 98.0 < READOFF  # outside, within h
    assert opt["inside"] is True
    assert opt["widened_pct"] == 0.0


# -- Figure 6: directions, power, trends ---------------------------------------------------------


def _long(pcts, p_tukey, p_paired):
    return [
        {
            "panel": "P",
            "mat": 30.0 * (1 + i // 4),
            "mttf": 30.0 * (1 + i % 4),
            "reps": 30,
            "pct": pct,
            "p_tukey": pt,
            "anova_p": 0.0,
            "stars": "*" if pt < 0.05 else "",
            "p_paired": pp,
            "r80": 10,
        }
        for i, (pct, pt, pp) in enumerate(zip(pcts, p_tukey, p_paired, strict=True))
    ]


def test_directions_count_better_and_worse_apart():
    pcts = [5.0] * 8 + [-2.0] * 4 + [0.5] * 4
    rows = _long(pcts, [0.001] * 12 + [0.5] * 4, [1e-6] * 12 + [0.04] * 4)
    fig6_stats.add_directions(rows)
    (v,) = fig6_stats.verdicts(rows)
    assert (v["tukey_better"], v["tukey_ns"], v["tukey_worse"]) == (8, 4, 4)
    # Holm over 16 cells: p = .04 no longer significant
    assert (v["paired_holm_better"], v["paired_holm_ns"], v["paired_holm_worse"]) == (8, 4, 4)
    assert v["most_tukey"] == "no"  # 8 of 16 is not more than half


def test_reps_for_power_is_the_smallest_with_80_percent():
    r = fig6_stats.reps_for_power(diff=10.0, sd=20.0)
    assert fig6_stats.power(10.0, 20.0, r) >= 0.8 > fig6_stats.power(10.0, 20.0, r - 1)
    assert fig6_stats.reps_for_power(20.0, 20.0) < r
    assert fig6_stats.reps_for_power(0.0, 20.0) is None


def test_trend_slope_and_verdict_from_replications():
    rng = np.random.default_rng(0)
    records = []
    for mat in (30.0, 60.0, 90.0, 120.0):
        for mttf in (30.0, 120.0):
            base = 1000 + rng.normal(0, 5, 20)
            subj = base * (1 - (0.12 - mat / 1000))  # the gain falls by 3 points per 30 s
            records.append(
                {
                    "cell": {"mat": mat, "mttf": mttf},
                    "runs": {
                        "single-task": {"total_time": list(base), "human_idle": list(base / 10)},
                        "optimized": {"total_time": list(subj), "human_idle": list(subj / 10)},
                    },
                }
            )
    total, _ = fig6_stats.trends(records, [("optimized", "single-task")])
    assert total["slope_per_30s"] == pytest.approx(-3.0, abs=0.05)
    assert total["df"] == 19 and total["slope_test"] == fig6_stats.SLOPE_TEST
    assert total["ci_low"] < total["slope_per_30s"] < total["ci_high"] < 0
    assert total["verdict"] == "supported" and total["kendall_tau"] < 0
    one_mat = [r for r in records if r["cell"]["mat"] == 60.0]
    assert fig6_stats.trends(one_mat, [("optimized", "single-task")]) == []


def test_trend_slope_is_tested_on_replications_minus_one_df():
    # three replications of a 4 x 1 grid: the t-test has 2 degrees of freedom
    mat = np.tile([30.0, 60.0, 90.0, 120.0], 3)
    reps = np.repeat([0, 1, 2], 4)
    per_rep = np.array([-3.0, -2.5, -3.6])
    y = 10 + per_rep[reps] * mat / 30
    slope, lo, hi, p, df = fig6_stats.replication_slopes(y, mat, np.zeros_like(mat), reps)
    assert df == 2 and slope == pytest.approx(per_rep.mean())
    half = 4.302652729911275 * per_rep.std(ddof=1) / np.sqrt(3)  # t(0.975, 2)
    assert (lo, hi) == pytest.approx((slope - half, slope + half))
    assert 0.001 < p < 0.05  # a normal approximation would claim far more


def test_a_trend_is_supported_only_when_slope_and_ranks_agree():
    v = fig6_stats.trend_verdict
    assert v(1, 3.8, 5.9, 0.5, 0.01) == "supported"
    assert v(1, 3.8, 5.9, 0.2, 0.30) == "not shown"  # slope from the grid's ends only
    assert v(1, -2.0, -1.0, -0.6, 0.001) == "contradicted"
    assert v(-1, -0.5, 0.4, -0.6, 0.001) == "not shown"
    assert fig6_stats.peak_mat([30, 30, 60, 60, 90], [-5, -3, 10, 12, 8]) == 60


# -- beyond the paper: intervals -----------------------------------------------------------------


def test_share_interval_is_bounded_only_for_a_clear_gap():
    rng = np.random.default_rng(1)
    gap = rng.normal(50, 5, 10)
    closed = 0.8 * gap + rng.normal(0, 2, 10)
    lo, hi = share_interval(gap, closed, np.random.default_rng(0))
    assert lo is not None and hi is not None and lo < 0.8 < hi
    lo, hi = share_interval(rng.normal(0, 5, 10), closed, np.random.default_rng(0))
    assert (lo, hi) == (None, None)


def test_window_gain_has_a_paired_interval():
    base = np.array([100.0, 102.0, 98.0, 101.0])
    gain = horizon._paired_gain(base, base - 1.0)
    assert gain["total_pct_ci_low"] == pytest.approx(gain["total_pct_ci_high"], abs=0.02)
    assert gain["total_pct_ci_low"] == pytest.approx(100 / 100.25, rel=0.02)


def test_quick_calibration_folder_works_for_figure6(quick_calibration, tmp_path):
    out, _ = quick_calibration
    cal_dir = tmp_path / "cal"
    shutil.copytree(out, cal_dir)
    timing, info = calibrated_timing(cal_dir)
    assert info["quick"] and timing.robot_scale == info["robot_scale"]
