"""Figures name what they show (docs/figures.md): every kit and task of a Gantt chart, every
part of a tray by its type; kit colours never resemble the chart's marks; one kit-label
format per chart; the comparison chart shows each method's gap on an axis that spans the
makespans."""

from __future__ import annotations

import itertools
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import pytest
from matplotlib.axes import Axes

from bilevel_kit import plots, solve, style
from bilevel_kit.generate import generate
from bilevel_kit.instance import Instance, from_dict
from bilevel_kit.plan import Kit, Placement, Plan
from bilevel_kit.plots.gantt import MAX_LISTED_KITS, KitSwatch, kit_colors

#: greedy-ce's plan of the table (8 kits), without layouts: the Gantt chart needs none.
GREEDY_KITS = (
    ("foot1", "conn1"),
    ("foot2", "foot3"),
    ("conn2", "foot4"),
    ("conn3", "conn4"),
    ("top1",),
    ("top2",),
    ("top3",),
    ("top4",),
)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def charts(table: Instance) -> dict[str, tuple[Instance, Plan]]:
    """The charts of the README's commands: 1, 8, 12 and 100 kits."""
    big = from_dict(generate("intree", 100, seed=1))
    out = {
        "whole-assembly": (table, solve(table, "whole-assembly").plan),
        "greedy-ce": (table, Plan(tuple(Kit(k) for k in GREEDY_KITS))),
        "single-task trays=1": (table.with_overrides(trays=1), solve(table, "single-task").plan),
        "100 kits": (big, solve(big, "single-task").plan),
    }
    return {k: (i, p) for k, (i, p) in out.items() if p is not None}


def labels(ax: Axes, kind: str) -> dict[str, str]:
    """gid -> text of the chart's labels of one kind ("task" or "kit")."""
    return {
        t.get_gid(): t.get_text()
        for t in ax.texts
        if (t.get_gid() or "").startswith(f"label:{kind}:")
    }


def legend_texts(ax: Axes) -> list[str]:
    fig = ax.figure
    legends = [*fig.legends, *(a.get_legend() for a in fig.axes if a.get_legend())]
    return [t.get_text() for leg in legends for t in leg.get_texts()]


def test_every_task_and_kit_is_named(table):
    for name, (inst, plan) in charts(table).items():
        ax = plots.plot_gantt(inst, plan, method=name)
        named = labels(ax, "task")
        listed = " ".join(legend_texts(ax) + legend_titles(ax))
        for k, kit in enumerate(plan.kits, 1):
            if k > MAX_LISTED_KITS and "tasks by kit" in listed:  # counted in the title
                assert f"kits {MAX_LISTED_KITS + 1}-{len(plan.kits)}: in the plan file" in listed
                continue
            for t in kit.tasks:
                on_chart = named.get(f"label:task:{t}") == t
                in_list = re.search(rf"(^|\s){k}: ([^\s]+, )*{re.escape(t)}(,|$|\s)", listed)
                assert on_chart or in_list, (name, t)
            if len(plan.kits) <= len(style.KIT_PALETTE):
                assert f"label:kit:{k}" in labels(ax, "kit") or re.search(rf"\b{k}: ", listed)


def legend_titles(ax: Axes) -> list[str]:
    fig = ax.figure
    legends = [*fig.legends, *(a.get_legend() for a in fig.axes if a.get_legend())]
    return [leg.get_title().get_text() for leg in legends]


def test_kit_k_has_one_colour_whatever_the_number_of_kits(table):
    """Issue 40 item 11: kit 3 of an 8-kit chart and of a 12-kit chart look the same (the
    viridis bar beyond 8 kits made two methods' charts look unrelated)."""
    swatch = {}
    for name in ("greedy-ce", "single-task trays=1"):
        inst, plan = charts(table)[name]
        ax = plots.plot_gantt(inst, plan)
        swatch[name] = {
            p.get_gid(): (tuple(p.get_facecolor()), p.get_hatch() or "")
            for p in ax.patches
            if (p.get_gid() or "").startswith("robot:kit:")
        }
    few, many = swatch["greedy-ce"], swatch["single-task trays=1"]
    assert len(few) == 8 and len(many) == 12
    for k in range(1, 9):
        assert few[f"robot:kit:{k}"] == many[f"robot:kit:{k}"]
        assert few[f"robot:kit:{k}"][1] == ""  # kits 1-8: plain
    # kit 9 takes kit 1's colour with the dotted hatch of the second round
    assert many["robot:kit:9"] == (many["robot:kit:1"][0], "..")


