"""The animated 3-D view of ``bilevel-kit execute --html`` in a real headless Chromium: it loads
with no console error and no network request, draws something, has one frame range per kit,
and shows each part on its slot once placed (docs/execution.md)."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pinocchio")
pytest.importorskip("meshcat")

from chromium import Chromium, console_errors, find_chromium, requested_urls

from bilevel_kit import load, solve
from bilevel_kit import solution as solution_io
from bilevel_kit.cli import main
from bilevel_kit.plan import evaluate
from bilevel_kit.sawyer import DEFAULT_WORK_CELL

BROWSER = find_chromium()
pytestmark = pytest.mark.skipif(
    BROWSER is None, reason="no Chromium on this machine (Debian package 'chromium')"
)
TABLE = Path(__file__).resolve().parents[2] / "instances" / "hrc_table.json"


@pytest.fixture(scope="module")
def plan():
    res = solve(load(TABLE), "single-task")
    assert res.plan is not None
    return res


@pytest.fixture(scope="module")
def pages(plan, tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("view")
    sol = folder / "single.json"
    solution_io.write(sol, plan)
    out = {"all": folder / "all.html", "kit3": folder / "kit3.html"}
    assert main(["execute", str(TABLE), str(sol), "--html", str(out["all"])]) == 0
    assert main(["execute", str(TABLE), str(sol), "--html", str(out["kit3"]), "--kit", "3"]) == 0
    return out


@pytest.fixture(scope="module")
def browser():
    assert BROWSER is not None
    b = Chromium(BROWSER)
    yield b
    b.close()


@pytest.fixture(scope="module")
def loaded(browser, pages):
    """The whole plan's page, opened; (load seconds, DevTools events until settled)."""
    seconds, events = browser.open(pages["all"])
    browser.evaluate(_FRAMES)
    events += browser.drain()
    return seconds, events


_FRAMES = "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(1))))"


def _pause_at(browser, t: float) -> None:
    browser.evaluate(f"bilevelKit.viewer.animator.pause(); bilevelKit.seek({t!r}); 1")
    browser.evaluate(_FRAMES)


def test_page_loads_with_no_console_error_and_no_network(loaded, pages):
    seconds, events = loaded
    assert console_errors(events) == []
    urls = requested_urls(events)
    assert pages["all"].resolve().as_uri() in urls
    assert all(u.startswith(("file:", "data:")) for u in urls), urls
    assert seconds < 60.0


def test_one_frame_range_per_kit(browser, loaded, plan):
    data = browser.evaluate("bilevelKit.data")
    timeline = evaluate(load(TABLE), plan.plan)
    assert len(data["kits"]) == len(plan.plan.kits) == data["n_plan_kits"]
    previous_last = -1.0
    for k, (kit, times) in enumerate(zip(data["kits"], timeline.kits, strict=True), start=1):
        assert kit["kit"] == k
        assert kit["first"] == pytest.approx(times.robot_start * data["fps"])
        assert kit["last"] == pytest.approx(times.arrive * data["fps"])
        assert previous_last <= kit["first"] < kit["last"]
        previous_last = kit["last"]
        _pause_at(browser, (times.robot_start + times.arrive) / 2)
        assert browser.evaluate("bilevelKit.status(bilevelKit.planTime()).kit") == k
        text = browser.evaluate("document.getElementById('bk-kit').textContent")
        assert text == f"kit {k} of {len(plan.plan.kits)}"


def _visible_parts(browser, k: int, n: int) -> list[bool]:
    return browser.evaluate(
        f"[...Array({n}).keys()].map(j => "
        f"bilevelKit.viewer.scene_tree.find(['bk', 'kits', 'k{k}', 'p' + j]).object.visible)"
    )


def test_parts_appear_on_their_slots(browser, loaded, plan):
    data = browser.evaluate("bilevelKit.data")
    work_cell = DEFAULT_WORK_CELL
    for kit, layout in zip(data["kits"], (k.layout for k in plan.plan.kits), strict=True):
        k = kit["kit"]
        arm_start, arm_end = data["arm"][str(k)]
        _pause_at(browser, arm_start + 1e-3)
        assert _visible_parts(browser, k, len(layout)) == [False] * len(layout)
        _pause_at(browser, arm_end + 1e-3)
        assert _visible_parts(browser, k, len(layout)) == [True] * len(layout)
        base = browser.evaluate(  # each part's position in the robot base frame (the bk node)
            "(() => { const bk = bilevelKit.viewer.scene_tree.find(['bk']).object; "
            "bilevelKit.viewer.scene.updateMatrixWorld(true); "
            f"return [...Array({len(layout)}).keys()].map(j => {{ const o = bilevelKit.viewer"
            f".scene_tree.find(['bk', 'kits', 'k{k}', 'p' + j]).object; "
            "return bk.worldToLocal(o.getWorldPosition(o.position.clone())).toArray(); }); })()"
        )
        for p, xyz in zip(layout, base, strict=True):
            slot = work_cell.tray_to_base(p.x, p.y)
            assert np.linalg.norm(np.array(xyz[:2]) - slot[:2]) <= 1e-3
            assert slot[2] < xyz[2] < slot[2] + 0.02  # lying on the tray


def _pixels(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=int)


def test_canvas_is_not_blank(browser, loaded):
    _pause_at(browser, 60.0)
    with_scene = _pixels(browser.screenshot())
    browser.evaluate(
        "bilevelKit.viewer.scene_tree.find(['bk']).object.visible = false; "
        "bilevelKit.viewer.set_dirty(); 1"
    )
    browser.evaluate(_FRAMES)
    empty = _pixels(browser.screenshot())
    browser.evaluate(
        "bilevelKit.viewer.scene_tree.find(['bk']).object.visible = true; "
        "bilevelKit.viewer.set_dirty(); 1"
    )
    changed = np.abs(with_scene - empty).sum(axis=2) > 30
    assert changed.mean() > 0.02, f"only {changed.mean():.2%} of the pixels show the scene"


def test_one_kit_page(browser, pages, plan):
    _seconds, events = browser.open(pages["kit3"])
    browser.evaluate(_FRAMES)
    assert console_errors(events + browser.drain()) == []
    data = browser.evaluate("bilevelKit.data")
    assert [k["kit"] for k in data["kits"]] == [3]
    times = evaluate(load(TABLE), plan.plan).kits[2]
    assert data["t0"] == pytest.approx(times.robot_start)
    assert data["kits"][0]["first"] == 0.0
    assert json.dumps(data)  # plain data
