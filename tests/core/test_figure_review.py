"""Figures as a reviewer marks them (issue 40, item 11; docs/figures.md): tray captions say
what the kit fitness means and that angles are drawn as solved, tray titles are never cut,
the tray outline does not hide edge parts, one tray gets a page of its own size."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import pytest

from bilevel_kit import plots, style
from bilevel_kit.plan import Kit, Placement, Plan
from bilevel_kit.plots.trays import FITNESS_MEANING, _task_lines, off_quarter_turn


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def place(part: str, type_: str, x: float, y: float, theta: float, w: float, h: float) -> Placement:
    return Placement(part=part, type=type_, x=x, y=y, theta=theta, w=w, h=h)


def screws(table, theta: float = 0.0) -> Kit:
    """Two long screws 6 mm apart: a kit of one type, fitness -6 mm."""
    return Kit(
        ("top1",),
        (
            place("screw_long-1", "screw_long", 145.0, 115.0, theta, 6.0, 14.0),
            place("screw_long-2", "screw_long", 151.0, 115.0, theta, 6.0, 14.0),
        ),
    )


def test_fitness_is_explained_and_signed_with_a_minus(table):
    kit = screws(table)
    assert plots.kit_fitness(table, kit) == pytest.approx(-6.0)
    fig = plots.plot_trays(table, Plan((kit,)))
    (ax,) = [a for a in fig.axes if a.get_visible()]
    assert ax.get_title().endswith("fitness \u22126 mm")
    caption = " ".join(fig.get_suptitle().split())
    assert "sum of the distances between parts of different types" in caption
    assert "negative for a kit of one part type" in caption
    assert " ".join(FITNESS_MEANING.split()) in caption


def test_continuous_angles_are_counted_and_said_drawn_as_solved(table):
    straight, tilted = screws(table, 90.0), screws(table, 1.42)
    assert off_quarter_turn(Plan((straight,))) == 0
    assert off_quarter_turn(Plan((tilted, straight))) == 2
    assert off_quarter_turn(Plan((screws(table, -0.18),))) == 2
    assert off_quarter_turn(Plan((screws(table, -0.01),))) == 0  # within 0.05 degrees
    assert "quarter turn" not in plots.plot_trays(table, Plan((straight,))).get_suptitle()
    caption = " ".join(plots.plot_trays(table, Plan((tilted,))).get_suptitle().split())
    assert "2 parts at angles off a quarter turn, drawn as solved" in caption
    fig = plots.plot_trays(table, Plan((tilted,)))
    (ax,) = [a for a in fig.axes if a.get_visible()]
    (part,) = [p for p in ax.patches if p.get_gid() == "part:screw_long-1"][:1]
    xy = part.get_xy()
    # drawn at 1.42 degrees, not rounded: the bottom edge rises by 6 * sin(1.42 deg) mm
    assert xy[1][1] - xy[0][1] == pytest.approx(6.0 * 0.024780, abs=1e-3)


def test_tray_outline_is_thin_and_under_the_parts(table):
    ax = plots.plot_tray(table, screws(table))
    (tray,) = [p for p in ax.patches if p.get_gid() == "tray"]
    parts = [p for p in ax.patches if (p.get_gid() or "").startswith("part:")]
    assert tray.get_linewidth() <= 0.6 < parts[0].get_linewidth() + 0.01
    assert all(tray.get_zorder() < p.get_zorder() for p in parts)
    assert style.color_distance(tray.get_edgecolor(), "black") > 20  # grey, not black


def test_titles_list_tasks_whole_or_count_the_rest():
    tasks = [f"task_{i:02d}" for i in range(12)]
    text = _task_lines(tasks, 2.0, style.SMALL_SIZE)
    assert "..." not in text and text.count("\n") == 1
    shown = [t for t in text.replace("\n", " ").replace(",", " ").split() if t.startswith("task")]
    more = int(text.rsplit("+", 1)[1].split()[0])
    assert shown == tasks[: len(shown)] and len(shown) + more == 12
    assert _task_lines(tasks[:2], 2.0, style.SMALL_SIZE) == "task_00, task_01"
    for line in text.split("\n"):
        assert style.text_width_in(line, style.SMALL_SIZE) <= 2.0


def test_one_tray_fills_its_page_and_names_every_task(table):
    from bilevel_kit import solve

    res = solve(table, "whole-assembly")
    fig = plots.plot_trays(table, res.plan, method="whole-assembly")
    (ax,) = [a for a in fig.axes if a.get_visible()]
    title = ax.get_title()
    assert all(t in title for t in res.plan.kits[0].tasks) and "more" not in title
    width, _ = fig.get_size_inches()
    pos = ax.get_position()
    assert pos.width * width == pytest.approx(5.5, abs=0.01)  # was 3.4 in on a wider title
    fig.canvas.draw()
    sup = fig._suptitle.get_window_extent()
    assert sup.x0 >= 0 and sup.x1 <= fig.bbox.width  # the caption is wrapped, not cut
