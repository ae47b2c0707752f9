"""Every exit code the CLI uses is listed, with one meaning, by ``--help`` and by the README."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bilevel_kit.cli import common, main

ROOT = Path(__file__).resolve().parents[2]


def test_every_exit_constant_has_a_meaning() -> None:
    constants = {v for k, v in vars(common).items() if k.startswith("EXIT_") and k != "EXIT_CODES"}
    assert constants == set(common.EXIT_CODES)


def test_help_lists_every_exit_code(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    listed = {int(m) for m in re.findall(r"^  (\d+) +\S", out.split("exit codes:")[1], re.M)}
    assert listed == set(common.EXIT_CODES)


def test_readme_lists_every_exit_code() -> None:
    """The README's "Exit codes" paragraph names each code in bold: **0**, **1**, ..."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    match = re.search(r"Exit codes:(.*?)(?:\n\n|$)", text, re.S)
    assert match, "README.md has no 'Exit codes:' paragraph"
    listed = {int(m) for m in re.findall(r"\*\*(\d+)\*\*", match[1])}
    assert listed == set(common.EXIT_CODES)
