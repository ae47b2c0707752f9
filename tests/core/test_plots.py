"""Tests of bilevel_kit.plots: the artists drawn match the plan, its timeline and its layout."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Polygon, Rectangle

from bilevel_kit import plots
from bilevel_kit.geometry import corners
from bilevel_kit.instance import from_dict
from bilevel_kit.plan import Kit, Placement, Plan, evaluate

DOC = {
    "format": "bilevel-kit/1",
    "name": "tiny",
    "tray": {"width": 300, "height": 200},
    "part_types": [
        {"id": "plate", "width": 120, "height": 80, "pick_time": 8},
        {"id": "bolt", "width": 20, "height": 60, "pick_time": 4},
        {"id": "gear", "width": 50, "height": 50, "pick_time": 6},
    ],
    "tasks": [
        {"id": "T1", "parts": [{"type": "plate", "count": 1}], "human_time": {"mean": 20}},
        {"id": "T2", "parts": [{"type": "bolt", "count": 2}], "human_time": {"mean": 8}},
        {
            "id": "T3",
            "parts": [{"type": "gear", "count": 1}, {"type": "bolt", "count": 1}],
            "human_time": {"mean": 15},
        },
        {"id": "T4", "parts": [{"type": "plate", "count": 1}], "human_time": {"mean": 3}},
    ],
    "precedence": [["T1", "T2"]],
    "delivery_time": 5,
    "kit_overhead": {"robot": 2, "human": 3},
}

P = Placement
PLAN = Plan(
    (
        Kit(
            ("T1", "T2"),
            (
                P("p1", "plate", 70, 50, 0, 120, 80),
                P("b1", "bolt", 160, 50, 30, 20, 60),
                P("b2", "bolt", 200, 50, 90, 20, 60),
            ),
        ),
        Kit(("T3",), (P("g1", "gear", 50, 150, 45, 50, 50), P("b3", "bolt", 120, 150, 0, 20, 60))),
        Kit(("T4",), (P("p2", "plate", 150, 100, 10, 120, 80),)),
    )
)


@pytest.fixture
def inst():
    return from_dict(DOC)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def bars(ax: Axes, prefix: str) -> list[Rectangle]:
    return [
        p for p in ax.patches if isinstance(p, Rectangle) and (p.get_gid() or "").startswith(prefix)
    ]


def span(r: Rectangle) -> tuple[float, float]:
    return r.get_x(), r.get_x() + r.get_width()


def texts(ax: Axes) -> list[str]:
    return [t.get_text() for t in ax.texts]


# -- Gantt chart --------------------------------------------------------------------------------


def test_gantt_robot_lane_has_kitting_and_delivery_bar_per_kit(inst):
    ax = plots.plot_gantt(inst, PLAN)
    tl = evaluate(inst, PLAN)
    assert isinstance(ax, Axes)
    kit_bars = bars(ax, "robot:kit:")
    delivery = bars(ax, "robot:delivery:")
    assert len(kit_bars) + len(delivery) == 2 * len(PLAN.kits)
    for k, kt in enumerate(tl.kits):
        (kb,) = bars(ax, f"robot:kit:{k + 1}")
        (db,) = bars(ax, f"robot:delivery:{k + 1}")
        assert span(kb) == pytest.approx((kt.robot_start, kt.robot_end))
        assert span(db) == pytest.approx((kt.robot_end, kt.arrive))
        assert kb.get_y() + kb.get_height() / 2 == pytest.approx(plots.ROBOT_Y)
        assert db.get_hatch() and not kb.get_hatch()
        assert db.get_facecolor() != kb.get_facecolor()
        assert f"kit {k + 1}" in texts(ax)


def test_gantt_human_lane_tasks_and_pickups(inst):
    ax = plots.plot_gantt(inst, PLAN)
    tl = evaluate(inst, PLAN)
    task_bars = bars(ax, "human:task:")
    assert len(task_bars) == len(PLAN.task_order)
    for t in PLAN.task_order:
        (b,) = bars(ax, f"human:task:{t}")
        assert span(b) == pytest.approx((tl.task_start[t], tl.task_end[t]))
        assert b.get_y() + b.get_height() / 2 == pytest.approx(plots.HUMAN_Y)
        assert t in texts(ax)
    for k, kt in enumerate(tl.kits):
        (pb,) = bars(ax, f"human:pickup:{k + 1}")
        assert span(pb) == pytest.approx((kt.human_start, kt.human_start + inst.kit_overhead_human))
        assert pb.get_hatch()


def test_gantt_idle_gaps_sum_to_timeline_idle(inst):
    ax = plots.plot_gantt(inst, PLAN)
    tl = evaluate(inst, PLAN)
    human_idle = bars(ax, "human:idle")
    robot_idle = bars(ax, "robot:idle")
    assert human_idle and robot_idle
    assert sum(b.get_width() for b in human_idle) == pytest.approx(tl.human_idle)
    assert sum(b.get_width() for b in robot_idle) == pytest.approx(tl.robot_idle)
    assert all(b.get_hatch() for b in human_idle + robot_idle)
    # the human waits for kit 1 from time 0; the robot is idle after its last delivery
    assert span(human_idle[0]) == pytest.approx((0.0, tl.kits[0].arrive))
    assert span(robot_idle[-1]) == pytest.approx((tl.kits[-1].arrive, tl.makespan))


def test_gantt_makespan_line_limits_title_legend(inst):
    ax = plots.plot_gantt(inst, PLAN)
    tl = evaluate(inst, PLAN)
    (line,) = [ln for ln in ax.lines if ln.get_gid() == "makespan"]
    assert np.allclose(line.get_xdata(), tl.makespan)
    lo, hi = ax.get_xlim()
    assert lo <= 0.0 and hi >= tl.makespan
    assert ax.get_xlabel() == "time (s)"
    title = ax.get_title()
    assert f"{tl.makespan:.1f}" in title
    assert f"human idle {tl.human_idle:.1f}" in title
    assert f"robot idle {tl.robot_idle:.1f}" in title
    legend = ax.get_legend()
    assert legend is not None
    labels = {t.get_text() for t in legend.get_texts()}
    assert {"delivery", "kit pickup", "idle", "makespan"} <= labels
    assert any(label.startswith("task") for label in labels)
    assert [t.get_text() for t in ax.get_yticklabels()] == ["human", "robot"]


def test_gantt_uses_given_timeline_and_given_axes(inst):
    slow = {t: 2 * inst.human_time(t) for t in PLAN.task_order}
    tl = evaluate(inst, PLAN, human_times=slow)
    fig, ax0 = plt.subplots()
    ax = plots.plot_gantt(inst, PLAN, timeline=tl, ax=ax0)
    assert ax is ax0
    assert len(fig.axes) == 1
    (b,) = bars(ax, "human:task:T1")
    assert span(b) == pytest.approx((tl.task_start["T1"], tl.task_end["T1"]))
    assert ax.get_xlim()[1] >= tl.makespan > evaluate(inst, PLAN).makespan


def test_gantt_skips_zero_length_bars():
    doc = {**DOC, "delivery_time": 0, "kit_overhead": {"robot": 0, "human": 0}}
    inst = from_dict(doc)
    ax = plots.plot_gantt(inst, PLAN)
    assert len(bars(ax, "robot:kit:")) == len(PLAN.kits)
    assert bars(ax, "robot:delivery:") == []
    assert bars(ax, "human:pickup:") == []
    assert len(bars(ax, "human:task:")) == 4


def test_gantt_empty_plan(inst):
    ax = plots.plot_gantt(inst, Plan(()))
    assert bars(ax, "robot:") == [] and bars(ax, "human:") == []
    assert ax.get_xlim()[1] > 0


# -- trays --------------------------------------------------------------------------------------


def polygons(ax: Axes) -> list[Polygon]:
    return [p for p in ax.patches if isinstance(p, Polygon)]


def test_tray_one_polygon_per_placement_with_exact_corners(inst):
    kit = PLAN.kits[0]
    ax = plots.plot_tray(inst, kit)
    assert isinstance(ax, Axes)
    polys = polygons(ax)
    assert len(polys) == len(kit.layout)
    for p in kit.layout:
        (poly,) = [q for q in polys if q.get_gid() == f"part:{p.part}"]
        xy = poly.get_xy()[:4]  # matplotlib closes the path by repeating the first vertex
        assert np.allclose(xy, corners(p.x, p.y, p.w, p.h, p.theta))
    # parts are named by type (the plate by its id, the 20 mm bolts by their key "B")
    named = {t.get_gid(): t.get_text() for t in ax.texts}
    assert named["label:part:p1"] == "plate"
    assert {named["label:part:b1"], named["label:part:b2"]} <= {"bolt", "B"}
    rotated = next(q for q in polys if q.get_gid() == "part:b1")
    assert not np.allclose(
        rotated.get_xy()[:4], corners(160, 50, 20, 60, 0)
    )  # really rotated (30 degrees)


def test_tray_outline_aspect_and_limits(inst):
    ax = plots.plot_tray(inst, PLAN.kits[1], title="hello")
    (tray,) = [p for p in ax.patches if p.get_gid() == "tray"]
    assert isinstance(tray, Rectangle)
    assert (tray.get_x(), tray.get_y()) == (0.0, 0.0)
    assert (tray.get_width(), tray.get_height()) == (inst.tray.width, inst.tray.height)
    assert ax.get_aspect() == 1.0
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    assert x0 < 0 and x1 > inst.tray.width and y0 < 0 and y1 > inst.tray.height
    assert ax.get_title() == "hello"


def test_tray_colours_consistent_per_type_across_calls(inst):
    colors = plots.type_colors(inst)
    assert list(colors) == sorted(inst.part_types)
    assert len(set(colors.values())) == len(colors)
    seen: dict[str, tuple] = {}
    for kit in PLAN.kits:
        ax = plots.plot_tray(inst, kit)
        by_part = {q.get_gid(): q.get_facecolor()[:3] for q in polygons(ax)}
        for p in kit.layout:
            fc = by_part[f"part:{p.part}"]
            assert np.allclose(fc, colors[p.type][:3])
            assert np.allclose(seen.setdefault(p.type, fc), fc)
    assert set(seen) == set(inst.part_types)


def test_tray_legend_lists_types_of_the_kit(inst):
    ax = plots.plot_tray(inst, PLAN.kits[0])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["bolt (B)", "plate (P)"]
    ax = plots.plot_tray(inst, PLAN.kits[0], legend=False)
    assert ax.get_legend() is None


def test_tray_empty_layout_and_given_axes(inst):
    _, ax0 = plt.subplots()
    ax = plots.plot_tray(inst, Kit(("T1",)), ax=ax0)
    assert ax is ax0 and polygons(ax) == []
    assert "no layout" in texts(ax)


@pytest.mark.parametrize(("ncols", "shape"), [(3, (1, 3)), (2, (2, 2)), (1, (3, 1)), (9, (1, 3))])
def test_plot_trays_grid(inst, ncols, shape):
    fig = plots.plot_trays(inst, PLAN, ncols=ncols)
    assert isinstance(fig, Figure)
    assert len(fig.axes) == shape[0] * shape[1]
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == len(PLAN.kits)
    for k, (ax, kit) in enumerate(zip(visible, PLAN.kits, strict=True)):
        assert len(polygons(ax)) == len(kit.layout)
        assert ax.get_title().startswith(f"kit {k + 1}:")
        assert ax.get_legend() is None
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == ["bolt (B)", "gear (G)", "plate (P)"]


def test_plot_trays_empty_plan(inst):
    fig = plots.plot_trays(inst, Plan(()))
    assert len(fig.axes) == 1 and "no kits" in texts(fig.axes[0])


# -- convergence --------------------------------------------------------------------------------


def test_convergence_line_and_overlay():
    trace = [10.0, 8.0, 7.5, 7.5, 7.0]
    ax = plots.plot_convergence(trace, label="run 1")
    assert isinstance(ax, Axes)
    (line,) = ax.lines
    assert list(line.get_xdata()) == [1, 2, 3, 4, 5]
    assert np.allclose(line.get_ydata(), trace)
    assert ax.get_xlabel() == "iteration"
    assert "score" in ax.get_ylabel()
    ax2 = plots.plot_convergence([9.0, float("inf"), 6.0], ax=ax, label="run 2")
    assert ax2 is ax and len(ax.lines) == 2
    assert np.isnan(ax.lines[1].get_ydata()[1])
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["run 1", "run 2"]


def test_convergence_without_label_has_no_legend():
    ax = plots.plot_convergence(np.array([3.0, 2.0]))
    assert ax.get_legend() is None and len(ax.lines) == 1


# -- saving -------------------------------------------------------------------------------------


def test_save_figure_writes_png_atomically(inst, tmp_path):
    ax = plots.plot_gantt(inst, PLAN)
    fig = ax.figure
    out = plots.save_figure(fig, tmp_path / "gantt.png")
    assert out == tmp_path / "gantt.png"
    data = out.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 1000
    assert [p.name for p in tmp_path.iterdir()] == ["gantt.png"]
    assert not plt.fignum_exists(fig.number)


def test_save_figure_replaces_existing_and_creates_dirs(inst, tmp_path):
    target = tmp_path / "sub" / "trays.png"
    target.parent.mkdir()
    target.write_bytes(b"old")
    plots.save_figure(plots.plot_trays(inst, PLAN), target)
    assert target.read_bytes().startswith(b"\x89PNG")
    assert sorted(p.name for p in target.parent.iterdir()) == ["trays.png"]
    new = plots.save_figure(plots.plot_convergence([1.0]).figure, tmp_path / "a" / "b" / "c.png")
    assert new.read_bytes().startswith(b"\x89PNG")


def test_save_figure_failure_leaves_no_temp_file(inst, tmp_path, monkeypatch):
    fig = plots.plot_tray(inst, PLAN.kits[0]).figure

    def boom(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(fig, "savefig", boom)
    with pytest.raises(RuntimeError, match="disk full"):
        plots.save_figure(fig, tmp_path / "tray.png")
    assert list(tmp_path.iterdir()) == []
    assert not plt.fignum_exists(fig.number)


def test_plot_comparison_stems_from_bound_and_idle_bars():
    from bilevel_kit.plots import plot_comparison

    recs = [
        {"instance": "x", "method": "a", "makespan": 100.0, "human_idle": 10.0, "best_bound": 90.0},
        {"instance": "x", "method": "b", "makespan": 120.0, "human_idle": 30.0, "best_bound": 90.0},
    ]
    ax = plot_comparison(recs)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["a", "b"]
    (line,) = [ln for ln in ax.get_lines() if ln.get_gid() == "bound"]
    assert line.get_ydata()[0] == 90.0
    dots = {ln.get_gid(): ln.get_ydata()[0] for ln in ax.get_lines() if ln.get_gid()}
    assert dots["makespan:a"] == 100.0 and dots["makespan:b"] == 120.0
    (idle_ax,) = [a for a in ax.figure.axes if a is not ax]
    assert sorted(p.get_height() for p in idle_ax.patches) == [10.0, 30.0]
    assert idle_ax.get_ylim()[0] == 0.0 and idle_ax.get_ylabel() == "human idle (s)"


def test_plot_gaps_bars_labels_and_missing():
    from bilevel_kit.plots import plot_gaps

    recs = [
        {"instance": "i1", "method": "a", "gap": 0.10},
        {"instance": "i1", "method": "b", "gap": 0.0},
        {"instance": "i2", "method": "a", "gap": 0.05},
    ]
    ax = plot_gaps(recs, methods=["a", "b"])
    bars = {p.get_gid(): p.get_height() for p in ax.patches if p.get_gid()}
    assert bars == {
        "gap:a:i1": pytest.approx(10.0),
        "gap:b:i1": 0.0,
        "gap:a:i2": pytest.approx(5.0),
    }
    texts = [t.get_text() for t in ax.texts]
    assert texts.count("n/a") == 1 and "10.0" in texts


# -- issue 17: one style, tray waits, labels that fit, status and broken axis ------------------


def test_categorical_swatches_never_repeat():
    from bilevel_kit import style

    for n in (1, 10, 11, style.MAX_SWATCHES, style.MAX_SWATCHES + 1, 150):
        sw = style.categorical(n)
        assert len(sw) == n
        assert len({(s.color, s.hatch) for s in sw}) == n
    assert [s.hatch for s in style.categorical(10)] == [""] * 10
    assert style.categorical(11)[10].hatch and style.categorical(11)[10].color == (
        style.categorical(1)[0].color
    )


def test_plural():
    from bilevel_kit.style import plural

    assert plural(1, "kit") == "1 kit" and plural(0, "kit") == "0 kits"
    assert plural(12, "kit") == "12 kits"


def test_gantt_title_names_method_once_and_says_1_kit(inst):
    ax = plots.plot_gantt(inst, Plan(PLAN.kits[:1]), method="greedy-ce")
    title = ax.get_title()
    assert title.count("tiny") == 1 and title.count("greedy-ce") == 1
    assert "1 kit" in title and "1 kits" not in title
    assert "3 kits" in plots.plot_gantt(inst, PLAN).get_title()


def test_gantt_draws_tray_waits_apart_from_idle(inst):
    one = inst.with_overrides(trays=1)
    tl = evaluate(one, PLAN)
    ax = plots.plot_gantt(one, PLAN)
    waits = bars(ax, "robot:tray_wait:")
    expected = plots.tray_waits(one, tl)
    assert waits and len(waits) == len(expected)
    for (k, s, e), b in zip(expected, waits, strict=True):
        assert b.get_gid() == f"robot:tray_wait:{k}"
        assert span(b) == pytest.approx((tl.kits[k - 2].arrive, tl.kits[k - 1].robot_start))
        assert (s, e) == pytest.approx(span(b)) and b.get_hatch()
    idle = bars(ax, "robot:idle")
    assert sum(b.get_width() for b in idle + waits) == pytest.approx(tl.robot_idle)
    labels = {t.get_text() for t in ax.get_legend().get_texts()}
    assert "waiting for tray" in labels
    # unlimited trays: nothing to wait for, no legend entry
    ax = plots.plot_gantt(inst, PLAN)
    assert bars(ax, "robot:tray_wait:") == []
    assert "waiting for tray" not in {t.get_text() for t in ax.get_legend().get_texts()}


def test_gantt_many_kits_hatched_rounds_and_no_scattered_labels(inst):
    four = Plan(tuple(Kit((t,)) for t in ("T1", "T2", "T3", "T4")))
    assert len(plots.plot_gantt(inst, four).figure.axes) == 1  # 4 kits: palette, no bar
    doc = {**DOC, "tasks": [{**DOC["tasks"][3], "id": f"U{i}"} for i in range(30)]}
    doc["precedence"] = []
    big = from_dict(doc)
    plan = Plan(tuple(Kit((f"U{i}",)) for i in range(30)))
    ax = plots.plot_gantt(big, plan)
    assert ax.figure.axes == [ax]  # one colour rule for any number of kits: no colour bar
    swatches = [(tuple(b.get_facecolor()), b.get_hatch() or "") for b in bars(ax, "robot:kit:")]
    assert len(set(swatches)) == 30 and len({c for c, _ in swatches}) == 8
    assert [h for _, h in swatches[::8]] == ["", "..", "\\\\", "oo"]  # one hatch per round
    # 30 kits on a 7-inch chart: the kit numbers fit, the task ids "U0".."U29" too
    assert "1" in texts(ax) or "kit 1" in texts(ax)


def test_tray_small_parts_are_named_by_their_type_key_on_a_leader(inst):
    kit = Kit(
        ("T2",),
        (P("bolt-12", "bolt", 150, 100, 0, 20, 60), P("tiny-3", "bolt", 20, 20, 0, 2, 2)),
    )
    ax = plots.plot_tray(inst, kit)
    named = {t.get_gid(): t.get_text() for t in ax.texts}
    assert named["label:part:bolt-12"] in ("bolt", "B")  # inside: the type or its key
    assert named["label:parts:tiny-3"] == "B"  # 2 x 2 mm: the key, beside the part
    assert not any(t in ("3", "12", "tiny-3", "bolt-12") for t in named.values())
    assert all(t.get_clip_on() for t in ax.texts if t.get_gid().startswith("label:part:"))


def test_tray_titles_give_kit_fitness(inst):
    from bilevel_kit.fitness import layout_fitness

    ax = plots.plot_tray(inst, PLAN.kits[0])
    f = layout_fitness(PLAN.kits[0].layout, inst.weights["W6"])
    assert f"fitness {round(f):,} mm".replace("-", "\u2212") in ax.get_title()  # true minus
    fig = plots.plot_trays(inst, PLAN)
    for ax, kit in zip([a for a in fig.axes if a.get_visible()], PLAN.kits, strict=True):
        f = round(plots.kit_fitness(inst, kit))
        assert f"fitness {f:,} mm".replace("-", "\u2212") in ax.get_title()
    assert plots.kit_fitness(inst, Kit(("T1",))) is None


def test_comparison_status_labels_and_values():
    recs = [
        {"instance": "x", "method": m, "makespan": ms, "human_idle": hi, "status": st}
        for m, ms, hi, st in (("a", 459.8, 37.0, "feasible"), ("b", 432.0, 10.0, "optimal"))
    ]
    recs[0]["best_bound"] = recs[1]["best_bound"] = 420.0
    ax = plots.plot_comparison(recs)
    shown = " ".join(texts(ax))
    assert "459.8 s" in shown and "432.0 s" in shown
    idle_ax = next(a for a in ax.figure.axes if a is not ax)
    assert {"37.0", "10.0"} <= set(texts(idle_ax))
    assert [t.get_text() for t in ax.get_xticklabels()] == ["a\n(feasible)", "b\n(optimal)"]


def test_convergence_unit_and_iteration_cap_mark():
    ax = plots.plot_convergence([1.0, 2.0, 3.0], converged=True)
    assert ax.get_ylabel().startswith("kit fitness (mm)")
    assert not [a for a in ax.get_children() if a.get_gid() == "cap"]
    ax = plots.plot_convergence([1.0, 2.0, 3.0], converged=False)
    marks = [a for a in ax.get_children() if a.get_gid() == "cap"]
    assert len(marks) == 2  # the marker on the last point and its note
    assert any("still improving" in getattr(a, "get_text", str)() for a in marks)


def test_plots_do_not_leak_style_into_rcparams(inst):
    before = dict(plt.rcParams)
    plots.plot_gantt(inst, PLAN)
    assert dict(plt.rcParams) == before


# -- Gantt chart with several assembly stations (docs/timeline.md#several-stations) -------------


def _stations_example():
    """The worked example of docs/timeline.md#several-stations: A (one tray) with a1, a2 and B
    (d = 2, no pickup) with b1, planned [a1] [a2] [b1]: B's human works while A's does."""
    from stations_example import worked_example_doc

    doc = worked_example_doc()
    return from_dict(doc), Plan((Kit(("a1",)), Kit(("a2",)), Kit(("b1",))))


def _lane(ax: Axes, label: str) -> float:
    ticks = dict(zip([t.get_text() for t in ax.get_yticklabels()], ax.get_yticks(), strict=True))
    return float(ticks[label])


def _mid_y(r: Rectangle) -> float:
    return r.get_y() + r.get_height() / 2


def test_gantt_one_human_lane_per_station_and_the_shared_robot():
    inst, plan = _stations_example()
    tl = evaluate(inst, plan)
    ax = plots.plot_gantt(inst, plan)
    assert isinstance(ax, Axes)
    assert [t.get_text() for t in ax.get_yticklabels()] == ["human A", "human B", "robot"]
    y_a, y_b, y_r = _lane(ax, "human A"), _lane(ax, "human B"), _lane(ax, "robot")
    assert y_a == plots.HUMAN_Y and y_r == plots.ROBOT_Y and y_b <= y_a - 1.0
    # the evaluator's times (the page's table): robot 0-3, 4.5-10.5, 11.5-15.5
    for k, want in enumerate([(0, 3), (4.5, 10.5), (11.5, 15.5)], 1):
        (kb,) = bars(ax, f"robot:kit:{k}")
        assert span(kb) == pytest.approx(want) and _mid_y(kb) == pytest.approx(y_r)
    (db,) = bars(ax, "robot:delivery:3")
    assert span(db) == pytest.approx((15.5, 17.5))
    (wait,) = bars(ax, "robot:tray_wait:")  # kit 2 waits for A's one tray (back at 4.5)
    assert span(wait) == pytest.approx((4.0, 4.5))
    # each task in its station's lane, A's and B's humans overlapping in time (17.5-19)
    where = {"a1": (y_a, (4.5, 14.5)), "a2": (y_a, (15.0, 19.0)), "b1": (y_b, (17.5, 23.5))}
    for t, (y, want) in where.items():
        (b,) = bars(ax, f"human:task:{t}")
        assert span(b) == pytest.approx(want) and _mid_y(b) == pytest.approx(y)
        assert (tl.task_start[t], tl.task_end[t]) == pytest.approx(want)
    (pickup,) = bars(ax, "human:pickup:1")
    assert span(pickup) == pytest.approx((4.0, 4.5)) and _mid_y(pickup) == pytest.approx(y_a)
    assert bars(ax, "human:pickup:3") == []  # o_H = 0 at B: nothing to draw
    # each human's idle up to its own completion: A waits 0-4, B 0-17.5 (station_metrics)
    idle = {
        name: [span(b) for b in bars(ax, "human:idle") if _mid_y(b) == pytest.approx(y)]
        for name, y in (("A", y_a), ("B", y_b))
    }
    assert idle == {"A": [pytest.approx((0.0, 4.0))], "B": [pytest.approx((0.0, 17.5))]}
    assert "completion A 19.0 s, B 23.5 s" in ax.get_title().replace("\n", "; ")


def test_gantt_stations_on_given_axes():
    inst, plan = _stations_example()
    _, ax0 = plt.subplots()
    assert plots.plot_gantt(inst, plan, ax=ax0) is ax0
    assert len(bars(ax0, "human:task:")) == 3
