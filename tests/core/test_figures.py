"""Every figure of bilevel_kit.plots drawn for 1, 12 and 100 kits: sane pixel sizes, a label
on every axis that shows tick labels, kit colours that never repeat."""

from __future__ import annotations

import struct
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import pytest
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from bilevel_kit import plots, solve
from bilevel_kit.generate import generate
from bilevel_kit.instance import Instance, from_dict
from bilevel_kit.plan import Plan

#: (family, size, method) giving 1, 12 and 100 kits on generated instances.
CASES = {
    1: ("table", 1, "whole-assembly"),
    12: ("table", 1, "single-task"),
    100: ("intree", 100, "single-task"),
}
DPI = 100
#: (min, max) pixel width and height of each figure at DPI.
LIMITS = {
    "gantt": ((600, 1100), (250, 600)),  # 100 kits: the list of tasks by kit adds ~1.8 in
    "trays": ((400, 2100), (250, 2100)),
    "comparison": ((400, 1200), (300, 600)),
    "convergence": ((400, 800), (250, 500)),
}


@pytest.fixture(scope="module", params=sorted(CASES), ids=lambda n: f"{n}kits")
def case(request) -> tuple[int, Instance, Plan, list[dict]]:
    family, size, method = CASES[request.param]
    inst = from_dict(generate(family, size, seed=1)).with_overrides(trays=1)
    res = solve(inst, method)
    assert res.plan is not None and len(res.plan.kits) == request.param
    other = solve(inst, "whole-assembly" if method == "single-task" else "single-task")
    records = [
        {
            "instance": inst.name,
            "method": r.method,
            "makespan": r.metrics["makespan"],
            "human_idle": r.metrics["human_idle"],
            "status": str(r.status),
            "best_bound": max(r.bound or 0.0, other.bound or 0.0),
        }
        for r in (res, other)
    ]
    return request.param, inst, res.plan, records


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n")
    return struct.unpack(">II", data[16:24])


def check(fig: Figure, kind: str, tmp_path: Path) -> None:
    """Saved at DPI the figure has a sane size, and every axis with tick labels a label."""
    out = plots.save_figure(fig, tmp_path / f"{kind}.png", dpi=DPI)
    (w_lo, w_hi), (h_lo, h_hi) = LIMITS[kind]
    width, height = png_size(out)
    assert w_lo <= width <= w_hi, (kind, width)
    assert h_lo <= height <= h_hi, (kind, height)
    for ax in fig.axes:
        if not ax.get_visible() or not ax.axison:
            continue
        for axis, label in ((ax.xaxis, ax.get_xlabel()), (ax.yaxis, ax.get_ylabel())):
            shown = [t for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
            if shown:
                assert label, f"{kind}: an axis with tick labels has no label"


def test_gantt(case, tmp_path):
    n, inst, plan, _ = case
    ax = plots.plot_gantt(inst, plan, method="m")
    assert isinstance(ax, Axes)
    title = ax.get_title()
    assert title.count(inst.name) == 1 and ("1 kit," if n == 1 else f"{n} kits") in title + ","
    kit_swatches = [
        (tuple(p.get_facecolor()), p.get_hatch() or "")
        for p in ax.patches
        if (p.get_gid() or "").startswith("robot:kit:")
    ]
    # no two of the first 48 kits share colour and hatch; one rule, no colour bar
    assert len(kit_swatches) == n and len(set(kit_swatches)) == min(n, 48)
    assert len(ax.figure.axes) == 1
    if n > 1:  # one tray in circulation: the robot waits for it
        labels = {t.get_text() for t in ax.get_legend().get_texts()}
        assert "waiting for tray" in labels
    check(ax.figure, "gantt", tmp_path)


def test_trays(case, tmp_path):
    n, inst, plan, _ = case
    fig = plots.plot_trays(inst, plan)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == n
    assert all("fitness" in ax.get_title() for ax in visible)
    check(fig, "trays", tmp_path)


def test_comparison(case, tmp_path):
    _, _, _, records = case
    ax = plots.plot_comparison(records)
    shown = {t.get_text() for a in ax.figure.axes for t in a.texts}
    assert shown >= {f"{r['human_idle']:.1f}" for r in records}
    check(ax.figure, "comparison", tmp_path)


def test_convergence(case, tmp_path):
    n, *_ = case
    trace = [1000.0 - 500.0 / (i + 1) for i in range(n)]
    ax = plots.plot_convergence(trace, label="run", converged=False)
    assert "(mm)" in ax.get_ylabel()
    check(ax.figure, "convergence", tmp_path)