def test_task_labels_take_one_place_per_lane(table):
    """All inside their bars, or all on leaders: never some of each (issue 40 item 11)."""
    for name, (inst, plan) in charts(table).items():
        ax = plots.plot_gantt(inst, plan)
        named = set(labels(ax, "task"))
        on_leaders = {
            ln.get_gid().removeprefix("leader:")
            for ln in ax.lines
            if (ln.get_gid() or "").startswith("leader:label:task:")
        }
        assert not named or on_leaders in (set(), named), name
    inst, plan = charts(table)["whole-assembly"]
    ax = plots.plot_gantt(inst, plan)
    assert len(labels(ax, "task")) == 12  # conn1..conn4 do not fit: all twelve on leaders
    assert sum((ln.get_gid() or "").startswith("leader:label:task:") for ln in ax.lines) == 12


def test_task_list_is_capped(table):
    inst, plan = charts(table)["100 kits"]
    ax = plots.plot_gantt(inst, plan)
    (legend,) = ax.figure.legends
    assert len(legend.get_texts()) == MAX_LISTED_KITS == 30
    assert legend.get_title().get_text() == (
        "tasks by kit (kits 1-30; kits 31-100: in the plan file)"
    )
    height = ax.figure.get_size_inches()[1]
    assert height < 5.0  # the list no longer outgrows the 3.4-inch chart


def test_whole_assembly_names_all_twelve_tasks_on_the_chart(table):
    inst, plan = charts(table)["whole-assembly"]
    ax = plots.plot_gantt(inst, plan)
    assert sorted(labels(ax, "task").values()) == sorted(plan.task_order)
    leaders = [ln for ln in ax.lines if (ln.get_gid() or "").startswith("leader:")]
    assert leaders  # conn1..conn4 do not fit their bars: they are named beside the lane


def test_labels_do_not_overlap(table):
    for name, (inst, plan) in charts(table).items():
        ax = plots.plot_gantt(inst, plan)
        ax.figure.canvas.draw()
        boxes = [
            t.get_window_extent()
            for t in ax.texts
            if (t.get_gid() or "").startswith("label:") and t.get_text()
        ]
        for a, b in itertools.combinations(boxes, 2):
            assert not a.overlaps(b), name


def test_kit_labels_take_one_format_per_chart(table):
    for name, (inst, plan) in charts(table).items():
        texts = list(labels(plots.plot_gantt(inst, plan), "kit").values())
        formats = {"long" if t.startswith("kit ") else "short" for t in texts}
        assert len(formats) <= 1, (name, texts)
        assert all(re.fullmatch(r"(kit )?\d+", t) for t in texts)
    inst, plan = charts(table)["whole-assembly"]
    assert list(labels(plots.plot_gantt(inst, plan), "kit").values()) == ["kit 1"]


@pytest.mark.parametrize("n", [1, 4, 8, 9, 12, 100])
def test_kit_colours_never_resemble_idle_or_makespan(n):
    colors = kit_colors(n)
    marks = style.mark_colors()
    must_differ = tuple(marks)  # one palette for any n: clear of the grey marks too
    for c in colors:
        for shade in (c, style.lighten(c)):
            for m in must_differ:
                assert style.color_distance(shade, marks[m]) >= style.MIN_CONTRAST, (n, c, m)


def test_palette_colours_differ_from_each_other():
    full = style.KIT_PALETTE
    light = [style.lighten(c) for c in full]
    for group in (full, light):
        for a, b in itertools.combinations(group, 2):
            assert style.color_distance(a, b) >= style.MIN_CONTRAST


def test_chart_draws_kits_apart_from_idle_and_makespan(table):
    inst, plan = charts(table)["greedy-ce"]
    ax = plots.plot_gantt(inst, plan)
    kits = [p.get_facecolor() for p in ax.patches if (p.get_gid() or "").startswith("robot:kit:")]
    idle = {p.get_facecolor() for p in ax.patches if (p.get_gid() or "").endswith(":idle")}
    (line,) = [ln for ln in ax.lines if ln.get_gid() == "makespan"]
    assert len(kits) == 8 and idle
    for k in kits:
        for mark in (*idle, line.get_color()):
            assert style.color_distance(k, mark) >= style.MIN_CONTRAST


def test_legend_swatches_show_the_kits_colours_not_kit_1s(table):
    inst, plan = charts(table)["greedy-ce"]
    ax = plots.plot_gantt(inst, plan)
    colors = kit_colors(8)
    drawn = [
        p
        for p in ax.get_legend().findobj()
        if (getattr(p, "get_gid", lambda: None)() or "").startswith("swatch:")
    ]
    task = [p.get_facecolor() for p in drawn if p.get_gid().startswith("swatch:task")]
    kit = [p.get_facecolor() for p in drawn if p.get_gid().startswith("swatch:kitting")]
    assert len(set(kit)) > 1 and len(set(task)) > 1
    assert kit == [style.rgba(c) for c in colors[:4]]
    assert task == [style.lighten(c) for c in colors[:4]]


def test_kit_swatch_is_a_handle_with_a_label():
    sw = KitSwatch(["red", "blue"], {}, "kitting")
    assert sw.get_label() == "kitting" and sw.colors == ["red", "blue"]


# -- comparison chart ---------------------------------------------------------------------------

