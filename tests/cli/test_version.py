"""``bilevel-kit --version`` prints the package version."""

from __future__ import annotations

import bilevel_kit
from bilevel_kit.cli import main


def test_version(capsys):
    assert main(["--version"]) == 0
    out, err = capsys.readouterr()
    assert out == f"bilevel-kit {bilevel_kit.__version__}\n" and err == ""
