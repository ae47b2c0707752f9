"""Every verdict the rendered pages print is computed from its interval (docs/reproduction.md,
"Verdicts"): each is checked here against its CSV row, with the rule written out plainly, and
no verdict word reaches a page by another way than :mod:`bilevel_kit.repro.verdict`."""

from __future__ import annotations

from bilevel_kit.repro.adaptive import share_text
from bilevel_kit.repro.common import PAPER_F, RESULTS_DIR
from bilevel_kit.repro.facts import SLUGS, facts
from bilevel_kit.repro.fmt import read_rows, yes
from bilevel_kit.repro.horizon_tables import paired_gap_difference, typed_rows
from bilevel_kit.repro.verdict import WORDS

FACTS = facts(RESULTS_DIR)


def _side(low: str | float, high: str | float, at: float = 0.0) -> int:
    """Plainly: +1 when the interval lies above ``at``, -1 below, 0 otherwise (or blank)."""
    if low in ("", None) or high in ("", None):
        return 0
    return 1 if float(low) > at else -1 if float(high) < at else 0


def _adaptive_idle() -> list[dict[str, str]]:
    return [r for r in read_rows(RESULTS_DIR / "adaptive.csv") if r["metric"] == "idle"]


def _key(r: dict[str, str]) -> str:
    return f"ad.{'none' if r['delay'] == 'none' else 'delay'}.{r['group']}"


def test_adaptive_gap_and_closed_verdicts_follow_their_intervals() -> None:
    for r in _adaptive_idle():
        k = _key(r)
        gap = _side(r["gap_low"], r["gap_high"])
        want = {1: "significantly faster", -1: "significantly slower", 0: "no significant gap"}
        assert want[gap] in FACTS[f"{k}.gap_verdict"], (k, r["gap_low"], r["gap_high"])
        closed = _side(r["closed_low"], r["closed_high"])
        want = {1: "significantly faster", -1: "significantly slower"}
        assert FACTS[f"{k}.closed_verdict"] == want.get(closed, "no significant difference")
        if gap != 1:  # no share without a significant positive gap, and the text says why
            assert not r["share_closed"]
            assert FACTS[f"{k}.gap_verdict"] in FACTS[f"{k}.share"]
            assert FACTS[f"{k}.gap_verdict"] in FACTS[f"{k}.half"]
        else:
            half = _side(r["share_low"], r["share_high"], 0.5)
            assert FACTS[f"{k}.half"].startswith({1: "met", -1: "not met", 0: "undecided"}[half])


def test_slow_participants_oracle_is_significantly_slower() -> None:
    # issue 38, item 1: -10 s [-19, -1] excludes 0; it was rendered "no significant gap"
    (slow,) = [r for r in _adaptive_idle() if r["delay"] == "none" and r["group"] == "slow"]
    assert float(slow["gap_high"]) < 0
    assert FACTS["ad.none.slow.gap_verdict"] == "the oracle is significantly slower"
    assert "no significant gap" not in share_text(slow)
    readme = (RESULTS_DIR.parent / "README.md").read_text()
    assert (
        f"{FACTS['ad.none.slow.gap']} without delays\n  (**{FACTS['ad.none.slow.gap_verdict']}"
        in (readme)
    )


def test_trend_verdicts_follow_slope_interval_and_ranks() -> None:
    for prefix, stem in (("fig6", "fig6"), ("r100", "fig6_r100")):  # R = 30 and R = 100
        _check_trends(prefix, read_rows(RESULTS_DIR / f"{stem}_trends.csv"))
    assert any(k.startswith("r100.") and ".trend." in k for k in FACTS)


def _check_trends(prefix: str, rows) -> None:
    for r in rows:
        sign = int(r["expected_sign"])
        slope = _side(r["ci_low"], r["ci_high"])
        ranks = (1 if float(r["kendall_tau"]) > 0 else -1) if float(r["kendall_p"]) < 0.05 else 0
        want = (
            "supported"
            if slope == ranks == sign
            else "contradicted"
            if slope == ranks == -sign
            else "not shown"
        )
        assert r["verdict"] == want, r["panel"]
        assert int(r["df"]) == int(r["reps"]) - 1 and "t-test" in r["slope_test"]
    got = {v for k, v in FACTS.items() if k.startswith(f"{prefix}.") and k.endswith("verdict")}
    assert got <= {r["verdict"] for r in rows}


def test_figure6_and_window_directions_agree_with_their_estimates() -> None:
    for r in read_rows(RESULTS_DIR / "fig6_improvements.csv"):
        for col in ("dir_tukey", "dir_tukey_holm", "dir_paired_holm"):
            want = {"better": 1, "worse": -1}.get(r[col], 0)
            assert want == 0 or _side(r["pct"], r["pct"]) == want, (r["panel"], col)
    for r in read_rows(RESULTS_DIR / "horizon_window.csv"):
        if r["direction"] in ("better", "worse"):  # Holm-significant: its 95 % CI excludes 0
            want = 1 if r["direction"] == "better" else -1
            assert _side(r["total_pct_ci_low"], r["total_pct_ci_high"]) == want


def test_horizon_neighbours_are_compared_with_an_interval_not_ranked() -> None:
    rows = typed_rows(read_rows(RESULTS_DIR / "horizon.csv"))
    d = int(FACTS["hz.default_n"])
    for m, key in ((d - 1, "prev"), (d + 1, "next")):
        diff = paired_gap_difference(rows, d, m)
        side = _side(diff["low"], diff["high"])
        want = {1: "significantly larger", -1: "significantly smaller"}
        assert FACTS[f"hz.diff_{key}.verdict"] == want.get(side, "not significantly different")
    assert "hz.best_mean_n" not in FACTS
    assert "smallest mean gap is at" not in (RESULTS_DIR.parent / "README.md").read_text()


def test_inside_is_the_interval_meeting_the_papers_range() -> None:
    for r in read_rows(RESULTS_DIR / "user_study_predictions.csv"):
        lo, hi = float(r["cal_low"]), float(r["cal_high"])
        p, h = float(r["paper"]), float(r["readoff"])
        assert yes(r["inside"]) == (lo - 0.01 <= p + h and p - h <= hi + 0.01), r["quantity"]
        slug = SLUGS[r["quantity"]]
        assert FACTS[f"us.{slug}.inside"].startswith("inside" if yes(r["inside"]) else "outside")


def test_participant_model_f_direction_is_its_comparison() -> None:
    rows = read_rows(RESULTS_DIR / "user_study_within.csv")
    for m in ("total", "idle"):
        (r,) = [x for x in rows if x["quantity"] == "F from the medians" and x["metric"] == m]
        want = "above" if float(r["ours"]) > PAPER_F[m] else "below"
        assert FACTS[f"within.{m}.direction"] == want


#: The facts that carry a verdict word, each checked against its row above.
CHECKED = (
    ".gap_verdict",
    ".closed_verdict",
    ".share",
    ".half",
    ".trend.verdict",
    ".diff_prev.verdict",
    ".diff_next.verdict",
    ".tukey",  # counts of the directions, checked per cell above
    ".tukey_holm",
    ".paired_holm",
    ".inside",
    ".worst",  # "W.. : 1/7 inside": a count of the CSV's rows, not a verdict of its own
    ".direction",
)


def test_every_verdict_fact_is_checked_against_its_row() -> None:
    verdicts = {k for k, v in FACTS.items() if any(w in v for w in WORDS if len(w) > 4)}
    unchecked = sorted(k for k in verdicts if not k.endswith(CHECKED))
    assert not unchecked, f"verdict facts with no check against their row: {unchecked}"
