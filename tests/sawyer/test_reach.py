"""Reachability maps over the tray, exact point checks, the empty-map error, plotting."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pytest

pytest.importorskip("pinocchio")

import bilevel_kit.sawyer as S  # noqa: N812
from bilevel_kit.errors import BilevelKitError

FAR = S.WorkCell(tray_x=1400.0, tray_y=300.0)  # tray corner 1.4 m ahead: beyond the reach
EDGE = S.WorkCell(tray_x=900.0, tray_y=300.0)  # near edge reachable, far part not


@pytest.fixture(scope="module")
def default_map() -> S.ReachMap:
    return S.build_reach_map(S.DEFAULT_WORK_CELL, 600.0, 400.0, 10.0)


def test_default_map_is_60_by_40_and_fully_reachable(default_map: S.ReachMap) -> None:
    m = default_map
    assert m.shape == (40, 60)
    assert m.cell_size == (10.0, 10.0)
    np.testing.assert_allclose(m.xs[:2], [5.0, 15.0])
    np.testing.assert_allclose(m.ys[-1], 395.0)
    assert m.reachable.all() and not m.is_empty and m.fraction == 1.0
    assert (m.manipulability > 0).all()
    assert np.isfinite(m.configs).all() and m.configs.shape == (40, 60, 7)
    assert np.all(m.configs >= S.Q_LOWER) and np.all(m.configs <= S.Q_UPPER)
    assert set(np.unique(m.yaws)) <= set(S.DEFAULT_WORK_CELL.grasp_yaws)
    # The goal is < 2 s on the 2-core machine; the bound here only guards regressions.
    assert m.build_time < 10.0


def test_map_configurations_put_the_tool_on_the_cell_centres(default_map: S.ReachMap) -> None:
    st = default_map.work_cell
    arm = S.Arm(st.tool_offset_m)
    for row, col in [(0, 0), (39, 59), (20, 30), (7, 51)]:
        p = st.tray_to_base(default_map.xs[col], default_map.ys[row], st.place_height)
        T = arm.fk(default_map.configs[row, col])
        assert np.linalg.norm(T[:3, 3] - p) <= S.POS_TOL
        assert T[2, 2] < -0.9999  # tool z points down


def test_lookup_uses_the_cell_containing_the_point() -> None:
    m = S.build_reach_map(EDGE, 600.0, 400.0, 50.0)
    assert 0.0 < m.fraction < 1.0
    assert m.reachable[0].any() and not m.reachable[-1].any()
    row, col = np.argwhere(m.reachable)[0]
    cw, ch = m.cell_size
    inside = (col * cw + 0.3 * cw, row * ch + 0.9 * ch)
    assert m.cell_index(*inside) == (row, col)
    assert m.reachable_at(*inside)
    assert not m.reachable_at(300.0, 399.0)
    assert not m.reachable_at(-1.0, 10.0) and not m.reachable_at(10.0, 400.5)
    assert m.cell_index(600.0, 400.0) == (m.shape[0] - 1, m.shape[1] - 1)
    np.testing.assert_array_equal(m.lookup([inside, (300.0, 399.0)]), [True, False])


def test_cells_tile_the_tray_when_the_resolution_does_not_divide_it() -> None:
    m = S.build_reach_map(S.DEFAULT_WORK_CELL, 250.0, 130.0, 40.0)
    assert m.shape == (4, 7)
    assert m.cell_size[0] <= 40.0 and m.cell_size[1] <= 40.0
    assert m.cell_size[0] * 7 == pytest.approx(250.0)


def test_map_agrees_with_exact_point_checks() -> None:
    m = S.build_reach_map(EDGE, 600.0, 400.0, 40.0)
    points = [(x, y) for y in m.ys for x in m.xs]
    exact = S.check_points(EDGE, points, approach=False).reshape(m.shape)
    np.testing.assert_array_equal(exact, m.reachable)


def test_check_points_does_not_depend_on_order() -> None:
    pts = [(10.0, 10.0), (300.0, 390.0), (590.0, 20.0), (300.0, 60.0)]
    a = S.check_points(EDGE, pts)
    b = S.check_points(EDGE, pts[::-1])[::-1]
    np.testing.assert_array_equal(a, b)
    assert a.dtype == bool and a.shape == (4,)
    assert a[0] and not a[1]


def test_far_tray_gives_an_empty_map_and_a_clear_error() -> None:
    start = time.perf_counter()
    m = S.build_reach_map(FAR, 600.0, 400.0, 10.0)
    assert time.perf_counter() - start < 1.0
    assert m.is_empty and m.fraction == 0.0
    assert (m.manipulability == 0).all() and np.isnan(m.configs).all()
    assert not m.reachable_at(300.0, 200.0)
    with pytest.raises(S.UnreachableError, match="no point of the 600 x 400 mm tray") as info:
        S.ensure_placeable(m, "kit 1")
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, BilevelKitError)
    assert "kit 1" in str(info.value)
    assert S.ensure_placeable(S.build_reach_map(EDGE, 600, 400, 100)) is not None
    assert not S.check_points(FAR, [(0.0, 0.0), (600.0, 400.0)]).any()


def test_ensure_points_reachable_names_the_bad_points() -> None:
    S.ensure_points_reachable(S.DEFAULT_WORK_CELL, [(100.0, 100.0), (500.0, 300.0)])
    with pytest.raises(S.UnreachableError, match="p2"):
        S.ensure_points_reachable(EDGE, [(300.0, 20.0), (300.0, 390.0)], labels=["p1", "p2"])


def test_bad_grid_arguments() -> None:
    with pytest.raises(ValueError):
        S.build_reach_map(S.DEFAULT_WORK_CELL, 600, 400, 0)
    with pytest.raises(ValueError):
        S.build_reach_map(S.DEFAULT_WORK_CELL, -1, 400, 10)


@dataclass
class _Item:
    x: float
    y: float
    theta: float
    w: float
    h: float


def test_plot_reach_map_draws_layout(tmp_path) -> None:
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m = S.build_reach_map(EDGE, 600.0, 400.0, 50.0)
    layout = [_Item(100, 30, 30, 80, 40), _Item(450, 300, 0, 100, 60)]
    ax = S.plot_reach_map(m, layout)
    assert len(ax.patches) == 2
    colours = [p.get_edgecolor()[:3] for p in ax.patches]
    assert colours[1] == (1.0, 0.0, 0.0)  # the far part is unreachable: red
    ax.figure.savefig(tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 0
    _fig, ax2 = plt.subplots()
    assert S.plot_reach_map(S.build_reach_map(FAR, 600, 400, 100), ax=ax2) is ax2
    plt.close("all")