TABLE_ROWS = [  # compare instances/hrc_table.json --methods all (makespan, idle, status)
    ("single-task", 466.695, 43.915, "feasible"),
    ("whole-assembly", 596.78, 218.0, "feasible"),
    ("greedy-ce", 463.78, 57.0, "feasible"),
    ("cpsat", 435.085, 40.315, "optimal"),
    ("milp", 435.085, 40.315, "optimal"),
    ("bilevel-milp", None, None, "unknown (for J)"),
]


def table_records() -> list[dict]:
    bound = 435.085
    return [
        {
            "instance": "hrc_table",
            "method": m,
            "makespan": ms,
            "human_idle": idle,
            "status": st,
            "best_bound": bound,
            "gap": None if ms is None else (ms - bound) / ms,
        }
        for m, ms, idle, st in TABLE_ROWS
    ]


def test_comparison_axis_spans_the_makespans_and_shows_each_lead_figure():
    recs = table_records()
    ax = plots.plot_comparison(recs)
    lo, hi = ax.get_ylim()
    assert 300 < lo < 435.085 and 596.78 < hi < 700  # not 0..600: the differences show
    shown = " ".join(t.get_text() for t in ax.texts)
    for r in recs:
        if r["makespan"] is not None:
            above = 100 * (r["makespan"] - r["best_bound"]) / r["best_bound"]
            assert f"{r['makespan']:.1f} s\n+{above:.1f} %" in shown
    # whole-assembly, greedy-ce: the README's "6.6 % above the optimum", not the 6.2 % gap
    assert "+37.2 %" in shown and "+6.6 %" in shown
    assert "gap" not in shown
    assert [t.get_gid() for t in ax.texts if t.get_text() == "no plan"] == ["noplan:bilevel-milp"]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "optimum = best lower bound 435.1 s" in legend
    assert ax.get_title().endswith(
        "\n+x %: above bound = (makespan - best lower bound) / best lower bound"
    )


def test_comparison_lead_figure_from_the_bound_when_records_have_none():
    recs = [{**r, "above_best": None, "gap": None} for r in table_records()]
    shown = " ".join(t.get_text() for t in plots.plot_comparison(recs).texts)
    assert "+6.6 %" in shown and "+37.2 %" in shown


# -- trays ----------------------------------------------------------------------------------


def test_every_part_is_named_by_its_type(table):
    plan = solve(table, "single-task").plan
    keys = plots.type_keys(table)
    assert keys == {
        "connector": "C",
        "foot": "F",
        "leg": "L",
        "screw_long": "SL",
        "screw_short": "SS",
    }
    fig = plots.plot_trays(table, plan, method="single-task")
    named: dict[str, str] = {}
    for ax in fig.axes:
        for t in ax.texts:
            gid = t.get_gid() or ""
            if gid.startswith("label:part:"):
                named[gid.removeprefix("label:part:")] = t.get_text()
            elif gid.startswith("label:parts:"):
                for part in gid.removeprefix("label:parts:").split(","):
                    named[part] = t.get_text()
    by_id = {p.part: p for kit in plan.kits for p in kit.layout}
    for part, p in by_id.items():
        assert named[part] in (p.type, keys[p.type]) or re.fullmatch(
            rf"{keys[p.type]} x\d+", named[part]
        ), (part, named[part])
    (legend,) = fig.legends
    assert "screw_short (SS)" in [t.get_text() for t in legend.get_texts()]
    assert fig.get_suptitle().startswith("hrc_table / single-task:")


def test_type_keys_are_unique():
    doc = generate("table", 1)
    for extra in ("cap", "clamp", "c"):
        doc["part_types"].append({**doc["part_types"][0], "id": extra})
    inst = from_dict(doc)
    keys = plots.type_keys(inst)
    assert len(set(keys.values())) == len(keys)
    assert keys["cap"] == "C2" and keys["connector"] == "C4"


def test_leader_labels_of_small_parts_do_not_overlap(table):
    kit = Kit(
        ("conn1", "top1"),
        (
            Placement("connector-1", "connector", 70, 20.5, 0, 41, 41),
            Placement("screw_long-1", "screw_long", 247, 3, 0, 14, 6),
            Placement("screw_long-2", "screw_long", 261, 3, 0, 14, 6),
            Placement("screw_short-1", "screw_short", 272, 3, 0, 8, 6),
            Placement("screw_short-2", "screw_short", 280, 3, 0, 8, 6),
        ),
    )
    fig = plots.plot_trays(table, Plan((kit, kit, kit)))
    fig.canvas.draw()
    for ax in fig.axes:
        boxes = [
            t.get_bbox_patch().get_window_extent()
            for t in ax.texts
            if (t.get_gid() or "").startswith("label:parts:")
        ]
        if ax.get_visible():
            assert len(boxes) == 2  # "SL x2" and "SS x2"
        for a, b in itertools.combinations(boxes, 2):
            assert not a.overlaps(b)
