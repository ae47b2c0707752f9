"""Shared fixtures: the shipped instances and a small instance document to break in tests."""

from __future__ import annotations

import copy
import os
from pathlib import Path

import pytest
from paths import INSTANCES, ROOT

from bilevel_kit.instance import document

os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def table():
    from bilevel_kit import load

    return load(INSTANCES / "hrc_table.json")


@pytest.fixture(scope="session")
def stool():
    from bilevel_kit import load

    return load(INSTANCES / "stool.json")


@pytest.fixture(scope="session")
def tiny():
    from bilevel_kit import load

    return load(INSTANCES / "tiny.json")


TINY_DOC = document(
    "doc",
    [
        {"id": "a", "width": 10.0, "height": 10.0, "pick_time": 1.0},
        {"id": "b", "width": 40.0, "height": 5.0, "pick_time": 2.0, "rotatable": False},
    ],
    [
        {"id": "x", "parts": [{"type": "a", "count": 2}], "human_time": {"mean": 5.0}},
        {"id": "y", "parts": [{"type": "b", "count": 1}], "human_time": {"mean": 3.0}},
        {"id": "z", "parts": [], "human_time": {"mean": 2.0}},
    ],
    precedence=[["x", "y"]],
)


@pytest.fixture
def doc() -> dict:
    """A fresh copy of a small valid instance document to break in tests."""
    return copy.deepcopy(TINY_DOC)


def pytest_sessionstart(session):
    """Load OR-Tools before any test imports cvxpy (see bilevel_kit/_native.py), and compile
    greedy-ce's kernels once up front (docs/scaling.md#first-run): on a fresh clone the first
    test that runs them would otherwise print the compile notice among its own output."""
    from bilevel_kit._native import ortools_first
    from bilevel_kit.heuristics.warmup import compile_kernels

    ortools_first()
    compile_kernels()
