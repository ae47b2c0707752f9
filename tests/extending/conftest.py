"""The extension guide's example plugin (docs/extending.md), registered for a test."""

from __future__ import annotations

from pathlib import Path

import pytest

from bilevel_kit.methods import REGISTRY
from bilevel_kit.objectives import OBJECTIVES
from bilevel_kit.sim import POLICIES

PLUGIN = Path(__file__).parent / "example_plugin"


@pytest.fixture
def pairs(monkeypatch):
    """The example registered the way the guide says (its plugin function: the objective
    ``kit_handling``, the method and the policy ``pairs``), then removed."""
    monkeypatch.syspath_prepend(str(PLUGIN))
    import bk_example_plugin

    bk_example_plugin.register_plugin()
    yield "pairs"
    REGISTRY.remove("pairs")
    POLICIES.remove("pairs")
    OBJECTIVES.remove("kit_handling")
