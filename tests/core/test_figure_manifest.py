"""Committed figures match the code that draws them (issue 40, item 3): every figure under
docs/figures/ has an entry in docs/figures/MANIFEST.json naming the command that draws it and
the SHA-256 of its inputs and code; the test fails when a figure has no entry, an entry names
a missing file, or a digest no longer matches (the figure is stale: rerun the command the
message names, or ``python docs/figures/regenerate.py NAME``). docs/figures.md explains."""

from __future__ import annotations

import copy
import importlib.util
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: The figures known to be stale (``stale_known`` of the manifest): their commands run for
#: hours or are a manual screenshot. This set may only shrink: redraw one, remove it here.
STALE_CEILING: set[str] = set()  # none since every committed figure was redrawn


@pytest.fixture(scope="module")
def regen() -> ModuleType:
    spec = importlib.util.spec_from_file_location("regenerate", ROOT / "docs/figures/regenerate.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_committed_figure_matches_its_manifest_entry(regen):
    found = regen.problems(regen.load())
    assert not found, "\n".join(found)


def test_stale_known_only_shrinks_and_says_why(regen):
    stale = regen.load()["stale_known"]
    assert set(stale) <= STALE_CEILING, set(stale) - STALE_CEILING
    assert all(reason.strip() for reason in stale.values())


def test_every_entry_says_how_it_is_drawn(regen):
    for name, entry in regen.load()["figures"].items():
        assert entry.get("command") or entry.get("snippet"), name
        assert entry["cost"] in ("quick", "long", "manual"), name
        if entry.get("snippet"):
            assert "save" in regen.snippet_code(entry["snippet"]), name
        if entry.get("command") and entry["cost"] != "manual":
            assert entry["command"].split()[0] in regen.HEADS, name


def test_each_kind_of_drift_is_caught(regen):
    manifest = copy.deepcopy(regen.load())
    figures = manifest["figures"]
    manifest["stale_known"] = {}
    figures.pop("docs/figures/gantt-1-kit.png")  # (a) a committed figure without an entry
    gantt = figures["docs/figures/gantt-12-kits.png"]
    gantt["code"]["bilevel_kit/plots/gantt.py"] = "0" * 64  # (b) the code changed since
    figures["docs/figures/tutorial-compare.png"]["inputs"]["instances/gone.json"] = "0" * 64
    found = "\n".join(regen.problems(manifest))
    assert "docs/figures/gantt-1-kit.png: committed figure without a manifest entry" in found
    assert (
        "docs/figures/gantt-12-kits.png is stale: bilevel_kit/plots/gantt.py changed since it "
        "was drawn; rerun docs/figures.md#regenerating-the-figures-above (or: python "
        "docs/figures/regenerate.py gantt-12-kits.png)"
    ) in found
    assert "tutorial-compare.png: names instances/gone.json, which does not exist" in found  # (c)
